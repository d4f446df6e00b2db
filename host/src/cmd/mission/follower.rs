//! Following a mission's telemetry: the trajectory, the plans as their chunks arrive, the
//! pictures and the live display, until the device's final report.

use super::*;

/// A plan as its telemetry arrives.
pub(super) struct PlanRecord {
    pub(super) number: u32,
    pub(super) t_ms: u32,
    pub(super) prefix_total: Option<u16>,
    pub(super) path_total: Option<u16>,
    pub(super) prefix: Vec<PointM>,
    pub(super) path: Vec<PointM>,
    pub(super) pictured: bool,
}

impl PlanRecord {
    pub(super) fn complete(&self) -> bool {
        matches!(self.prefix_total, Some(n) if self.prefix.len() >= n as usize)
            && matches!(self.path_total, Some(n) if self.path.len() >= n as usize)
    }
}

/// Everything gathered from the telemetry.
pub(crate) struct Follower {
    pub(super) half: u16,
    pub(super) pictures: bool,
    pub(super) grid: Box<Grid400>,
    pub(super) poses: Vec<PoseReport>,
    pub(super) trajectory: Vec<TrajectoryRow>,
    pub(super) distance_m: f32,
    pub(super) phase: Option<MissionPhase>,
    /// Places the robot stood to sweep, counted as the device counts them (`MissionStats::stops`).
    pub(super) stops: u32,
    /// Where the last standing sweep began, and the start before any pose has come.
    last_stop: Option<PointM>,
    start: PointM,
    /// Within this of the last standing sweep a sweep is the same stop (the device's
    /// `MissionConfig::stall_distance_m`).
    pub(super) same_stop_m: f32,
    pub(super) sweep: u32,
    pub(super) hits: Vec<PointM>,
    pub(super) plan: Option<PlanRecord>,
    pub(super) plans: u32,
    /// Where the robot was when each plan's report arrived (a stall's sentence counts the
    /// plans from the place where the mission gave up: `crate::answer`).
    pub(super) plan_positions: Vec<PointM>,
    pub(super) plan_snapshots: Vec<Snapshot>,
    pub(super) frames: Vec<Snapshot>,
    pub(super) next_frame_s: f32,
    pub(crate) finished: Option<MissionReport>,
    /// Telemetry chunks that arrived after a gap (a lost chunk before them): the pictured map
    /// and plans miss what was lost (see `link.rs`).
    pub(super) telemetry_gaps: u32,
    /// Sweeps whose hits have all arrived.
    pub(super) sweeps: u32,
    /// `--record` / `--live`.
    pub(super) recorder: Option<TelemetryRecorder>,
    /// Why each plan happened and the band of the latest sweep, read from the device's phase
    /// and sweep reports (see [`Follower::observe_for_reasons`]).
    pub(super) reasons: crate::sim::reason::ReasonTracker,
    /// Phase changes not yet used to explain a plan: mission time (ms) and phase.
    pub(super) phases_to_explain: Vec<(u32, MissionPhase)>,
}

/// Seconds between two frames of `mission.gif`.
pub(super) const FRAME_PERIOD_S: f32 = 0.5;

impl Follower {
    pub(super) fn new(inputs: &Inputs, pictures: bool) -> Result<Self> {
        let mut grid =
            Box::new(Grid400::new(inputs.geometry).map_err(|e| anyhow!("the map: {e:?}"))?);
        let half = inputs
            .geometry
            .expansion_cells(inputs.params.robot_radius_m);
        if let Some(known) = &inputs.known {
            for polygon in known.iter() {
                twil_core::raster::mark_polygon(&mut grid, polygon, half);
            }
        }
        let same_stop_m =
            twil_core::mission::MissionConfig::from_params(&inputs.params, inputs.robot)
                .stall_distance_m;
        Ok(Self {
            last_stop: None,
            start: inputs.params.start,
            same_stop_m,
            half,
            pictures,
            grid,
            poses: Vec::new(),
            trajectory: Vec::new(),
            distance_m: 0.0,
            phase: None,
            stops: 0,
            sweep: 0,
            hits: Vec::new(),
            plan: None,
            plans: 0,
            plan_positions: Vec::new(),
            plan_snapshots: Vec::new(),
            frames: Vec::new(),
            next_frame_s: 0.0,
            finished: None,
            telemetry_gaps: 0,
            sweeps: 0,
            recorder: None,
            // Stop mode whatever the mission's: the telemetry does not say whether a moving
            // sweep found the path blocked, so a replan while moving is told as a plain
            // "a sweep ended" rather than guessed (see `observe_for_reasons`).
            reasons: crate::sim::reason::ReasonTracker::new(
                twil_core::mission::MissionMode::Stop,
                inputs.robot.normal_half_sweep_deg,
                95.0,
            ),
            phases_to_explain: Vec::new(),
        })
    }

    /// Record (and/or serve) what arrives from now on.
    pub(super) fn record_into(&mut self, recorder: Recorder, inputs: &Inputs) {
        let scene = crate::record::topics::WorldScene {
            real: inputs.real.as_ref(),
            known: inputs.known.as_ref(),
            start: inputs.params.start,
            goal: inputs.params.goal,
            body_radius_m: Some(
                (inputs.params.robot_radius_m - twil_core::robot::PLANNING_MARGIN_M).max(0.05),
            ),
        };
        self.recorder = Some(TelemetryRecorder::new(
            recorder,
            &scene,
            &inputs.robot,
            &self.grid,
        ));
    }

    pub(super) fn pose(&self) -> Pose {
        self.poses.last().map_or(Pose::default(), |p| {
            Pose::new(p.position.x_m, p.position.y_m, p.heading_rad)
        })
    }

    /// A standing sweep began: a new stop unless it is where the last one was (a full sweep
    /// the band or the body corridor asked for right after a sweep), the device's rule
    /// (`twil_core::mission`, `MissionStats::stops`), so the live line, the pictures and the
    /// summary give one number.
    pub(super) fn count_stop(&mut self) {
        let here = self.poses.last().map_or(self.start, |p| p.position);
        let same_place = self
            .last_stop
            .is_some_and(|p| (here.x_m - p.x_m).hypot(here.y_m - p.y_m) < self.same_stop_m);
        if !same_place {
            self.stops += 1;
        }
        self.last_stop = Some(here);
    }

    /// The mission time of the latest pose, milliseconds.
    pub(super) fn t_ms(&self) -> u32 {
        self.poses.last().map_or(0, |p| p.t_ms)
    }

    pub(super) fn t_s(&self) -> f32 {
        self.poses.last().map_or(0.0, |p| p.t_ms as f32 / 1000.0)
    }

    pub(super) fn snapshot(&self, t_s: f32, plan_number: u32) -> Snapshot {
        let (path, prefix) = self
            .plan
            .as_ref()
            .map(|p| (p.path.clone(), p.prefix.clone()))
            .unwrap_or_default();
        Snapshot {
            t_s,
            pose: self.pose(),
            grid: self.grid.clone(),
            path,
            prefix,
            hits: self.hits.clone(),
            trail_len: self.trajectory.len(),
            plan_number,
            // The device does not report the space it has seen.
            seen: None,
            stops: self.stops,
            plans: self.plans,
            reason: self.reasons.reason(),
            band: self.reasons.band(),
        }
    }

    /// Tell the reason tracker why the plan reported at `t_ms` happened, from the phases the
    /// device reported before it, as the mission events they stand for: a standing sweep starts
    /// a sweep (a full one after the first plan was asked for because the prefix left the
    /// band), settling means the prefix ended, and no standing sweep since the last plan means
    /// a sweep taken while moving. Phases stamped at `t_ms` or later are this plan's
    /// consequences (the device sends a phase change before the plan that caused it), so
    /// they wait for the next plan.
    pub(super) fn explain_plan(&mut self, t_ms: u32, status: twil_core::plan::PlanStatus) {
        let first = self.reasons.reason().is_none();
        let events = crate::sim::reason::events_before_plan(
            &mut self.phases_to_explain,
            t_ms,
            status,
            first,
        );
        self.reasons.observe(&events);
    }

    /// Picture the current plan once it has all arrived (or will get no more).
    pub(super) fn picture_plan(&mut self, force: bool) {
        let ready = match &self.plan {
            Some(p) => !p.pictured && (force || p.complete()),
            None => false,
        };
        if !ready {
            return;
        }
        if self.pictures {
            let (number, t_ms) = self.plan.as_ref().map_or((0, 0), |p| (p.number, p.t_ms));
            let snap = self.snapshot(t_ms as f32 / 1000.0, number);
            self.plan_snapshots.push(snap);
        }
        if let (Some(p), Some(r)) = (&self.plan, &mut self.recorder) {
            r.plan(p.t_ms as f32 / 1000.0, &p.path, &p.prefix);
        }
        if let Some(p) = &mut self.plan {
            p.pictured = true;
        }
    }

    pub(crate) fn absorb(&mut self, telemetry: Telemetry) {
        match telemetry {
            Telemetry::Pose(report) => {
                if let Some(last) = self.poses.last() {
                    let d = ((report.position.x_m - last.position.x_m).powi(2)
                        + (report.position.y_m - last.position.y_m).powi(2))
                    .sqrt();
                    if d.is_finite() {
                        self.distance_m += d;
                    }
                }
                self.poses.push(report);
                let row = TrajectoryRow {
                    t_s: report.t_ms as f32 / 1000.0,
                    pose: self.pose(),
                    control: ControlSample {
                        left_voltage_v: report.left_voltage_v,
                        right_voltage_v: report.right_voltage_v,
                        ..ControlSample::default()
                    },
                    phase: self.phase,
                };
                if let Some(r) = &mut self.recorder {
                    r.pose(&row);
                }
                self.trajectory.push(row);
                let t_s = self.t_s();
                if self.pictures && t_s >= self.next_frame_s {
                    self.next_frame_s = t_s + FRAME_PERIOD_S;
                    let snap = self.snapshot(t_s, 0);
                    self.frames.push(snap);
                }
            }
            Telemetry::Phase {
                t_ms,
                phase,
                status,
            } => {
                if matches!(phase, MissionPhase::Sweep { .. }) && self.phase != Some(phase) {
                    self.count_stop();
                }
                // Bounded: a device that never plans cannot grow it past a few minutes' worth.
                if self.phases_to_explain.len() >= 4096 {
                    self.phases_to_explain.remove(0);
                }
                self.phases_to_explain.push((t_ms, phase));
                self.phase = Some(phase);
                let (pose, counts) = (self.pose(), (self.plans, self.stops));
                if let Some(r) = &mut self.recorder {
                    r.phase(t_ms as f32 / 1000.0, phase, status, &pose, counts);
                }
            }
            Telemetry::SweepHits {
                sweep,
                first,
                total,
                hits,
            } => {
                if sweep != self.sweep || first == 0 {
                    self.sweep = sweep;
                    self.hits.clear();
                }
                if first as usize != self.hits.len() {
                    self.telemetry_gaps += 1;
                }
                for p in &hits {
                    twil_core::raster::mark_point_m(&mut self.grid, *p, self.half);
                }
                self.hits.extend_from_slice(&hits);
                if self.hits.len() == total as usize {
                    self.sweeps += 1;
                    let t_s = self.t_s();
                    if let Some(r) = &mut self.recorder {
                        r.sweep(t_s, &self.hits, &self.grid);
                    }
                }
            }
            Telemetry::Planned {
                t_ms, plan, status, ..
            } => {
                self.picture_plan(true);
                self.explain_plan(t_ms, status);
                self.plans = self.plans.max(plan);
                let here = self.pose();
                self.plan_positions.push(PointM::new(here.x_m, here.y_m));
                self.plan = Some(PlanRecord {
                    number: plan,
                    t_ms,
                    prefix_total: None,
                    path_total: None,
                    prefix: Vec::new(),
                    path: Vec::new(),
                    pictured: false,
                });
            }
            Telemetry::Prefix {
                plan,
                first,
                total,
                points,
            } => {
                if let Some(p) = self.plan.as_mut().filter(|p| p.number == plan) {
                    if !append_chunk(&mut p.prefix, &mut p.prefix_total, first, total, &points) {
                        self.telemetry_gaps += 1;
                    }
                }
                self.picture_plan(false);
            }
            Telemetry::Path {
                plan,
                first,
                total,
                points,
            } => {
                if let Some(p) = self.plan.as_mut().filter(|p| p.number == plan) {
                    if !append_chunk(&mut p.path, &mut p.path_total, first, total, &points) {
                        self.telemetry_gaps += 1;
                    }
                }
                self.picture_plan(false);
            }
            Telemetry::Finished(report) => {
                self.picture_plan(true);
                if report.status == MissionStatus::Unreachable {
                    // No plan any more (a stalled mission sends no last `Planned`): the final
                    // frame must not draw the previous plan as if it were followed.
                    if let Some(p) = &mut self.plan {
                        p.path.clear();
                        p.prefix.clear();
                    }
                }
                if self.pictures {
                    let snap = self.snapshot(report.stats.time_s, 0);
                    self.frames.push(snap);
                }
                if let Some(r) = &mut self.recorder {
                    r.finished(&report);
                }
                self.finished = Some(report);
            }
            Telemetry::Boot { .. } | Telemetry::Status(_) => {}
        }
    }

    /// One line for the live display.
    pub(super) fn status_line(&self) -> String {
        let pose = self.pose();
        format!(
            "t {:6.1} s  {:<10}  x {:6.2} y {:6.2} heading {:4.0}°  stops {:3}  {:6.2} m",
            self.t_s(),
            self.phase.map_or("starting", MissionPhase::as_str),
            pose.x_m,
            pose.y_m,
            pose.heading_rad.to_degrees(),
            self.stops,
            self.distance_m
        )
    }
}

/// A short name of a phase.
/// Append a `Prefix` / `Path` chunk that starts at point `first` to `points` and note the
/// total; `false` (nothing appended) when an earlier chunk was lost.
pub(super) fn append_chunk(
    points: &mut Vec<PointM>,
    total_points: &mut Option<u16>,
    first: u16,
    total: u16,
    chunk: &[PointM],
) -> bool {
    *total_points = Some(total);
    if first as usize != points.len() {
        return false;
    }
    points.extend_from_slice(chunk);
    true
}

/// Follow the telemetry until `Finished`; `true` if Ctrl-C aborted the mission.
pub(super) fn follow(
    args: &Args,
    remote: &mut Remote,
    follower: &mut Follower,
    bar: &ProgressBar,
) -> Result<bool> {
    let silence = Duration::from_secs_f32(args.silence);
    remote.set_timeout(silence);
    let mut aborted = false;
    let mut last_draw = Instant::now();
    let heartbeat = heartbeat_period(args.link_timeout_ms);
    let mut last_beat = Instant::now();
    // The device measures the silence on its own clock, which under QEMU (`sleep=off`) runs
    // ahead of the host's: a heartbeat is also due when the mission time of its telemetry
    // has advanced by a period.
    let mut last_beat_mission_ms = 0u32;
    // The device was last heard when the link last read a frame from it, whole or damaged,
    // whoever read it (telemetry read while a poll waits for its reply counts).
    let started = Instant::now();
    let heard = |remote: &Remote| remote.last_frame_at().map_or(started, |at| at.max(started));
    let mut fault_notes = super::link::FaultNotes::from_env();
    loop {
        for t in std::mem::take(&mut remote.telemetry) {
            follower.absorb(t);
        }
        if follower.finished.is_some() {
            return Ok(aborted);
        }
        if !aborted && INTERRUPTED.load(Ordering::SeqCst) {
            note(bar, "twil: Ctrl-C: aborting the mission…");
            aborted = true;
            match remote
                .request(Request::AbortMission)
                .context("Ctrl-C: sending AbortMission")?
            {
                Reply::Ack => {}
                other => bail!("Ctrl-C: the device did not accept AbortMission: {other:?}"),
            }
            continue;
        }
        // Ask `MissionStatus` when the heartbeat is due (the device's link-loss policy needs
        // to hear from the host) or when the device has been quiet for `POLL_AFTER` (its final
        // report may have been lost on the way, see link.rs). Under QEMU (`sleep=off`)
        // the device's clock runs ahead of the host's, so the heartbeat is also due when the
        // mission time of its telemetry has advanced by a period.
        use super::link::POLL_AFTER;
        let mission_ms = follower.t_ms();
        let beat_due = heartbeat.is_some_and(|period| {
            last_beat.elapsed() >= period
                || u128::from(mission_ms.saturating_sub(last_beat_mission_ms)) >= period.as_millis()
        });
        let quiet = heard(remote).elapsed() >= POLL_AFTER && last_beat.elapsed() >= POLL_AFTER;
        if beat_due || quiet {
            last_beat = Instant::now();
            last_beat_mission_ms = mission_ms;
            match recover_final_report(remote, follower) {
                Poll::Finished | Poll::Alive => continue,
                Poll::NoReply(_) if heard(remote).elapsed() < silence => {
                    note(bar, "twil: MissionStatus unanswered, still listening");
                    continue;
                }
                Poll::NoReply(why) => bail!(
                    "{}; the last poll: MissionStatus: {why}",
                    went_silent(args, follower)
                ),
            }
        }
        let last_heard = heard(remote);
        let mut deadline = (last_heard + silence).min(last_beat.max(last_heard) + POLL_AFTER);
        if let Some(period) = heartbeat {
            deadline = deadline.min(last_beat + period);
        }
        let frame = match remote.next_frame(deadline) {
            Ok(frame) => frame,
            // The wait ended for a heartbeat or a poll, not for the silence: go round.
            Err(_) if Instant::now() >= deadline && heard(remote).elapsed() < silence => continue,
            Err(e) if Instant::now() >= deadline => {
                return Err(e).with_context(|| went_silent(args, follower));
            }
            Err(e) => return Err(e).context("reading the mission's telemetry"),
        };
        match frame {
            Ok(DeviceFrame::Telemetry(t)) => follower.absorb(t),
            Ok(DeviceFrame::Reply { .. }) => {} // a stale reply
            Err(fault) => {
                if let Some(line) = fault_notes.line(&fault) {
                    note(bar, &line);
                }
            }
        }
        if last_draw.elapsed() >= Duration::from_millis(50) {
            last_draw = Instant::now();
            let link = super::link::LinkReport::of(remote, follower.telemetry_gaps);
            bar.set_message(match link.words() {
                Some(words) => format!("{}  {words}", follower.status_line()),
                None => follower.status_line(),
            });
        }
    }
}

/// What [`recover_final_report`] learnt.
#[derive(Clone, Debug, PartialEq, Eq)]
enum Poll {
    /// The mission has ended: the follower has its final report.
    Finished,
    /// The device answered: the mission goes on (the link is alive, only quiet).
    Alive,
    /// No reply within the timeout: the caller's silence limit decides.
    NoReply(String),
}

/// Ask `MissionStatus`; if the mission has ended, hand its report to `follower` as the final
/// report (the `Finished` telemetry was lost).
fn recover_final_report(remote: &mut Remote, follower: &mut Follower) -> Poll {
    let reply = remote.request(Request::MissionStatus);
    // Telemetry that came in meanwhile goes first, in order.
    for t in std::mem::take(&mut remote.telemetry) {
        follower.absorb(t);
    }
    if follower.finished.is_some() {
        return Poll::Finished;
    }
    match reply {
        Ok(Reply::Mission(report)) if report.state == twil_core::link::RunState::Ended => {
            follower.absorb(Telemetry::Finished(report));
            Poll::Finished
        }
        Ok(_) => Poll::Alive,
        Err(e) => Poll::NoReply(format!("{e:#}")),
    }
}
