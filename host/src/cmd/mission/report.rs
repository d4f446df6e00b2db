//! What `twil mission` writes: the JSON result, `summary.json`, `trajectory.csv`, the plan
//! pictures and `mission.gif`.

use super::*;

pub(super) fn round3(x: f32) -> f64 {
    ((x as f64) * 1000.0).round() / 1000.0
}

/// The outcome of a mission as the host saw it.
pub struct Outcome {
    /// The device's final report.
    pub report: MissionReport,
    /// Who answered.
    pub info: DeviceInfo,
    /// Distance along the reported poses, metres.
    pub distance_m: f32,
    /// Smallest clearance of the robot's body to the real polygons along the reported poses
    /// (`None` without a real world).
    pub min_clearance_m: Option<f32>,
    /// Poses reported.
    pub poses: usize,
    /// Ctrl-C aborted the mission.
    pub interrupted: bool,
    /// What the link lost and repaired (`summary.json`).
    pub link: super::link::LinkReport,
    /// Where and how the mission ended, for the sentence that says why (crate::answer).
    pub place: EndPlace,
}

/// Where the mission ended and what its sentence needs (crate::answer::MissionEnd).
#[derive(Clone, Debug, Default)]
pub struct EndPlace {
    /// The last pose reported, or the first in contact with the real world.
    pub at: PointM,
    /// Plans in a row whose reports arrived within `stall_distance_m` of `at`.
    pub plans_here: u32,
    /// The device's stall distance, metres.
    pub stall_distance_m: f32,
    /// The goal.
    pub goal: PointM,
    /// The planning radius, metres.
    pub radius_m: f32,
    /// The mission's time limit, seconds.
    pub time_limit_s: f32,
    /// The real world's file name (simulated devices).
    pub real: Option<String>,
    /// The planner's verdict on the last plan reported.
    pub last_plan: Option<twil_core::plan::PlanStatus>,
}

/// The `--json` object: the keys of `twil simulate --json` plus `mcu`.
pub fn result_json(outcome: &Outcome) -> serde_json::Value {
    let s = &outcome.report.stats;
    let mut v = json!({
        "status": status_word(outcome),
        "stop_cause": stop_cause(outcome),
        "stops": s.stops,
        "full_sweeps": s.full_sweeps,
        "replans": s.replans,
        "distance_m": round3(outcome.distance_m),
        "sim_time_s": round3(s.time_s),
        "min_clearance_m": outcome.min_clearance_m.map(round3),
        "controller_overruns": s.controller_overruns,
        "mcu": mcu_json(outcome),
    });
    if let (Some(why), Some(obj)) = (mission_end(outcome).why(), v.as_object_mut()) {
        obj.insert("why".into(), why.into());
    }
    v
}

/// How the mission ended, for its word and sentence (crate::answer).
pub fn mission_end(outcome: &Outcome) -> crate::answer::MissionEnd<'static> {
    let p = &outcome.place;
    let s = &outcome.report.stats;
    let collided = outcome.min_clearance_m.is_some_and(|c| c < 0.0);
    crate::answer::MissionEnd {
        // A contact with the real world is a `collision` whatever the device reports, as the
        // exit status says (4).
        status: if collided {
            "collision"
        } else {
            outcome.report.status.as_str()
        },
        unreachable: s.unreachable_reason,
        device: outcome.report.stop_cause,
        interrupted: outcome.interrupted,
        at: p.at,
        goal: p.goal,
        radius_m: p.radius_m,
        plans_here: p.plans_here,
        stall_distance_m: p.stall_distance_m,
        clearance_m: outcome.min_clearance_m.unwrap_or(0.0),
        real: p.real.clone(),
        time_limit_s: p.time_limit_s,
        plan_error: s.last_plan_error.map(|e| format!("{e:?}")),
        no_start: p.last_plan == Some(twil_core::plan::PlanStatus::StartBlocked),
    }
}

/// Why the mission ended, one word on every end ([`crate::stop_cause`]).
pub fn stop_cause(outcome: &Outcome) -> &'static str {
    crate::stop_cause::name(
        mission_end(outcome).status,
        outcome.report.stats.unreachable_reason,
        outcome.report.stop_cause,
        outcome.interrupted,
    )
}

/// The mission's status word (crate::answer): the device's status made precise by its
/// reason and stop cause (`gave_up`, `goal_blocked`), except that a contact with the real
/// world (`--real`) is a `collision` whatever the device reports, as the exit status says (4).
pub fn status_word(outcome: &Outcome) -> &'static str {
    mission_end(outcome).word()
}

/// The firmware's measurements, or `null` when the device is the in-process one
/// (`--remote sim`), which measures nothing (its report carries zeros).
fn mcu_json(outcome: &Outcome) -> serde_json::Value {
    if !measured(outcome) {
        return serde_json::Value::Null;
    }
    json!({
        "max_control_instructions": outcome.report.max_control_instructions,
        "max_plan_instructions": outcome.report.max_plan_instructions,
        "max_turn_instructions": outcome.report.max_turn_instructions,
        "static_ram_bytes": outcome.info.static_ram_bytes,
        "stack_high_water_bytes": outcome.report.stack_high_water_bytes,
    })
}

/// The device is the firmware (a board or QEMU), which measures instructions, stack and stop
/// latency.
pub(super) fn measured(outcome: &Outcome) -> bool {
    outcome.info.build != twil_core::link::Build::Host
}

/// `summary.json`: the `--json` object plus details.
pub(super) fn summary_json(args: &Args, inputs: &Inputs, outcome: &Outcome) -> serde_json::Value {
    let mut v = result_json(outcome);
    let s = &outcome.report.stats;
    let extra = json!({
        "remote": remote_name(&args.remote),
        "build": format!("{:?}", outcome.info.build).to_lowercase(),
        "mode": args.mission.mode_name(),
        "preset": args.mission.loop_args.preset.name(),
        "planner": args.choices().planner_name(),
        "constant_depth_filter": args.choices().rcd,
        "trust_seen_space": !args.choices().seed_prune,
        "settle": args.choices().settle_name(),
        "reference_feed_forward": args.choices().reference_feed_forward,
        "turn_in_place": args.choices().turn_in_place,
        // The layout used: the preset's, `--sweep-readings`' or the robot file's.
        "sweep_readings": crate::cmd::args::LoopChoices {
            sweep_layout: inputs.robot.sweep_layout,
            ..args.choices()
        }
        .sweep_readings_name(),
        "real": args.real.as_ref().map(|p| p.display().to_string()),
        "known": args.world.known.as_ref().map(|p| p.display().to_string()),
        "params": args.world.params.display().to_string(),
        "seed": args.robot.seed,
        "sonar_range_m": inputs.robot.sonar_range_m,
        "robot": crate::robot_file::robot_json(&inputs.robot),
        "moving_sweeps": s.moving_sweeps,
        "plans": s.plans,
        "blocked_replans": s.blocked_replans,
        "band_cuts": s.band_cuts,
        "blind_cuts": s.blind_cuts,
        "readings": s.readings,
        "hits": s.hits,
        "odometry_distance_m": round3(s.odometry_distance_m),
        "saturated_periods": s.saturated_periods,
        "unreachable_reason": s.unreachable_reason.map(|r| format!("{r:?}")),
        "plan_errors": s.plan_errors,
        "poses_reported": outcome.poses,
        "stop_latency_us": measured(outcome).then_some(outcome.report.stop_latency_us),
        "interrupted": outcome.interrupted,
        "link": outcome.link.json(),
    });
    if let (Some(obj), Some(extra)) = (v.as_object_mut(), extra.as_object()) {
        for (k, val) in extra {
            obj.insert(k.clone(), val.clone());
        }
    }
    v
}

/// With `--out`: `summary.json`, `trajectory.csv`, `plan-NNN.png`, `mission.gif`, written as
/// `twil simulate` writes them ([`OutputArgs::write`]) from the telemetry followed.
pub(super) fn write_outputs(
    args: &Args,
    inputs: &Inputs,
    outcome: &Outcome,
    follower: Follower,
) -> Result<()> {
    if args.output.out.is_none() {
        return Ok(());
    }
    let setup = SimSetup {
        real: inputs.real.clone().unwrap_or_default(),
        known: inputs.known.clone(),
        params: inputs.params,
        geometry: inputs.geometry,
        mode: args.mission.mission_mode(),
        planner: args.choices().planner_kind(),
        robot: inputs.robot,
        time_limit_s: args.mission.time_limit_s(),
        constant_depth_filter: args.choices().rcd,
        trust_seen_space: !args.choices().seed_prune,
        evidence_map: args
            .mission
            .loop_args
            .evidence_map_for(inputs.robot.sonar_beam),
        moving_half_sweep_deg: 95.0,
        snapshot_period_s: FRAME_PERIOD_S,
        plan_latency_s: 0.0,
        settle: args.choices().settle,
        reference_feed_forward: args.choices().reference_feed_forward,
        turn_in_place: args.choices().turn_in_place,
        world_name: crate::sim::pictures::world_name(
            args.real.as_deref(),
            args.world.known.as_deref(),
        ),
    };
    let report = &outcome.report;
    let result = SimResult {
        status: match report.status {
            MissionStatus::Reached => SimStatus::Reached,
            MissionStatus::Unreachable => SimStatus::Unreachable,
            MissionStatus::Timeout => SimStatus::Timeout,
            MissionStatus::Aborted | MissionStatus::Running => SimStatus::Aborted,
        },
        stats: report.stats,
        distance_m: outcome.distance_m,
        sim_time_s: report.stats.time_s,
        min_clearance_m: outcome.min_clearance_m.unwrap_or(f32::NAN),
        sweeps: follower.sweeps,
        final_odometry_pose: follower.pose(),
        trajectory: follower.trajectory,
        plans: follower.plan_snapshots,
        frames: follower.frames,
        known_map_plan_length_m: None,
    };
    let mut summary = summary_json(args, inputs, outcome);
    // The plans the device reported (telemetry `Planned`), one picture each: a plan replaced
    // on the device before its report went out has none (`plans` counts it).
    summary["plans_reported"] = json!(result.plans.len());
    args.output.write(&setup, &result, &summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outcome(status: MissionStatus, cause: StopCause, min_clearance_m: Option<f32>) -> Outcome {
        Outcome {
            report: super::super::tests::ended_report(status, cause),
            info: DeviceInfo::for_build(Build::Host),
            distance_m: 1.0,
            min_clearance_m,
            poses: 3,
            interrupted: false,
            link: Default::default(),
            place: Default::default(),
        }
    }

    #[test]
    fn the_json_says_why_on_every_end_and_a_failsafe_abort_names_its_cause() {
        let lost = outcome(MissionStatus::Aborted, StopCause::LinkLost, Some(0.2));
        let v = result_json(&lost);
        assert_eq!(
            (&v["status"], &v["stop_cause"]),
            (&json!("aborted"), &json!("link_lost"))
        );
        let reached = outcome(MissionStatus::Reached, StopCause::None, Some(0.2));
        assert_eq!(result_json(&reached)["stop_cause"], "reached");
        let hit = outcome(MissionStatus::Reached, StopCause::None, Some(-0.01));
        assert_eq!(result_json(&hit)["stop_cause"], "collision");
        let overrun = outcome(MissionStatus::Aborted, StopCause::ControllerOverrun, None);
        assert_eq!(stop_cause(&overrun), "controller_overrun");
    }
}
