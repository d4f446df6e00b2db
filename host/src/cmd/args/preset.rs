//! `--preset seed|ours`: the mission loop of seed 003 as the seed ran it, or ours (the
//! default), and the options that override a preset's choices one by one.
//!
//! `twil simulate` and `twil mission` share [`LoopArgs`] (planner, regions-of-constant-depth
//! filter, pruning) and [`FollowArgs`] (settle time, reference feed-forward, turns in place,
//! sweep readings); `SetMission` carries all of them to a device. Every choice of the seed
//! preset, with the seed's section or function, is listed in `docs/simulate.md`.

use twil_core::mission::SettleRule;
use twil_core::plan::PlannerKind;
use twil_core::sonar::SweepLayout;

use super::PlannerArg;

/// A whole set of loop choices.
#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Preset {
    /// The seed's loop: BFS, the seed's pruning only, the RCD filter, the seed's settle time
    /// (3·2π/α = 18.85 s), no reference feed-forward, no turns in place, the seed's 2n sweep
    /// readings, the seed's marking (no evidence map).
    Seed,
    /// Today's defaults (each departure from the seed is in docs/simulate.md).
    #[default]
    Ours,
}

impl Preset {
    /// Its name in `summary.json`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Seed => "seed",
            Self::Ours => "ours",
        }
    }

    /// Its mission time limit, seconds: a guard against a mission that never ends, not its
    /// judge. The seed's 18.85 s settle after each of its 20-odd stops needs 1800 s (office,
    /// 1.5 m, stop mode: 900 s ran out at 31 stops); ours, with the evidence map's shorter
    /// steps under a specular sonar, too (900 s ran out on the office and the corridor at
    /// 1.5 m while still on their way, and on 38 of the 576 missions of `twil sonar-grid
    /// --worlds 8`; 1800 s on none of those and 2 of these: docs/simulate.md).
    pub fn time_limit_s(self) -> f32 {
        match self {
            Self::Seed | Self::Ours => 1800.0,
        }
    }

    /// The choices this preset makes.
    pub fn choices(self) -> LoopChoices {
        match self {
            Self::Seed => LoopChoices {
                planner: PlannerArg::Bfs,
                rcd: true,
                seed_prune: true,
                settle: SettleRule::SeedCode,
                reference_feed_forward: false,
                sweep_layout: SweepLayout::Seed,
                turn_in_place: false,
                evidence_map: false,
            },
            Self::Ours => LoopChoices {
                planner: PlannerArg::Anyangle,
                rcd: false,
                seed_prune: false,
                settle: SettleRule::ReferenceModel,
                reference_feed_forward: true,
                sweep_layout: SweepLayout::Symmetric,
                turn_in_place: true,
                evidence_map: true,
            },
        }
    }
}

/// `--settle`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SettleArg {
    /// The reference model's 2 % time plus two periods (4.01 s; ours).
    Model,
    /// The seed's code: 3·2π/α (18.85 s).
    Seed,
}

/// `--sweep-readings`.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SweepReadingsArg {
    /// 2n + 1 readings, −n to +n steps (105 for ±95°; ours).
    Symmetric,
    /// The seed's 2n readings, −n to +n − 1 steps (104 for ±95°, −93.6° to +91.8°).
    Seed,
}

/// Loop options of `twil simulate` and `twil mission`: a preset, then explicit overrides.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct LoopArgs {
    /// Loop choices: `seed` (the seed's loop as it ran) or `ours`; the options below override
    /// it one by one (see docs/simulate.md).
    #[arg(long, value_enum, default_value_t = Preset::Ours)]
    pub preset: Preset,
    /// Planner [default: the preset's: anyangle; seed: bfs].
    #[arg(long, value_enum)]
    pub planner: Option<PlannerArg>,
    /// Filter each sweep with the seed's regions-of-constant-depth filter before marking
    /// (`--rcd=false` turns it off) [default: the preset's: off; seed: on].
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    pub rcd: Option<bool>,
    /// Keep only the seed's prefix (within sonar range, visible from the robot); otherwise the
    /// prefix may go on through space seen free by earlier sweeps (`--seed-prune=false`)
    /// [default: the preset's: off; seed: on].
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    pub seed_prune: Option<bool>,
    /// Map with the evidence map (docs/mapping.md): one reflector per run of constant depth,
    /// silence marks nothing, the body only enters space a standing sweep vouches for by the
    /// Thales rule; `--evidence-map=false` marks as the seed does (every echo on the neck's
    /// axis, silence free) [default: the preset's: on, but off with `--sonar ray`; seed: off].
    /// `twil mission` sends it in `SetMission` (the firmware runs it too).
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    pub evidence_map: Option<bool>,
}

/// Following options of `twil simulate` and `twil mission` (`SetMission` fields 16-19).
#[derive(clap::Args, Debug, Clone, Default)]
pub struct FollowArgs {
    /// Settle time after each prefix [default: the preset's: model; seed: seed].
    #[arg(long, value_enum)]
    pub settle: Option<SettleArg>,
    /// Add τ × velocity to the controller's reference (`--feed-forward=false`: the path point
    /// alone, as the seed) [default: the preset's: on; seed: off].
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    pub feed_forward: Option<bool>,
    /// Which neck positions a sweep reads [default: the preset's: symmetric; seed: seed].
    #[arg(long, value_enum)]
    pub sweep_readings: Option<SweepReadingsArg>,
    /// Turn in place at the start of a prefix and at vertices that turn by more than 30°
    /// (`--turn-in-place=false`: follow the time-stamped points only, as the seed)
    /// [default: the preset's: on; seed: off].
    #[arg(long, value_name = "BOOL", num_args = 0..=1, require_equals = true, default_missing_value = "true")]
    pub turn_in_place: Option<bool>,
}

/// The loop choices a run uses: the preset's, with the explicit options applied.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoopChoices {
    /// Planner.
    pub planner: PlannerArg,
    /// Regions-of-constant-depth filter on.
    pub rcd: bool,
    /// The seed's pruning only (no trust of space seen by earlier sweeps).
    pub seed_prune: bool,
    /// Settle time rule.
    pub settle: SettleRule,
    /// Reference feed-forward on.
    pub reference_feed_forward: bool,
    /// Sweep readings.
    pub sweep_layout: SweepLayout,
    /// Turns in place at the start and at sharp vertices.
    pub turn_in_place: bool,
    /// The evidence map (`--evidence-map`).
    pub evidence_map: bool,
}

impl LoopArgs {
    /// The preset's choices with the explicit options of `self` (and `follow`, when the
    /// command has them) applied.
    pub fn resolve(&self, follow: Option<&FollowArgs>) -> LoopChoices {
        let mut c = self.preset.choices();
        if let Some(p) = self.planner {
            c.planner = p;
        }
        if let Some(on) = self.rcd {
            c.rcd = on;
        }
        if let Some(on) = self.seed_prune {
            c.seed_prune = on;
        }
        if let Some(on) = self.evidence_map {
            c.evidence_map = on;
        }
        if let Some(f) = follow {
            if let Some(s) = f.settle {
                c.settle = match s {
                    SettleArg::Model => SettleRule::ReferenceModel,
                    SettleArg::Seed => SettleRule::SeedCode,
                };
            }
            if let Some(on) = f.feed_forward {
                c.reference_feed_forward = on;
            }
            if let Some(on) = f.turn_in_place {
                c.turn_in_place = on;
            }
            if let Some(s) = f.sweep_readings {
                c.sweep_layout = match s {
                    SweepReadingsArg::Symmetric => SweepLayout::Symmetric,
                    SweepReadingsArg::Seed => SweepLayout::Seed,
                };
            }
        }
        c
    }
}

impl LoopArgs {
    /// The evidence map for a run whose simulated sonar is the beam (`sonar_beam`) or the
    /// single ray: `--evidence-map`'s value when given, else the preset's for the beam and
    /// off for the ray. The ray is the exact sensor: it hears every wall it points at, at any
    /// angle, so silence along it is free space and the seed's marking is right for it; the
    /// evidence map is made for the beam's silent smooth walls (with it the ray collided in
    /// 3 of 64 generated missions: zero-thickness wall ends between two rays, docs/mapping.md).
    pub fn evidence_map_for(&self, sonar_beam: bool) -> bool {
        self.evidence_map
            .unwrap_or(self.preset.choices().evidence_map && sonar_beam)
    }
}

impl LoopChoices {
    /// The planner to run.
    pub fn planner_kind(&self) -> PlannerKind {
        match self.planner {
            PlannerArg::Bfs => PlannerKind::Bfs,
            PlannerArg::Astar => PlannerKind::AStar,
            PlannerArg::Anyangle => PlannerKind::AnyAngle,
        }
    }

    /// The planner's name in `summary.json`.
    pub fn planner_name(&self) -> String {
        format!("{:?}", self.planner).to_lowercase()
    }

    /// The settle rule's name in `summary.json`.
    pub fn settle_name(&self) -> &'static str {
        match self.settle {
            SettleRule::ReferenceModel => "model",
            SettleRule::SeedCode => "seed",
        }
    }

    /// The sweep layout's name in `summary.json`.
    pub fn sweep_readings_name(&self) -> &'static str {
        match self.sweep_layout {
            SweepLayout::Symmetric => "symmetric",
            SweepLayout::Seed => "seed",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_seed_preset_sets_every_listed_choice() {
        let seed = LoopArgs {
            preset: Preset::Seed,
            ..LoopArgs::default()
        }
        .resolve(Some(&FollowArgs::default()));
        assert_eq!(seed.planner, PlannerArg::Bfs);
        assert!(seed.rcd && seed.seed_prune && !seed.reference_feed_forward);
        assert_eq!(seed.settle, SettleRule::SeedCode);
        assert_eq!(seed.sweep_layout, SweepLayout::Seed);
        assert!(!seed.turn_in_place);
        assert!(!seed.evidence_map);
        // Every choice differs from ours: the preset is not a partial one.
        let ours = Preset::Ours.choices();
        assert_ne!(seed.planner, ours.planner);
        assert_ne!(seed.rcd, ours.rcd);
        assert_ne!(seed.seed_prune, ours.seed_prune);
        assert_ne!(seed.settle, ours.settle);
        assert_ne!(seed.reference_feed_forward, ours.reference_feed_forward);
        assert_ne!(seed.sweep_layout, ours.sweep_layout);
        assert_ne!(seed.turn_in_place, ours.turn_in_place);
        assert_ne!(seed.evidence_map, ours.evidence_map);
    }

    #[test]
    fn ours_is_the_mission_default() {
        let ours = LoopArgs::default().resolve(Some(&FollowArgs::default()));
        let idle = twil_core::mission::MissionConfig::IDLE;
        assert!(!ours.rcd && !ours.seed_prune);
        assert_eq!(idle.constant_depth_filter, ours.rcd);
        assert_eq!(idle.trust_seen_space, !ours.seed_prune);
        assert_eq!(idle.settle, ours.settle);
        assert_eq!(idle.reference_feed_forward, ours.reference_feed_forward);
        assert_eq!(idle.robot.sweep_layout, ours.sweep_layout);
        assert!(ours.turn_in_place && idle.turn_in_place_above_rad < core::f32::consts::PI);
        assert_eq!(ours.planner, PlannerArg::Anyangle);
    }

    #[test]
    fn explicit_options_override_the_preset() {
        let c = LoopArgs {
            preset: Preset::Seed,
            planner: Some(PlannerArg::Astar),
            rcd: Some(false),
            seed_prune: None,
            evidence_map: Some(true),
        }
        .resolve(Some(&FollowArgs {
            settle: Some(SettleArg::Model),
            feed_forward: None,
            sweep_readings: Some(SweepReadingsArg::Symmetric),
            turn_in_place: None,
        }));
        assert_eq!(c.planner, PlannerArg::Astar);
        assert!(!c.rcd);
        assert!(c.seed_prune, "not overridden: the preset's");
        assert_eq!(c.settle, SettleRule::ReferenceModel);
        assert!(!c.reference_feed_forward, "not overridden: the preset's");
        assert_eq!(c.sweep_layout, SweepLayout::Symmetric);
        assert!(!c.turn_in_place, "not overridden: the preset's");
        assert!(c.evidence_map);
        let off = LoopArgs {
            evidence_map: Some(false),
            ..LoopArgs::default()
        };
        assert!(!off.resolve(None).evidence_map);
        // Without the following options (twil mission) the preset's stand.
        let m = LoopArgs {
            preset: Preset::Seed,
            ..LoopArgs::default()
        }
        .resolve(None);
        assert_eq!(m.settle, SettleRule::SeedCode);
    }
}
