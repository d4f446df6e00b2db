//! A wall heard at its cone edges: the readings of a standing sweep whose ranges rise one
//! after another away from a wall's nearest point place their reflectors on the wall itself,
//! and a chain of them marks the wall between them (the evidence map's marking,
//! `evidence_marking`).
//!
//! Why: a reading hears the nearest echoing point in its cone. For a wall whose nearest point
//! (its foot) lies outside the cone, that is where the cone's edge toward the foot meets the
//! wall, at the reading's range (Moravec & Elfes 1985's cone; the simulated beam, `plant::echo`,
//! casts its rays out to the edges). So a reading whose neighbour toward the foot heard nearer
//! and whose other neighbour heard farther or nothing has its reflector at its cone's edge on
//! that side, not on its axis. The run rule (`reflector`) already places a lone reading's
//! reflector there, but never confirms it: one reading could have heard anything in its arc.
//!
//! What this adds: when three readings or more in a row do so and their edge points lie on one
//! straight line (within [`EDGE_LINE_TOLERANCE_M`]), that is a wall heard along its length.
//! Each edge point is the nearest point of the line in its cone; had the wall a gap there as
//! wide as the narrowest way the robot can use (`w`), the echo would have come from the gap's
//! far side, at least `w · sin α` farther (α: the edge ray's angle from the wall's normal),
//! and its point would lie behind the line. So each edge point must meet the wall at
//! `sin α ≥ 2 · tolerance / w`, and then the chain is a wall with no way through it between
//! consecutive edge points: they lie less than the body's diameter apart (farther apart,
//! the chain is cut there). Its cells, the edge points joined in order, are occupied evidence:
//! one step per sweep, as every reflector (one viewpoint, one step), so a second sweep from
//! elsewhere that hears the same wall confirms the cells both chains cover (Leonard &
//! Durrant-Whyte 1991's several viewpoints, here along the whole heard stretch rather than at
//! the foot alone, which is what a proof of a walled-in goal needs: `verdict`).
//!
//! Bounded: one pass over the readings; a chain's line check is O(chain²) with a chain at most
//! [`MAX_CHAIN_READINGS`] readings; its cells are the Bresenham lines between its points.

use heapless::Vec;

use crate::geom::PointM;
use crate::math::{abs, cos, hypot, sin, wrap_angle_rad};
use crate::raster::{mark_point_m, BresenhamLine};
use crate::sonar::{hit_to_world, Reading};

use super::evidence_marking::centre;
use super::Mission;

/// How far an edge point may lie off its chain's line, metres: three standard deviations of
/// the measured HC-SR04's range noise (5 mm, `docs/robot-model.md`). A noisier ranger makes
/// fewer chains, never more.
pub const EDGE_LINE_TOLERANCE_M: f32 = 0.015;

/// Least rise of the range from one reading of a chain to the next beyond the sonar's own
/// movement, metres.
pub const MIN_RISE_PER_READING_M: f32 = 0.001;

/// Least rise of the range over a whole chain, metres: twice the line tolerance, past what
/// the noise makes of a constant range (4σ of the difference of two readings).
pub const MIN_CHAIN_RISE_M: f32 = 2.0 * EDGE_LINE_TOLERANCE_M;

/// Readings a chain needs (three points make a line that a coincidence rarely fits).
pub const MIN_CHAIN_READINGS: usize = 3;

/// Readings per chain at most; a longer one is cut and goes on as a new chain.
pub const MAX_CHAIN_READINGS: usize = 32;

/// Cells one sweep's chains step at most; past it a chain's cells are left as they are (its
/// points still mark the grid).
pub const MAX_CHAIN_CELLS_PER_SWEEP: usize = 256;

/// One edge point: where the reading's cone edge toward the nearer neighbour meets its range,
/// and the edge ray's bearing (world radians).
#[derive(Clone, Copy, Debug, PartialEq)]
struct EdgePoint {
    at: PointM,
    ray_rad: f32,
    range_m: f32,
    sonar: PointM,
    /// The reading's index in the sweep.
    index: usize,
}

/// Which neighbour heard nearer: the side of the wall's foot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Toward {
    Before,
    After,
}

/// The side of reading `i`'s nearer neighbour, when one neighbour heard nearer and the other
/// farther or nothing (the range rises away from the foot).
fn toward_foot(readings: &[Reading], i: usize) -> Option<Toward> {
    let here = readings.get(i)?.range_m?;
    let range = |j: Option<usize>| j.and_then(|j| readings.get(j)).map(|r| r.range_m);
    let (before, after) = (range(i.checked_sub(1)), range(Some(i + 1)));
    let nearer = |r: Option<Option<f32>>| matches!(r, Some(Some(m)) if m < here);
    let farther_or_silent = |r: Option<Option<f32>>| match r {
        Some(Some(m)) => m > here,
        Some(None) => true,
        None => false,
    };
    if nearer(before) && farther_or_silent(after) {
        Some(Toward::Before)
    } else if nearer(after) && farther_or_silent(before) {
        Some(Toward::After)
    } else {
        None
    }
}

/// Distance of `p` from the line through `a` and `b`, metres (from `a` when they coincide).
fn off_line_m(a: PointM, b: PointM, p: PointM) -> f32 {
    let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
    let length_m = hypot(dx, dy);
    if length_m < 1.0e-6 {
        return hypot(p.x_m - a.x_m, p.y_m - a.y_m);
    }
    abs((p.x_m - a.x_m) * dy - (p.y_m - a.y_m) * dx) / length_m
}

/// `sin α` of `p`'s edge ray against the normal of the line through `a` and `b` (the
/// |cosine| of its angle to the line); 0 when they coincide.
fn sin_incidence(a: PointM, b: PointM, p: &EdgePoint) -> f32 {
    let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
    let length_m = hypot(dx, dy);
    if length_m < 1.0e-6 {
        return 0.0;
    }
    abs(cos(p.ray_rad) * dx + sin(p.ray_rad) * dy) / length_m
}

/// The part of `chain` that is a wall heard at its cone edges, if any: its points nearest the
/// foot (on the `toward` side) dropped while their edge rays meet the line through the
/// chain's ends at `sin α < min_sin_incidence` (too near square for a gap to show, see the
/// module docs); then at least [`MIN_CHAIN_READINGS`] points left, every one within
/// [`EDGE_LINE_TOLERANCE_M`] of the line through its ends and meeting it at
/// `sin α ≥ min_sin_incidence`, the range rising by [`MIN_CHAIN_RISE_M`] at least.
fn wall_part(chain: &[EdgePoint], toward: Toward, min_sin_incidence: f32) -> Option<&[EdgePoint]> {
    let (first, last) = (chain.first()?, chain.last()?);
    let (a, b) = (first.at, last.at);
    let steep = |p: &EdgePoint| sin_incidence(a, b, p) < min_sin_incidence;
    let part = match toward {
        Toward::Before => {
            let skip = chain.iter().take_while(|p| steep(p)).count();
            chain.get(skip..)?
        }
        Toward::After => {
            let keep = chain.len() - chain.iter().rev().take_while(|p| steep(p)).count();
            chain.get(..keep)?
        }
    };
    let (first, last) = (part.first()?, part.last()?);
    if part.len() < MIN_CHAIN_READINGS {
        return None;
    }
    // The part rises by more than the noise can: a point reflector's constant range with
    // noise is monotone over three readings one time in three.
    if abs(last.range_m - first.range_m) < MIN_CHAIN_RISE_M {
        return None;
    }
    let (a, b) = (first.at, last.at);
    part.iter()
        .all(|p| {
            off_line_m(a, b, p.at) <= EDGE_LINE_TOLERANCE_M
                && sin_incidence(a, b, p) >= min_sin_incidence
        })
        .then_some(part)
}

/// The cells this sweep's chains have stepped.
type ChainCells = Vec<(u16, u16), MAX_CHAIN_CELLS_PER_SWEEP>;

impl<const W: usize, const E: usize> Mission<W, E> {
    /// Mark the walls heard at their cone edges in this standing sweep (see the module docs);
    /// returns the chains marked.
    pub(super) fn mark_edge_chains(&mut self) -> u16 {
        let robot = self.config.robot;
        if !robot.sonar_beam {
            return 0;
        }
        let beam_rad = robot.sonar_beam_half_angle_deg.max(0.0) * (core::f32::consts::PI / 180.0);
        if beam_rad.is_nan() || beam_rad <= 0.0 {
            return 0;
        }
        let g = *self.grid.geometry();
        // The narrowest way the robot can use (as the gap visits count it, `verdict`), and the
        // widest space left between two edge points: less than the body's diameter.
        let way_m = 2.0 * robot.planning_radius_m + 2.0 * g.resolution_m();
        let min_sin_incidence = (2.0 * EDGE_LINE_TOLERANCE_M / way_m).min(1.0);
        let max_spacing_m = 2.0 * robot.physical_radius_m();
        let n = self.readings.len();
        let mut chain: Vec<EdgePoint, MAX_CHAIN_READINGS> = Vec::new();
        let mut side = None;
        let mut chains = 0u16;
        let mut stepped = ChainCells::new();
        for i in 0..=n {
            let point = toward_foot(self.readings.as_slice(), i).and_then(|toward| {
                let readings = self.readings.as_slice();
                let r = readings.get(i)?;
                let j = match toward {
                    Toward::Before => i.checked_sub(1)?,
                    Toward::After => i + 1,
                };
                let nearer = readings.get(j)?;
                // The nearer neighbour's side, in this reading's frame.
                let apart_rad = nearer.neck_angle_rad
                    + wrap_angle_rad(nearer.pose.heading_rad - r.pose.heading_rad)
                    - r.neck_angle_rad;
                let edge_rad = r.neck_angle_rad + beam_rad.copysign(apart_rad);
                let range_m = r.range_m?;
                let at = hit_to_world(r.pose, robot.sonar_offset_m, edge_rad, range_m);
                at.is_finite().then_some((
                    toward,
                    EdgePoint {
                        at,
                        ray_rad: r.pose.heading_rad + edge_rad,
                        range_m,
                        sonar: r.pose.point_ahead(robot.sonar_offset_m),
                        index: i,
                    },
                ))
            });
            let goes_on = match (&point, chain.last()) {
                (Some((toward, p)), Some(last)) => {
                    // The range rises away from the foot by more than the sonar moved (a
                    // body turning in place carries it round): a point reflector heard by
                    // a turning sonar drifts, a wall rises.
                    let moved_m = hypot(p.sonar.x_m - last.sonar.x_m, p.sonar.y_m - last.sonar.y_m);
                    let rise_m = match toward {
                        Toward::Before => p.range_m - last.range_m,
                        Toward::After => last.range_m - p.range_m,
                    };
                    side == Some(*toward)
                        && !chain.is_full()
                        && rise_m > moved_m + MIN_RISE_PER_READING_M
                        && hypot(p.at.x_m - last.at.x_m, p.at.y_m - last.at.y_m) < max_spacing_m
                }
                _ => false,
            };
            if !goes_on {
                let wall = side.and_then(|toward| {
                    wall_part(&chain, toward, min_sin_incidence)
                        .filter(|part| self.foot_heard(part, toward, beam_rad))
                });
                if let Some(part) = wall {
                    self.mark_chain(part, &mut stepped);
                    chains = chains.saturating_add(1);
                }
                chain.clear();
                side = None;
            }
            if let Some((toward, p)) = point {
                side = Some(toward);
                let _ = chain.push(p);
            }
        }
        chains
    }

    /// Was the foot of the chain's line heard: walking from the chain towards the foot, the
    /// ranges fall (within the line tolerance) until a reading whose cone holds the foot and
    /// whose range is the line's distance from its sonar (within twice the tolerance)? A wall
    /// heard at its cone edges is heard at its foot too, in a region of constant depth beside
    /// them; a chain whose edge rays a silent wall (met beyond the incidence limit) cut off, so
    /// that its echoes came from farther inside the cone, has no such foot. At most
    /// [`MAX_CHAIN_READINGS`] readings are walked.
    fn foot_heard(&self, chain: &[EdgePoint], toward: Toward, beam_rad: f32) -> bool {
        let (Some(first), Some(last)) = (chain.first(), chain.last()) else {
            return false;
        };
        let (a, b) = (first.at, last.at);
        let (dx, dy) = (b.x_m - a.x_m, b.y_m - a.y_m);
        let length_m = hypot(dx, dy);
        if length_m < 1.0e-6 {
            return false;
        }
        let (ux, uy) = (dx / length_m, dy / length_m);
        let readings = self.readings.as_slice();
        let robot = self.config.robot;
        let (mut index, mut previous_m) = match toward {
            Toward::Before => (first.index.checked_sub(1), first.range_m),
            Toward::After => (Some(last.index + 1), last.range_m),
        };
        for _ in 0..MAX_CHAIN_READINGS {
            let Some(r) = index.and_then(|j| readings.get(j)) else {
                return false;
            };
            let Some(range_m) = r.range_m else {
                return false;
            };
            if range_m > previous_m + EDGE_LINE_TOLERANCE_M {
                return false;
            }
            let sonar = r.pose.point_ahead(robot.sonar_offset_m);
            // The foot: the line's point nearest this sonar.
            let t_m = (sonar.x_m - a.x_m) * ux + (sonar.y_m - a.y_m) * uy;
            let (fx, fy) = (a.x_m + t_m * ux - sonar.x_m, a.y_m + t_m * uy - sonar.y_m);
            let axis_rad = r.pose.heading_rad + r.neck_angle_rad;
            let foot_rad = crate::math::atan2(fy, fx);
            if abs(wrap_angle_rad(foot_rad - axis_rad)) <= beam_rad {
                return abs(range_m - hypot(fx, fy)) <= 2.0 * EDGE_LINE_TOLERANCE_M;
            }
            previous_m = range_m;
            index = match (toward, index) {
                (Toward::Before, Some(j)) => j.checked_sub(1),
                (Toward::After, Some(j)) => Some(j + 1),
                (_, None) => None,
            };
        }
        false
    }

    /// The cells of a wall chain, its points joined in order: one evidence step each (unless a
    /// reflector of this sweep already stepped it), and its points grown into the grid and
    /// kept as the sweep's hits (the host redraws the robot's map from them; the growth
    /// covers the space between two points, less than a body's diameter).
    fn mark_chain(&mut self, chain: &[EdgePoint], stepped: &mut ChainCells) {
        let g = *self.grid.geometry();
        let e = self.expansion_cells;
        let mut previous: Option<(i32, i32)> = None;
        for p in chain {
            let Some(cell) = g.cell_xy_of(p.at) else {
                previous = None;
                continue;
            };
            let from = previous.unwrap_or(cell);
            for (k, (x, y)) in BresenhamLine::new(from, cell).enumerate() {
                if k == 0 && previous.is_some() {
                    continue; // the previous segment's last cell
                }
                // One viewpoint, one step: not where a reflector or another chain of this
                // sweep stepped already.
                // Cells off the map (negative) take no evidence.
                let (Ok(kx), Ok(ky)) = (u16::try_from(x), u16::try_from(y)) else {
                    continue;
                };
                let key = (kx, ky);
                if !stepped.contains(&key)
                    && !self.seen_this_sweep(Some((x, y)))
                    && stepped.push(key).is_ok()
                {
                    self.step_occupied(x, y);
                }
            }
            if !self.seen_this_sweep(Some(cell)) {
                mark_point_m(&mut self.grid, centre(&g, cell.0, cell.1), e);
                let _ = self.hits.push(p.at);
            }
            previous = Some(cell);
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::boxed::Box;

    use super::super::evidence::CellEvidence;
    use super::super::tests::{beam_evidence_config, geometry, sweep_east_from};
    use super::super::Mission400;
    use crate::geom::PointM;

    /// The x of a wall about 1.2 m ahead of a sonar at (1 + offset, y) facing east, in the
    /// middle of a cell column (so that its points fall in one column).
    fn wall_x_m(offset_m: f32) -> f32 {
        let res_m = geometry().resolution_m();
        ((1.0 + offset_m + 1.2) / res_m).floor() * res_m + 0.5 * res_m
    }

    /// The range a reading at `bearing_rad` from `sonar` hears off a wall along x = `wall_x_m`
    /// that echoes at any angle, with no wall between `gap` (y from, y to): the nearest point
    /// of the wall in its cone, from 61 rays across it (as the simulated beam casts them).
    fn heard_m(
        sonar: PointM,
        wall_x_m: f32,
        beam_rad: f32,
        gap: (f32, f32),
        bearing_rad: f32,
    ) -> Option<f32> {
        (0..=60)
            .filter_map(|k| {
                let ray_rad = bearing_rad - beam_rad + 2.0 * beam_rad * k as f32 / 60.0;
                let t_m = (wall_x_m - sonar.x_m) / ray_rad.cos();
                let y_m = sonar.y_m + t_m * ray_rad.sin();
                (t_m > 0.0 && !(y_m > gap.0 && y_m < gap.1)).then_some(t_m)
            })
            .reduce(f32::min)
    }

    #[test]
    fn a_wall_heard_at_its_cone_edges_is_marked_along_it_and_confirmed_from_a_second_place() {
        let c = beam_evidence_config();
        let beam_rad = c.robot.sonar_beam_half_angle_deg.to_radians();
        let offset_m = c.robot.sonar_offset_m;
        let wall_m = wall_x_m(offset_m);
        let sonar = |y_m: f32| PointM::new(1.0 + offset_m, y_m);
        let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
        sweep_east_from(&mut m, 3.0, |b| {
            heard_m(sonar(3.0), wall_m, beam_rad, (0.0, 0.0), b)
        });
        // One chain on each side of the foot.
        assert_eq!(m.mark_edge_chains(), 2);
        // The wall is marked without a hole from 0.15 m to 0.45 m off the foot, on both sides.
        for k in 0..=6 {
            for side in [-1.0f32, 1.0] {
                let at = PointM::new(wall_m, 3.0 + side * (0.15 + 0.05 * k as f32));
                assert_ne!(m.evidence.get(at), CellEvidence::Unknown, "{at:?}");
                assert_ne!(m.evidence.get(at), CellEvidence::Free, "{at:?}");
            }
        }
        let point = PointM::new(wall_m, 3.45);
        assert_eq!(m.evidence.get(point), CellEvidence::Tentative);
        // The same sweep again from the same place is no second viewpoint: nothing confirmed.
        sweep_east_from(&mut m, 3.0, |b| {
            heard_m(sonar(3.0), wall_m, beam_rad, (0.0, 0.0), b)
        });
        m.mark_edge_chains();
        assert_eq!(m.evidence.get(point), CellEvidence::Tentative);
        // From 0.25 m further along, a second viewpoint hears the same stretch: confirmed.
        sweep_east_from(&mut m, 3.25, |b| {
            heard_m(sonar(3.25), wall_m, beam_rad, (0.0, 0.0), b)
        });
        m.mark_edge_chains();
        assert_eq!(m.evidence.get(point), CellEvidence::Confirmed);
    }

    #[test]
    fn a_doorway_in_the_wall_stays_open() {
        let c = beam_evidence_config();
        let beam_rad = c.robot.sonar_beam_half_angle_deg.to_radians();
        let offset_m = c.robot.sonar_offset_m;
        let wall_m = wall_x_m(offset_m);
        let sonar = |y_m: f32| PointM::new(1.0 + offset_m, y_m);
        // A 0.6 m doorway from 0.2 m to 0.8 m off the first foot, seen from both sides.
        let gap = (3.2, 3.8);
        let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
        for y_m in [3.0, 4.0, 3.5] {
            sweep_east_from(&mut m, y_m, |b| {
                heard_m(sonar(y_m), wall_m, beam_rad, gap, b)
            });
            m.mark_edge_chains();
        }
        let res_m = geometry().resolution_m();
        let mut y_m = gap.0 + res_m;
        while y_m < gap.1 - res_m {
            for dx_m in [-res_m, 0.0, res_m] {
                let at = PointM::new(wall_m + dx_m, y_m);
                assert_ne!(m.evidence.get(at), CellEvidence::Confirmed, "{at:?}");
            }
            y_m += res_m;
        }
    }

    #[test]
    fn a_post_heard_by_drifting_readings_is_no_wall() {
        // A post 2 m ahead heard by every reading whose cone holds it, each 2 mm farther than
        // the last (a sonar carried round by a turning body): monotone, but an arc, not a line.
        let c = beam_evidence_config();
        let beam_rad = c.robot.sonar_beam_half_angle_deg.to_radians();
        let mut m = Box::new(Mission400::new(c, geometry()).unwrap());
        sweep_east_from(&mut m, 4.0, |b| {
            (b.abs() <= beam_rad).then(|| 2.0 + 0.002 * (b.to_degrees() / 1.8))
        });
        assert_eq!(m.mark_edge_chains(), 0);
    }
}
