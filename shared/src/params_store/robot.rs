//! Stored values onto a [`RobotConfig`] through its one validation
//! ([`RobotConfig::validate`], by way of the parameter table [`PARAMS`]): what the firmware
//! does at boot with what [`ParamStore`] kept.
//!
//! Every row of [`PARAMS`] (the robot file's keys) is a stored parameter; its id is the
//! name's hash ([`ParamId::of_name`]), so a row added or reordered later keeps every stored
//! value. A stored value the model refuses is not applied: the field keeps its default and
//! [`BootParams::refused`] counts it.

use super::{LoadReport, ParamId, ParamStore};
use crate::params::{set_many, PARAMS, PARAM_COUNT};
use crate::robot::{ConfigError, RobotConfig};
use embedded_storage::nor_flash::NorFlash;

/// The ids of [`PARAMS`], in its order.
pub const ROBOT_PARAM_IDS: [ParamId; PARAM_COUNT] = {
    let mut ids = [ParamId(0); PARAM_COUNT];
    let mut i = 0;
    while i < PARAM_COUNT {
        ids[i] = ParamId::of_name(PARAMS[i].name);
        i += 1;
    }
    ids
};

/// What the boot made of the store.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BootParams {
    /// What the store held.
    pub load: LoadReport,
    /// Stored values applied.
    pub applied: u8,
    /// Stored values the model refused (those fields kept their defaults).
    pub refused: u8,
    /// The first refusal: field, value, what is accepted.
    pub first_refused: Option<ConfigError>,
}

/// `base` with the stored `values` (indexed like [`PARAMS`]) that validation accepts.
/// All together if the result validates; otherwise one at a time in table order, each kept
/// only if the config still validates with it. `base` is assumed valid (a refused value is
/// blamed on itself).
pub fn apply_values(
    base: &RobotConfig,
    values: &[Option<f32>],
) -> (RobotConfig, u8, u8, Option<ConfigError>) {
    let mut stored: heapless::Vec<(&crate::params::Param, f32), PARAM_COUNT> = heapless::Vec::new();
    for (p, v) in PARAMS.iter().zip(values) {
        if let Some(v) = v {
            // Cannot fail: at most one value per row.
            let _ = stored.push((p, *v));
        }
    }
    let count = stored.len() as u8;
    let mut all = *base;
    if set_many(&mut all, &stored).is_ok() {
        return (all, count, 0, None);
    }
    let (mut config, mut applied, mut refused, mut first) = (*base, 0, 0, None);
    for (p, v) in &stored {
        match p.set(&mut config, *v) {
            Ok(()) => applied += 1,
            Err(e) => {
                refused += 1;
                first = first.or(Some(e));
            }
        }
    }
    (config, applied, refused, first)
}

/// Load `store` and apply what it holds to `base` (see [`apply_values`]).
pub fn load_robot_config<F: NorFlash>(
    store: &mut ParamStore<F>,
    base: &RobotConfig,
) -> (RobotConfig, BootParams) {
    let mut values = [None; PARAM_COUNT];
    let load = store.load(&ROBOT_PARAM_IDS, &mut values);
    let (config, applied, refused, first_refused) = apply_values(base, &values);
    (
        config,
        BootParams {
            load,
            applied,
            refused,
            first_refused,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_distinct_and_none_is_the_format_record() {
        for (i, a) in ROBOT_PARAM_IDS.iter().enumerate() {
            assert_ne!(*a, ParamId::FORMAT, "{}", PARAMS[i].name);
            for b in &ROBOT_PARAM_IDS[i + 1..] {
                assert_ne!(a, b);
            }
        }
    }

    #[test]
    fn a_refused_value_keeps_its_default_and_is_counted() {
        let mut values = [None; PARAM_COUNT];
        let wheel = PARAMS.iter().position(|p| p.name == "wheel_radius_m");
        let range = PARAMS.iter().position(|p| p.name == "sonar_range_m");
        let pulses = PARAMS
            .iter()
            .position(|p| p.name == "encoder_pulses_per_rev");
        values[wheel.unwrap()] = Some(0.05);
        values[range.unwrap()] = Some(7.0); // above the 6 m limit
        values[pulses.unwrap()] = Some(1000.5); // not whole
        let (c, applied, refused, first) = apply_values(&RobotConfig::DEFAULT, &values);
        assert_eq!((applied, refused), (1, 2));
        assert_eq!(c.wheel_radius_m, 0.05);
        assert_eq!(c.sonar_range_m, RobotConfig::DEFAULT.sonar_range_m);
        assert_eq!(
            c.encoder_pulses_per_rev,
            RobotConfig::DEFAULT.encoder_pulses_per_rev
        );
        assert_eq!(first.unwrap().field, "encoder_pulses_per_rev");
    }

    #[test]
    fn values_valid_only_together_are_applied_together() {
        // A longer minimum range than the default maximum: valid only with the new maximum.
        let mut values = [None; PARAM_COUNT];
        let min = PARAMS.iter().position(|p| p.name == "sonar_min_range_m");
        let max = PARAMS.iter().position(|p| p.name == "sonar_range_m");
        values[min.unwrap()] = Some(2.0);
        values[max.unwrap()] = Some(3.0);
        let (c, applied, refused, _) = apply_values(&RobotConfig::DEFAULT, &values);
        assert_eq!((applied, refused), (2, 0));
        assert_eq!((c.sonar_min_range_m, c.sonar_range_m), (2.0, 3.0));
    }
}
