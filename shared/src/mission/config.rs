//! What a mission is told before it starts: [`MissionMode`], [`MissionConfig`] and its
//! checks, and [`MissionError`] when they fail.
//!
//! The config is a plain `Copy` value, checked once ([`MissionConfig::validate`]) when a
//! mission is set up, so that the step functions can rely on every value without checking
//! again.

use crate::geom::PointM;
use crate::grid::GridError;
use crate::plan::PlannerKind;
use crate::robot::RobotConfig;
use crate::trajectory::SupplierConfig;
use crate::world::Params;

use super::SettleRule;

/// How the robot uses its sonar.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionMode {
    /// Stop, sweep, plan, follow the prefix, settle, repeat (the seed).
    #[default]
    Stop,
    /// Sweep while moving and replan on the fly.
    Continuous,
}

/// Everything a mission needs to know before it starts.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MissionConfig {
    /// Stop-and-sweep or continuous.
    pub mode: MissionMode,
    /// Which planner to run.
    pub planner: PlannerKind,
    /// Robot constants (its `planning_radius_m` grows obstacles, its `sonar_range_m` prunes).
    pub robot: RobotConfig,
    /// Start position, world metres.
    pub start: PointM,
    /// Initial heading, world radians, counter-clockwise from +x.
    pub initial_heading_rad: f32,
    /// Goal position, world metres.
    pub goal: PointM,
    /// Cruise speed along the path, metres per second.
    pub speed_m_s: f32,
    /// Turn rate when turning in place, radians per second.
    pub turn_rate_rad_s: f32,
    /// Direction changes larger than this are done as turns in place, radians.
    pub turn_in_place_above_rad: f32,
    /// Mission time after which it ends in
    /// [`MissionStatus::Timeout`](super::MissionStatus::Timeout), seconds.
    pub time_limit_s: f32,
    /// Reached when the odometry position is this close to the goal (stop mode: checked after
    /// the settle time; continuous mode: every period), metres.
    pub goal_tolerance_m: f32,
    /// Plans in a row that start within [`Self::stall_distance_m`] of the previous plan's start
    /// before the mission gives up as unreachable.
    pub max_stalled_plans: u16,
    /// A plan that starts closer than this to the previous one counts as stalled, metres.
    pub stall_distance_m: f32,
    /// Filter each sweep with the regions-of-constant-depth filter of [`crate::sonar`] (the
    /// seed's); `false` marks every valid reading.
    pub constant_depth_filter: bool,
    /// Also trust the path through space seen free by *earlier* sweeps (see
    /// [`Mission::seen`](super::Mission::seen)); `false` keeps the seed's rule only (within range
    /// of the robot and visible from it).
    pub trust_seen_space: bool,
    /// Longest prefix kept through seen space, measured along the path, metres.
    pub max_trusted_path_m: f32,
    /// Continuous mode: half-width of the sweeps taken while moving, degrees (narrower sweeps
    /// come round to each direction more often).
    pub moving_half_sweep_deg: f32,
    /// How long a stop waits after the end of a prefix (see [`SettleRule`]).
    pub settle: SettleRule,
    /// Add `τ × velocity` to the controller's reference so the first-order reference model
    /// does not lag the path (ours); `false` feeds the path point alone, as the seed did.
    pub reference_feed_forward: bool,
    /// Map with the evidence map (`evidence.rs`, `docs/mapping.md`): one reflector per run of
    /// constant depth, free evidence only along rays that echoed, silence marks nothing, a
    /// point is vouched for by the Thales rule, suspects beside the robot after a full sweep;
    /// `false` (the default) keeps the 1-bit seen grid and its rules.
    #[serde(default)]
    pub evidence_map: bool,
}

impl MissionConfig {
    /// A placeholder for missions that have not been set up
    /// ([`Mission::IDLE`](super::Mission::IDLE)): the default robot at the origin, facing +x, with
    /// the goal there too.
    pub const IDLE: Self = Self {
        mode: MissionMode::Stop,
        planner: PlannerKind::AStar,
        robot: RobotConfig::DEFAULT,
        start: PointM { x_m: 0.0, y_m: 0.0 },
        initial_heading_rad: 0.0,
        goal: PointM { x_m: 0.0, y_m: 0.0 },
        speed_m_s: 0.2,
        turn_rate_rad_s: 0.8,
        turn_in_place_above_rad: core::f32::consts::FRAC_PI_6,
        time_limit_s: 600.0,
        goal_tolerance_m: 0.10,
        max_stalled_plans: 6,
        stall_distance_m: 0.10,
        constant_depth_filter: false,
        trust_seen_space: true,
        max_trusted_path_m: 30.0,
        moving_half_sweep_deg: 95.0,
        settle: SettleRule::ReferenceModel,
        reference_feed_forward: true,
        evidence_map: false,
    };

    /// A configuration from a `.par` file's parameters and a robot config (whose planning
    /// radius is replaced by the `.par` radius), stop mode, A*, a 600 s time limit.
    pub fn from_params(params: &Params, robot: RobotConfig) -> Self {
        let robot = robot.with_planning_radius_m(params.robot_radius_m);
        // Every other value is the mission defaults of [`MissionConfig::IDLE`].
        Self {
            robot,
            start: params.start,
            initial_heading_rad: params.initial_heading_deg * (core::f32::consts::PI / 180.0),
            goal: params.goal,
            speed_m_s: params.speed_m_s,
            ..Self::IDLE
        }
    }

    /// Check every value the mission relies on; the error names the field and its value.
    pub fn validate(&self) -> Result<(), MissionError> {
        if let Err(e) = self.robot.validate() {
            return Err(MissionError::Robot(e));
        }
        let positive = [
            ("speed_m_s", self.speed_m_s),
            ("turn_rate_rad_s", self.turn_rate_rad_s),
            ("time_limit_s", self.time_limit_s),
            ("goal_tolerance_m", self.goal_tolerance_m),
        ];
        for (field, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(MissionError::BadValue { field, value });
            }
        }
        // Beyond these the robot cannot be trusted to stay clear (see `crate::limits`).
        if crate::limits::check_speed_m_s(&self.robot, self.speed_m_s).is_err() {
            return Err(MissionError::BadValue {
                field: "speed_m_s",
                value: self.speed_m_s,
            });
        }
        let radius_m = self.robot.planning_radius_m;
        if crate::limits::check_planning_radius_m(&self.robot, radius_m).is_err() {
            return Err(MissionError::BadValue {
                field: "planning_radius_m",
                value: radius_m,
            });
        }
        let finite = [
            ("start x", self.start.x_m),
            ("start y", self.start.y_m),
            ("goal x", self.goal.x_m),
            ("goal y", self.goal.y_m),
            ("initial_heading_rad", self.initial_heading_rad),
            ("turn_in_place_above_rad", self.turn_in_place_above_rad),
            ("stall_distance_m", self.stall_distance_m),
        ];
        for (field, value) in finite {
            if !value.is_finite() {
                return Err(MissionError::BadValue { field, value });
            }
        }
        Ok(())
    }

    pub(super) fn supplier_config(&self) -> SupplierConfig {
        SupplierConfig {
            speed_m_s: self.speed_m_s,
            turn_rate_rad_s: self.turn_rate_rad_s,
            turn_in_place_above_rad: self.turn_in_place_above_rad,
            settle_time_s: self.settle.settle_time_s(&self.robot),
        }
    }
}

/// Why a mission could not be set up.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MissionError {
    /// The robot config is invalid.
    Robot(crate::robot::ConfigError),
    /// A mission value is out of range.
    BadValue {
        /// Field name.
        field: &'static str,
        /// Its value.
        value: f32,
    },
    /// The grid geometry does not fit the mission's grid capacity.
    Grid(GridError),
    /// The start or the goal lies off the map.
    OffMap {
        /// `"start"` or `"goal"`.
        which: &'static str,
    },
}

impl core::fmt::Display for MissionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MissionError::Robot(e) => write!(f, "robot config: {e}"),
            MissionError::BadValue { field, value } => write!(f, "{field}: bad value {value}"),
            MissionError::Grid(e) => write!(f, "grid: {e}"),
            MissionError::OffMap { which } => write!(f, "the {which} lies off the map"),
        }
    }
}
