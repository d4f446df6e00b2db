//! Where the reflectors of one run of constant depth lie, from the run's bearings and what its
//! neighbours heard (the evidence map's marking, `evidence_marking`).
//!
//! A reading hears the nearest reflector anywhere in its cone (half-angle β), so a point
//! reflector at bearing R makes every reading within β of R echo at one depth: its run spans
//! 2β and R is the run's middle. Two things move R off the middle:
//!
//! - **A side where the reflector left the cone.** When the reading just past one end of the
//!   run heard something farther, or nothing, the reflector was not in that reading's cone: it
//!   lies β inside that end (within half a bearing step). When the neighbour heard something
//!   *nearer*, it says nothing (the nearer echo masks the run's reflector), and neither does
//!   the sweep's edge. An oblique wall's arc is the common case: each reading hears the wall's
//!   nearest point in its cone, at the cone's edge, not on its axis.
//! - **A run wider than 2β** holds more than one reflector: no point lies within β of both its
//!   ends. Two jambs of a doorway seen from its axis, farther than h / tan β (h the doorway's
//!   half-width: 1.9 m for a 1 m doorway at 15°), are heard at one depth by every reading from
//!   β before the first jamb to β past the second; the run's middle is the doorway's middle,
//!   where nothing is. Its reflectors are β inside each end (and, past 4β, every 2β between).
//!
//! Every single reflector is kept inside the bearings the run's readings allow,
//! `[last − β, first + β]`, so a dropped echo read as "left the cone" moves it at most within
//! the cone that heard it.

use heapless::Vec;

use crate::math::ceil;

/// Reflectors placed for one run at most; a run wider than `2β · (MAX − 1)` keeps its two end
/// reflectors and spreads the rest evenly.
pub(super) const MAX_REFLECTORS_PER_RUN: usize = 8;

/// What the reading just past one end of a run heard.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum RunSide {
    /// Something farther than the run, or nothing: the run's reflector left the cone there.
    Open,
    /// Something nearer: it masks the run's reflector, so the side says nothing.
    Masked,
    /// The sweep ends there.
    Edge,
}

/// What the reading past one end of a run heard (`None`: no echo), how far its sonar stood
/// from the end reading's, metres, and the ranger's window `(min, max)`, metres.
pub(super) type Neighbour = (Option<f32>, f32, (f32, f32));

impl RunSide {
    /// The side a neighbour gives a run whose end reading heard `end_m` (`None`: the sweep
    /// ends there). Its silence opens the side only when the run's reflector, `moved_m`
    /// nearer or farther for it, still lay inside the window: otherwise the blind disc or
    /// the range may have hidden it. A farther echo opens it only beyond that move too.
    pub(super) fn of_neighbour(neighbour: Option<Neighbour>, end_m: f32) -> Self {
        let Some((range_m, moved_m, (min_m, max_m))) = neighbour else {
            return RunSide::Edge;
        };
        let moved_m = if moved_m.is_finite() {
            moved_m.max(0.0)
        } else {
            f32::INFINITY
        };
        match range_m {
            None if end_m - moved_m >= min_m && end_m + moved_m <= max_m => RunSide::Open,
            None => RunSide::Edge,
            Some(m) if m > end_m + moved_m => RunSide::Open,
            Some(m) if m > end_m => RunSide::Edge,
            Some(_) => RunSide::Masked,
        }
    }
}

/// One end of a run: the bearing of its outermost reading and what lies past it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct RunEnd {
    pub bearing_rad: f32,
    pub side: RunSide,
}

/// The bearings of a run's reflectors (same frame as the ends' bearings), in order from
/// `first` to `last`. `step_rad` is the sweep's bearing step from one reading to the next
/// (signed: a one-reading run knows which neighbour is which by it), `beam_rad` the
/// half-angle β.
/// A beam narrower than a step (a ray) puts one reflector in the middle.
pub(super) fn reflector_bearings(
    first: RunEnd,
    last: RunEnd,
    step_rad: f32,
    beam_rad: f32,
) -> Vec<f32, MAX_REFLECTORS_PER_RUN> {
    let mut out = Vec::new();
    // Work from the lower bearing up; give the answer in the caller's order.
    // A one-reading run has no direction of its own: the sweep's step gives it.
    let ascending = if last.bearing_rad == first.bearing_rad {
        step_rad >= 0.0 || step_rad.is_nan()
    } else {
        last.bearing_rad > first.bearing_rad
    };
    let (lo, hi) = if ascending {
        (first, last)
    } else {
        (last, first)
    };
    let step_rad = if step_rad.is_finite() {
        step_rad.abs()
    } else {
        0.0
    };
    let middle_rad = 0.5 * (lo.bearing_rad + hi.bearing_rad);
    if !(beam_rad >= step_rad && beam_rad > 0.0) {
        let _ = out.push(middle_rad);
        return out;
    }
    let half_step_rad = 0.5 * step_rad;
    let width_rad = hi.bearing_rad - lo.bearing_rad;
    // β inside each end; half a step less where the reflector is known to have left the cone
    // between this end and its neighbour.
    let from_lo_rad = lo.bearing_rad + beam_rad
        - if lo.side == RunSide::Open {
            half_step_rad
        } else {
            0.0
        };
    let from_hi_rad = hi.bearing_rad - beam_rad
        + if hi.side == RunSide::Open {
            half_step_rad
        } else {
            0.0
        };
    if width_rad <= 2.0 * beam_rad + half_step_rad {
        // One reflector, inside [hi − β, lo + β].
        let (allowed_lo, allowed_hi) = (hi.bearing_rad - beam_rad, lo.bearing_rad + beam_rad);
        let guess_rad = match (lo.side == RunSide::Open, hi.side == RunSide::Open) {
            (true, false) => from_lo_rad,
            (false, true) => from_hi_rad,
            _ => middle_rad,
        };
        let _ = out.push(if allowed_lo <= allowed_hi {
            guess_rad.clamp(allowed_lo, allowed_hi)
        } else {
            middle_rad
        });
    } else {
        // Several: one β inside each end, the rest at most 2β apart between them.
        let span_rad = (from_hi_rad - from_lo_rad).max(0.0);
        let gaps =
            (ceil(span_rad / (2.0 * beam_rad)) as usize).clamp(1, MAX_REFLECTORS_PER_RUN - 1);
        for k in 0..=gaps {
            let _ = out.push(from_lo_rad + span_rad * k as f32 / gaps as f32);
        }
    }
    if !ascending {
        out.reverse();
    }
    out
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;

    const DEG: f32 = core::f32::consts::PI / 180.0;
    const STEP: f32 = 1.8 * DEG;
    const BEAM: f32 = 15.0 * DEG;

    fn end(bearing_deg: f32, side: RunSide) -> RunEnd {
        RunEnd {
            bearing_rad: bearing_deg * DEG,
            side,
        }
    }

    fn degrees(v: &[f32]) -> std::vec::Vec<f32> {
        v.iter().map(|r| r / DEG).collect()
    }

    #[test]
    fn a_point_heard_by_a_full_cone_lies_at_the_runs_middle() {
        let b = reflector_bearings(
            end(10.0, RunSide::Open),
            end(40.0, RunSide::Open),
            STEP,
            BEAM,
        );
        assert_eq!(b.len(), 1);
        assert!((b[0] / DEG - 25.0).abs() < 1e-3, "{:?}", degrees(&b));
    }

    #[test]
    fn a_run_cut_short_by_a_nearer_echo_is_placed_from_its_open_end() {
        // The far jamb of a doorway seen off its axis: the near jamb masks the run's first
        // readings, the far jamb leaves the cone past the last.
        let b = reflector_bearings(
            end(30.0, RunSide::Masked),
            end(40.0, RunSide::Open),
            STEP,
            BEAM,
        );
        assert_eq!(b.len(), 1);
        assert!(
            (b[0] / DEG - (40.0 - 15.0 + 0.9)).abs() < 1e-3,
            "{:?}",
            degrees(&b)
        );
        // The same run read the other way round gives the same bearing.
        let r = reflector_bearings(
            end(40.0, RunSide::Open),
            end(30.0, RunSide::Masked),
            STEP,
            BEAM,
        );
        assert!((r[0] - b[0]).abs() < 1e-6);
    }

    #[test]
    fn a_doorway_seen_from_its_axis_gives_its_two_jambs_not_its_middle() {
        // Jambs at ±8° (a 1 m doorway 3.6 m away), both heard at one depth by every reading
        // from −23° to +23°.
        let b = reflector_bearings(
            end(-23.0, RunSide::Open),
            end(23.0, RunSide::Open),
            STEP,
            BEAM,
        );
        let d = degrees(&b);
        assert_eq!(b.len(), 2, "{d:?}");
        assert!(
            (d[0] + 8.9).abs() < 1e-3 && (d[1] - 8.9).abs() < 1e-3,
            "{d:?}"
        );
        assert!(
            d.iter().all(|x| x.abs() > 5.0),
            "nothing in the doorway: {d:?}"
        );
    }

    #[test]
    fn a_one_reading_run_takes_its_direction_from_the_sweeps_step() {
        // A sweep read from high bearings to low: the reading before (60°) heard nothing, the
        // one after (56.4°) something nearer. The reflector is in the 58.2° cone but not the
        // 60° one: β below 58.2°, within half a step.
        let b = reflector_bearings(
            end(58.2, RunSide::Open),
            end(58.2, RunSide::Masked),
            -STEP,
            BEAM,
        );
        assert!(
            (b[0] / DEG - (58.2 - 15.0 + 0.9)).abs() < 1e-3,
            "{:?}",
            degrees(&b)
        );
        let a = reflector_bearings(
            end(58.2, RunSide::Masked),
            end(58.2, RunSide::Open),
            -STEP,
            BEAM,
        );
        assert!(
            (a[0] / DEG - (58.2 + 15.0 - 0.9)).abs() < 1e-3,
            "{:?}",
            degrees(&a)
        );
    }

    #[test]
    fn a_very_wide_run_spreads_reflectors_at_most_two_half_angles_apart() {
        let b = reflector_bearings(
            end(-90.0, RunSide::Edge),
            end(90.0, RunSide::Edge),
            STEP,
            BEAM,
        );
        let d = degrees(&b);
        assert!((d[0] + 75.0).abs() < 1e-3 && (d[d.len() - 1] - 75.0).abs() < 1e-3);
        assert!(d.windows(2).all(|w| w[1] - w[0] <= 30.0 + 1e-3), "{d:?}");
        assert!(b.len() <= MAX_REFLECTORS_PER_RUN);
    }

    #[test]
    fn a_single_reflector_never_leaves_the_bearings_its_readings_allow() {
        // An open side pins the reflector β inside that end, but never outside
        // [last − β, first + β], the bearings within β of every reading of the run.
        for side in [RunSide::Open, RunSide::Masked, RunSide::Edge] {
            for (a, z) in [(0.0, 0.0), (0.0, 5.4), (0.0, 30.0)] {
                let b = reflector_bearings(end(a, side), end(z, RunSide::Open), STEP, BEAM);
                for r in degrees(&b) {
                    assert!(r >= z - 15.0 - 1e-3 && r <= a + 15.0 + 1e-3, "{a} {z} {r}");
                }
            }
        }
    }

    #[test]
    fn a_ray_or_bad_numbers_put_one_reflector_in_the_middle() {
        let b = reflector_bearings(end(0.0, RunSide::Open), end(10.0, RunSide::Open), STEP, 0.0);
        assert_eq!(degrees(&b), [5.0]);
        let n = reflector_bearings(
            end(0.0, RunSide::Open),
            end(10.0, RunSide::Open),
            f32::NAN,
            f32::NAN,
        );
        assert_eq!(n.len(), 1);
    }

    #[test]
    fn a_neighbour_farther_or_silent_opens_a_side_a_nearer_one_masks_it() {
        let window = (0.26, 3.0);
        assert_eq!(RunSide::of_neighbour(None, 2.0), RunSide::Edge);
        assert_eq!(
            RunSide::of_neighbour(Some((None, 0.0, window)), 2.0),
            RunSide::Open
        );
        assert_eq!(
            RunSide::of_neighbour(Some((Some(2.5), 0.0, window)), 2.0),
            RunSide::Open
        );
        assert_eq!(
            RunSide::of_neighbour(Some((Some(1.5), 0.0, window)), 2.0),
            RunSide::Masked
        );
    }

    #[test]
    fn silence_where_the_moving_sonar_may_have_lost_the_reflector_says_nothing() {
        // Heard at 0.28 m; the next reading's sonar had moved 0.03 m: the reflector may have
        // been 0.25 m from it, inside the 0.26 m blind disc.
        let window = (0.26, 3.0);
        assert_eq!(
            RunSide::of_neighbour(Some((None, 0.03, window)), 0.28),
            RunSide::Edge
        );
        assert_eq!(
            RunSide::of_neighbour(Some((None, 0.01, window)), 0.28),
            RunSide::Open
        );
        // Near the far end of the window, likewise out of range.
        assert_eq!(
            RunSide::of_neighbour(Some((None, 0.03, window)), 2.98),
            RunSide::Edge
        );
        // A farther echo within the move may be the same reflector.
        assert_eq!(
            RunSide::of_neighbour(Some((Some(2.02), 0.03, window)), 2.0),
            RunSide::Edge
        );
        assert_eq!(
            RunSide::of_neighbour(Some((Some(f32::NAN), f32::NAN, window)), 2.0),
            RunSide::Masked
        );
    }
}
