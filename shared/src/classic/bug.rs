//! Lumelsky's Bug1 as a pure step function: the decision logic of a robot that knows no map,
//! only its pose and what its sonar says at a few bearings.
//!
//! Seed 004 §1.5.3 ("interacţiunea cu sistemul senzorial"): drive straight at the goal; when an
//! obstacle blocks the way, follow its boundary in a fixed direction all the way round back to
//! the hit point, then go back the shorter way to the leave point and drive at the goal again.
//! The path is at most `D + 1.5 Σ pᵢ` long (`D` the start–goal distance, `pᵢ` the perimeters of
//! the C-obstacles meeting the disc of radius `D` around the start).
//!
//! Design choices:
//! - **Leave point: the boundary point closest to the goal** (classic Bug1), not the seed's
//!   crossing of the start–goal segment. The closest point is what gives the bound and the
//!   termination argument (every leave point is strictly closer to the goal than the hit
//!   point before it), it exists for every loop (a sensed loop may never cross the segment
//!   exactly), and it gives the classic unreachable test: if the way to the goal is blocked
//!   right at the closest point, the goal is enclosed ([`Phase::Unreachable`]).
//! - **Sensing**: every step reads the sonar at the nine bearings of [`BEARINGS_DEG`]
//!   (−120° … 120° every 30°, relative to the heading: with the beam's 15° half-angle the
//!   cones tile ±135° without gaps). A beam's echo can come from anywhere in its cone; placing
//!   it on the axis puts an oblique wall up to ~40 % too near. So each echo is placed on the
//!   cone's edge towards a neighbouring bearing that read no farther (the wall's normal lies that
//!   way), or on the axis when both neighbours read farther (the normal, or a corner, is inside
//!   this cone). On a straight wall this puts every echo on the wall.
//! - **Memory**: the last [`ECHO_CAPACITY`] echo points nearer than
//!   [`BugConfig::near_m`] (a ring, world frame; the world is static and the pose exact, so a
//!   point stays true); control reads only those. No map is built.
//! - **Boundary following**: towards the tangent of the nearest remembered echo (obstacle on
//!   the left, i.e. clockwise round it; on the right when going back the other way), turned
//!   towards the obstacle in proportion to the distance error from [`BugConfig::follow_m`]. A
//!   move whose end comes within [`BugConfig::safe_m`] of an echo is turned away in 15° steps.
//! - **Hit**: an echo within the robot's width ([`BugConfig::safe_m`] either side of the way)
//!   less than [`BugConfig::follow_m`] + 0.1 m ahead.
//! - **Loop closure**: the robot first gets 2 × [`RETURN_ZONE_M`] away from the hit point, then
//!   the loop closes at its closest approach to it inside [`RETURN_ZONE_M`]. Going back to the
//!   leave point works the same way (closest approach within [`RETURN_ZONE_M`], once at least
//!   half the expected arc is done).
//! - **Bounded**: at most [`BugConfig::max_steps`] calls (the host derives it from the bound);
//!   then [`Phase::GaveUp`]. Each call costs `O(READINGS × ECHO_CAPACITY)`.
//!
//! The robot is kinematic: the step answers a heading (turn in place) and a distance (a straight
//! move of at most [`BugConfig::step_m`]). The host's simulator does the sensing and checks for
//! collisions against the true polygons (`host/src/classic/bug.rs`).
//!
//! Measured (`twil plan --planner bug`, sonar 3 m, step 0.02 m): see `docs/classic.md`.

use crate::geom::PointM;
use crate::geom::Pose;
use crate::math::{abs, atan2, cos, hypot, sin, wrap_angle_rad};

/// Sonar bearings read every step, degrees relative to the heading (the neck turns ±180°).
pub const BEARINGS_DEG: [f32; READINGS] =
    [-120.0, -90.0, -60.0, -30.0, 0.0, 30.0, 60.0, 90.0, 120.0];

/// Readings per step.
pub const READINGS: usize = 9;

/// Echo points the robot remembers (a ring: the oldest goes first).
pub const ECHO_CAPACITY: usize = 96;

/// Radius round the hit point (and the leave point) inside which the loop is taken as closed
/// (the leave point as reached), metres.
pub const RETURN_ZONE_M: f32 = 0.3;

/// Obstacle on the robot's left: going round clockwise.
const LEFT: f32 = 1.0;

/// The Bug's parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BugConfig {
    /// The robot's planning radius (the `.par` radius), metres.
    pub radius_m: f32,
    /// Distance from the robot's centre to the boundary it follows, metres
    /// (default radius + 0.15 m: margin for the echoes' placement error).
    pub follow_m: f32,
    /// No move may end nearer than this to a remembered echo, metres (default radius + 0.03 m).
    pub safe_m: f32,
    /// Echoes farther than this from the centre are not remembered, metres (default
    /// `follow_m` + 1 m: the Bug only reacts to what is near).
    pub near_m: f32,
    /// Longest move of one step, metres (default 0.02 m).
    pub step_m: f32,
    /// The goal counts as reached within this distance, metres (default 0.01 m).
    pub goal_tolerance_m: f32,
    /// The sonar sits this far ahead of the centre, metres (default 0.20 m, the robot's).
    pub sonar_offset_m: f32,
    /// Half-angle of the sonar's beam, degrees (default 15°).
    pub beam_half_angle_deg: f32,
    /// Most steps before giving up.
    pub max_steps: u32,
}

impl BugConfig {
    /// The defaults for a robot of `radius_m`, giving up after `max_steps` steps.
    pub fn new(radius_m: f32, max_steps: u32) -> Self {
        let follow_m = radius_m + 0.15;
        Self {
            radius_m,
            follow_m,
            safe_m: radius_m + 0.03,
            near_m: follow_m + 1.0,
            step_m: 0.02,
            goal_tolerance_m: 0.01,
            sonar_offset_m: 0.20,
            beam_half_angle_deg: 15.0,
            max_steps,
        }
    }

    /// `true` when every length is finite and positive and they are in order
    /// (`radius < safe < follow < near`, step below the radius).
    pub fn is_valid(&self) -> bool {
        let all = [
            self.radius_m,
            self.follow_m,
            self.safe_m,
            self.near_m,
            self.step_m,
            self.goal_tolerance_m,
            self.sonar_offset_m,
            self.beam_half_angle_deg,
        ];
        all.iter().all(|v| v.is_finite() && *v >= 0.0)
            && self.radius_m < self.safe_m
            && self.safe_m < self.follow_m
            && self.follow_m < self.near_m
            && self.step_m > 0.0
            && self.step_m <= 0.1
            && self.beam_half_angle_deg <= 45.0
    }
}

/// Where the Bug is in its algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Driving straight at the goal.
    MotionToGoal,
    /// Going all the way round the obstacle hit, remembering the point closest to the goal.
    FollowBoundary,
    /// Going back along the boundary, the shorter way, to that point.
    ReturnToLeave,
    /// At the goal.
    Reached,
    /// The way to the goal is blocked at the closest point of a loop: the goal is enclosed.
    Unreachable,
    /// The step limit ran out, or the robot could not move without coming too near an echo.
    GaveUp,
}

impl Phase {
    /// `true` for the three phases that end the run.
    pub fn is_final(self) -> bool {
        matches!(self, Phase::Reached | Phase::Unreachable | Phase::GaveUp)
    }
}

/// What the robot should do next.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Command {
    /// Turn in place to `heading_rad` (world frame), then drive `distance_m` straight.
    Move {
        /// Heading, radians.
        heading_rad: f32,
        /// Distance, metres (at most [`BugConfig::step_m`]).
        distance_m: f32,
    },
    /// The run is over, with this final phase.
    Stop(Phase),
}

/// Something worth recording that happened in this step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event {
    /// Nothing.
    None,
    /// An obstacle blocked the way here: boundary following starts.
    Hit(PointM),
    /// The robot leaves the boundary here towards the goal.
    Leave(PointM),
}

/// The answer of one [`Bug::step`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// The next motion, or the end.
    pub command: Command,
    /// What happened.
    pub event: Event,
}

/// The Bug's state: phase, remembered echoes, the loop being walked.
#[derive(Clone, Debug)]
pub struct Bug {
    config: BugConfig,
    goal: PointM,
    phase: Phase,
    echoes: heapless::Vec<PointM, ECHO_CAPACITY>,
    next_slot: usize,
    steps: u32,
    last: Option<PointM>,
    /// Boundary side being followed: +1 obstacle on the left, −1 on the right.
    side: f32,
    hit: PointM,
    /// Arc driven since the hit (following) or since the loop closed (going back), metres.
    arc_m: f32,
    /// The robot has been 2 × RETURN_ZONE_M away from the point it must come back to.
    left_zone: bool,
    /// Closest approach to that point so far inside the zone, metres.
    zone_min_m: f32,
    /// Best (closest to the goal) point of the loop, its distance to the goal and its arc.
    best: PointM,
    best_goal_m: f32,
    best_arc_m: f32,
    /// Arc expected back to the leave point, metres.
    return_arc_m: f32,
    /// Loop perimeter as driven, metres.
    loop_m: f32,
    /// The robot has just left: a block now means the goal is enclosed.
    just_left: bool,
    /// The last heading commanded, radians.
    heading_rad: f32,
}

impl Bug {
    /// A Bug heading for `goal`; `None` when the config is not valid or the goal not finite.
    pub fn new(config: BugConfig, goal: PointM) -> Option<Self> {
        if !(config.is_valid() && goal.is_finite()) {
            return None;
        }
        Some(Self {
            config,
            goal,
            phase: Phase::MotionToGoal,
            echoes: heapless::Vec::new(),
            next_slot: 0,
            steps: 0,
            last: None,
            side: LEFT,
            hit: goal,
            arc_m: 0.0,
            left_zone: false,
            zone_min_m: f32::INFINITY,
            best: goal,
            best_goal_m: f32::INFINITY,
            best_arc_m: 0.0,
            return_arc_m: 0.0,
            loop_m: 0.0,
            just_left: false,
            heading_rad: 0.0,
        })
    }

    /// The phase now.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u32 {
        self.steps
    }

    /// The echoes remembered now (world frame).
    pub fn echoes(&self) -> &[PointM] {
        &self.echoes
    }

    /// The bearings to read before the next [`step`](Self::step), radians relative to the
    /// heading (always the same nine).
    pub fn bearings_rad(&self) -> [f32; READINGS] {
        BEARINGS_DEG.map(|d| d * core::f32::consts::PI / 180.0)
    }

    /// One decision: `pose` is where the robot is now, `ranges[i]` the sonar's reading at
    /// [`BEARINGS_DEG`]`[i]` from that pose (`None`: no echo). Never panics.
    pub fn step(&mut self, pose: Pose, ranges: &[Option<f32>; READINGS]) -> Step {
        let out = self.decide(pose, ranges);
        if let Command::Move { heading_rad, .. } = out.command {
            self.heading_rad = heading_rad;
        }
        out
    }

    fn decide(&mut self, pose: Pose, ranges: &[Option<f32>; READINGS]) -> Step {
        if self.steps == 0 {
            self.heading_rad = pose.heading_rad;
        }
        let none = |command| Step {
            command,
            event: Event::None,
        };
        if self.phase.is_final() {
            return none(Command::Stop(self.phase));
        }
        if self.steps >= self.config.max_steps || !pose.is_finite() {
            return none(self.finish(Phase::GaveUp));
        }
        self.steps += 1;
        let p = pose.position();
        if let Some(last) = self.last {
            self.arc_m += last.distance_m(p);
        }
        self.last = Some(p);
        self.sense(pose, ranges);
        let to_goal_m = p.distance_m(self.goal);
        if to_goal_m <= self.config.goal_tolerance_m {
            return none(self.finish(Phase::Reached));
        }
        match self.phase {
            Phase::MotionToGoal => self.motion_to_goal(p, to_goal_m),
            Phase::FollowBoundary => {
                if to_goal_m < self.best_goal_m {
                    self.best = p;
                    self.best_goal_m = to_goal_m;
                    self.best_arc_m = self.arc_m;
                }
                if self.back_at(p, self.hit) {
                    self.close_loop(p)
                } else {
                    none(self.follow(p))
                }
            }
            Phase::ReturnToLeave => {
                let done = self.return_arc_m < 0.05
                    || (self.arc_m >= 0.5 * self.return_arc_m && self.back_at(p, self.best));
                if done {
                    self.phase = Phase::MotionToGoal;
                    self.just_left = true;
                    let mut out = self.motion_to_goal(p, to_goal_m);
                    if out.event == Event::None {
                        out.event = Event::Leave(p);
                    }
                    out
                } else if self.arc_m > self.loop_m + 1.0 {
                    none(self.finish(Phase::GaveUp))
                } else {
                    none(self.follow(p))
                }
            }
            _ => none(Command::Stop(self.phase)),
        }
    }

    fn finish(&mut self, phase: Phase) -> Command {
        self.phase = phase;
        Command::Stop(phase)
    }

    /// Turn the readings into echo points and remember the near ones.
    fn sense(&mut self, pose: Pose, ranges: &[Option<f32>; READINGS]) {
        let half_rad = self.config.beam_half_angle_deg * core::f32::consts::PI / 180.0;
        let origin = pose.point_ahead(self.config.sonar_offset_m);
        let p = pose.position();
        for (i, (range, bearing_deg)) in ranges.iter().zip(BEARINGS_DEG).enumerate() {
            let Some(r) = range.filter(|r| r.is_finite() && *r > 0.0) else {
                continue;
            };
            let near = |j: Option<usize>| {
                j.and_then(|j| ranges.get(j).copied().flatten())
                    .filter(|n| n.is_finite() && *n <= r + 1.0e-3)
            };
            let below = near(i.checked_sub(1));
            let above = near(Some(i + 1));
            // Towards the neighbour that read no farther (the nearer one if both did, the
            // axis if they read the same or neither did).
            let shift = match (below, above) {
                (Some(b), Some(a)) if abs(a - b) <= 1.0e-3 => 0.0,
                (Some(b), Some(a)) if b < a => -half_rad,
                (Some(_), Some(_)) => half_rad,
                (Some(_), None) => -half_rad,
                (None, Some(_)) => half_rad,
                (None, None) => 0.0,
            };
            let angle = pose.heading_rad + bearing_deg * core::f32::consts::PI / 180.0 + shift;
            let q = PointM::new(origin.x_m + r * cos(angle), origin.y_m + r * sin(angle));
            if q.is_finite() && q.distance_m(p) <= self.config.near_m {
                self.remember(q);
            }
        }
    }

    fn remember(&mut self, q: PointM) {
        if self.echoes.push(q).is_err() {
            if let Some(slot) = self.echoes.get_mut(self.next_slot) {
                *slot = q;
            }
            self.next_slot = (self.next_slot + 1) % ECHO_CAPACITY;
        }
    }

    /// The nearest remembered echo within `near_m` and its distance.
    fn nearest(&self, p: PointM) -> Option<(PointM, f32)> {
        let mut best: Option<(PointM, f32)> = None;
        for &q in &self.echoes {
            let d = q.distance_m(p);
            if d <= self.config.near_m && best.is_none_or(|(_, b)| d < b) {
                best = Some((q, d));
            }
        }
        best
    }

    /// Whether driving from `p` along unit `(ux, uy)` is blocked: an echo within
    /// `safe_m` of the way in the next `follow_m + 0.1` metres.
    fn blocked(&self, p: PointM, ux: f32, uy: f32, ahead_m: f32) -> bool {
        let look_m = (self.config.follow_m + 0.1).min(ahead_m + self.config.safe_m);
        self.echoes.iter().any(|q| {
            let (dx, dy) = (q.x_m - p.x_m, q.y_m - p.y_m);
            let along = dx * ux + dy * uy;
            let across = abs(dx * uy - dy * ux);
            along > 0.0 && along <= look_m && across < self.config.safe_m
        })
    }

    fn motion_to_goal(&mut self, p: PointM, to_goal_m: f32) -> Step {
        let ux = (self.goal.x_m - p.x_m) / to_goal_m;
        let uy = (self.goal.y_m - p.y_m) / to_goal_m;
        let just_left = core::mem::replace(&mut self.just_left, false);
        if self.blocked(p, ux, uy, to_goal_m) {
            if just_left {
                return Step {
                    command: self.finish(Phase::Unreachable),
                    event: Event::Leave(p),
                };
            }
            self.phase = Phase::FollowBoundary;
            self.side = LEFT;
            self.hit = p;
            self.arc_m = 0.0;
            self.left_zone = false;
            self.zone_min_m = f32::INFINITY;
            self.best = p;
            self.best_goal_m = to_goal_m;
            self.best_arc_m = 0.0;
            return Step {
                command: self.follow(p),
                event: Event::Hit(p),
            };
        }
        let distance_m = to_goal_m.min(self.config.step_m);
        self.safe_move(p, atan2(uy, ux), distance_m, 0.0)
            .map_or_else(
                || Step {
                    command: self.finish(Phase::GaveUp),
                    event: Event::None,
                },
                |command| Step {
                    command,
                    event: Event::None,
                },
            )
    }

    /// Whether the robot is back at `target` (see the module doc: out of the zone once, then
    /// the closest approach inside it).
    fn back_at(&mut self, p: PointM, target: PointM) -> bool {
        let d = p.distance_m(target);
        if d > 2.0 * RETURN_ZONE_M {
            self.left_zone = true;
        }
        if !self.left_zone || d > RETURN_ZONE_M {
            return false;
        }
        if d < self.zone_min_m {
            self.zone_min_m = d;
            false
        } else {
            true
        }
    }

    fn close_loop(&mut self, p: PointM) -> Step {
        self.loop_m = self.arc_m;
        // Back at the hit point, the leave point is `best_arc_m` further on the same way round,
        // or the rest of the loop back the other way: take the shorter (turning round means
        // keeping the obstacle on the other side).
        let forward_m = self.best_arc_m;
        let backward_m = (self.loop_m - self.best_arc_m).max(0.0);
        if forward_m <= backward_m {
            self.return_arc_m = forward_m;
        } else {
            self.return_arc_m = backward_m;
            self.side = -self.side;
        }
        self.phase = Phase::ReturnToLeave;
        self.arc_m = 0.0;
        self.left_zone = self.best.distance_m(p) > 2.0 * RETURN_ZONE_M;
        self.zone_min_m = f32::INFINITY;
        let to_goal_m = p.distance_m(self.goal);
        if self.return_arc_m < 0.05 {
            // Already at the leave point.
            self.phase = Phase::MotionToGoal;
            self.just_left = true;
            let mut out = self.motion_to_goal(p, to_goal_m);
            if out.event == Event::None {
                out.event = Event::Leave(p);
            }
            return out;
        }
        Step {
            command: self.follow(p),
            event: Event::None,
        }
    }

    /// One step along the boundary, obstacle on `side`.
    fn follow(&mut self, p: PointM) -> Command {
        let s = self.side;
        let heading = match self.nearest(p) {
            Some((q, d)) if d > 0.0 => {
                let normal = atan2(q.y_m - p.y_m, q.x_m - p.x_m);
                let tangent = normal - s * core::f32::consts::FRAC_PI_2;
                let correction = (3.0 * (d - self.config.follow_m)).clamp(-0.6, 0.6);
                tangent + s * correction
            }
            // Lost the boundary: the last heading turned towards the obstacle's side.
            _ => self.heading_rad + s * 0.5,
        };
        match self.safe_move(p, heading, self.config.step_m, -s) {
            Some(c) => c,
            None => self.finish(Phase::GaveUp),
        }
    }

    /// The move along `heading` (or turned by 15° steps towards `away`, alternately both ways
    /// when `away` is 0) whose end stays `safe_m` from every echo or at least gets no nearer.
    fn safe_move(&self, p: PointM, heading: f32, distance_m: f32, away: f32) -> Option<Command> {
        let now_m = self.nearest(p).map_or(f32::INFINITY, |(_, d)| d);
        let step_rad = 15.0 * core::f32::consts::PI / 180.0;
        for k in 0..=12u8 {
            let turn = if away == 0.0 {
                let n = f32::from(k.div_ceil(2));
                if k % 2 == 1 {
                    n
                } else {
                    -n
                }
            } else {
                away * f32::from(k)
            };
            let h = wrap_angle_rad(heading + turn * step_rad);
            let end = PointM::new(p.x_m + distance_m * cos(h), p.y_m + distance_m * sin(h));
            let end_m = self
                .echoes
                .iter()
                .map(|q| hypot(q.x_m - end.x_m, q.y_m - end.y_m))
                .fold(f32::INFINITY, f32::min);
            if end_m >= self.config.safe_m || end_m >= now_m {
                return Some(Command::Move {
                    heading_rad: h,
                    distance_m,
                });
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A synthetic sensor: exact ranges to an axis-aligned square (the nearest point of the
    /// square within the beam's cone, from the sonar), for the state machine alone.
    struct Square {
        min: PointM,
        max: PointM,
    }

    impl Square {
        fn contains(&self, x: f32, y: f32) -> bool {
            x >= self.min.x_m && x <= self.max.x_m && y >= self.min.y_m && y <= self.max.y_m
        }

        /// Distance from `p` to the square (0 inside).
        fn distance_m(&self, p: PointM) -> f32 {
            let dx = (self.min.x_m - p.x_m).max(p.x_m - self.max.x_m).max(0.0);
            let dy = (self.min.y_m - p.y_m).max(p.y_m - self.max.y_m).max(0.0);
            (dx * dx + dy * dy).sqrt()
        }

        /// Ray-march the cone (1° rays) and keep the nearest hit, up to 3 m.
        fn read(&self, pose: Pose, bearing_deg: f32) -> Option<f32> {
            let o = pose.point_ahead(0.2);
            let mut best: Option<f32> = None;
            for k in -15..=15 {
                let a = pose.heading_rad + (bearing_deg + k as f32).to_radians();
                let mut t = 0.0f32;
                while t < 3.0 {
                    if self.contains(o.x_m + t * a.cos(), o.y_m + t * a.sin()) {
                        best = Some(best.map_or(t, |b: f32| b.min(t)));
                        break;
                    }
                    t += 0.005;
                }
            }
            best.filter(|r| *r >= 0.26)
        }
    }

    struct Outcome {
        phase: Phase,
        length_m: f32,
        min_distance_m: f32,
        hits: usize,
        leaves: usize,
    }

    fn drive(world: &[Square], start: PointM, goal: PointM, max_steps: u32) -> Outcome {
        let mut bug = Bug::new(BugConfig::new(0.4, max_steps), goal).unwrap();
        let mut pose = Pose::new(start.x_m, start.y_m, 0.0);
        let (mut length_m, mut min_distance_m, mut hits, mut leaves) = (0.0, f32::INFINITY, 0, 0);
        loop {
            let mut ranges = [None; READINGS];
            for (r, b) in ranges.iter_mut().zip(BEARINGS_DEG) {
                *r = world
                    .iter()
                    .filter_map(|s| s.read(pose, b))
                    .reduce(f32::min);
            }
            let out = bug.step(pose, &ranges);
            match out.event {
                Event::Hit(_) => hits += 1,
                Event::Leave(_) => leaves += 1,
                Event::None => {}
            }
            match out.command {
                Command::Stop(phase) => {
                    return Outcome {
                        phase,
                        length_m,
                        min_distance_m,
                        hits,
                        leaves,
                    }
                }
                Command::Move {
                    heading_rad,
                    distance_m,
                } => {
                    assert!(distance_m <= 0.02 + 1e-6);
                    pose = Pose::new(
                        pose.x_m + distance_m * heading_rad.cos(),
                        pose.y_m + distance_m * heading_rad.sin(),
                        heading_rad,
                    );
                    length_m += distance_m;
                    for s in world {
                        min_distance_m = min_distance_m.min(s.distance_m(pose.position()));
                    }
                }
            }
        }
    }

    fn square(x0: f32, y0: f32, x1: f32, y1: f32) -> Square {
        Square {
            min: PointM::new(x0, y0),
            max: PointM::new(x1, y1),
        }
    }

    #[test]
    fn a_free_way_goes_straight_to_the_goal() {
        let o = drive(&[], PointM::new(0.0, 0.0), PointM::new(3.0, 4.0), 1000);
        assert_eq!(o.phase, Phase::Reached);
        assert!((o.length_m - 5.0).abs() < 0.03, "{}", o.length_m);
        assert_eq!(o.hits, 0);
    }

    #[test]
    fn a_square_in_the_way_is_walked_round_and_left_at_its_far_side() {
        let world = [square(2.0, -0.5, 3.0, 0.5)];
        let o = drive(&world, PointM::new(0.0, 0.0), PointM::new(5.0, 0.0), 5000);
        assert_eq!(o.phase, Phase::Reached);
        assert_eq!((o.hits, o.leaves), (1, 1));
        // Never nearer than the radius, and a full loop (about 4 + 2π·0.55 m) plus the way
        // back to the far side plus the straight parts: within the seed's bound on the square
        // grown by the distance the robot keeps, D + 1.5 (4 + 2π·0.55) (grown by the radius
        // alone, 14.77 m, a lone small square is 0.13 m over: the loop is 0.15 m out).
        assert!(o.min_distance_m > 0.4, "{}", o.min_distance_m);
        let loop_m = 4.0 + 2.0 * core::f32::consts::PI * 0.55;
        assert!(o.length_m > 5.0 + loop_m, "{}", o.length_m);
        let bound_m = 5.0 + 1.5 * loop_m;
        assert!(o.length_m <= bound_m, "{} > {bound_m}", o.length_m);
    }

    #[test]
    fn the_way_back_to_the_leave_point_is_the_shorter_one() {
        // A tall square off-centre: the hit is near its lower end. Whichever way round the
        // loop went, going on or turning back, the way from the hit point to the far side's
        // closest point is about 3.1 m one way and 6.8 m the other; the robot must take the
        // short one both when it lies ahead and when it lies behind.
        let loop_m = 2.0 * (1.0 + 2.2) + 2.0 * core::f32::consts::PI * 0.55;
        for (y0, y1) in [(-0.2, 2.0), (-2.0, 0.2)] {
            let world = [square(2.0, y0, 3.0, y1)];
            let o = drive(&world, PointM::new(0.0, 0.0), PointM::new(5.0, 0.0), 20000);
            assert_eq!(o.phase, Phase::Reached, "{y0}");
            assert!(o.min_distance_m > 0.4, "{}", o.min_distance_m);
            // Straight parts (< 5 m) + loop + the short way (~3.1 m), with slack for the
            // following's wiggles; the long way would add 3.7 m more.
            assert!(
                o.length_m < 5.0 + loop_m + 3.1 + 1.2,
                "{y0}: {}",
                o.length_m
            );
            assert!(o.length_m > 5.0 + loop_m, "{y0}: {}", o.length_m);
        }
    }

    #[test]
    fn a_goal_inside_a_ring_of_squares_is_unreachable() {
        // Four walls round (10, 0) with no gap wider than the robot.
        let world = [
            square(8.0, -2.0, 12.0, -1.8),
            square(8.0, 1.8, 12.0, 2.0),
            square(8.0, -2.0, 8.2, 2.0),
            square(11.8, -2.0, 12.0, 2.0),
        ];
        let o = drive(&world, PointM::new(4.0, 0.3), PointM::new(10.0, 0.0), 20000);
        assert_eq!(o.phase, Phase::Unreachable);
        assert_eq!((o.hits, o.leaves), (1, 1));
        assert!(o.min_distance_m > 0.4, "{}", o.min_distance_m);
    }

    #[test]
    fn the_step_limit_gives_up() {
        let world = [square(2.0, -0.5, 3.0, 0.5)];
        let o = drive(&world, PointM::new(0.0, 0.0), PointM::new(5.0, 0.0), 200);
        assert_eq!(o.phase, Phase::GaveUp);
    }

    #[test]
    fn an_oblique_wall_echo_is_placed_on_the_wall() {
        // Wall y = 1 seen from the origin heading +x: the 60° cone's echo comes from its 75°
        // edge; placed there, not on the axis (which would be 0.58 m up the wall's normal).
        let mut bug = Bug::new(BugConfig::new(0.4, 10), PointM::new(50.0, 0.0)).unwrap();
        let pose = Pose::new(-0.2, 0.0, 0.0); // sonar at the origin
        let mut ranges = [None; READINGS];
        let sq = square(-10.0, 1.0, 10.0, 2.0);
        for (r, b) in ranges.iter_mut().zip(BEARINGS_DEG) {
            *r = sq.read(pose, b);
        }
        bug.step(pose, &ranges);
        assert!(!bug.echoes().is_empty());
        for q in bug.echoes() {
            assert!((q.y_m - 1.0).abs() < 0.03, "{q:?}");
        }
    }

    #[test]
    fn bad_inputs_never_panic() {
        assert!(Bug::new(BugConfig::new(0.4, 10), PointM::new(f32::NAN, 0.0)).is_none());
        assert!(Bug::new(BugConfig::new(f32::NAN, 10), PointM::new(1.0, 0.0)).is_none());
        let mut bug = Bug::new(BugConfig::new(0.4, 10), PointM::new(1.0, 0.0)).unwrap();
        let odd = [
            Some(f32::NAN),
            Some(-1.0),
            Some(f32::INFINITY),
            None,
            Some(0.0),
            Some(1e30),
            None,
            Some(0.5),
            Some(0.5),
        ];
        let out = bug.step(Pose::new(0.0, 0.0, 0.0), &odd);
        assert!(matches!(out.command, Command::Move { .. }));
        let out = bug.step(Pose::new(f32::NAN, 0.0, 0.0), &odd);
        assert_eq!(out.command, Command::Stop(Phase::GaveUp));
        // Once over, it stays over.
        assert_eq!(
            bug.step(Pose::new(0.0, 0.0, 0.0), &odd).command,
            Command::Stop(Phase::GaveUp)
        );
    }
}
