//! Safe mission parameters (`twil_core::limits`): every speed and radius the `.par` check
//! accepts gives a mission without collision on the bundled worlds, in both modes and at
//! every sonar range; values beyond the bounds are refused naming the file, line and bound.
//!
//! The simulations go through `setup_from_args`, so each one also proves the check accepted
//! its values. About 30 missions of up to 900 simulated seconds each.

use crate::common;

use std::path::Path;

use clap::Parser;
use proptest::prelude::*;
use twil_core::robot::RobotConfig;
use twil_host::cmd::simulate::{setup_from_args, Args};
use twil_host::sim::{self, NoProgress, SimResult, SimStatus};

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: Args,
}

/// The bundled worlds a robot can cross, and the enclosed one (ends unreachable).
const WORLDS: [&str; 4] = ["office", "corridor", "pillars", "enclosed"];

/// Write `world`'s `.par` with another radius and speed into `dir`.
fn par_with(dir: &Path, world: &str, radius_m: f32, speed_m_s: f32) -> String {
    let text = std::fs::read_to_string(common::world(&format!("{world}.par"))).unwrap();
    let tokens: Vec<&str> = text.split_whitespace().collect();
    assert_eq!(tokens.len(), 7, "{world}.par");
    let path = dir.join(format!("{world}-{radius_m}-{speed_m_s}.par"));
    let body = format!(
        "{radius_m}\n{speed_m_s}\n{}\n{} {}\n{} {}\n",
        tokens[2], tokens[3], tokens[4], tokens[5], tokens[6]
    );
    std::fs::write(&path, body).unwrap();
    path.display().to_string()
}

fn simulate(world: &str, par: &str, mode: &str, sonar_range_m: f32) -> SimResult {
    let da = common::world(&format!("{world}.da")).display().to_string();
    let range = sonar_range_m.to_string();
    let argv = [
        "twil",
        "--real",
        &da,
        "--params",
        par,
        "--mode",
        mode,
        "--sonar-range",
        &range,
    ];
    let args = Cli::parse_from(argv).args;
    let setup = setup_from_args(&args).expect("the check accepts the value");
    sim::run(&setup, &mut NoProgress).expect("simulation")
}

fn assert_safe(r: &SimResult, what: &str) {
    assert_ne!(r.status, SimStatus::Collision, "{what}: {:?}", r.stats);
    assert!(
        r.min_clearance_m > 0.0,
        "{what}: clearance {}",
        r.min_clearance_m
    );
}

fn robot(sonar_range_m: f32) -> RobotConfig {
    RobotConfig {
        sonar_range_m,
        ..RobotConfig::DEFAULT
    }
}

/// The fastest accepted speed, every world and mode, at the seed's sonar range and at 6 m.
#[test]
fn the_safe_speed_bound_itself_never_collides() {
    let dir = tempfile::tempdir().unwrap();
    let v = RobotConfig::DEFAULT.max_safe_speed_m_s();
    for world in WORLDS {
        let par = par_with(dir.path(), world, world_radius_m(world), v);
        for mode in ["stop", "continuous"] {
            for range in [1.5, 6.0] {
                let r = simulate(world, &par, mode, range);
                let what = format!("{world} {mode} {range} m at {v} m/s");
                assert_safe(&r, &what);
                // At 6 m the beam (without the filter, ours) draws arcs up to 3 m wide that
                // can close the office's doorways: unreachable, never a collision
                // (docs/simulate.md, Known limits).
                if world != "enclosed" && range < 6.0 {
                    assert_eq!(r.status, SimStatus::Reached, "{what}: {:?}", r.stats);
                }
            }
        }
    }
}

fn world_radius_m(world: &str) -> f32 {
    if world == "pillars" {
        0.35
    } else {
        0.4
    }
}

proptest! {
    // A fixed seed: CI runs the same cases every time (a new finding is a bug to fix, not a
    // flaky run); `PROPTEST_RNG_SEED` does not override it, edit the seed to explore.
    #![proptest_config(ProptestConfig {
        cases: 200,
        failure_persistence: None,
        rng_seed: proptest::test_runner::RngSeed::Fixed(3),
        ..ProptestConfig::default()
    })]

    /// Any accepted speed, any world, mode and sonar range up to 3 m (the worlds' own radii):
    /// no collision. (Beyond 3 m the single-ray sonar leaves a known gap: docs/simulate.md.)
    #[test]
    fn accepted_speeds_never_collide(
        world in 0..WORLDS.len(),
        continuous in any::<bool>(),
        range_m in prop::sample::select(vec![1.5f32, 2.0, 2.5, 3.0]),
        speed_fraction in 0.05f32..=1.0,
    ) {
        let speed = speed_fraction * robot(range_m).max_safe_speed_m_s();
        let radius = world_radius_m(WORLDS[world]);
        let dir = tempfile::tempdir().unwrap();
        let par = par_with(dir.path(), WORLDS[world], radius, speed);
        let mode = if continuous { "continuous" } else { "stop" };
        let r = simulate(WORLDS[world], &par, mode, range_m);
        let what = format!("{} {mode} {range_m} m, {speed} m/s", WORLDS[world]);
        prop_assert_ne!(r.status, SimStatus::Collision, "{}: {:?}", what, r.stats);
        prop_assert!(r.min_clearance_m > 0.0, "{}: clearance {}", what, r.min_clearance_m);
    }

    /// Any accepted radius and speed with the seed's 1.5 m sonar: no collision. (Longer ranges
    /// with radii near the lower bound are a known gap: see docs/simulate.md.)
    #[test]
    fn accepted_radii_never_collide_with_the_seed_sonar(
        world in 0..WORLDS.len(),
        continuous in any::<bool>(),
        speed_fraction in 0.05f32..=1.0,
        radius_fraction in 0.0f32..=1.0,
    ) {
        let robot = robot(1.5);
        let speed = speed_fraction * robot.max_safe_speed_m_s();
        let (r_min, r_max) = (robot.min_safe_planning_radius_m(), robot.max_safe_planning_radius_m());
        let radius = r_min + radius_fraction * (r_max - r_min);
        let dir = tempfile::tempdir().unwrap();
        let par = par_with(dir.path(), WORLDS[world], radius, speed);
        let mode = if continuous { "continuous" } else { "stop" };
        let r = simulate(WORLDS[world], &par, mode, 1.5);
        let what = format!("{} {mode}, radius {radius} m, {speed} m/s", WORLDS[world]);
        prop_assert_ne!(r.status, SimStatus::Collision, "{}: {:?}", what, r.stats);
        prop_assert!(r.min_clearance_m > 0.0, "{}: clearance {}", what, r.min_clearance_m);
    }
}

#[test]
fn speeds_and_radii_beyond_the_bounds_are_refused_naming_file_line_and_bound() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        // (radius, speed, sonar range, line, field, value)
        ("0.4", "0.5", "1.5", 2, "speed", "0.5"),
        ("0.4", "10", "6", 2, "speed", "10"),
        ("0.2", "0.2", "1.5", 1, "robot radius", "0.2"),
        ("1.3", "0.2", "1.5", 1, "robot radius", "1.3"),
    ];
    for (radius, speed, range, line, field, value) in cases {
        let par = dir.path().join(format!("p-{radius}-{speed}.par"));
        std::fs::write(&par, format!("{radius}\n{speed}\n90\n1.5 1.5\n13.5 13\n")).unwrap();
        for command in ["simulate", "mission"] {
            let mut cmd = common::twil();
            cmd.args([
                command,
                "--real",
                &common::world("office.da").display().to_string(),
            ]);
            if command == "mission" {
                cmd.args(["--remote", "sim"]);
            }
            let out = cmd
                .args([
                    "--params",
                    &par.display().to_string(),
                    "--sonar-range",
                    range,
                ])
                .arg("--json")
                .output()
                .unwrap();
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(
                out.status.code(),
                Some(1),
                "{command} {radius} {speed}: {stderr}"
            );
            let expected = format!(
                "{}: line {line}: field `{field}`: `{value}` is out of range",
                par.display()
            );
            assert!(stderr.contains(&expected), "{command}: {stderr}");
            let bound = if field == "speed" {
                "0.364 m/s"
            } else {
                "0.31 to 1.1 m"
            };
            assert!(stderr.contains(bound), "{command}: {stderr}");
            assert!(out.stdout.is_empty(), "{command}: nothing on stdout");
        }
    }
    // With a 3 m sonar a 1.3 m radius is fine.
    let par = dir.path().join("wide.par");
    std::fs::write(&par, "1.3\n0.2\n90\n1.5 1.5\n13.5 13\n").unwrap();
    let args = Cli::parse_from([
        "twil",
        "--real",
        &common::world("office.da").display().to_string(),
        "--params",
        &par.display().to_string(),
        "--sonar-range",
        "3",
    ])
    .args;
    assert!(setup_from_args(&args).is_ok());
}

/// The measured collision rate behind docs/simulate.md#known-limits: every bundled world, both
/// modes, sonar ranges 1.5-6 m, 31 speeds from 0.05 m/s to the bound, at the worlds' radii
/// (1 488 missions, about 40 s). Prints the counts; fails if they grow past what the docs
/// state (the single-ray sonar's unseen wall ends: issue 13's beam sonar is to close them).
/// `cargo test --release -p twil-host --test suite safe_params::collision_grid -- --nocapture`
#[test]
fn collision_grid() {
    let dir = tempfile::tempdir().unwrap();
    let bound = RobotConfig::DEFAULT.max_safe_speed_m_s();
    let (mut near, mut far) = ((0, 0), (0, 0));
    let mut stops = 0u32;
    for world in WORLDS {
        for mode in ["stop", "continuous"] {
            for range in [1.5f32, 2.0, 2.5, 3.0, 4.5, 6.0] {
                for i in 0..31 {
                    let speed = 0.05 + i as f32 * (bound - 0.05) / 30.0;
                    let par = par_with(dir.path(), world, world_radius_m(world), speed);
                    let r = simulate(world, &par, mode, range);
                    let collided = r.status == SimStatus::Collision;
                    if collided {
                        println!("collision: {world} {mode} {range} m {speed:.4} m/s");
                    }
                    let counts = if range <= 3.0 { &mut near } else { &mut far };
                    counts.0 += 1;
                    counts.1 += u32::from(collided);
                    if world != "enclosed" {
                        stops += r.stats.stops;
                    }
                }
            }
        }
    }
    println!(
        "sonar ≤ 3 m: {} collisions in {} missions; 4.5-6 m: {} in {}; stops on the three \
         crossable worlds: {stops}",
        near.1, near.0, far.1, far.0
    );
    // Beam sonar, filter off (the default since issue 13): 0 and 0 (the single ray had 0 and
    // 21; before the body-corridor fix, 10 and 30).
    assert!(near.1 == 0, "{near:?}");
    assert!(far.1 == 0, "{far:?}");
}
