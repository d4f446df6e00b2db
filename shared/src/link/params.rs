//! The device's parameters on the link: `ParamList`, `ParamGet` and `ParamSet` answered from
//! the robot config the device runs its next mission with (issue 25, part 2).
//!
//! Why: a user tunes a robot without editing Rust or reflashing, with the names of the robot
//! file (`twil param set wheel_radius_m 0.07`). Seed 003 compiles its constants in
//! (`twlparam.h`); this is the ArduPilot habit instead: read, set, keep across resets.
//!
//! - A row is one of [`PARAMS`] (its index is its place in the table; a reply carries one row,
//!   well inside a frame: about 80 bytes).
//! - `ParamSet` goes through [`Param::set`], the one validation the simulator and the robot
//!   file use, against the device's current config: a refused value changes nothing and the
//!   reply names the field whose rule broke, its value and the rule.
//! - An accepted value is stored first ([`ParamSave`], the device's [`ParamStore`]) and only
//!   then applied, so a failed write changes nothing either. A device without a store (a test,
//!   a shell that attaches none) applies the value in RAM.
//! - `controller_period_s` stays at its default: the device's control period is built in.
//! - Refused while a mission runs or is paused: the running mission's config does not change
//!   under it; the next `StartMission` takes the new config.
//!
//! Work is bounded: one lookup in the table, one validation, one store write.
//!
//! Measured: the unit tests below (`cargo test --release -p twil-core link::params`).

use heapless::String;

use super::message::{
    ErrorCode, ErrorReply, ParamEntry, ParamRefusal, Reply, Request, PARAM_NAME_BYTES,
};
use crate::params::{Param, PARAMS, PARAM_COUNT};
use crate::params_store::{ParamId, ParamStore, StoreError, StoreStatus};
use crate::robot::RobotConfig;
use embedded_storage::nor_flash::NorFlash;

/// The one row a device cannot change: its control task runs every 50 ms, a period built in
/// (the firmware's `PERIOD_MS`, `--remote sim`'s tick), so a config with another period
/// would integrate the wrong time step. The row and its rule.
const FIXED_PERIOD: (&str, &str) = (
    "controller_period_s",
    "0.05 s: the device's control period is built in",
);

/// Where the device keeps an accepted value: its [`ParamStore`] (flash on a board, RAM under
/// QEMU and `--remote sim`).
pub trait ParamSave {
    /// Store `value` as the newest value of `id`.
    fn save(&mut self, id: ParamId, value: f32) -> Result<(), StoreError>;
}

impl<F: NorFlash> ParamSave for ParamStore<F> {
    fn save(&mut self, id: ParamId, value: f32) -> Result<(), StoreError> {
        ParamStore::save(self, id, value)
    }
}

/// The robot config the device's next mission uses, and what its store holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviceParams {
    /// The config (the defaults with the stored values applied at boot, then every accepted
    /// `ParamSet`).
    pub robot: RobotConfig,
    /// What the store held at boot, `Ok` after a value was stored; `None`: no store.
    pub store: Option<StoreStatus>,
}

impl DeviceParams {
    /// The defaults, no store.
    pub const DEFAULT: DeviceParams = DeviceParams {
        robot: RobotConfig::DEFAULT,
        store: None,
    };

    /// Answer a parameter request (`None`: not one). `running`: a mission runs or is paused
    /// (then `ParamSet` is refused with `WrongState` `state`). `store`: where an accepted value
    /// is written first.
    pub fn handle(
        &mut self,
        request: &Request,
        running: Option<u32>,
        store: Option<&mut dyn ParamSave>,
    ) -> Option<Result<Reply, ErrorReply>> {
        Some(match request {
            Request::ParamList { index } => match PARAMS.get(*index as usize) {
                Some(p) => Ok(Reply::Param(self.entry(*index as usize, p))),
                None => Err(ErrorReply::new(
                    ErrorCode::OutOfRange,
                    *index as u32,
                    PARAM_COUNT as u32,
                )),
            },
            Request::ParamGet { name } => self
                .lookup(name)
                .map(|(i, p)| Reply::Param(self.entry(i, p))),
            Request::ParamSet { name, value } => {
                if let Some(state) = running {
                    return Some(Err(ErrorReply::new(ErrorCode::WrongState, state, 0)));
                }
                self.set(name, *value, store)
            }
            _ => return None,
        })
    }

    fn lookup(&self, name: &str) -> Result<(usize, &'static Param), ErrorReply> {
        PARAMS
            .iter()
            .position(|p| p.name == name)
            .map(|i| (i, &PARAMS[i]))
            .ok_or(ErrorReply::new(
                ErrorCode::UnknownParam,
                name.len() as u32,
                0,
            ))
    }

    fn set(
        &mut self,
        name: &str,
        value: f32,
        store: Option<&mut dyn ParamSave>,
    ) -> Result<Reply, ErrorReply> {
        let (index, param) = self.lookup(name)?;
        if param.name == FIXED_PERIOD.0 && value != param.default_value() {
            return Ok(Reply::ParamRefused(ParamRefusal {
                name: bounded(param.name),
                value,
                rule: bounded(FIXED_PERIOD.1),
            }));
        }
        let mut candidate = self.robot;
        if let Err(e) = param.set(&mut candidate, value) {
            return Ok(Reply::ParamRefused(ParamRefusal {
                name: bounded(e.field),
                value: e.value,
                rule: bounded(e.expected),
            }));
        }
        if let Some(store) = store {
            store
                .save(ParamId::of_name(param.name), value)
                .map_err(|e| {
                    let why = match e {
                        StoreError::Flash => 0,
                        StoreError::Full => 1,
                        StoreError::Corrupt => 2,
                        _ => 3,
                    };
                    ErrorReply::new(ErrorCode::StoreFailed, why, 0)
                })?;
            self.store = Some(StoreStatus::Ok);
        }
        self.robot = candidate;
        Ok(Reply::Param(self.entry(index, param)))
    }

    /// Row `index` (`param` = `PARAMS[index]`) as the link carries it.
    fn entry(&self, index: usize, param: &Param) -> ParamEntry {
        ParamEntry {
            index: index as u16,
            count: PARAM_COUNT as u16,
            name: bounded(param.name),
            unit: bounded(param.unit),
            value: param.get(&self.robot),
            default: param.default_value(),
            min: param.min,
            max: param.max,
            store: self.store,
        }
    }
}

/// `text` in a string of `N` bytes, cut at the last character boundary that fits.
fn bounded<const N: usize>(text: &str) -> String<N> {
    let mut end = text.len().min(N);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let mut s = String::new();
    // Cannot fail: `end` <= N.
    let _ = s.push_str(&text[..end]);
    s
}

/// `name` as a [`Request::ParamGet`] / [`Request::ParamSet`] carries it; `None` when it is
/// longer than [`PARAM_NAME_BYTES`] (no parameter's name is).
pub fn wire_name(name: &str) -> Option<String<PARAM_NAME_BYTES>> {
    String::try_from(name).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params_store::ram_flash::RamFlash;

    fn set(name: &str, value: f32) -> Request {
        Request::ParamSet {
            name: wire_name(name).unwrap(),
            value,
        }
    }

    fn get(name: &str) -> Request {
        Request::ParamGet {
            name: wire_name(name).unwrap(),
        }
    }

    fn value_of(reply: Option<Result<Reply, ErrorReply>>) -> f32 {
        match reply {
            Some(Ok(Reply::Param(e))) => e.value,
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn list_walks_every_row_and_stops_past_the_end() {
        let mut d = DeviceParams::DEFAULT;
        for (i, p) in PARAMS.iter().enumerate() {
            match d.handle(&Request::ParamList { index: i as u16 }, None, None) {
                Some(Ok(Reply::Param(e))) => {
                    assert_eq!((e.index as usize, e.count as usize), (i, PARAM_COUNT));
                    assert_eq!(e.name.as_str(), p.name);
                    assert_eq!(e.unit.as_str(), p.unit);
                    assert_eq!((e.value, e.default), (p.default_value(), p.default_value()));
                    assert_eq!((e.min, e.max), (p.min, p.max));
                    assert_eq!(e.store, None);
                }
                other => panic!("{other:?}"),
            }
        }
        let past = d.handle(
            &Request::ParamList {
                index: PARAM_COUNT as u16,
            },
            None,
            None,
        );
        assert_eq!(
            past,
            Some(Err(ErrorReply::new(
                ErrorCode::OutOfRange,
                PARAM_COUNT as u32,
                PARAM_COUNT as u32
            )))
        );
        assert_eq!(d.handle(&Request::Status, None, None), None);
    }

    #[test]
    fn a_set_is_stored_then_applied_and_survives_a_reload() {
        let mut flash = RamFlash::<2048, 1024>::ERASED;
        let mut store = ParamStore::new(&mut flash, 0..2048).unwrap();
        let mut d = DeviceParams {
            robot: RobotConfig::DEFAULT,
            store: Some(StoreStatus::Empty),
        };
        let v = value_of(d.handle(&set("wheel_radius_m", 0.07), None, Some(&mut store)));
        assert_eq!(v, 0.07);
        assert_eq!(d.robot.wheel_radius_m, 0.07);
        assert_eq!(d.store, Some(StoreStatus::Ok));
        assert_eq!(value_of(d.handle(&get("wheel_radius_m"), None, None)), 0.07);
        // What the next boot makes of the store.
        let (config, boot) =
            crate::params_store::robot::load_robot_config(&mut store, &RobotConfig::DEFAULT);
        assert_eq!(boot.load.status, StoreStatus::Ok);
        assert_eq!((config.wheel_radius_m, boot.applied), (0.07, 1));
    }

    #[test]
    fn a_refused_value_changes_nothing_and_names_the_rule() {
        let mut flash = RamFlash::<2048, 1024>::ERASED;
        let mut store = ParamStore::new(&mut flash, 0..2048).unwrap();
        let mut d = DeviceParams::DEFAULT;
        let before = d;
        let reply = d.handle(&set("wheel_radius_m", -1.0), None, Some(&mut store));
        match reply {
            Some(Ok(Reply::ParamRefused(r))) => {
                assert_eq!(r.name.as_str(), "wheel_radius_m");
                assert_eq!(r.value, -1.0);
                assert_eq!(r.rule.as_str(), "above 0 and at most 1 m");
            }
            other => panic!("{other:?}"),
        }
        match d.handle(&set("controller_period_s", 0.1), None, Some(&mut store)) {
            Some(Ok(Reply::ParamRefused(r))) => assert_eq!(r.rule.as_str(), FIXED_PERIOD.1),
            other => panic!("{other:?}"),
        }
        // A value that breaks another field's rule names that field.
        match d.handle(&set("sonar_min_range_m", 2.0), None, Some(&mut store)) {
            Some(Ok(Reply::ParamRefused(r))) => assert_eq!(r.name.as_str(), "sonar_range_m"),
            other => panic!("{other:?}"),
        }
        assert_eq!(d, before);
        let mut values = [None; PARAM_COUNT];
        let load = store.load(&crate::params_store::robot::ROBOT_PARAM_IDS, &mut values);
        assert_eq!(load.status, StoreStatus::Empty, "nothing was written");
    }

    #[test]
    fn unknown_names_and_running_missions_are_refused() {
        let mut d = DeviceParams::DEFAULT;
        let unknown = ErrorReply::new(ErrorCode::UnknownParam, 12, 0);
        assert_eq!(
            d.handle(&get("wheel_radius"), None, None),
            Some(Err(unknown))
        );
        assert_eq!(
            d.handle(&set("wheel_radius", 1.0), None, None),
            Some(Err(unknown))
        );
        assert_eq!(
            d.handle(&set("wheel_radius_m", 0.07), Some(2), None),
            Some(Err(ErrorReply::new(ErrorCode::WrongState, 2, 0)))
        );
        assert_eq!(d, DeviceParams::DEFAULT);
        // Reads are answered while a mission runs.
        assert_eq!(
            value_of(d.handle(&get("wheel_radius_m"), Some(2), None)),
            0.075
        );
    }

    /// A store whose every write fails.
    struct Broken;
    impl ParamSave for Broken {
        fn save(&mut self, _: ParamId, _: f32) -> Result<(), StoreError> {
            Err(StoreError::Flash)
        }
    }

    #[test]
    fn a_failed_write_changes_nothing() {
        let mut d = DeviceParams::DEFAULT;
        assert_eq!(
            d.handle(&set("wheel_radius_m", 0.07), None, Some(&mut Broken)),
            Some(Err(ErrorReply::new(ErrorCode::StoreFailed, 0, 0)))
        );
        assert_eq!(d, DeviceParams::DEFAULT);
    }

    #[test]
    fn bounded_cuts_at_a_character_boundary() {
        assert_eq!(bounded::<4>("abcdef").as_str(), "abcd");
        assert_eq!(bounded::<4>("ab±c").as_str(), "ab±");
        assert_eq!(bounded::<3>("ab±c").as_str(), "ab");
        assert!(wire_name("a_name_of_thirty_three_bytes_long").is_none());
    }
}
