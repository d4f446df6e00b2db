//! Mission tests: whole missions against the plant, and inputs that must change nothing.
extern crate std;
use std::boxed::Box;

use super::*;
use crate::control::Pose;
use crate::geom::PointM;
use crate::grid::GridGeometry;
use crate::math::hypot;
use crate::plan::{PlanError, PlanReport, PlanStatus, PlannerKind};
use crate::plant::Plant;
use crate::robot::RobotConfig;
use crate::sonar::{SweepKind, SweepPlan};
use crate::world::{Obstacles, Params};

fn square(x0: f32, y0: f32, x1: f32, y1: f32) -> [PointM; 4] {
    [
        PointM::new(x0, y0),
        PointM::new(x1, y0),
        PointM::new(x1, y1),
        PointM::new(x0, y1),
    ]
}

fn config(start: PointM, goal: PointM, mode: MissionMode) -> MissionConfig {
    let params = Params {
        robot_radius_m: 0.4,
        speed_m_s: 0.2,
        initial_heading_deg: 0.0,
        start,
        goal,
    };
    let mut c = MissionConfig::from_params(&params, RobotConfig::default());
    c.mode = mode;
    c
}

/// Drive a mission against the plant until it ends, plans handed back at once; returns the
/// status and the smallest clearance.
fn run(mission: &mut Mission300, real: &Obstacles, plant: &mut Plant) -> (MissionStatus, f32) {
    run_with_latency(mission, real, plant, 0)
}

/// [`run`] with each plan handed back `latency_ticks` controller periods after its request.
fn run_with_latency(
    mission: &mut Mission300,
    real: &Obstacles,
    plant: &mut Plant,
    latency_ticks: u64,
) -> (MissionStatus, f32) {
    let mut planner = Box::new(MissionPlanner300::new());
    let period = mission.config().robot.controller_period_s;
    let range = mission.config().robot.sonar_range_m;
    let mut runner = LocalRunner::new(mission, &mut planner, latency_ticks);
    let mut previous = plant.encoder_counts();
    let mut min_clearance = f32::INFINITY;
    for _ in 0..200_000u64 {
        let counts = plant.encoder_counts();
        let outcome = runner.tick(
            counts.0 - previous.0,
            counts.1 - previous.1,
            period,
            &mut |angle| plant.sonar_range_m(real, angle, range),
        );
        previous = counts;
        if outcome.status != MissionStatus::Running {
            return (outcome.status, min_clearance);
        }
        plant.step(period, outcome.left_voltage_v, outcome.right_voltage_v);
        min_clearance = min_clearance.min(plant.clearance_m(real));
    }
    (runner.mission().status(), min_clearance)
}

/// One period of a robot whose wheels never turn: the pilot ticks with no counts, the
/// mission steps with its report, the pilot takes the mission's command.
fn tick_still(mission: &mut Mission300, pilot: &mut Pilot) -> MissionOutput {
    let report = pilot.tick(0, 0, 0.05);
    step(mission, pilot, MissionInput::Tick(report))
}

/// A mission step whose command the pilot carries out.
fn step(mission: &mut Mission300, pilot: &mut Pilot, input: MissionInput) -> MissionOutput {
    let out = mission.step(input);
    if let Some(command) = out.pilot_command {
        let _ = pilot.command(command, mission.prefix());
    }
    out
}

pub(super) fn geometry() -> GridGeometry {
    GridGeometry::from_size_m(8.0, 8.0, 0.05).unwrap()
}

fn room_with_block() -> Obstacles {
    let mut o = Obstacles::new();
    o.push(&square(0.0, 0.0, 8.0, 0.1)).unwrap();
    o.push(&square(0.0, 7.9, 8.0, 8.0)).unwrap();
    o.push(&square(0.0, 0.0, 0.1, 8.0)).unwrap();
    o.push(&square(7.9, 0.0, 8.0, 8.0)).unwrap();
    o.push(&square(3.5, 1.5, 4.0, 6.5)).unwrap();
    o
}

#[test]
fn reaches_the_goal_around_an_unknown_block_in_both_modes() {
    let real = room_with_block();
    for mode in [MissionMode::Stop, MissionMode::Continuous] {
        let start = PointM::new(1.5, 4.0);
        let goal = PointM::new(6.5, 4.0);
        let c = config(start, goal, mode);
        let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
        let mut plant = Plant::new(&c.robot, Pose::new(start.x_m, start.y_m, 0.0));
        let (status, clearance) = run(&mut mission, &real, &mut plant);
        assert_eq!(status, MissionStatus::Reached, "{mode:?}");
        assert!(clearance > 0.0, "{mode:?}: clearance {clearance}");
        let p = plant.pose();
        assert!(
            hypot(p.x_m - goal.x_m, p.y_m - goal.y_m) < 0.25,
            "{mode:?}: ended at {p:?}"
        );
        let s = mission.stats();
        assert!(s.stops >= 1 && s.plans >= 2 && s.hits > 0, "{s:?}");
    }
}

#[test]
fn a_goal_inside_a_known_box_is_unreachable_after_the_first_sweep() {
    let real = room_with_block();
    let start = PointM::new(1.5, 4.0);
    let goal = PointM::new(6.0, 4.0);
    let c = config(start, goal, MissionMode::Stop);
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    for wall in [
        square(5.0, 3.0, 7.0, 3.1),
        square(5.0, 4.9, 7.0, 5.0),
        square(5.0, 3.0, 5.1, 5.0),
        square(6.9, 3.0, 7.0, 5.0),
    ] {
        mission.add_known_polygon(&wall);
    }
    let mut plant = Plant::new(&c.robot, Pose::new(start.x_m, start.y_m, 0.0));
    let (status, _) = run(&mut mission, &real, &mut plant);
    assert_eq!(status, MissionStatus::Unreachable);
    let s = mission.stats();
    assert_eq!(s.stops, 1);
    assert!(matches!(
        s.unreachable_reason,
        Some(UnreachableReason::NoPath | UnreachableReason::GoalBlocked)
    ));
}

#[test]
fn the_time_limit_ends_the_mission() {
    let real = room_with_block();
    let start = PointM::new(1.5, 4.0);
    let mut c = config(start, PointM::new(6.5, 4.0), MissionMode::Stop);
    c.time_limit_s = 2.0;
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    let mut plant = Plant::new(&c.robot, Pose::new(start.x_m, start.y_m, 0.0));
    let (status, _) = run(&mut mission, &real, &mut plant);
    assert_eq!(status, MissionStatus::Timeout);
    assert!(mission.stats().time_s >= 2.0 && mission.stats().time_s < 2.2);
}

#[test]
fn abort_stops_the_motors_and_ignores_later_inputs() {
    let c = config(
        PointM::new(1.5, 4.0),
        PointM::new(6.5, 4.0),
        MissionMode::Stop,
    );
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    let out = mission.step(MissionInput::Abort);
    assert_eq!(out.status, MissionStatus::Aborted);
    assert!(out
        .events
        .contains(&MissionEvent::Finished(MissionStatus::Aborted)));
    assert_eq!(out.pilot_command, Some(PilotCommand::Stop));
    let mut pilot = Pilot::new(&c);
    pilot.command(PilotCommand::Stop, &[]).unwrap();
    let report = pilot.tick(1000, -1000, 0.05);
    assert_eq!((report.left_voltage_v, report.right_voltage_v), (0.0, 0.0));
    let out = step(&mut mission, &mut pilot, MissionInput::Tick(report));
    assert_eq!(out.pilot_command, Some(PilotCommand::Stop));
    assert_eq!(pilot.voltages_v(), (0.0, 0.0));
    assert_eq!(out.sonar_request, None);
    assert_eq!(mission.phase(), MissionPhase::Done);
}

#[test]
fn readings_nobody_asked_for_and_nonsense_values_change_nothing() {
    let c = config(
        PointM::new(1.5, 4.0),
        PointM::new(6.5, 4.0),
        MissionMode::Stop,
    );
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    let before = mission.grid().count_occupied();
    let out = mission.step(MissionInput::SonarReading {
        neck_angle_rad: 0.0,
        range_m: Some(1.0),
    });
    assert!(out.events.is_empty());
    assert_eq!(mission.grid().count_occupied(), before);
    assert_eq!(mission.stats().readings, 0);
    // A requested reading with NaN/inf values: counted, nothing marked, no panic.
    let mut pilot = Pilot::new(&c);
    let report = pilot.tick(0, 0, f32::NAN);
    let out = step(&mut mission, &mut pilot, MissionInput::Tick(report));
    assert!(out.sonar_request.is_some());
    mission.step(MissionInput::SonarReading {
        neck_angle_rad: f32::NAN,
        range_m: Some(f32::INFINITY),
    });
    assert_eq!(mission.stats().readings, 1);
    assert_eq!(mission.grid().count_occupied(), before);
}

#[test]
fn bad_configs_are_errors_naming_the_field() {
    let mut c = config(
        PointM::new(1.5, 4.0),
        PointM::new(6.5, 4.0),
        MissionMode::Stop,
    );
    c.speed_m_s = f32::NAN;
    assert!(matches!(
        Mission300::new(c, geometry()),
        Err(MissionError::BadValue {
            field: "speed_m_s",
            ..
        })
    ));
    let c = config(
        PointM::new(1.5, 4.0),
        PointM::new(9.5, 4.0),
        MissionMode::Stop,
    );
    assert!(matches!(
        Mission300::new(c, geometry()),
        Err(MissionError::OffMap { which: "goal" })
    ));
    let big = GridGeometry::new(400, 400, 0.05).unwrap();
    let c = config(
        PointM::new(1.5, 4.0),
        PointM::new(6.5, 4.0),
        MissionMode::Stop,
    );
    assert!(matches!(
        Mission300::new(c, big),
        Err(MissionError::Grid(_))
    ));
}

#[test]
fn a_sweep_asks_for_the_seed_angles_at_the_echo_rate() {
    let c = config(
        PointM::new(1.5, 4.0),
        PointM::new(6.5, 4.0),
        MissionMode::Stop,
    );
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    let mut pilot = Pilot::new(&c);
    let mut angles = std::vec::Vec::new();
    let mut ticks = 0;
    while mission.stats().plans == 0 && ticks < 1000 {
        ticks += 1;
        let mut out = tick_still(&mut mission, &mut pilot);
        while let Some(r) = out.sonar_request {
            angles.push(r.neck_angle_rad);
            out = step(
                &mut mission,
                &mut pilot,
                MissionInput::SonarReading {
                    neck_angle_rad: r.neck_angle_rad,
                    range_m: None,
                },
            );
        }
    }
    // ±95° at 1.8°: 52 steps each side, 105 readings from -93.6° to +93.6°.
    assert_eq!(angles.len(), 105);
    assert!((angles[0].to_degrees() + 93.6).abs() < 1e-3);
    assert!((angles[104].to_degrees() - 93.6).abs() < 1e-3);
    // 36 ms per reading: 105 readings take 3.78 s = 76 periods of 50 ms.
    assert!((75..=77).contains(&ticks), "{ticks}");
}

#[test]
fn the_mcu_sized_mission_crosses_the_bundled_worlds() {
    for (da, par) in [
        (
            include_str!("../../../worlds/office.da"),
            include_str!("../../../worlds/office.par"),
        ),
        (
            include_str!("../../../worlds/pillars.da"),
            include_str!("../../../worlds/pillars.par"),
        ),
        (
            include_str!("../../../worlds/corridor.da"),
            include_str!("../../../worlds/corridor.par"),
        ),
    ] {
        mcu_sized_mission_reaches(da, par);
    }
}

fn mcu_sized_mission_reaches(da: &str, par: &str) {
    let mut real = Obstacles::new();
    crate::world::parse_da(da, &mut real).unwrap();
    let params = crate::world::parse_par(par).unwrap();
    // Plans handed back at once, and one control period later (the MCU's latency).
    for (mode, latency_ticks) in [
        (MissionMode::Stop, 0),
        (MissionMode::Continuous, 0),
        (MissionMode::Stop, 1),
        (MissionMode::Continuous, 1),
    ] {
        let mut c = MissionConfig::from_params(&params, RobotConfig::default());
        c.planner = PlannerKind::AStar;
        c.mode = mode;
        let mut mission = Box::new(Mission300::new(c, GridGeometry::seed_default()).unwrap());
        let mut plant = Plant::new(
            &c.robot,
            Pose::new(params.start.x_m, params.start.y_m, c.initial_heading_rad),
        );
        let (status, clearance) = run_with_latency(&mut mission, &real, &mut plant, latency_ticks);
        assert_eq!(
            status,
            MissionStatus::Reached,
            "{mode:?} latency {latency_ticks}: {:?}",
            mission.stats()
        );
        assert!(clearance > 0.0, "{mode:?} latency {latency_ticks}");
        assert_eq!(mission.stats().plan_errors, 0);
    }
}

/// Tick with no motion until the mission asks for a plan; answers every sonar request with
/// `range_m`. Returns the request and the ticks it took.
fn tick_until_plan_request(
    mission: &mut Mission300,
    pilot: &mut Pilot,
    range_m: Option<f32>,
) -> (PlanRequest, u32) {
    for ticks in 1..10_000 {
        let mut out = tick_still(mission, pilot);
        loop {
            if let Some(r) = out.plan_request {
                return (r, ticks);
            }
            let Some(s) = out.sonar_request else { break };
            out = step(
                mission,
                pilot,
                MissionInput::SonarReading {
                    neck_angle_rad: s.neck_angle_rad,
                    range_m,
                },
            );
        }
    }
    panic!("no plan request: {:?}", mission.stats());
}

#[test]
fn the_robot_holds_while_the_planner_runs_and_stale_results_are_ignored() {
    let c = config(
        PointM::new(1.5, 4.0),
        PointM::new(6.5, 4.0),
        MissionMode::Stop,
    );
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    let mut pilot = Pilot::new(&c);
    // A result before any request changes nothing.
    let stray = MissionInput::PlanDone {
        id: 1,
        result: Err(PlanError::QueueFull { capacity: 1 }),
    };
    assert!(step(&mut mission, &mut pilot, stray).events.is_empty());
    assert_eq!(mission.stats().plan_errors, 0);

    let (request, _) = tick_until_plan_request(&mut mission, &mut pilot, None);
    assert_eq!(mission.phase(), MissionPhase::Plan);
    assert!(mission.plan_pending());
    assert_eq!(request.goal, c.goal);
    // Ten periods without the result: the controller keeps stepping (holding), nothing else
    // is asked, the phase stays.
    for _ in 0..10 {
        let out = tick_still(&mut mission, &mut pilot);
        assert_eq!(out.sonar_request, None);
        assert_eq!(out.plan_request, None);
        assert_eq!(mission.phase(), MissionPhase::Plan);
    }
    // A result for another id is ignored; the right one is applied.
    let wrong = MissionInput::PlanDone {
        id: request.id.wrapping_add(1),
        result: Err(PlanError::QueueFull { capacity: 1 }),
    };
    step(&mut mission, &mut pilot, wrong);
    assert!(mission.plan_pending());
    assert_eq!(mission.stats().plan_errors, 0);
    let mut planner = Box::new(MissionPlanner300::new());
    let (grid, path) = mission.plan_workspace();
    let result = planner.plan(request.kind, grid, request.start, request.goal, path);
    let out = step(
        &mut mission,
        &mut pilot,
        MissionInput::PlanDone {
            id: request.id,
            result,
        },
    );
    assert!(
        out.events.iter().any(|e| matches!(
            e,
            MissionEvent::Planned {
                status: PlanStatus::Found,
                ..
            }
        )),
        "{:?}",
        out.events
    );
    // Follow, or first a full sweep: after a ±95° sweep the space beside the start, within
    // the planning radius of the path, is unseen (see `corridor`).
    assert!(
        matches!(
            mission.phase(),
            MissionPhase::Follow | MissionPhase::Sweep { full: true }
        ),
        "{:?}",
        mission.phase()
    );
    assert!(!mission.plan_pending());
    // Answering the same id twice does nothing more.
    let again = step(
        &mut mission,
        &mut pilot,
        MissionInput::PlanDone {
            id: request.id,
            result,
        },
    );
    assert!(again.events.is_empty());
}

#[test]
fn a_sweep_that_ends_while_the_planner_runs_is_marked_after_the_result() {
    // Continuous mode, a wall 1 m ahead: the first (standing) sweep asks for a plan; the
    // result comes back only after the first moving sweep has ended.
    let c = config(
        PointM::new(1.5, 4.0),
        PointM::new(6.5, 4.0),
        MissionMode::Continuous,
    );
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    let mut pilot = Pilot::new(&c);
    let (request, _) = tick_until_plan_request(&mut mission, &mut pilot, None);
    let mut planner = Box::new(MissionPlanner300::new());
    let (grid, path) = mission.plan_workspace();
    let result = planner.plan(request.kind, grid, request.start, request.goal, path);
    step(
        &mut mission,
        &mut pilot,
        MissionInput::PlanDone {
            id: request.id,
            result,
        },
    );
    if mission.phase() == (MissionPhase::Sweep { full: true }) {
        // The space beside the start is unseen after the ±95° sweep: a full sweep first.
        let (request, _) = tick_until_plan_request(&mut mission, &mut pilot, None);
        let (grid, path) = mission.plan_workspace();
        let result = planner.plan(request.kind, grid, request.start, request.goal, path);
        step(
            &mut mission,
            &mut pilot,
            MissionInput::PlanDone {
                id: request.id,
                result,
            },
        );
    }
    assert_eq!(mission.phase(), MissionPhase::Follow);
    // The first moving sweep (hits at 1 m) ends with a replan request; hold its result back.
    let (request, _) = tick_until_plan_request(&mut mission, &mut pilot, Some(1.0));
    let occupied = mission.grid().count_occupied();
    assert!(occupied > 0, "the moving sweep's hits are marked");
    let hits_before = mission.stats().hits;
    // A whole second sweep goes by: it ends, but nothing is marked while the plan is out.
    let mut readings = 0;
    for _ in 0..400 {
        let mut out = tick_still(&mut mission, &mut pilot);
        assert_eq!(out.plan_request, None);
        while let Some(s) = out.sonar_request {
            readings += 1;
            out = step(
                &mut mission,
                &mut pilot,
                MissionInput::SonarReading {
                    neck_angle_rad: s.neck_angle_rad,
                    range_m: Some(1.2),
                },
            );
            assert_eq!(out.plan_request, None);
        }
    }
    assert!(readings >= 105, "{readings}");
    assert_eq!(mission.grid().count_occupied(), occupied);
    assert_eq!(mission.stats().hits, hits_before);
    // The result comes back: the deferred sweep is marked.
    let (grid, path) = mission.plan_workspace();
    let result = planner.plan(request.kind, grid, request.start, request.goal, path);
    step(
        &mut mission,
        &mut pilot,
        MissionInput::PlanDone {
            id: request.id,
            result,
        },
    );
    assert!(mission.stats().hits > hits_before);
    assert!(mission.grid().count_occupied() > occupied);
}

#[test]
fn mission_sizes_fit_their_targets() {
    // Documented in docs/simulate.md.
    std::println!(
        "Mission300 {} B, Mission400 {} B",
        Mission300::SIZE_BYTES,
        Mission400::SIZE_BYTES
    );
    // The MCU's mission lives in the 64 KiB CCM (the planner takes the main SRAM).
    const { assert!(Mission300::SIZE_BYTES <= 64 * 1024) };
    const { assert!(Mission300::SIZE_BYTES < Mission400::SIZE_BYTES) };
}

mod props {
    use super::*;
    use proptest::prelude::*;

    fn any_f32() -> impl Strategy<Value = f32> {
        prop_oneof![
            -10.0f32..10.0,
            Just(f32::NAN),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            Just(0.0f32),
        ]
    }

    /// A tick of the pilot (whose report goes to the mission) or a mission input.
    #[derive(Clone, Debug)]
    enum Input {
        Tick {
            left: i32,
            right: i32,
            elapsed_s: f32,
        },
        Mission(MissionInput),
    }

    fn any_input() -> impl Strategy<Value = Input> {
        prop_oneof![
            8 => (-5000i32..5000, -5000i32..5000, any_f32()).prop_map(|(l, r, e)| {
                Input::Tick { left: l, right: r, elapsed_s: e }
            }),
            8 => (any_f32(), prop::option::of(any_f32())).prop_map(|(a, r)| {
                Input::Mission(MissionInput::SonarReading {
                    neck_angle_rad: a,
                    range_m: r,
                })
            }),
            2 => (0u32..4, prop::bool::ANY).prop_map(|(id, ok)| Input::Mission(MissionInput::PlanDone {
                id,
                result: if ok {
                    Ok(PlanReport {
                        status: PlanStatus::Found,
                        expanded: 1,
                        cost: 1,
                        length_m: 1.0,
                    })
                } else {
                    Err(PlanError::QueueFull { capacity: 8 })
                },
            })),
            1 => Just(Input::Mission(MissionInput::Interrupt)),
            1 => Just(Input::Mission(MissionInput::Abort)),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]
        /// Any sequence of inputs, however absurd: no panic, voltages within the
        /// saturation, and once ended the mission stays ended with the motors off.
        #[test]
        fn nonsense_inputs_never_panic(inputs in prop::collection::vec(any_input(), 1..400)) {
            let c = config(PointM::new(1.5, 4.0), PointM::new(6.5, 4.0), MissionMode::Continuous);
            let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
            let mut pilot = Pilot::new(&c);
            let max_v = c.robot.max_voltage_v;
            let mut ended = false;
            for input in inputs {
                let out = match input {
                    Input::Tick { left, right, elapsed_s } => {
                        let report = pilot.tick(left, right, elapsed_s);
                        prop_assert!(report.left_voltage_v.abs() <= max_v + 1e-4);
                        prop_assert!(report.right_voltage_v.abs() <= max_v + 1e-4);
                        if ended {
                            prop_assert_eq!((report.left_voltage_v, report.right_voltage_v), (0.0, 0.0));
                        }
                        step(&mut mission, &mut pilot, MissionInput::Tick(report))
                    }
                    Input::Mission(input) => step(&mut mission, &mut pilot, input),
                };
                let (left, right) = pilot.voltages_v();
                prop_assert!(left.abs() <= max_v + 1e-4 && right.abs() <= max_v + 1e-4);
                if ended {
                    prop_assert!(out.status != MissionStatus::Running);
                    prop_assert_eq!(out.pilot_command, Some(PilotCommand::Stop));
                    prop_assert_eq!((left, right), (0.0, 0.0));
                }
                ended |= out.status != MissionStatus::Running;
            }
        }
    }
}

#[test]
fn a_restarted_mission_runs_like_a_new_one_and_a_bad_restart_changes_nothing() {
    let real = room_with_block();
    let start = PointM::new(1.5, 4.0);
    let c = config(start, PointM::new(6.5, 4.0), MissionMode::Stop);
    let mut fresh = Box::new(Mission300::new(c, geometry()).unwrap());
    let mut plant = Plant::new(&c.robot, Pose::new(start.x_m, start.y_m, 0.0));
    let expected = run(&mut fresh, &real, &mut plant);

    // The idle mission ignores everything until it is set up.
    let mut reused = Box::new(Mission300::IDLE);
    assert_eq!(reused.status(), MissionStatus::Aborted);
    assert_eq!(reused.phase(), MissionPhase::Done);
    // A bad setup is refused and leaves it idle.
    let mut bad = c;
    bad.goal = PointM::new(50.0, 4.0);
    assert!(matches!(
        reused.restart(bad, geometry()),
        Err(MissionError::OffMap { which: "goal" })
    ));
    assert_eq!(reused.status(), MissionStatus::Aborted);
    // Twice in a row, each run equals the fresh mission's.
    for _ in 0..2 {
        reused.restart(c, geometry()).unwrap();
        let mut plant = Plant::new(&c.robot, Pose::new(start.x_m, start.y_m, 0.0));
        assert_eq!(run(&mut reused, &real, &mut plant), expected);
        assert_eq!(reused.stats(), fresh.stats());
        assert_eq!(reused.grid(), fresh.grid());
    }
}

/// The phase right after the first plan of a mission standing at `start`, facing
/// `heading_deg`, in an empty 8 × 8 m map whose sweep hears nothing, and whether that plan
/// asked for a full sweep.
fn phase_after_the_first_plan(
    start: PointM,
    heading_deg: f32,
    goal: PointM,
) -> (MissionPhase, bool) {
    let mut c = config(start, goal, MissionMode::Stop);
    c.initial_heading_rad = heading_deg.to_radians();
    let mut mission = Box::new(Mission300::new(c, geometry()).unwrap());
    let mut pilot = Pilot::new(&c);
    let (request, _) = tick_until_plan_request(&mut mission, &mut pilot, None);
    let mut planner = Box::new(MissionPlanner300::new());
    let (grid, path) = mission.plan_workspace();
    let result = planner.plan(request.kind, grid, request.start, request.goal, path);
    let out = step(
        &mut mission,
        &mut pilot,
        MissionInput::PlanDone {
            id: request.id,
            result,
        },
    );
    // The straight path north was kept whole.
    let prefix = mission.prefix();
    assert_eq!(prefix.len(), 2, "{prefix:?}");
    assert!((prefix[1].x_m - goal.x_m).abs() < 1e-4, "{prefix:?}");
    assert!((prefix[1].y_m - goal.y_m).abs() < 1e-4, "{prefix:?}");
    let full = out
        .events
        .iter()
        .any(|e| matches!(e, MissionEvent::FullSweepRequested));
    (mission.phase(), full)
}

#[test]
fn the_band_check_trusts_only_the_bearings_the_sweep_read() {
    // The ±95° sweep's outermost readings are at ±93.6° (52 steps of 1.8°). The robot stands
    // in the map's north-west corner (what lies west and north of the path is off the map, so
    // the body corridor is known) and the straight path goes north, just behind its side.
    let plan = SweepPlan::new(&RobotConfig::default(), SweepKind::Normal);
    assert!((plan.covered_half_angle_rad().to_degrees() - 93.6).abs() < 1e-3);
    let (start, goal) = (PointM::new(0.325, 7.125), PointM::new(0.325, 7.875));
    // 93.4° off the heading: read by the sweep, followed at once.
    assert_eq!(
        phase_after_the_first_plan(start, -3.4, goal),
        (MissionPhase::Follow, false)
    );
    // 93.8° off: inside the nominal ±95° but never read, so a full sweep comes first.
    assert_eq!(
        phase_after_the_first_plan(start, -3.8, goal),
        (MissionPhase::Sweep { full: true }, true)
    );
}

#[test]
fn a_mission_without_its_occupied_plane_refuses_the_evidence_map_and_the_mcu_sized_one_keeps_it() {
    let c = MissionConfig {
        evidence_map: true,
        ..config(
            PointM::new(1.0, 1.0),
            PointM::new(5.0, 5.0),
            MissionMode::Stop,
        )
    };
    // No room for the occupied plane (one word): the option is refused, naming the capacity.
    type NoPlane = Mission<{ crate::grid::words_for_cells(300 * 300) }, 1>;
    match NoPlane::new(c, geometry()) {
        Err(MissionError::Grid(crate::grid::GridError::CapacityExceeded { cells, capacity })) => {
            assert_eq!((cells, capacity), (160 * 160, 32));
        }
        other => panic!("expected a capacity error, got {:?}", other.map(|_| ())),
    }
    let plain = MissionConfig {
        evidence_map: false,
        ..c
    };
    assert!(NoPlane::new(plain, geometry()).is_ok());
    // The MCU's mission (300 × 300) has both planes, like the host's.
    let mcu = Box::new(Mission300::new(c, geometry()).unwrap());
    assert!(mcu.evidence().has_occupied_plane());
    let host = Box::new(Mission400::new(c, geometry()).unwrap());
    assert!(host.evidence().has_occupied_plane());
    // At the start the body's disc is free evidence, nothing is occupied.
    let g = geometry();
    let (x, y) = g.cell_xy_of(PointM::new(1.0, 1.0)).unwrap();
    assert_eq!(host.evidence().get_xy(x, y), CellEvidence::Free);
    assert_eq!(host.evidence().counts().1 + host.evidence().counts().2, 0);
}

#[test]
fn a_gap_visit_that_took_no_mark_back_closes_the_gap_until_no_other_gap_is_left() {
    use super::verdict::VisitedGap;
    let c = MissionConfig {
        evidence_map: true,
        ..config(
            PointM::new(4.0, 1.0),
            PointM::new(4.0, 6.0),
            MissionMode::Stop,
        )
    };
    let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
    // A wall of tentative marks along y = 3 m across the whole map.
    for x in 0..160 {
        m.evidence.observe_arc_xy(x, 60);
    }
    let gap = PointM::new(4.0, 3.025);
    let before = m.tentative_cells_within(gap, 1.0);
    assert_eq!(before, 40, "cell centres 3.025 to 4.975 m on the wall");
    let mut out = no_output(&m);
    let visited = |m: &Mission400| VisitedGap {
        centre: gap,
        reach_m: 1.0,
        tentative_cells: m.tentative_cells_within(gap, 1.0) as u16,
        closed: false,
        stand_off: PointM::new(4.0, 2.0),
        futile: false,
    };
    // A visit that took some marks back leaves its gap open: only confirmed marks are drawn.
    m.visited_gaps.push(visited(&m)).unwrap();
    for x in 78..83 {
        m.evidence.observe_vouched_xy(x, 60);
    }
    m.gap_visits = 1;
    m.seek_proof(&mut out);
    assert!(!m.visited_gaps[0].closed);
    assert!(out.plan_request.is_some(), "the proof plan is asked");
    let at = |m: &Mission400, x_m: f32| {
        let (x, y) = m
            .grid
            .geometry()
            .cell_xy_of(PointM::new(x_m, 3.025))
            .unwrap();
        m.grid.is_occupied_xy(x, y)
    };
    assert!(!at(&m, 3.5) && !at(&m, 1.0));
    // A visit that took none back closes its gap: its marks within the reach are drawn into
    // the proof plan's grid, the others are not.
    m.pending_plan = None;
    m.visited_gaps.clear();
    m.visited_gaps.push(visited(&m)).unwrap();
    m.seek_proof(&mut out);
    assert!(m.visited_gaps[0].closed && m.visited_gaps[0].futile);
    assert!(at(&m, 3.5) && at(&m, 4.9));
    assert!(!at(&m, 1.0) && !at(&m, 7.0));
    // No way with the closed gap drawn in: not a verdict, the gap opens again and the proof
    // is planned once more on the confirmed marks alone.
    m.pending_plan = None;
    out.plan_request = None;
    m.on_proof(PlanStatus::Unreachable, &mut out);
    assert!(!m.visited_gaps[0].closed);
    // Reopened, but its viewpoint stays spent: a later visit of this gap stands elsewhere.
    assert!(m.visited_gaps[0].futile);
    assert!(out.plan_request.is_some(), "the proof plan is asked again");
    assert!(!at(&m, 3.5) && !at(&m, 4.9));
    assert_eq!(m.status, MissionStatus::Running);
    // No way on the confirmed marks alone, no gap closed: that is the proof.
    m.pending_plan = None;
    m.on_proof(PlanStatus::Unreachable, &mut out);
    assert_eq!(m.status, MissionStatus::Unreachable);
    assert_eq!(
        m.stats.unreachable_reason,
        Some(UnreachableReason::ConfirmedCut)
    );
}

/// An output with nothing in it yet, for calling a mission's handlers directly.
fn no_output(m: &Mission400) -> MissionOutput {
    MissionOutput {
        pilot_command: None,
        sonar_request: None,
        plan_request: None,
        events: Vec::new(),
        status: m.status,
    }
}

/// Stop mode with the evidence map and a beam sonar, from (1, 4) to (7, 4).
pub(super) fn beam_evidence_config() -> MissionConfig {
    let mut c = MissionConfig {
        evidence_map: true,
        ..config(
            PointM::new(1.0, 4.0),
            PointM::new(7.0, 4.0),
            MissionMode::Stop,
        )
    };
    c.robot.sonar_beam = true;
    c
}

#[test]
fn a_reflectors_run_survives_a_missed_and_a_spurious_echo_and_a_lone_echo_marks_nothing() {
    use crate::sonar::Reading;
    let mut c = beam_evidence_config();
    let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
    let pose = Pose {
        x_m: 1.0,
        y_m: 4.0,
        heading_rad: 0.0,
    };
    let beam_deg = c.robot.sonar_beam_half_angle_deg;
    m.readings.clear();
    for i in 0..45 {
        let bearing_deg = -39.6 + 1.8 * i as f32;
        // A post straight ahead at 2 m is heard by every reading whose cone holds it; one of
        // them misses it, one hears a spurious echo at 1 m; far off to the right one reading
        // alone hears something at 1.2 m.
        let range_m = match i {
            18 => None,
            24 => Some(1.0),
            5 => Some(1.2),
            _ if bearing_deg.abs() <= beam_deg => Some(2.0),
            _ => None,
        };
        m.readings
            .push(Reading {
                neck_angle_rad: bearing_deg.to_radians(),
                range_m,
                pose,
            })
            .unwrap();
    }
    let marked = m.mark_reflectors();
    let hits: std::vec::Vec<PointM> = m.hits.iter().copied().collect();
    assert_eq!(marked, 1, "{hits:?}");
    let expected_x_m = 1.0 + c.robot.sonar_offset_m + 2.0;
    assert!(
        (hits[0].x_m - expected_x_m).abs() < 0.03 && (hits[0].y_m - 4.0).abs() < 0.03,
        "{hits:?}"
    );
    // Heard through a ray (`sonar_beam` false) the same readings are five reflectors: a
    // ray's echo lies on its axis, and its missed echo is no fault to bridge.
    c.robot.sonar_beam = false;
    let mut ray = Box::new(Mission400::new(c, geometry()).unwrap());
    ray.readings = m.readings.clone();
    assert_eq!(ray.mark_reflectors(), 5);
}

/// A standing sweep of 45 readings (−39.6° to +39.6° in 1.8° steps) from (1, `y_m`) facing
/// east, each reading's range from its bearing; returns the reflectors marked.
pub(super) fn sweep_east_from(
    m: &mut Mission400,
    y_m: f32,
    range_at: impl Fn(f32) -> Option<f32>,
) -> u16 {
    let pose = Pose {
        x_m: 1.0,
        y_m,
        heading_rad: 0.0,
    };
    m.readings.clear();
    for i in 0..45 {
        let bearing_rad = (-39.6f32 + 1.8 * i as f32).to_radians();
        m.readings
            .push(crate::sonar::Reading {
                neck_angle_rad: bearing_rad,
                range_m: range_at(bearing_rad),
                pose,
            })
            .unwrap();
    }
    m.mark_reflectors()
}

#[test]
fn a_plane_heard_from_two_places_confirms_the_second_foot_a_parallel_one_does_not() {
    let c = beam_evidence_config();
    let beam_deg = c.robot.sonar_beam_half_angle_deg;
    let offset_m = c.robot.sonar_offset_m;
    // A standing sweep from (1, y) facing east at a smooth wall `range_m` ahead: the readings
    // whose cone holds the wall's normal hear its foot, the others nothing.
    let sweep = |m: &mut Mission400, y_m: f32, range_m: f32| {
        sweep_east_from(m, y_m, |bearing_rad| {
            (bearing_rad.to_degrees().abs() <= beam_deg + 1.0e-3).then_some(range_m)
        })
    };

    let foot = |y_m: f32, range_m: f32| PointM::new(1.0 + offset_m + range_m, y_m);
    let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
    assert_eq!(sweep(&mut m, 3.0, 1.2), 1);
    assert_eq!(m.evidence.get(foot(3.0, 1.2)), CellEvidence::Tentative);
    // The same wall 1 m further along: the second look agrees with the first plane.
    assert_eq!(sweep(&mut m, 4.0, 1.2), 1);
    assert_eq!(m.evidence.get(foot(4.0, 1.2)), CellEvidence::Confirmed);
    assert_eq!(m.evidence.get(foot(3.0, 1.2)), CellEvidence::Tentative);
    // A wall 0.3 m nearer (within the 1.5 m range), parallel to the first: another plane, left tentative.
    let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
    sweep(&mut m, 3.0, 1.2);
    sweep(&mut m, 4.0, 0.9);
    assert_eq!(m.evidence.get(foot(4.0, 0.9)), CellEvidence::Tentative);
}

#[test]
fn a_wall_heard_diffusely_has_its_foot_marked_and_confirmed_from_a_second_place() {
    let c = beam_evidence_config();
    let beam_rad = c.robot.sonar_beam_half_angle_deg.to_radians();
    let offset_m = c.robot.sonar_offset_m;
    // A wall 1.2 m ahead that echoes at any angle: each reading hears the nearest point of
    // the wall in its cone, at 1.2 m / cos(|bearing| − β) beyond the cone's reach of the foot.
    let sweep = |m: &mut Mission400, y_m: f32| {
        sweep_east_from(m, y_m, |bearing_rad| {
            Some(1.2 / (bearing_rad.abs() - beam_rad).max(0.0).cos())
        })
    };

    let foot = |y_m: f32| PointM::new(1.0 + offset_m + 1.2, y_m);
    let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
    sweep(&mut m, 3.0);
    assert_eq!(m.evidence.get(foot(3.0)), CellEvidence::Tentative);
    sweep(&mut m, 4.0);
    assert_eq!(m.evidence.get(foot(4.0)), CellEvidence::Confirmed);
}

#[test]
fn a_second_sweep_from_the_same_place_makes_no_confirmation_one_from_elsewhere_does() {
    // A post 2 m ahead: a point reflector, a region of constant depth from any viewpoint.
    let c = beam_evidence_config();
    let beam_rad = c.robot.sonar_beam_half_angle_deg.to_radians();
    let offset_m = c.robot.sonar_offset_m;
    let post = PointM::new(1.0 + offset_m + 2.025, 4.025);
    let heard_from = |y_m: f32| {
        let (dx, dy) = (post.x_m - (1.0 + offset_m), post.y_m - y_m);
        let (bearing_rad, range_m) = (dy.atan2(dx), dx.hypot(dy));
        move |b: f32| ((b - bearing_rad).abs() <= beam_rad).then_some(range_m)
    };
    let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
    assert_eq!(sweep_east_from(&mut m, 4.0, heard_from(4.0)), 1);
    assert_eq!(m.evidence.get(post), CellEvidence::Tentative);
    // The same readings again from the same place (a moving sweep that ended where the
    // standing sweep then stood): the same cell, and no second viewpoint.
    assert_eq!(sweep_east_from(&mut m, 4.0, heard_from(4.0)), 1);
    assert_eq!(m.evidence.get(post), CellEvidence::Tentative);
    // From 0.3 m to the side: a second viewpoint agrees.
    assert_eq!(sweep_east_from(&mut m, 4.3, heard_from(4.3)), 1);
    assert_eq!(
        m.evidence.get(post),
        CellEvidence::Confirmed,
        "{:?} {:?}",
        m.hits,
        post
    );
}

#[test]
fn a_beams_sweep_takes_a_mark_back_exact_rays_never_do() {
    use crate::sonar::Reading;
    // A tentative mark about 1 m ahead of the sonar, and full standing sweeps from the start.
    let sweep = |c: MissionConfig, echo_beyond_centre_m: Option<f32>| {
        let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
        let pose = m.pose_world();
        let sonar = pose.point_ahead(c.robot.sonar_offset_m);
        let (x, y) = m
            .grid
            .geometry()
            .cell_xy_of(PointM::new(sonar.x_m + 1.0, sonar.y_m))
            .unwrap();
        m.evidence.observe_arc_xy(x, y);
        assert_eq!(m.evidence.get_xy(x, y), CellEvidence::Tentative);
        let centre = super::evidence_marking::centre(m.grid.geometry(), x, y);
        let d_m = (centre.x_m - sonar.x_m).hypot(centre.y_m - sonar.y_m);
        let beam_rad = c.robot.sonar_beam_half_angle_deg.to_radians();
        m.readings.clear();
        for i in 0..201 {
            let bearing_rad = (-180.0f32 + 1.8 * i as f32).to_radians();
            let range_m = echo_beyond_centre_m
                .filter(|_| bearing_rad.abs() <= beam_rad)
                .map(|e| d_m + e);
            m.readings
                .push(Reading {
                    neck_angle_rad: bearing_rad,
                    range_m,
                    pose,
                })
                .unwrap();
        }
        m.mark_vouched_free(true);
        m.evidence.get_xy(x, y)
    };
    let beam = beam_evidence_config();
    // Silence all round (every bearing read): the cell is free, its mark goes.
    assert_eq!(sweep(beam, None), CellEvidence::Free);
    // An echo on the cell's bearing: vouched for when a cell short of it, not otherwise.
    assert_eq!(sweep(beam, Some(0.30)), CellEvidence::Free);
    assert_eq!(sweep(beam, Some(0.03)), CellEvidence::Tentative);
    // Exact rays 1.8° apart can slip past a wall's end seen edge-on: they take no mark back.
    let mut ray = beam;
    ray.robot.sonar_beam = false;
    assert_eq!(sweep(ray, None), CellEvidence::Tentative);
}
