//! Stored values onto a [`RobotConfig`] through its one validation
//! ([`RobotConfig::validate`]): what the firmware does at boot with what [`ParamStore`] kept.
//!
//! The named parameter table of issue 25 (robot file keys, units, limits) is being built
//! beside this; until it joins the store, [`ROBOT_PARAMS`] lists a placeholder set of
//! `RobotConfig` fields by their robot-file names (the id is the name's hash, so the ids stay
//! when the table replaces this list). A stored value the model refuses is not applied: the
//! field keeps its default and [`BootParams::refused`] counts it.

use super::{LoadReport, ParamId, ParamStore};
use crate::robot::{ConfigError, RobotConfig};
use embedded_storage::nor_flash::NorFlash;

/// A `RobotConfig` field reachable as a stored parameter.
pub struct RobotParam {
    /// The field's name (= the robot file's key).
    pub name: &'static str,
    /// The field's value as an `f32`.
    pub get: fn(&RobotConfig) -> f32,
    /// Set the field (integers: only whole values in range are taken; others are made
    /// invalid so that validation refuses them).
    pub set: fn(&mut RobotConfig, f32),
}

/// `RobotParam` of an `f32` field.
macro_rules! f32_param {
    ($field:ident) => {
        RobotParam {
            name: stringify!($field),
            get: |c| c.$field,
            set: |c, v| c.$field = v,
        }
    };
}

/// Placeholder list of the parameters the boot applies (see the module's doc).
pub const ROBOT_PARAMS: [RobotParam; 14] = [
    f32_param!(planning_radius_m),
    f32_param!(wheel_radius_m),
    f32_param!(half_axle_m),
    f32_param!(point_offset_m),
    RobotParam {
        name: "encoder_pulses_per_rev",
        get: |c| c.encoder_pulses_per_rev as f32,
        // A fraction, a negative or NaN becomes 0, which validation refuses (the cast
        // saturates; a whole value past the limit fails validation itself).
        set: |c, v| {
            let whole = v as u32;
            c.encoder_pulses_per_rev = if whole as f32 == v { whole } else { 0 };
        },
    },
    f32_param!(motor_gain_rad_s_per_v),
    f32_param!(motor_time_constant_s),
    f32_param!(max_voltage_v),
    f32_param!(pid_kp_v_per_rad_s),
    f32_param!(pid_ki_v_per_rad),
    f32_param!(pid_kd_v_s2_per_rad),
    f32_param!(sonar_offset_m),
    f32_param!(sonar_min_range_m),
    f32_param!(sonar_range_m),
];

/// Number of [`ROBOT_PARAMS`].
pub const ROBOT_PARAM_COUNT: usize = ROBOT_PARAMS.len();

/// The ids of [`ROBOT_PARAMS`], in its order.
pub const ROBOT_PARAM_IDS: [ParamId; ROBOT_PARAM_COUNT] = {
    let mut ids = [ParamId(0); ROBOT_PARAM_COUNT];
    let mut i = 0;
    while i < ROBOT_PARAM_COUNT {
        ids[i] = ParamId::of_name(ROBOT_PARAMS[i].name);
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

/// `base` with the stored `values` (indexed like [`ROBOT_PARAMS`]) that validation accepts.
/// All together if the result validates; otherwise one at a time in table order, each kept
/// only if the config still validates with it. `base` is assumed valid (a refused value is
/// blamed on itself).
pub fn apply_values(
    base: &RobotConfig,
    values: &[Option<f32>],
) -> (RobotConfig, u8, u8, Option<ConfigError>) {
    let stored = || {
        ROBOT_PARAMS
            .iter()
            .zip(values)
            .filter_map(|(p, v)| v.map(|v| (p, v)))
    };
    let mut all = *base;
    stored().for_each(|(p, v)| (p.set)(&mut all, v));
    let count = stored().count() as u8;
    if all.validate().is_ok() {
        return (all, count, 0, None);
    }
    let (mut config, mut applied, mut refused, mut first) = (*base, 0, 0, None);
    for (p, v) in stored() {
        let mut candidate = config;
        (p.set)(&mut candidate, v);
        match candidate.validate() {
            Ok(()) => {
                config = candidate;
                applied += 1;
            }
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
    let mut values = [None; ROBOT_PARAM_COUNT];
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
            assert_ne!(*a, ParamId::FORMAT, "{}", ROBOT_PARAMS[i].name);
            for b in &ROBOT_PARAM_IDS[i + 1..] {
                assert_ne!(a, b);
            }
        }
    }

    #[test]
    fn getters_and_setters_name_the_same_field() {
        for p in &ROBOT_PARAMS {
            let mut c = RobotConfig::DEFAULT;
            let v = (p.get)(&c) + 1.0;
            (p.set)(&mut c, v);
            assert_eq!((p.get)(&c), v, "{}", p.name);
            assert_ne!(c, RobotConfig::DEFAULT, "{}", p.name);
        }
    }

    #[test]
    fn a_refused_value_keeps_its_default_and_is_counted() {
        let mut values = [None; ROBOT_PARAM_COUNT];
        let wheel = ROBOT_PARAMS.iter().position(|p| p.name == "wheel_radius_m");
        let range = ROBOT_PARAMS.iter().position(|p| p.name == "sonar_range_m");
        let pulses = ROBOT_PARAMS
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
        let mut values = [None; ROBOT_PARAM_COUNT];
        let min = ROBOT_PARAMS
            .iter()
            .position(|p| p.name == "sonar_min_range_m");
        let max = ROBOT_PARAMS.iter().position(|p| p.name == "sonar_range_m");
        values[min.unwrap()] = Some(2.0);
        values[max.unwrap()] = Some(3.0);
        let (c, applied, refused, _) = apply_values(&RobotConfig::DEFAULT, &values);
        assert_eq!((applied, refused), (2, 0));
        assert_eq!((c.sonar_min_range_m, c.sonar_range_m), (2.0, 3.0));
    }
}
