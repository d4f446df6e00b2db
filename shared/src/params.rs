//! The robot's parameters: one row per constant of [`RobotConfig`], by the name a user sees.
//!
//! Why: a user who builds their own Twil-like robot sets its wheel radius, axle, gains and
//! sonar limits without editing Rust. The same names are the keys of the robot file
//! (`twil robot init`, `--robot FILE.toml`), the keys of `summary.json`'s `robot` object, the
//! rows of the constants table of `docs/robot-model.md` (generated from [`PARAMS`]) and,
//! later, the device's parameters read and set over the link. Seed 003 does not list its
//! constants header (`twlparam.h`); each row's `source` says where its default comes from
//! (a seed constant, or a value chosen for a robot of the seed's size).
//!
//! Every value crosses this table as an `f32` (what a parameter message on the link carries):
//!
//! - [`Kind::Real`]: the field's value;
//! - [`Kind::Integer`]: a whole number, exact in an `f32` up to 2^24 (every integer row's
//!   maximum is far below);
//! - [`Kind::Bool`]: `0` false, `1` true;
//! - [`Kind::Choice`]: the index of the choice in the row's list of names (`0` the first).
//!
//! [`Param::set`] refuses a value that is not of the row's kind, and then validates the whole
//! config with [`RobotConfig::validate`] (the one validation the simulator and the firmware
//! share): a refused value leaves the config unchanged. Work is bounded: a lookup walks the
//! [`PARAM_COUNT`] rows once.
//!
//! `noise_seed` is not a row: it seeds the simulated noise of one run (`--seed`), it is no
//! constant of a robot, and a `u64` does not survive an `f32`.
//!
//! Measured: every row's getter and setter round-trip on the defaults and on a second value,
//! and every refused value leaves the config unchanged (unit tests below).

use crate::robot::{ConfigError, RobotConfig};
use crate::sonar::SweepLayout;

/// What a parameter's `f32` value stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// A real number.
    Real,
    /// A whole number.
    Integer,
    /// `0` false, `1` true.
    Bool,
    /// The index of one of these names.
    Choice(&'static [&'static str]),
}

/// One constant of the robot model.
#[derive(Clone, Copy)]
pub struct Param {
    /// The key: the [`RobotConfig`] field's name, unit included (`wheel_radius_m`).
    pub name: &'static str,
    /// The unit, in words (`m`, `rad/s per V`, `` for a number without one).
    pub unit: &'static str,
    /// What it means.
    pub doc: &'static str,
    /// Where the default comes from.
    pub source: &'static str,
    /// How the `f32` is read.
    pub kind: Kind,
    /// Lower limit: with the other fields at their defaults, a value below it is refused
    /// (`rule` says whether the limit itself is accepted).
    pub min: f32,
    /// Upper limit, likewise (`f32::INFINITY`: none).
    pub max: f32,
    /// The rule in words, as [`RobotConfig::validate`] states it (bounds may be exclusive
    /// or depend on another field).
    pub rule: &'static str,
    get: fn(&RobotConfig) -> f32,
    put: fn(&mut RobotConfig, f32),
}

impl core::fmt::Debug for Param {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Param").field("name", &self.name).finish()
    }
}

/// Why a value was refused because of its kind (before the config's own rules).
const WHOLE: &str = "a whole number";
const BOOL: &str = "0 (false) or 1 (true)";
const CHOICE: &str = "the index of a choice";

impl Param {
    /// The value of this constant in `config`.
    pub fn get(&self, config: &RobotConfig) -> f32 {
        (self.get)(config)
    }

    /// The default value.
    pub fn default_value(&self) -> f32 {
        (self.get)(&RobotConfig::DEFAULT)
    }

    /// Set this constant in `config` to `value`, if the value is of the row's kind and the
    /// whole config stays valid; otherwise `config` is left unchanged and the error names the
    /// field, the value and the rule broken.
    pub fn set(&self, config: &mut RobotConfig, value: f32) -> Result<(), ConfigError> {
        set_many(config, &[(self, value)])
    }

    /// Check that `value` is of the row's kind (a whole number, 0 or 1, a choice's index).
    fn check_kind(&self, value: f32) -> Result<(), ConfigError> {
        let refuse = |expected| ConfigError {
            field: self.name,
            value,
            expected,
        };
        let whole = value.is_finite() && value == (value as i64) as f32;
        match self.kind {
            Kind::Real => {}
            Kind::Integer if !whole || value < self.min || value > self.max => {
                return Err(refuse(if whole { self.rule } else { WHOLE }))
            }
            Kind::Bool if !(value == 0.0 || value == 1.0) => return Err(refuse(BOOL)),
            Kind::Choice(names) if !whole || value < 0.0 || value >= names.len() as f32 => {
                return Err(refuse(CHOICE))
            }
            _ => {}
        }
        Ok(())
    }

    /// The name of choice `value` of a [`Kind::Choice`] row (`None` for other kinds or an
    /// index out of the list).
    pub fn choice_name(&self, value: f32) -> Option<&'static str> {
        match self.kind {
            Kind::Choice(names) if value >= 0.0 => names.get(value as usize).copied(),
            _ => None,
        }
    }

    /// The index of choice `name` of a [`Kind::Choice`] row.
    pub fn choice_index(&self, name: &str) -> Option<f32> {
        match self.kind {
            Kind::Choice(names) => names.iter().position(|n| *n == name).map(|i| i as f32),
            _ => None,
        }
    }
}

/// How many rows [`PARAMS`] has.
pub const PARAM_COUNT: usize = 39;

/// Set several constants at once (a robot file, a batch of device parameters): each value
/// must be of its row's kind, then the whole config must be valid with all of them, so that
/// values that depend on each other (`sonar_min_range_m` below `sonar_range_m`) can change
/// together. On any error `config` is unchanged; the error names the first field refused.
pub fn set_many(config: &mut RobotConfig, values: &[(&Param, f32)]) -> Result<(), ConfigError> {
    let mut candidate = *config;
    for (param, value) in values {
        param.check_kind(*value)?;
        (param.put)(&mut candidate, *value);
    }
    candidate.validate()?;
    *config = candidate;
    Ok(())
}

/// The row named `name`, if any.
pub fn find(name: &str) -> Option<&'static Param> {
    PARAMS.iter().find(|p| p.name == name)
}

/// One row of a real-valued field.
macro_rules! real {
    ($field:ident, $unit:expr, $min:expr, $max:expr, $rule:expr, $doc:expr, $source:expr) => {
        Param {
            name: stringify!($field),
            unit: $unit,
            doc: $doc,
            source: $source,
            kind: Kind::Real,
            min: $min,
            max: $max,
            rule: $rule,
            get: |c| c.$field,
            put: |c, v| c.$field = v,
        }
    };
}

/// One row of an integer field (`$t` its type; [`Param::set`] has checked the value is whole
/// and within the row's bounds, which fit `$t`, before the cast).
macro_rules! integer {
    ($field:ident, $t:ty, $unit:expr, $min:expr, $max:expr, $rule:expr, $doc:expr, $source:expr) => {
        Param {
            name: stringify!($field),
            unit: $unit,
            doc: $doc,
            source: $source,
            kind: Kind::Integer,
            min: $min,
            max: $max,
            rule: $rule,
            get: |c| c.$field as f32,
            put: |c, v| c.$field = v as $t,
        }
    };
}

const INF: f32 = f32::INFINITY;

/// Every constant of the robot model, in the order of [`RobotConfig`]'s fields.
pub static PARAMS: [Param; PARAM_COUNT] = [
    real!(planning_radius_m, "m", 0.0, 10.0, "0 to 10 m",
        "radius the planner grows obstacles by; the body is 0.10 m smaller (seed `RAIO_REAL`), the difference is the safety margin",
        "seed: the `.par` radius of its worlds (0.40); a `.par` file's radius replaces it unless the robot file sets it"),
    real!(wheel_radius_m, "m", 0.0, 1.0, "above 0 and at most 1 m",
        "wheel radius",
        "chosen: 15 cm wheels, usual for a 60 cm indoor base (the seed's `twlparam.h` is not in the seed)"),
    real!(half_axle_m, "m", 0.0, 5.0, "above 0 and at most 5 m",
        "half the distance between the two wheel contact points",
        "chosen: wheels inside the 0.30 m body"),
    real!(point_offset_m, "m", 0.0, 5.0, "above 0 and at most 5 m",
        "distance of the controlled point ahead of the axle midpoint (the feedback divides by it)",
        "chosen (seed `Xcr`): larger is smoother but cuts corners wider"),
    integer!(encoder_pulses_per_rev, u32, "counts", 1.0, 1_000_000.0, "1 to 1000000 counts",
        "encoder counts per wheel revolution, after gearing and x4 quadrature",
        "chosen: 0.24 mm of travel per count"),
    real!(motor_gain_rad_s_per_v, "rad/s per V", 0.0, INF, "above 0 rad/s per V",
        "steady-state wheel speed per volt (first-order motor model)",
        "chosen: 11.7 V gives 9.4 rad/s, a 0.70 m/s top speed"),
    real!(motor_time_constant_s, "s", 0.0, INF, "above 0 s",
        "motor and wheel mechanical time constant",
        "chosen: a geared DC motor with the robot's inertia"),
    real!(max_voltage_v, "V", 0.0, 1000.0, "above 0 and at most 1000 V",
        "motor voltage saturation (both signs)",
        "seed `rpid.saturate(1, -11.7, 11.7)`: a 12 V battery minus the driver's drop"),
    real!(controller_period_s, "s", 1.0e-4, 1.0, "0.0001 to 1 s",
        "controller period",
        "seed `ST`"),
    real!(pid_kp_v_per_rad_s, "V per rad/s", 0.0, INF, "0 or more",
        "wheel-speed PID proportional gain",
        "seed `rgain` (2.5)"),
    real!(pid_ki_v_per_rad, "V per rad", 0.0, INF, "0 or more",
        "wheel-speed PID integral gain",
        "seed `rgain` (3.25)"),
    real!(pid_kd_v_s2_per_rad, "V s^2 per rad", 0.0, INF, "0 or more",
        "wheel-speed PID derivative gain",
        "seed `rgain` (0.05)"),
    real!(reference_time_constant_s, "s", 0.0, 100.0, "above 0 and at most 100 s",
        "time constant of the first-order reference model (it lags a moving reference by speed x this)",
        "seed `ALPHA0 = 1` 1/s"),
    real!(tracking_gain_1_s, "1/s", 0.0, 100.0, "above 0 and at most 100 1/s",
        "gain of the linearizing feedback on the control point's error",
        "seed: the same `ALPHA0`"),
    real!(turn_gain_1_s, "1/s", 0.0, 100.0, "above 0 and at most 100 1/s",
        "gain of the turn-in-place mode on the heading error",
        "chosen: not in the seed (turn-in-place mode)"),
    real!(max_turn_rate_rad_s, "rad/s", 0.0, 100.0, "above 0 and at most 100 rad/s",
        "largest turn rate of the turn-in-place mode",
        "chosen: not in the seed (turn-in-place mode)"),
    real!(settle_tolerance, "", 0.0, 1.0, "between 0 and 1, exclusive",
        "relative error at which the reference model counts as settled",
        "seed: 2 % settling of the reference model"),
    real!(sonar_offset_m, "m", 0.0, 5.0, "0 to 5 m",
        "distance of the sonar ahead of the axle midpoint, along the heading",
        "seed `DIST_CENTRO_SONAR`"),
    real!(sonar_min_range_m, "m", 0.0, 6.0, "0 m or more, below 6 m",
        "shortest range the sonar reports; nearer echoes count as none (the transducer still rings)",
        "seed `sonar.cpp` `DIST_MIN`"),
    real!(sonar_range_m, "m", 0.26, 6.0, "above sonar_min_range_m and at most 6 m",
        "longest range trusted; farther echoes count as none",
        "seed `ALCANCE_SONAR`; `--sonar-range` overrides it"),
    real!(neck_step_deg, "deg", 1.79, 90.0, "0.1 to 90 degrees",
        "neck stepper angle per step; the widest sweep must fit 201 readings (at least 1.79 for a full sweep of 180)",
        "seed `ANG_PASSO_MOTOR_SONAR` (a 200-step stepper)"),
    real!(normal_half_sweep_deg, "deg", 0.0, 180.0, "above 0 and at most 180 degrees",
        "half-width of a normal sweep (read out to the last whole neck step inside it)",
        "seed `AMPLITUDE_LEITURA_NORMAL_SONAR`"),
    real!(full_half_sweep_deg, "deg", 0.0, 180.0, "above 0 and at most 180 degrees",
        "half-width of a full sweep",
        "seed `ler_toda_volta`"),
    real!(echo_wait_s, "s", 0.0, 10.0, "0 to 10 s",
        "wait for the echo of one reading: the round trip for 6 m",
        "seed `sonar.cpp` `DELAY`"),
    real!(neck_step_time_s, "s", 0.0, 10.0, "0 to 10 s",
        "time for one neck step",
        "seed `TEMPO_MOV_PASSO_MOTOR_SONAR`"),
    Param {
        name: "sweep_layout",
        unit: "",
        doc: "which neck positions a sweep reads: `symmetric` 2n + 1 from -n to +n steps, `seed` the seed's 2n",
        source: "chosen: symmetric (always reads straight ahead); `--preset seed` and `--sweep-readings` set it",
        kind: Kind::Choice(&["symmetric", "seed"]),
        min: 0.0,
        max: 1.0,
        rule: "symmetric or seed",
        get: |c| match c.sweep_layout {
            SweepLayout::Symmetric => 0.0,
            SweepLayout::Seed => 1.0,
        },
        put: |c, v| {
            c.sweep_layout = if v == 1.0 {
                SweepLayout::Seed
            } else {
                SweepLayout::Symmetric
            }
        },
    },
    real!(sonar_cone_deg, "deg", 0.0, 90.0, "0 to 90 degrees",
        "simulation, legacy ray model: full angle of the beam (rays cast, the minimum kept)",
        "chosen: 0, one ray"),
    integer!(sonar_cone_rays, u8, "rays", 1.0, 31.0, "1 to 31 rays",
        "simulation, legacy ray model: rays cast across the beam",
        "chosen: 1"),
    real!(sonar_noise_std_m, "m", 0.0, 1.0, "0 to 1 m",
        "simulation: standard deviation of the range noise",
        "measured: an HC-SR04's 1 to 5 mm spread, the worse end (R. Gonzalez, Arduino forum, 2014; docs/robot-model.md); 0 in the core's tests; `--sonar-noise` overrides it"),
    real!(sonar_dropout_probability, "", 0.0, 1.0, "a probability, 0 to 1",
        "simulation: probability that a reading which would echo returns none (missed echo)",
        "judged: 0.02, about two readings of a 105-reading sweep (no data sheet states a rate; docs/robot-model.md); 0 in the core's tests; `--sonar-dropout` overrides it"),
    real!(sonar_spurious_probability, "", 0.0, 1.0, "a probability, 0 to 1",
        "simulation: probability of a spurious echo nearer than the true one (crosstalk, multipath)",
        "judged: 0.01, about one reading a sweep (no data sheet states a rate; docs/robot-model.md); 0 in the core's tests; `--sonar-spurious` overrides it"),
    Param {
        name: "sonar_beam",
        unit: "",
        doc: "simulation: true the ultrasonic beam model (cone, first echo, incidence limit, corners), false one exact ray",
        source: "chosen: true, the beam (`--sonar beam`); false, the exact ray, in the core's tests and `--sonar ray`",
        kind: Kind::Bool,
        min: 0.0,
        max: 1.0,
        rule: "true or false",
        get: |c| if c.sonar_beam { 1.0 } else { 0.0 },
        put: |c, v| c.sonar_beam = v == 1.0,
    },
    real!(sonar_beam_half_angle_deg, "deg", 0.0, 45.0, "0 to 45 degrees",
        "simulation, beam model: half-angle of the cone",
        "HC-SR04 data sheet, \"Measuring Angle 15 degree\""),
    real!(sonar_incidence_limit_deg, "deg", 0.0, 90.0, "0 to 90 degrees",
        "simulation, beam model: a smooth wall echoes only when the ray is within this angle of its normal",
        "Kuc & Siegel 1987: a smooth wall echoes only while its normal lies in the beam, so the beam's half-angle, 15; 70 in the core's tests; why in docs/robot-model.md"),
    real!(sonar_corner_radius_m, "m", 0.0, 1.0, "0 to 1 m",
        "simulation, beam model: a hit this close to a polygon vertex echoes at any angle",
        "chosen"),
    real!(rcd_depth_tolerance_m, "m", 0.0, 1.0, "0 to 1 m",
        "regions of constant depth: largest depth difference of neighbouring readings of one region",
        "seed `PRECISION` (0.5 px at 50 px/m)"),
    integer!(rcd_min_pairs, u8, "pairs", 0.0, 255.0, "0 to 255 pairs",
        "regions of constant depth: neighbour pairs that make a region trusted",
        "seed `PADROES`"),
    real!(rcd_min_arc_m, "m", 0.0, INF, "0 m or more",
        "regions of constant depth: arc length that makes a region trusted even with fewer pairs",
        "seed `ARC` (2 pi px at 50 px/m)"),
    real!(plant_substep_s, "s", 1.0e-5, 0.05, "1e-5 s up to controller_period_s",
        "simulation: integration step of the plant",
        "chosen"),
];

#[cfg(test)]
mod tests {
    use super::*;

    /// A second valid value for every row, different from the default.
    fn other(p: &Param) -> f32 {
        match (p.kind, p.name) {
            (Kind::Bool, _) => 1.0 - p.default_value(),
            (Kind::Choice(_), _) => 1.0,
            (_, "sonar_range_m") => 2.0,
            (_, "plant_substep_s") => 0.002,
            (_, "sonar_min_range_m") => 0.3,
            (_, "neck_step_deg") => 3.6,
            (Kind::Integer, _) => p.default_value() + 1.0,
            _ => p.default_value() * 0.5 + if p.default_value() == 0.0 { 0.01 } else { 0.0 },
        }
    }

    #[test]
    fn every_field_round_trips_and_changes_only_itself() {
        let mut names: heapless::Vec<&str, PARAM_COUNT> = heapless::Vec::new();
        for p in PARAMS.iter() {
            assert!(!names.contains(&p.name), "{} twice", p.name);
            names.push(p.name).unwrap();
            let mut c = RobotConfig::DEFAULT;
            assert_eq!(p.get(&c), p.default_value());
            let v = other(p);
            assert_ne!(v, p.default_value(), "{}", p.name);
            p.set(&mut c, v)
                .unwrap_or_else(|e| panic!("{}: {e}", p.name));
            assert_eq!(p.get(&c), v, "{}", p.name);
            for q in PARAMS.iter().filter(|q| q.name != p.name) {
                assert_eq!(
                    q.get(&c),
                    q.default_value(),
                    "{} changed {}",
                    p.name,
                    q.name
                );
            }
            assert_eq!(find(p.name).map(|q| q.name), Some(p.name));
        }
        assert!(find("wheel_radius").is_none());
    }

    #[test]
    fn every_refused_value_leaves_the_config_unchanged() {
        let start = RobotConfig {
            wheel_radius_m: 0.05,
            ..RobotConfig::DEFAULT
        };
        for p in PARAMS.iter() {
            let mut bad: heapless::Vec<f32, 6> = heapless::Vec::new();
            bad.push(f32::NAN).unwrap();
            if p.min.is_finite() {
                bad.push(p.min - 0.5).unwrap();
            }
            if p.max.is_finite() {
                bad.push(p.max + 0.5).unwrap();
            }
            if p.kind != Kind::Real {
                bad.push(0.5).unwrap();
            }
            for v in bad {
                let mut c = start;
                let e = p.set(&mut c, v).unwrap_err();
                assert_eq!(c, start, "{} = {v} changed the config", p.name);
                assert!(e.value.is_nan() || e.value == v, "{}: {e}", p.name);
            }
        }
    }

    #[test]
    fn a_real_row_states_the_rule_of_the_validation() {
        // NaN fails every real field's first check, whose words are the row's rule.
        for p in PARAMS.iter().filter(|p| p.kind == Kind::Real) {
            let mut c = RobotConfig::DEFAULT;
            let e = p.set(&mut c, f32::NAN).unwrap_err();
            assert_eq!((e.field, e.expected), (p.name, p.rule));
        }
    }

    #[test]
    fn the_bounds_are_accepted_on_their_own_where_inclusive() {
        for p in PARAMS.iter() {
            let d = p.default_value();
            assert!(p.min <= d && d <= p.max, "{} default {d}", p.name);
        }
        let mut c = RobotConfig::DEFAULT;
        assert!(find("sonar_range_m").unwrap().set(&mut c, 6.0).is_ok());
        assert!(find("sonar_range_m").unwrap().set(&mut c, 6.01).is_err());
        assert!(find("wheel_radius_m").unwrap().set(&mut c, 0.0).is_err());
        assert_eq!(c.sonar_range_m, 6.0);
    }

    #[test]
    fn kinds_have_one_representation() {
        let layout = find("sweep_layout").unwrap();
        assert_eq!(layout.choice_name(1.0), Some("seed"));
        assert_eq!(layout.choice_index("symmetric"), Some(0.0));
        assert_eq!(layout.choice_index("spiral"), None);
        let mut c = RobotConfig::DEFAULT;
        layout.set(&mut c, 1.0).unwrap();
        assert_eq!(c.sweep_layout, SweepLayout::Seed);
        let beam = find("sonar_beam").unwrap();
        beam.set(&mut c, 1.0).unwrap();
        assert!(c.sonar_beam);
        let e = beam.set(&mut c, 2.0).unwrap_err();
        assert_eq!(e.expected, BOOL);
        let pairs = find("rcd_min_pairs").unwrap();
        assert_eq!(pairs.set(&mut c, 4.5).unwrap_err().expected, WHOLE);
        assert_eq!(
            pairs.set(&mut c, 256.0).unwrap_err().expected,
            "0 to 255 pairs"
        );
        pairs.set(&mut c, 255.0).unwrap();
        assert_eq!(c.rcd_min_pairs, 255);
    }

    #[test]
    fn values_that_depend_on_each_other_change_together() {
        let (min, range) = (
            find("sonar_min_range_m").unwrap(),
            find("sonar_range_m").unwrap(),
        );
        let mut c = RobotConfig::DEFAULT;
        // Alone, a shortest range of 2 m is above the 1.5 m range.
        assert_eq!(min.set(&mut c, 2.0).unwrap_err().field, "sonar_range_m");
        set_many(&mut c, &[(min, 2.0), (range, 3.0)]).unwrap();
        assert_eq!((c.sonar_min_range_m, c.sonar_range_m), (2.0, 3.0));
        let before = c;
        let e = set_many(&mut c, &[(range, 4.0), (min, 5.0)]).unwrap_err();
        assert_eq!((e.field, e.value), ("sonar_range_m", 4.0));
        assert_eq!(c, before);
    }
}
