//! The pilot: the control half of a mission, run once per control period.
//!
//! Encoder counts → odometry → trajectory supplier → reference of the control point →
//! controller → wheel voltages (seed `twlckin.cpp` and `ft()`). It is cheap and its cost does
//! not depend on the map: the firmware runs it in its highest-priority task every 50 ms, and
//! nothing that task does waits for the sonar, the map or the planner.
//!
//! The navigation half, [`super::Mission`], steers it with [`PilotCommand`]s (follow this
//! prefix, hold, stop for good) and learns from each tick's [`PilotReport`] where the robot
//! believes it is and what the supplier did. The simulator calls the two in turn each period;
//! the firmware passes the same values between its tasks.

use crate::control::{ControlInput, ControlOutput, Controller, Pose};
use crate::geom::PointM;
use crate::math::{cos, hypot, sin};
use crate::robot::RobotConfig;
use crate::trajectory::{
    FrameTransform, SupplierConfig, SupplyEvent, TrajectoryError, TrajectorySupplier,
};

use super::MissionConfig;

/// What the navigation half asks of the pilot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PilotCommand {
    /// Follow [`super::Mission::prefix`] from the next tick on (the shell hands the points
    /// to [`Pilot::follow`]).
    Follow,
    /// Stop supplying points: the controller holds the control point's place on the path
    /// (the last reference without its feed-forward lead).
    Hold,
    /// The mission ended: zero volts on both motors from now on.
    Stop,
}

/// What one tick of the pilot tells the navigation half.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PilotReport {
    /// Odometry pose after this tick (odometry frame: the start pose is the origin).
    pub pose_odom: Pose,
    /// The point the supplier hands out now, odometry frame (where a new trajectory starts
    /// while moving).
    pub supply_point_odom: PointM,
    /// Index of the prefix segment the supplier is on.
    pub segment: u16,
    /// The supplier reached the end of the prefix, or the settle time after it went by.
    pub event: Option<SupplyEvent>,
    /// Left motor voltage applied until the next tick, volts.
    pub left_voltage_v: f32,
    /// Right motor voltage, volts.
    pub right_voltage_v: f32,
    /// The tick came late (more than a period plus the tolerance after the previous one).
    pub overrun: bool,
    /// A voltage was clamped to the saturation.
    pub saturated: bool,
    /// Distance the odometry moved during this tick, metres.
    pub moved_m: f32,
}

/// The control half of a mission: see the module documentation.
#[derive(Clone, Debug)]
pub struct Pilot {
    robot: RobotConfig,
    supplier_config: SupplierConfig,
    supplier: TrajectorySupplier,
    controller: Controller,
    frame: FrameTransform,
    /// Controller reference (control point), odometry frame.
    reference: PointM,
    /// The control point's place on the path at the last tick (the reference without the
    /// feed-forward lead), odometry frame: where [`Pilot::hold`] stops it.
    on_path: PointM,
    pose_odom: Pose,
    voltages_v: (f32, f32),
    /// The supplier is handing out points (following or settling).
    supplying: bool,
    stopped: bool,
    /// [`MissionConfig::reference_feed_forward`].
    feed_forward: bool,
}

impl Pilot {
    /// A pilot for no mission yet (the default robot at the origin, holding): what a
    /// `static` holds until [`Pilot::restart`] sets it up in place.
    pub const IDLE: Self = Self {
        robot: RobotConfig::DEFAULT,
        supplier_config: SupplierConfig {
            speed_m_s: 0.2,
            turn_rate_rad_s: 0.8,
            turn_in_place_above_rad: core::f32::consts::FRAC_PI_6,
            settle_time_s: 4.0,
        },
        supplier: TrajectorySupplier::new(),
        controller: Controller::at_origin(&RobotConfig::DEFAULT),
        frame: FrameTransform::identity(),
        reference: PointM {
            x_m: RobotConfig::DEFAULT.point_offset_m,
            y_m: 0.0,
        },
        on_path: PointM {
            x_m: RobotConfig::DEFAULT.point_offset_m,
            y_m: 0.0,
        },
        pose_odom: Pose {
            x_m: 0.0,
            y_m: 0.0,
            heading_rad: 0.0,
        },
        voltages_v: (0.0, 0.0),
        supplying: false,
        stopped: false,
        feed_forward: true,
    };

    /// A pilot at the mission's start pose, holding.
    pub fn new(config: &MissionConfig) -> Self {
        Self {
            robot: config.robot,
            supplier_config: config.supplier_config(),
            supplier: TrajectorySupplier::new(),
            controller: Controller::new(&config.robot, Pose::default()),
            frame: FrameTransform::new(config.start, config.initial_heading_rad),
            reference: PointM::new(config.robot.point_offset_m, 0.0),
            on_path: PointM::new(config.robot.point_offset_m, 0.0),
            pose_odom: Pose::default(),
            voltages_v: (0.0, 0.0),
            supplying: false,
            stopped: false,
            feed_forward: config.reference_feed_forward,
        }
    }

    /// Set the pilot up afresh for the mission of `config`, in place (its trajectory buffer is
    /// 8 KiB: no temporary of that size on the stack), holding at the start pose.
    pub fn restart(&mut self, config: &MissionConfig) {
        self.robot = config.robot;
        self.supplier_config = config.supplier_config();
        self.supplier.stop();
        self.controller = Controller::new(&config.robot, Pose::default());
        self.frame = FrameTransform::new(config.start, config.initial_heading_rad);
        self.reference = PointM::new(config.robot.point_offset_m, 0.0);
        self.on_path = self.reference;
        self.pose_odom = Pose::default();
        self.voltages_v = (0.0, 0.0);
        self.supplying = false;
        self.stopped = false;
        self.feed_forward = config.reference_feed_forward;
    }

    /// One control period: the encoder counts since the previous tick and the real time
    /// elapsed since it (for the overrun flag).
    pub fn tick(
        &mut self,
        left_delta_counts: i32,
        right_delta_counts: i32,
        elapsed_s: f32,
    ) -> PilotReport {
        let period = self.robot.controller_period_s;
        let mut event = None;
        if self.supplying && !self.stopped {
            let supply = self.supplier.tick(period);
            // Where the control point (offset ahead of the axle) should be, and how fast it
            // moves: along the heading when moving, on a circle of radius `d` when turning.
            let d = self.robot.point_offset_m;
            let (c, s) = (cos(supply.heading_rad), sin(supply.heading_rad));
            let vx = supply.speed_m_s * c - d * supply.turn_rate_rad_s * s;
            let vy = supply.speed_m_s * s + d * supply.turn_rate_rad_s * c;
            // Feed-forward through the first-order reference model: with p = y + τ·ẏ the
            // model output follows y without the lag τ·v (0.2 m at 0.2 m/s), so the centre
            // stays on the path and turns in place stay in place.
            // The seed fed the path point alone (`reference_feed_forward` off).
            let tau = if self.feed_forward {
                self.robot.reference_time_constant_s
            } else {
                0.0
            };
            self.on_path = PointM::new(supply.point.x_m + d * c, supply.point.y_m + d * s);
            self.reference = PointM::new(self.on_path.x_m + tau * vx, self.on_path.y_m + tau * vy);
            event = supply.event;
        }
        let before = self.pose_odom;
        let control = self.controller.step(ControlInput {
            reference: self.reference,
            encoder_left_delta_counts: left_delta_counts,
            encoder_right_delta_counts: right_delta_counts,
            elapsed_since_last_step_s: elapsed_s,
        });
        self.pose_odom = control.pose;
        self.voltages_v = if self.stopped {
            (0.0, 0.0)
        } else {
            (control.left_voltage_v, control.right_voltage_v)
        };
        let moved_m = hypot(
            self.pose_odom.x_m - before.x_m,
            self.pose_odom.y_m - before.y_m,
        );
        PilotReport {
            pose_odom: self.pose_odom,
            supply_point_odom: self.supplier.current_point_odom(),
            segment: self.supplier.segment().min(u16::MAX as usize) as u16,
            event,
            left_voltage_v: self.voltages_v.0,
            right_voltage_v: self.voltages_v.1,
            overrun: control.overrun,
            saturated: control.saturated,
            moved_m: if moved_m.is_finite() { moved_m } else { 0.0 },
        }
    }

    /// Follow `prefix_world` (world metres) from the next tick on, turning in place first when
    /// its first segment points elsewhere. On error the pilot holds.
    pub fn follow(&mut self, prefix_world: &[PointM]) -> Result<(), TrajectoryError> {
        if self.stopped {
            return Ok(());
        }
        let heading_odom = self.pose_odom.heading_rad;
        match self.supplier.start(
            prefix_world,
            &self.frame,
            heading_odom,
            &self.supplier_config,
        ) {
            Ok(()) => {
                self.supplying = true;
                Ok(())
            }
            Err(e) => {
                self.hold();
                Err(e)
            }
        }
    }

    /// Stop supplying points; the controller holds the control point's place on the path.
    ///
    /// Not the last reference itself: while moving it leads the path by the feed-forward
    /// `τ·v` (0.36 m at 0.36 m/s), past the end of a prefix cut short (a standing sweep begun
    /// mid-pass), into space no sweep vouched for. The robot then stopped up to that far
    /// beyond where it was told to.
    pub fn hold(&mut self) {
        self.supplier.stop();
        self.supplying = false;
        self.reference = self.on_path;
    }

    /// Zero volts on both motors, now and at every later tick.
    pub fn stop(&mut self) {
        self.hold();
        self.stopped = true;
        self.voltages_v = (0.0, 0.0);
    }

    /// Carry out a command of the navigation half; `prefix_world` is the mission's prefix
    /// (read only for [`PilotCommand::Follow`]).
    pub fn command(
        &mut self,
        command: PilotCommand,
        prefix_world: &[PointM],
    ) -> Result<(), TrajectoryError> {
        match command {
            PilotCommand::Follow => self.follow(prefix_world),
            PilotCommand::Hold => {
                self.hold();
                Ok(())
            }
            PilotCommand::Stop => {
                self.stop();
                Ok(())
            }
        }
    }

    /// The voltages to apply until the next tick (zero once stopped).
    pub fn voltages_v(&self) -> (f32, f32) {
        self.voltages_v
    }

    /// `true` once [`Pilot::stop`] was called.
    pub fn is_stopped(&self) -> bool {
        self.stopped
    }

    /// The odometry pose after the last tick.
    pub fn pose_odom(&self) -> Pose {
        self.pose_odom
    }

    /// The odometry pose after the last tick, world frame.
    pub fn pose_world(&self) -> Pose {
        pose_to_world(&self.frame, self.pose_odom)
    }

    /// What the controller decided at the last tick (references, measured wheel speeds,
    /// voltages before a stop zeroes them), odometry frame: read by logs and plots only.
    pub fn last_control(&self) -> ControlOutput {
        self.controller.last_output()
    }

    /// The reference handed to the controller at the last tick, world frame.
    pub fn reference_world(&self) -> PointM {
        self.frame.odom_to_world(self.reference)
    }

    /// An odometry-frame point in the world frame.
    pub fn odom_to_world(&self, point_odom: PointM) -> PointM {
        self.frame.odom_to_world(point_odom)
    }
}

/// An odometry pose in the world frame.
pub(super) fn pose_to_world(frame: &FrameTransform, pose_odom: Pose) -> Pose {
    let p = frame.odom_to_world(PointM::new(pose_odom.x_m, pose_odom.y_m));
    Pose {
        x_m: p.x_m,
        y_m: p.y_m,
        heading_rad: frame.heading_odom_to_world(pose_odom.heading_rad),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::Plant;
    use crate::world::Params;

    /// Follow a straight 3 m prefix east at `speed_m_s`, hold after `hold_after_s`, and let
    /// the robot come to rest: where the held path point was, and where the robot stopped
    /// (world metres).
    fn hold_mid_pass(speed_m_s: f32, hold_after_s: f32) -> (PointM, PointM) {
        let params = Params {
            robot_radius_m: 0.4,
            speed_m_s,
            initial_heading_deg: 0.0,
            start: PointM::new(1.0, 1.0),
            goal: PointM::new(4.0, 1.0),
        };
        let config = MissionConfig::from_params(&params, RobotConfig::default());
        assert!(config.reference_feed_forward);
        let mut pilot = Pilot::new(&config);
        let mut plant = Plant::new(&config.robot, Pose::new(1.0, 1.0, 0.0));
        pilot
            .command(
                PilotCommand::Follow,
                &[PointM::new(1.0, 1.0), PointM::new(4.0, 1.0)],
            )
            .unwrap();
        let period_s = config.robot.controller_period_s;
        let mut previous = plant.encoder_counts();
        let mut held_at = None;
        for n in 0..((hold_after_s + 10.0) / period_s) as u32 {
            if held_at.is_none() && n as f32 * period_s >= hold_after_s {
                held_at = Some(
                    pilot
                        .frame
                        .odom_to_world(pilot.supplier.current_point_odom()),
                );
                pilot.command(PilotCommand::Hold, &[]).unwrap();
            }
            let counts = plant.encoder_counts();
            pilot.tick(counts.0 - previous.0, counts.1 - previous.1, period_s);
            previous = counts;
            let (left_v, right_v) = pilot.voltages_v();
            plant.step(period_s, left_v, right_v);
        }
        let p = plant.pose();
        (held_at.unwrap(), PointM::new(p.x_m, p.y_m))
    }

    #[test]
    fn a_hold_mid_pass_stops_at_the_path_point_not_at_the_feed_forward_lead() {
        // At the safe-speed bound of the default robot (0.3645 m/s) the feed-forward lead is
        // τ·v = 0.36 m: holding the last reference itself stopped the robot that far past
        // the held point (0.36 m on the enclosed world, into a wall no sweep had vouched for).
        for speed_m_s in [0.2, 0.3645] {
            let (held, stopped) = hold_mid_pass(speed_m_s, 4.0);
            let past_m = stopped.x_m - held.x_m;
            assert!(
                past_m < 0.05,
                "{speed_m_s} m/s: stopped {past_m:.3} m past the held point {held:?}"
            );
            assert!(
                past_m > -0.2,
                "{speed_m_s} m/s: stopped short by {past_m:.3} m"
            );
            assert!((stopped.y_m - 1.0).abs() < 0.02, "{stopped:?}");
        }
    }
}
