//! `twil sonar-grid`: missions over a grid of sonar models on generated worlds, counted by how
//! they end against the world's true verdict.
//!
//! ```text
//! twil sonar-grid                 # 12 worlds x 4 ranges x 2 modes x 9 sonars = 864 missions
//! twil sonar-grid --quick --json  # 4 worlds x 2 ranges x stop x 5 sonars = 40 missions
//! twil sonar-grid --out grid --preset seed
//! ```
//!
//! Why: issue 23 (part 5) wants the mission measured, not hoped, on worlds the project does not
//! ship ([`crate::sim::worldgen`]) under a sensor-faithful ranger: beam half-angle 10°–25°,
//! incidence limit from the half-angle (specular) to 90°, the ranger's faults
//! ([`twil_core::plant::faults`]) off and on, sonar range 1.5–6 m, both modes, and the single
//! ray as the yardstick. Each mission is one `twil simulate` run: its options are parsed by
//! `twil simulate`'s own parser and set up by its own function, and the loop options given to
//! the grid (`--preset`, `--planner`, every option of `LoopArgs` and `FollowArgs`) are passed
//! through word for word, so a new loop option works here the day it exists.
//!
//! Measured: see docs/sonar-grid.md (the quick grid in about 40 s on one core).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Parser;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::json;
use twil_core::plant::faults;

use super::args::{FollowArgs, LoopArgs};
use super::simulate;
use crate::sim::{self, worldgen, NoProgress};

/// Arguments of `twil sonar-grid`.
#[derive(clap::Args, Debug, Clone)]
pub struct Args {
    /// The quick slice: 4 worlds, ranges 1.5 and 3 m, stop mode, the ray and 4 beams (40
    /// missions).
    #[arg(long)]
    pub quick: bool,
    /// Worlds generated [default: 12; --quick: 4].
    #[arg(long, value_name = "N")]
    pub worlds: Option<u32>,
    /// Seed of the world generator.
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub world_seed: u64,
    /// Sonar ranges, metres, comma-separated [default: 1.5,3,4,6; --quick: 1.5,3].
    #[arg(long, value_delimiter = ',', value_name = "M,M")]
    pub ranges: Option<Vec<f32>>,
    /// The faulty cells' range noise, metres (a measured HC-SR04's; docs/robot-model.md).
    #[arg(long, default_value_t = faults::MEASURED_NOISE_STD_M, value_name = "M")]
    pub sonar_noise: f32,
    /// The faulty cells' probability of a missed echo.
    #[arg(long, default_value_t = faults::JUDGED.dropout_probability, value_name = "P")]
    pub sonar_dropout: f32,
    /// The faulty cells' probability of a spurious short echo.
    #[arg(long, default_value_t = faults::JUDGED.spurious_probability, value_name = "P")]
    pub sonar_spurious: f32,
    /// Mission time limit of every mission, simulated seconds [default: the preset's].
    #[arg(long, value_name = "S")]
    pub time_limit: Option<f32>,
    /// Missions run at once [default: the machine's cores].
    #[arg(long, value_name = "N")]
    pub jobs: Option<usize>,
    /// Print exactly one JSON object on stdout and nothing else.
    #[arg(long)]
    pub json: bool,
    /// Keep each failing mission's world, summary.json and `twil simulate` command here.
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Loop choices passed to every mission: `--preset`, `--planner`, `--rcd`, `--seed-prune`.
    #[command(flatten)]
    pub loop_args: LoopArgs,
    /// Following choices passed to every mission: `--settle`, `--feed-forward`, ….
    #[command(flatten)]
    pub follow: FollowArgs,
}

/// Beam half-angles of the grid, degrees (issue 23: 10°–25°).
pub const HALF_ANGLES_DEG: [f32; 2] = [10.0, 25.0];
/// Sonar ranges of the full grid, metres (issue 23: 1.5–6 m).
pub const RANGES_M: [f32; 4] = [1.5, 3.0, 4.0, 6.0];
/// Ranges of the quick slice, metres.
pub const QUICK_RANGES_M: [f32; 2] = [1.5, 3.0];

/// One simulated sonar of the grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sonar {
    /// `None`: the single exact ray; else the beam's half-angle and incidence limit, degrees.
    pub beam: Option<(f32, f32)>,
    /// The ranger's faults (noise, dropouts, spurious echoes) on.
    pub faults: bool,
}

impl Sonar {
    /// Its name in the table and the JSON, e.g. `ray`, `beam 10/90`, `beam 25/25 +faults`.
    pub fn label(&self) -> String {
        match self.beam {
            None => "ray".into(),
            Some((h, l)) => format!("beam {h}/{l}{}", if self.faults { " +faults" } else { "" }),
        }
    }
}

/// The sonars of the grid: the ray, then each half-angle with the incidence limit at the
/// half-angle (specular) and at 90°, faults off and on; the quick slice keeps four beams.
pub fn sonars(quick: bool) -> Vec<Sonar> {
    let mut all = vec![Sonar {
        beam: None,
        faults: false,
    }];
    for h in HALF_ANGLES_DEG {
        for l in [h, 90.0] {
            for f in [false, true] {
                // Quick: the specular limit with faults at 10°, without at 25°, and the reverse
                // at 90°: every axis changes within the slice.
                let keep = !quick || ((l == h) == (f == (h == HALF_ANGLES_DEG[0])));
                if keep {
                    all.push(Sonar {
                        beam: Some((h, l)),
                        faults: f,
                    });
                }
            }
        }
    }
    all
}

/// One mission of the grid.
#[derive(Clone, Copy, Debug)]
struct Job {
    world: usize,
    range_m: f32,
    mode: &'static str,
    sonar: Sonar,
}

/// How a mission ended, against the verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Class {
    Reached,
    Collision,
    FalseUnreachable,
    TrueUnreachable,
    GaveUp,
    Timeout,
    /// Anything else (a reached goal the verdict calls unreachable, an aborted run).
    Other,
}

const CLASSES: [(Class, &str); 7] = [
    (Class::Reached, "reached"),
    (Class::Collision, "collision"),
    (Class::FalseUnreachable, "false_unreachable"),
    (Class::TrueUnreachable, "true_unreachable"),
    (Class::GaveUp, "gave_up"),
    (Class::Timeout, "timeout"),
    (Class::Other, "other"),
];

/// What one mission gave.
#[derive(Clone, Debug)]
struct Outcome {
    class: Class,
    status: String,
    stops: u32,
    distance_m: f32,
    sim_time_s: f32,
    plan_length_m: Option<f32>,
    summary: serde_json::Value,
}

/// The words of the loop options in `argv` (the command line after `sonar-grid`): every
/// option `LoopArgs` and `FollowArgs` define, with its value, in the user's order.
pub fn loop_option_words(argv: &[String]) -> Vec<String> {
    let mut command = <LoopArgs as clap::Args>::augment_args(clap::Command::new("loop"));
    command = <FollowArgs as clap::Args>::augment_args(command);
    command.build();
    let mut words = Vec::new();
    let mut i = 0;
    while let Some(word) = argv.get(i) {
        i += 1;
        let Some(name) = word.strip_prefix("--") else {
            continue;
        };
        let (name, inline_value) = match name.split_once('=') {
            Some((n, _)) => (n, true),
            None => (name, false),
        };
        let Some(arg) = command.get_arguments().find(|a| a.get_long() == Some(name)) else {
            continue;
        };
        words.push(word.clone());
        let takes_value = arg.get_num_args().is_some_and(|r| r.min_values() > 0);
        if takes_value && !inline_value {
            if let Some(value) = argv.get(i) {
                words.push(value.clone());
                i += 1;
            }
        }
    }
    words
}

/// `twil simulate`'s parser, for the missions' words.
#[derive(Parser)]
#[command(name = "twil simulate", no_binary_name = true)]
struct SimulateCli {
    #[command(flatten)]
    args: simulate::Args,
}

/// The `twil simulate` words of one mission on the world files `da`, `par`.
fn mission_words(args: &Args, job: &Job, da: &Path, par: &Path, passed: &[String]) -> Vec<String> {
    let mut w: Vec<String> = vec![
        "--real".into(),
        da.display().to_string(),
        "--params".into(),
        par.display().to_string(),
        "--sonar-range".into(),
        job.range_m.to_string(),
        "--mode".into(),
        job.mode.into(),
        "--seed".into(),
        (job.world + 1).to_string(),
    ];
    match job.sonar.beam {
        None => w.extend(["--sonar".into(), "ray".into()]),
        Some((h, l)) => w.extend([
            "--sonar".into(),
            "beam".into(),
            "--beam-half-angle".into(),
            h.to_string(),
            "--incidence-limit".into(),
            l.to_string(),
        ]),
    }
    // Every cell names its faults, on or off: `twil simulate`'s default ranger has them.
    let (noise, dropout, spurious) = if job.sonar.faults {
        (args.sonar_noise, args.sonar_dropout, args.sonar_spurious)
    } else {
        (0.0, 0.0, 0.0)
    };
    w.extend([
        "--sonar-noise".into(),
        noise.to_string(),
        "--sonar-dropout".into(),
        dropout.to_string(),
        "--sonar-spurious".into(),
        spurious.to_string(),
    ]);
    if let Some(s) = args.time_limit {
        w.extend(["--time-limit".into(), s.to_string()]);
    }
    w.extend(passed.iter().cloned());
    w
}

/// Run one mission.
fn run_mission(words: &[String], reachable: bool) -> Result<Outcome> {
    let cli = SimulateCli::try_parse_from(words)
        .map_err(|e| anyhow::anyhow!("{}", e.to_string().trim()))?;
    let setup = simulate::setup_from_args(&cli.args)?;
    let result = sim::run(&setup, &mut NoProgress)?;
    // The word `twil simulate --json` prints (`gave_up` for an `unreachable` without a proof),
    // so that a kept failure's status is what its command prints when run again.
    let status = simulate::mission_end(&cli.args, &setup, &result)
        .word()
        .to_string();
    let cause = simulate::stop_cause(&result);
    let class = if result.min_clearance_m < 0.0 || status == "collision" {
        Class::Collision
    } else {
        match (cause, reachable) {
            ("reached", true) => Class::Reached,
            ("unreachable", true) => Class::FalseUnreachable,
            ("unreachable", false) => Class::TrueUnreachable,
            ("gave_up", _) => Class::GaveUp,
            ("timeout", _) => Class::Timeout,
            _ => Class::Other,
        }
    };
    Ok(Outcome {
        class,
        status,
        stops: result.stats.stops,
        distance_m: result.distance_m,
        sim_time_s: result.sim_time_s,
        plan_length_m: result.known_map_plan_length_m,
        summary: simulate::summary_json(&cli.args, &setup, &result),
    })
}

/// Counts and efficiency of a set of missions.
#[derive(Clone, Debug, Default)]
struct Tally {
    counts: [u32; CLASSES.len()],
    reached_stops: f64,
    reached_ratio: f64,
    reached_ratio_n: u32,
    reached_time_s: f64,
}

impl Tally {
    fn add(&mut self, o: &Outcome) {
        if let Some(i) = CLASSES.iter().position(|(c, _)| *c == o.class) {
            self.counts[i] += 1;
        }
        if o.class == Class::Reached {
            self.reached_stops += f64::from(o.stops);
            self.reached_time_s += f64::from(o.sim_time_s);
            if let Some(plan) = o.plan_length_m.filter(|p| *p > 0.0) {
                self.reached_ratio += f64::from(o.distance_m / plan);
                self.reached_ratio_n += 1;
            }
        }
    }

    fn total(&self) -> u32 {
        self.counts.iter().sum()
    }

    fn count(&self, class: Class) -> u32 {
        CLASSES
            .iter()
            .position(|(c, _)| *c == class)
            .map_or(0, |i| self.counts[i])
    }

    /// Mean stops, distance over the known-map plan, and mission time of the reached missions.
    fn efficiency(&self) -> Option<(f64, f64, f64)> {
        let n = f64::from(self.count(Class::Reached));
        (n > 0.0).then(|| {
            let ratio = if self.reached_ratio_n > 0 {
                self.reached_ratio / f64::from(self.reached_ratio_n)
            } else {
                f64::NAN
            };
            (self.reached_stops / n, ratio, self.reached_time_s / n)
        })
    }

    fn json(&self) -> serde_json::Value {
        let mut v = serde_json::Map::new();
        v.insert("missions".into(), json!(self.total()));
        for (i, (_, name)) in CLASSES.iter().enumerate() {
            v.insert((*name).into(), json!(self.counts[i]));
        }
        if let Some((stops, ratio, time)) = self.efficiency() {
            v.insert("mean_stops".into(), json!(round2(stops)));
            v.insert("mean_distance_over_plan".into(), json!(round2(ratio)));
            v.insert("mean_time_s".into(), json!(round2(time)));
        }
        serde_json::Value::Object(v)
    }

    fn row(&self, label: &str) -> String {
        let c = |k| self.count(k);
        let eff = match self.efficiency() {
            Some((s, r, t)) => format!("{s:>6.1} {r:>9.2} {t:>7.0}"),
            None => format!("{:>6} {:>9} {:>7}", "-", "-", "-"),
        };
        format!(
            "{label:<34} {:>4} {:>7} {:>9} {:>9} {:>8} {:>7} {:>7} {eff}",
            self.total(),
            c(Class::Reached),
            c(Class::Collision),
            c(Class::FalseUnreachable),
            c(Class::TrueUnreachable),
            c(Class::GaveUp),
            c(Class::Timeout),
        )
    }
}

fn round2(x: f64) -> f64 {
    (x * 100.0).round() / 100.0
}

/// Removes the worlds' scratch folder when the run ends, however it ends.
struct Scratch(Option<PathBuf>);

impl Drop for Scratch {
    fn drop(&mut self) {
        if let Some(dir) = &self.0 {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
}

/// A word as a shell reads it back.
fn shell_word(word: &str) -> String {
    let plain = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=,:+".contains(c));
    if plain {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

/// Run `twil sonar-grid`.
pub fn run(args: Args) -> Result<crate::exit::Ending> {
    let argv: Vec<String> = std::env::args()
        .skip_while(|a| a != "sonar-grid")
        .skip(1)
        .collect();
    run_with(args, &loop_option_words(&argv))
}

/// Run the grid with `passed`, the loop options' words for every mission.
pub fn run_with(args: Args, passed: &[String]) -> Result<crate::exit::Ending> {
    let started = Instant::now();
    let world_count = args.worlds.unwrap_or(if args.quick { 4 } else { 12 });
    if !(1..=1000).contains(&world_count) {
        bail!("--worlds {world_count}: 1 to 1000");
    }
    let ranges = args.ranges.clone().unwrap_or_else(|| {
        if args.quick {
            QUICK_RANGES_M.to_vec()
        } else {
            RANGES_M.to_vec()
        }
    });
    let jobs_wanted = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    if !(1..=256).contains(&jobs_wanted) {
        bail!("--jobs {jobs_wanted}: 1 to 256");
    }
    for (option, value) in [
        ("--sonar-dropout", args.sonar_dropout),
        ("--sonar-spurious", args.sonar_spurious),
    ] {
        if !(0.0..=1.0).contains(&value) {
            bail!("{option} {value}: a probability, 0 to 1");
        }
    }
    if !(0.0..=1.0).contains(&args.sonar_noise) {
        bail!("--sonar-noise {}: 0 to 1 m", args.sonar_noise);
    }
    let modes: &[&'static str] = if args.quick {
        &["stop"]
    } else {
        &["stop", "continuous"]
    };
    let sonars = sonars(args.quick);

    let worlds: Vec<worldgen::GenWorld> = (0..world_count)
        .map(|i| worldgen::generate(args.world_seed, i))
        .collect::<Result<_>>()?;
    let (world_dir, _scratch) = match &args.out {
        Some(dir) => (dir.join("worlds"), Scratch(None)),
        None => {
            let dir = std::env::temp_dir().join(format!("twil-sonar-grid-{}", std::process::id()));
            (dir.clone(), Scratch(Some(dir)))
        }
    };
    std::fs::create_dir_all(&world_dir)
        .with_context(|| format!("{}: cannot create directory", world_dir.display()))?;
    let world_paths: Vec<(PathBuf, PathBuf)> = worlds
        .iter()
        .enumerate()
        .map(|(i, w)| {
            let stem = format!("world-{i:02}");
            w.write(&world_dir, &stem)?;
            Ok((
                world_dir.join(format!("{stem}.da")),
                world_dir.join(format!("{stem}.par")),
            ))
        })
        .collect::<Result<_>>()?;

    let mut jobs = Vec::new();
    for &mode in modes {
        for &range_m in &ranges {
            for &sonar in &sonars {
                for world in 0..worlds.len() {
                    jobs.push(Job {
                        world,
                        range_m,
                        mode,
                        sonar,
                    });
                }
            }
        }
    }
    // One mission set up before the threads start: a bad option fails once, clearly.
    if let Some(first) = jobs.first() {
        let (da, par) = &world_paths[first.world];
        let words = mission_words(&args, first, da, par, passed);
        let cli = SimulateCli::try_parse_from(&words)
            .map_err(|e| anyhow::anyhow!("{}", e.to_string().trim()))?;
        simulate::setup_from_args(&cli.args)?;
    }

    let bar = if args.json || !std::io::stderr().is_terminal() {
        ProgressBar::with_draw_target(Some(jobs.len() as u64), ProgressDrawTarget::hidden())
    } else {
        let b = ProgressBar::new(jobs.len() as u64);
        if let Ok(style) = ProgressStyle::with_template(
            "{bar:30} {pos}/{len} missions  {elapsed} (eta {eta})  {msg}",
        ) {
            b.set_style(style);
        }
        b
    };
    let threads = jobs_wanted.min(jobs.len()).max(1);
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<Outcome>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    let failures_seen = AtomicUsize::new(0);
    std::thread::scope(|scope| {
        for t in 0..threads {
            let (jobs, worlds, world_paths, next, results, bar, args, failures_seen) = (
                &jobs,
                &worlds,
                &world_paths,
                &next,
                &results,
                &bar,
                &args,
                &failures_seen,
            );
            let spawned = std::thread::Builder::new()
                .name(format!("grid-{t}"))
                .stack_size(64 * 1024 * 1024)
                .spawn_scoped(scope, move || loop {
                    let i = next.fetch_add(1, Ordering::SeqCst);
                    let Some(job) = jobs.get(i) else { break };
                    let (da, par) = &world_paths[job.world];
                    let words = mission_words(args, job, da, par, passed);
                    let outcome = run_mission(&words, worlds[job.world].reachable);
                    if let Ok(o) = &outcome {
                        if is_failure(o.class) {
                            let n = failures_seen.fetch_add(1, Ordering::SeqCst) + 1;
                            bar.set_message(format!("{n} failing"));
                        }
                    }
                    if let Ok(mut r) = results.lock() {
                        r[i] = Some(outcome);
                    }
                    bar.inc(1);
                });
            if let Err(e) = spawned {
                eprintln!("twil: cannot start a grid thread: {e}");
            }
        }
    });
    bar.finish_and_clear();
    let results = results
        .into_inner()
        .map_err(|_| anyhow::anyhow!("a grid thread failed"))?;
    let mut outcomes = Vec::with_capacity(jobs.len());
    for (job, r) in jobs.iter().zip(results) {
        match r {
            Some(Ok(o)) => outcomes.push(o),
            Some(Err(e)) => bail!(
                "world-{:02} {} {} m {}: {e:#}",
                job.world,
                job.sonar.label(),
                job.range_m,
                job.mode
            ),
            None => bail!(
                "world-{:02} {} {} m {}: not run",
                job.world,
                job.sonar.label(),
                job.range_m,
                job.mode
            ),
        }
    }
    let elapsed_s = started.elapsed().as_secs_f64();

    // Failing missions kept for a rerun.
    let mut kept = Vec::new();
    if let Some(dir) = &args.out {
        for (job, o) in jobs.iter().zip(&outcomes) {
            if !is_failure(o.class) {
                continue;
            }
            let id = format!(
                "world-{:02}-{}-{}m-{}",
                job.world,
                job.sonar.label().replace([' ', '/'], "-").replace('+', ""),
                job.range_m,
                job.mode
            );
            let mission_dir = dir.join(&id);
            std::fs::create_dir_all(&mission_dir)
                .with_context(|| format!("{}: cannot create directory", mission_dir.display()))?;
            worlds[job.world].write(&mission_dir, "real")?;
            let (da, par) = (mission_dir.join("real.da"), mission_dir.join("real.par"));
            let words = mission_words(&args, job, &da, &par, passed);
            let command = std::iter::once("twil simulate".to_string())
                .chain(words.iter().map(|w| shell_word(w)))
                .collect::<Vec<_>>()
                .join(" ");
            let path = mission_dir.join("summary.json");
            std::fs::write(&path, serde_json::to_string_pretty(&o.summary)? + "\n")
                .with_context(|| format!("{}: cannot write", path.display()))?;
            let path = mission_dir.join("command.txt");
            std::fs::write(&path, format!("{command}\n"))
                .with_context(|| format!("{}: cannot write", path.display()))?;
            kept.push((id, o.status.clone(), command));
        }
    }

    // Tallies per cell (sonar, range, mode) and in total.
    let mut cells: Vec<((Sonar, f32, &'static str), Tally)> = Vec::new();
    let (mut ray, mut beam, mut total) = (Tally::default(), Tally::default(), Tally::default());
    for (job, o) in jobs.iter().zip(&outcomes) {
        let key = (job.sonar, job.range_m, job.mode);
        match cells.iter_mut().find(|(k, _)| *k == key) {
            Some((_, t)) => t.add(o),
            None => {
                let mut t = Tally::default();
                t.add(o);
                cells.push((key, t));
            }
        }
        if job.sonar.beam.is_some() {
            &mut beam
        } else {
            &mut ray
        }
        .add(o);
        total.add(o);
    }
    let reachable = worlds.iter().filter(|w| w.reachable).count();

    if args.json {
        let v = json!({
            "missions": outcomes.len(),
            "threads": threads,
            "elapsed_s": round2(elapsed_s),
            "world_seed": args.world_seed,
            "worlds": worlds.iter().enumerate().map(|(i, w)| json!({
                "name": format!("world-{i:02}"),
                "reachable": w.reachable,
                "features": w.features,
                "attempts": w.attempts,
            })).collect::<Vec<_>>(),
            "faults": {
                "sonar_noise_m": args.sonar_noise,
                "sonar_dropout": args.sonar_dropout,
                "sonar_spurious": args.sonar_spurious,
            },
            "loop_options": passed,
            "cells": cells.iter().map(|((s, r, m), t)| {
                let mut v = t.json();
                if let Some(o) = v.as_object_mut() {
                    o.insert("sonar".into(), json!(s.label()));
                    o.insert("range_m".into(), json!(r));
                    o.insert("mode".into(), json!(m));
                }
                v
            }).collect::<Vec<_>>(),
            "ray": ray.json(),
            "beam": beam.json(),
            "total": total.json(),
            "kept": kept.iter().map(|(id, status, command)| json!({
                "id": id, "status": status, "command": command,
            })).collect::<Vec<_>>(),
        });
        println!("{v}");
        return Ok(crate::exit::Ending::Done);
    }
    println!(
        "{} worlds (seed {}: {reachable} reachable, {} walled-in goal{}); faults: noise {} m, dropout {}, spurious {}{}",
        worlds.len(),
        args.world_seed,
        worlds.len() - reachable,
        if worlds.len() - reachable == 1 { "" } else { "s" },
        args.sonar_noise,
        args.sonar_dropout,
        args.sonar_spurious,
        if passed.is_empty() { String::new() } else { format!("; loop options: {}", passed.join(" ")) },
    );
    println!(
        "{:<34} {:>4} {:>7} {:>9} {:>9} {:>8} {:>7} {:>7} {:>6} {:>9} {:>7}",
        "sonar, range, mode",
        "n",
        "reached",
        "collision",
        "false_unr",
        "true_unr",
        "gave_up",
        "timeout",
        "stops",
        "dist/plan",
        "time_s"
    );
    for ((s, r, m), t) in &cells {
        println!("{}", t.row(&format!("{} {r} m {m}", s.label())));
    }
    println!("{}", ray.row("total ray"));
    println!("{}", beam.row("total beam"));
    println!("{}", total.row("total"));
    println!(
        "{} missions in {:.0} s on {threads} thread{}",
        outcomes.len(),
        elapsed_s,
        if threads == 1 { "" } else { "s" }
    );
    if let Some(dir) = &args.out {
        if kept.is_empty() {
            println!("no failing mission; worlds in {}", world_dir.display());
        } else {
            let list = dir.join("failures.txt");
            let text: String = kept
                .iter()
                .map(|(id, status, c)| format!("{id}: {status}\n  {c}\n"))
                .collect();
            std::fs::write(&list, text)
                .with_context(|| format!("{}: cannot write", list.display()))?;
            println!(
                "{} failing missions kept in {} (list: {}); rerun one with:",
                kept.len(),
                dir.display(),
                list.display()
            );
            for (id, status, command) in kept.iter().take(5) {
                println!("  {id} ({status}): {command}");
            }
        }
    }
    Ok(crate::exit::Ending::Done)
}

/// A mission that did not end as it should: anything but a reachable goal reached or a
/// walled-in goal reported unreachable.
fn is_failure(class: Class) -> bool {
    !matches!(class, Class::Reached | Class::TrueUnreachable)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(text: &str) -> Vec<String> {
        text.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn loop_options_pass_through_with_their_values() {
        let argv = words("--quick --preset seed --planner bfs --rcd=false --out x --jobs 2 --seed-prune --settle model --feed-forward=true");
        assert_eq!(
            loop_option_words(&argv),
            words("--preset seed --planner bfs --rcd=false --seed-prune --settle model --feed-forward=true")
        );
        assert!(loop_option_words(&words("--quick --json")).is_empty());
    }

    #[test]
    fn the_grids_have_the_sizes_of_the_docs() {
        let full = sonars(false);
        assert_eq!(full.len(), 9);
        assert_eq!(full[0].label(), "ray");
        assert_eq!(full.iter().filter(|s| s.faults).count(), 4);
        assert!(full.iter().all(|s| s
            .beam
            .is_none_or(|(h, l)| (10.0..=25.0).contains(&h) && (h..=90.0).contains(&l))));
        // 12 worlds x 4 ranges x 2 modes x 9 sonars: at least 500 missions.
        assert_eq!(12 * RANGES_M.len() * 2 * full.len(), 864);
        let quick = sonars(true);
        assert_eq!(4 * QUICK_RANGES_M.len() * quick.len(), 40);
        assert_eq!(quick.iter().filter(|s| s.faults).count(), 2);
        assert!(quick.iter().any(|s| s.beam == Some((10.0, 10.0))));
        assert!(quick.iter().any(|s| s.beam == Some((25.0, 90.0))));
    }

    #[test]
    fn shell_words_are_quoted_when_needed() {
        assert_eq!(shell_word("--rcd=false"), "--rcd=false");
        assert_eq!(shell_word("a b"), "'a b'");
        assert_eq!(shell_word("it's"), r"'it'\''s'");
    }
}
