//! `twil mission`'s inputs: the files read and checked, and the mission set-up sent to the
//! device (with the explanation of a set-up the device refuses).

use super::*;

/// What the files give, checked.
pub struct Inputs {
    /// The mission.
    pub params: Params,
    /// Obstacles known before the first sweep.
    pub known: Option<Obstacles>,
    /// The real world of a simulated device.
    pub real: Option<Obstacles>,
    /// The map.
    pub geometry: GridGeometry,
    /// The robot (its body radius measures the clearance).
    pub robot: RobotConfig,
    /// The robot file's values for `ParamSet` (name, value, `FILE:LINE`).
    pub robot_file_values: Vec<(&'static str, f32, String)>,
}

/// Read and check the files and numbers of `args` (errors name the file and line, or the
/// option).
pub fn read_inputs(args: &Args) -> Result<Inputs> {
    let (mut params, known) = args.world.read()?;
    let real = args.real.as_deref().map(read_da).transpose()?;
    let geometry = args.world.geometry(DEFAULT_RESOLUTION_M)?;
    let robot = args.robot.resolve(
        &args.choices(),
        args.mission.follow.sweep_readings.is_some(),
        &args.world.params,
        &mut params,
    )?;
    let robot_file_values = match &args.robot.robot_file {
        Some(path) => file_values(path)?,
        None => Vec::new(),
    };
    args.mission.checked_time_limit_s()?;
    if !(args.silence.is_finite() && args.silence > 0.0 && args.silence <= 3600.0) {
        bail!(
            "--silence: must be between 0 and 3600 seconds, got {}",
            args.silence
        );
    }
    if !args.link_loss().is_valid() {
        bail!(
            "--link-timeout-ms: must be 0 (never) or {} to {} milliseconds, got {}",
            LinkLossPolicy::MIN_TIMEOUT_MS,
            LinkLossPolicy::MAX_TIMEOUT_MS,
            args.link_timeout_ms
        );
    }
    // `run` answers `out_of_bounds` (crate::answer).
    args.world.check_on_map(&geometry, &params)?;
    Ok(Inputs {
        params,
        known,
        real,
        geometry,
        robot,
        robot_file_values,
    })
}

impl Args {
    /// The loop choices of this run: `--preset`'s, with the explicit options applied.
    pub fn choices(&self) -> crate::cmd::args::LoopChoices {
        self.mission.choices()
    }
}

/// The robot file's values, sent to the device with `ParamSet` before the mission (issue 25):
/// name, value, and `FILE:LINE` for the messages. `SetParams` (the planning radius) and
/// `SetMission` (the sonar range, noise and beam, the sweep layout) carry their own for this
/// mission as well; every other key the file leaves out keeps the device's value
/// (`twil param list`).
fn file_values(path: &std::path::Path) -> Result<Vec<(&'static str, f32, String)>> {
    let file = crate::robot_file::read(path)?;
    Ok(file
        .entries
        .iter()
        .map(|e| {
            (
                e.param.name,
                e.value,
                format!("{}:{}", path.display(), e.line),
            )
        })
        .collect())
}

/// The `SetMission` of `args` and `inputs` (the robot's sonar constants, resolved from the
/// options and the robot file).
pub fn mission_setup(args: &Args, inputs: &Inputs) -> MissionSetup {
    let (params, robot) = (&inputs.params, &inputs.robot);
    MissionSetup {
        mode: args.mission.mission_mode(),
        planner: args.choices().planner_kind(),
        start: params.start,
        initial_heading_rad: params.initial_heading_deg.to_radians(),
        goal: params.goal,
        speed_m_s: params.speed_m_s,
        sonar_range_m: robot.sonar_range_m,
        time_limit_s: args.mission.time_limit_s(),
        constant_depth_filter: args.choices().rcd,
        trust_seen_space: !args.choices().seed_prune,
        noise_seed: args.robot.seed,
        sonar_noise_std_m: robot.sonar_noise_std_m,
        link_loss: args.link_loss(),
        sonar_beam: robot.sonar_beam,
        beam_half_angle_deg: robot.sonar_beam_half_angle_deg,
        incidence_limit_deg: robot.sonar_incidence_limit_deg,
        settle: args.choices().settle,
        reference_feed_forward: args.choices().reference_feed_forward,
        turn_in_place: args.choices().turn_in_place,
        sweep_layout: robot.sweep_layout,
        evidence_map: args.mission.loop_args.evidence_map_for(robot.sonar_beam),
        sonar_dropout_probability: robot.sonar_dropout_probability,
        sonar_spurious_probability: robot.sonar_spurious_probability,
    }
}

/// What the device says about a refused `SetMission`, naming the field and where it came from.
pub(super) fn explain_bad_mission(args: &Args, robot: &RobotConfig, error: &ErrorReply) -> String {
    if error.code != ErrorCode::BadMission {
        return format!("the device refused the mission: {error}");
    }
    if error.detail == 1 {
        // `value` is the field off the map: 2 start, 4 goal.
        let which = match error.value {
            2 => "the start",
            4 => "the goal",
            _ => "the start or the goal",
        };
        return format!(
            "the device refused the mission: {which} of {} lies off its map",
            args.world.params.display()
        );
    }
    let par = args.world.params.display();
    let field = match error.value {
        0 => "mode (--mode)".to_string(),
        1 => "planner (--planner)".to_string(),
        2 => format!("start ({par})"),
        3 => format!("initial heading ({par})"),
        4 => format!("goal ({par})"),
        5 if error.limit > 0 => format!(
            "speed ({par}; the robot's safe speed is at most {:.3} m/s)",
            error.limit as f32 / 1000.0
        ),
        5 => format!("speed ({par})"),
        6 => format!("sonar range (--sonar-range {})", robot.sonar_range_m),
        7 => format!("time limit (--time-limit {})", args.mission.time_limit_s()),
        11 => format!("sonar noise (--sonar-noise {})", robot.sonar_noise_std_m),
        14 => format!(
            "beam half-angle (--beam-half-angle {})",
            robot.sonar_beam_half_angle_deg
        ),
        15 => format!(
            "incidence limit (--incidence-limit {})",
            robot.sonar_incidence_limit_deg
        ),
        21 => format!(
            "missed-echo probability (--sonar-dropout {})",
            robot.sonar_dropout_probability
        ),
        22 => format!(
            "spurious-echo probability (--sonar-spurious {})",
            robot.sonar_spurious_probability
        ),
        12 => format!("link timeout (--link-timeout-ms {})", args.link_timeout_ms),
        100 => format!(
            "planning radius ({par}; at most the sonar range minus {} m)",
            twil_core::limits::MIN_PREFIX_M
        ),
        v if v >= 100 => format!("robot configuration field {} (see the device log)", v - 100),
        v => format!("field {v}"),
    };
    format!("the device refused the mission: its {field} is not a valid value")
}
