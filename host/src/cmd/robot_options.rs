//! A robot configuration refused for a value the user gave as an option, said in the user's
//! words: the option, its value and the bound in numbers (`--sonar-range 100: at most 6 m`),
//! not the internal field name (`sonar_range_m`) and a rule about another field.
//!
//! `twil simulate` and `twil mission` build a `RobotConfig` from their options and validate
//! it; only the fields an option sets are translated, any other (a constant of the robot) keeps
//! the core's wording.

use twil_core::robot::{ConfigError, RobotConfig, SONAR_MAX_RANGE_LIMIT_M};

/// The message for `e`, a validation error of `robot`.
pub fn message(e: &ConfigError, robot: &RobotConfig) -> String {
    let v = e.value;
    match e.field {
        "sonar_range_m" if v > SONAR_MAX_RANGE_LIMIT_M => {
            format!("--sonar-range {v}: at most {SONAR_MAX_RANGE_LIMIT_M} m")
        }
        "sonar_range_m" => format!(
            "--sonar-range {v}: above {} m, the sonar's shortest range, and at most \
             {SONAR_MAX_RANGE_LIMIT_M} m",
            robot.sonar_min_range_m
        ),
        "sonar_noise_std_m" => format!("--sonar-noise {v}: 0 to 1 m"),
        "sonar_dropout_probability" => format!("--sonar-dropout {v}: a probability, 0 to 1"),
        "sonar_spurious_probability" => format!("--sonar-spurious {v}: a probability, 0 to 1"),
        "sonar_beam_half_angle_deg" => format!("--beam-half-angle {v}: 0 to 45 degrees"),
        "sonar_incidence_limit_deg" => format!("--incidence-limit {v}: 0 to 90 degrees"),
        _ => format!("robot config: {e}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn refused(robot: RobotConfig) -> String {
        message(&robot.validate().unwrap_err(), &robot)
    }

    #[test]
    fn an_option_error_names_the_option_its_value_and_the_bound() {
        let d = RobotConfig::default();
        let range = |r| RobotConfig {
            sonar_range_m: r,
            ..d
        };
        assert_eq!(refused(range(100.0)), "--sonar-range 100: at most 6 m");
        assert_eq!(
            refused(range(0.1)),
            "--sonar-range 0.1: above 0.26 m, the sonar's shortest range, and at most 6 m"
        );
        let noise = RobotConfig {
            sonar_noise_std_m: -1.0,
            ..d
        };
        assert_eq!(refused(noise), "--sonar-noise -1: 0 to 1 m");
        let beam = RobotConfig {
            sonar_beam_half_angle_deg: 50.0,
            ..d
        };
        assert_eq!(refused(beam), "--beam-half-angle 50: 0 to 45 degrees");
        let incidence = RobotConfig {
            sonar_incidence_limit_deg: 91.0,
            ..d
        };
        assert_eq!(refused(incidence), "--incidence-limit 91: 0 to 90 degrees");
        let dropout = RobotConfig {
            sonar_dropout_probability: 1.5,
            ..d
        };
        assert_eq!(
            refused(dropout),
            "--sonar-dropout 1.5: a probability, 0 to 1"
        );
        let spurious = RobotConfig {
            sonar_spurious_probability: -0.1,
            ..d
        };
        assert_eq!(
            refused(spurious),
            "--sonar-spurious -0.1: a probability, 0 to 1"
        );
    }

    #[test]
    fn a_field_no_option_sets_keeps_the_core_wording() {
        let robot = RobotConfig {
            wheel_radius_m: 0.0,
            ..RobotConfig::default()
        };
        assert!(refused(robot).starts_with("robot config: robot config field `wheel_radius_m`"));
    }
}
