//! How long the robot stands still at the end of a prefix before it sweeps again.
//!
//! The seed's trajectory supplier (`ft.c`) waits `espera_robo_parar` after the controller
//! handed out the last point: `t_acom = 3·2π/α` (`twlckin.cpp`, `ALPHA0 = 1`), 18.85 s, three
//! periods of `2π/α` of the reference model. Its text (§IV.5.4, step 5) says the wait is the
//! time for an error below 2 %, computed from the reference model: for the first-order model
//! that is `τ·ln 50` = 3.91 s (`control::settle_time_s`), which is what the mission waits by
//! default (plus two control periods for the closed loop's own lag).

use crate::robot::RobotConfig;

/// Which settle time a stop waits ([`super::MissionConfig::settle`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SettleRule {
    /// The reference model's time to come within [`RobotConfig::settle_tolerance`] (the seed's
    /// text: 2 %), plus two control periods: 4.01 s with the defaults.
    #[default]
    ReferenceModel,
    /// The seed's code, `3·2π/α` with `α = 1/τ` ([`RobotConfig::reference_time_constant_s`]):
    /// 18.85 s with the defaults.
    SeedCode,
}

impl SettleRule {
    /// The wait after the end of a prefix, seconds (0 for a robot config that makes no sense:
    /// `RobotConfig::validate` refuses those first).
    pub fn settle_time_s(self, robot: &RobotConfig) -> f32 {
        match self {
            Self::ReferenceModel => {
                crate::control::settle_time_s(robot) + 2.0 * robot.controller_period_s
            }
            Self::SeedCode => {
                let tau_s = robot.reference_time_constant_s;
                if tau_s.is_finite() && tau_s > 0.0 {
                    3.0 * core::f32::consts::TAU * tau_s
                } else {
                    0.0
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settle_rules_give_the_documented_times() {
        let robot = RobotConfig::DEFAULT;
        let ours = SettleRule::ReferenceModel.settle_time_s(&robot);
        assert!((ours - (3.912 + 0.1)).abs() < 0.01, "{ours}");
        let seed = SettleRule::SeedCode.settle_time_s(&robot);
        assert!((seed - 18.85).abs() < 0.01, "{seed}");
        // The seed's rule scales with the model's time constant, as 3·2π/α does.
        let slow = RobotConfig {
            reference_time_constant_s: 2.0,
            ..RobotConfig::DEFAULT
        };
        assert!((SettleRule::SeedCode.settle_time_s(&slow) - 37.70).abs() < 0.01);
        let broken = RobotConfig {
            reference_time_constant_s: f32::NAN,
            ..RobotConfig::DEFAULT
        };
        assert_eq!(SettleRule::SeedCode.settle_time_s(&broken), 0.0);
    }
}
