//! Potential field planner (seed 003 §III.3, seed 004 §2.2.3): an attractive paraboloid
//! centred on the goal plus a repulsive term from the obstacles, descended from the start.
//!
//! `U(c) = ½·k_a·ρ(c)² + ½·η·(1/d(c) − 1/d₀)²` when `d(c) < d₀` (Khatib's form), where `ρ` is the
//! distance from the cell's centre to the goal cell's centre and `d` the clearance of the robot's body:
//! the distance transform of the polygon outlines ([`super::distance`]) less the robot radius.
//! Cells of the grown grid are forbidden (infinite potential).
//!
//! Design:
//! - **Steepest descent over the 8 neighbours on the grid**, as seed 003 describes the method
//!   (a fine regular grid of configurations with a potential value each), rather than gradient
//!   steps in continuous coordinates: no step size to tune, no oscillation across a valley, and
//!   a local minimum is exact and cheap to recognise: a cell none of whose free neighbours is
//!   lower. Because every step strictly lowers `U`, no cell is visited twice, so the descent
//!   ends within the free cell count (and `max_steps`, the path buffer) whatever the input.
//! - **An honest local minimum**: stopping anywhere but the goal's cell is
//!   [`DescentStatus::LocalMinimum`], with the path as far as it got.
//! - The field is evaluated on the fly for the 8 neighbours of the current cell only; the
//!   per-cell memory is the distance transform's (site and distance).

use super::distance::{self, DistanceError, DIST_PER_CELL, NEIGHBOURS_8};
use super::voronoi::endpoints;
use crate::geom::PointM;
use crate::grid::Grid;
use crate::plan::PlanStatus;

/// The field's constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PotentialParams {
    /// `k_a`, the paraboloid's gain, 1/m² (units of `U` are arbitrary).
    pub attraction: f32,
    /// `η`, the repulsive gain, m².
    pub repulsion: f32,
    /// `d₀`, the clearance beyond which obstacles do not repel, metres.
    pub influence_m: f32,
    /// The robot's radius, metres (clearance = distance − radius).
    pub robot_radius_m: f32,
}

impl PotentialParams {
    /// The defaults `twil` uses: a unit paraboloid; repulsion that outweighs the pull of a goal
    /// 15 m away at 0.1 m of clearance and fades at 1 m.
    pub const DEFAULT: PotentialParams = PotentialParams {
        attraction: 1.0,
        repulsion: 0.02,
        influence_m: 1.0,
        robot_radius_m: 0.4,
    };
}

/// How a descent ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DescentStatus {
    /// It reached the goal's cell.
    Reached,
    /// It stopped at a cell with no lower free neighbour that is not the goal's.
    LocalMinimum,
    /// Start or goal blocked or off the map (before any step).
    NotStarted(PlanStatusCode),
}

/// [`PlanStatus`] without its derives, for [`DescentStatus::NotStarted`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanStatusCode {
    /// The start cell is occupied.
    StartBlocked,
    /// The goal cell is occupied.
    GoalBlocked,
    /// Start or goal off the map.
    OutOfBounds,
}

/// Why a descent could not run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PotentialError {
    /// A buffer is too short.
    Distance(DistanceError),
    /// `grid` and `raw` have different geometries.
    GeometryMismatch,
    /// The descent had more steps than the path buffer holds.
    PathTooLong,
}

impl core::fmt::Display for PotentialError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            PotentialError::Distance(e) => write!(f, "{e}"),
            PotentialError::GeometryMismatch => {
                write!(f, "the grid and the raw map have different geometries")
            }
            PotentialError::PathTooLong => {
                write!(f, "the descent has more steps than the path buffer holds")
            }
        }
    }
}

impl core::error::Error for PotentialError {}

impl From<DistanceError> for PotentialError {
    fn from(e: DistanceError) -> Self {
        PotentialError::Distance(e)
    }
}

/// What a descent did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DescentReport {
    /// How it ended.
    pub status: DescentStatus,
    /// Cells written to the path (start cell first).
    pub path_cells: usize,
    /// Descent steps taken (`path_cells − 1`).
    pub steps: usize,
    /// Potential values evaluated.
    pub evaluations: u64,
    /// The potential where it stopped.
    pub final_potential: f32,
}

/// The potential of cell `(x, y)` whose distance to the nearest obstacle is `dist` (1/16 cell).
pub fn potential(
    params: &PotentialParams,
    resolution_m: f32,
    x: i32,
    y: i32,
    dist: u16,
    goal: PointM,
) -> f32 {
    let cx = (x as f32 + 0.5) * resolution_m;
    let cy = (y as f32 + 0.5) * resolution_m;
    let rho2 = (cx - goal.x_m) * (cx - goal.x_m) + (cy - goal.y_m) * (cy - goal.y_m);
    let mut u = 0.5 * params.attraction * rho2;
    let d = dist as f32 / DIST_PER_CELL as f32 * resolution_m - params.robot_radius_m;
    if d < params.influence_m {
        // A body touching the obstacle is as repelled as one a thousandth of a cell away.
        let d = d.max(resolution_m * 1e-3);
        let r = 1.0 / d - 1.0 / params.influence_m;
        u += 0.5 * params.repulsion * r * r;
    }
    u
}

/// Descend from `start` towards `goal` on `grid` (grown obstacles), with distances from
/// `raw`'s outlines and the map border. `sites` and `dist` are the distance transform's
/// buffers, `path` receives the visited cells' indices.
#[allow(clippy::too_many_arguments)]
pub fn descend<const W: usize>(
    grid: &Grid<W>,
    raw: &Grid<W>,
    start: PointM,
    goal: PointM,
    params: &PotentialParams,
    sites: &mut [u32],
    dist: &mut [u16],
    path: &mut [u32],
) -> Result<DescentReport, PotentialError> {
    let geo = *grid.geometry();
    if *raw.geometry() != geo {
        return Err(PotentialError::GeometryMismatch);
    }
    let mut report = DescentReport {
        status: DescentStatus::LocalMinimum,
        path_cells: 0,
        steps: 0,
        evaluations: 0,
        final_potential: 0.0,
    };
    let (s, t) = match endpoints(grid, start, goal) {
        Ok(st) => st,
        Err(status) => {
            report.status = DescentStatus::NotStarted(match status {
                PlanStatus::StartBlocked => PlanStatusCode::StartBlocked,
                PlanStatus::GoalBlocked => PlanStatusCode::GoalBlocked,
                _ => PlanStatusCode::OutOfBounds,
            });
            return Ok(report);
        }
    };
    distance::nearest_sites(raw, true, sites)?;
    distance::distances(&geo, sites, dist)?;
    // Attract to the goal cell's centre, so that the goal cell is the paraboloid's unique
    // lowest cell (a goal on a cell corner would otherwise tie four cells).
    let goal = geo.center_of(t);
    let w = geo.width() as i32;
    let res = geo.resolution_m();
    let field = |x: i32, y: i32| -> Option<f32> {
        if grid.is_occupied_xy(x, y) {
            return None;
        }
        let d = *dist.get((y * w + x) as usize)?;
        Some(potential(params, res, x, y, d, goal))
    };
    let (mut x, mut y) = (s.x as i32, s.y as i32);
    let mut u = field(x, y).unwrap_or(f32::INFINITY);
    report.evaluations = 1;
    loop {
        *path
            .get_mut(report.path_cells)
            .ok_or(PotentialError::PathTooLong)? = (y * w + x) as u32;
        report.path_cells += 1;
        if (x, y) == (t.x as i32, t.y as i32) {
            report.status = DescentStatus::Reached;
            break;
        }
        let mut best: Option<(f32, i32, i32)> = None;
        for (dx, dy) in NEIGHBOURS_8 {
            // A diagonal step may not cut the corner of an occupied cell.
            if dx != 0
                && dy != 0
                && (grid.is_occupied_xy(x + dx, y) || grid.is_occupied_xy(x, y + dy))
            {
                continue;
            }
            report.evaluations += 1;
            if let Some(v) = field(x + dx, y + dy) {
                if best.is_none_or(|b| v < b.0) {
                    best = Some((v, x + dx, y + dy));
                }
            }
        }
        match best {
            Some((v, nx, ny)) if v < u => {
                (x, y, u) = (nx, ny, v);
                report.steps += 1;
            }
            _ => {
                report.status = DescentStatus::LocalMinimum;
                break;
            }
        }
    }
    report.final_potential = u;
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{words_for_cells, GridGeometry};
    use crate::raster::mark_polygon;

    type G = Grid<{ words_for_cells(200 * 200) }>;

    fn world(polys: &[&[(f32, f32)]], expansion: u16) -> (G, G) {
        let geo = GridGeometry::new(200, 200, 0.05).unwrap();
        let (mut grid, mut raw) = (G::new(geo).unwrap(), G::new(geo).unwrap());
        for p in polys {
            let pts: heapless::Vec<PointM, 8> = p.iter().map(|&(x, y)| PointM::new(x, y)).collect();
            mark_polygon(&mut grid, &pts, expansion);
            mark_polygon(&mut raw, &pts, 0);
        }
        (grid, raw)
    }

    fn run(
        polys: &[&[(f32, f32)]],
        start: (f32, f32),
        goal: (f32, f32),
    ) -> (DescentReport, [u32; 40000]) {
        let (grid, raw) = world(polys, 6);
        let mut sites = [0u32; 40000];
        let mut dist = [0u16; 40000];
        let mut path = [0u32; 40000];
        let params = PotentialParams {
            robot_radius_m: 0.3,
            ..PotentialParams::DEFAULT
        };
        let r = descend(
            &grid,
            &raw,
            PointM::new(start.0, start.1),
            PointM::new(goal.0, goal.1),
            &params,
            &mut sites,
            &mut dist,
            &mut path,
        )
        .unwrap();
        (r, path)
    }

    #[test]
    fn reaches_the_goal_past_a_block_beside_the_line() {
        // The block is within the influence distance of the straight line, not across it.
        let block: &[(f32, f32)] = &[(4.5, 5.6), (5.5, 5.6), (5.5, 7.5), (4.5, 7.5)];
        let (r, path) = run(&[block], (2.0, 5.0), (8.0, 5.0));
        assert_eq!(r.status, DescentStatus::Reached);
        assert_eq!(r.steps + 1, r.path_cells);
        // Strict descent: no cell twice.
        let cells = &path[..r.path_cells];
        for (i, a) in cells.iter().enumerate() {
            assert!(!cells[i + 1..].contains(a));
        }
        // The repulsion bent the path away from the block (below the line y = 5 m).
        assert!(cells.iter().any(|&c| c / 200 < 99));
    }

    #[test]
    fn stops_in_a_u_shaped_trap() {
        // A U open to the left; the goal lies behind its closed side.
        let top: &[(f32, f32)] = &[(3.0, 6.8), (6.0, 6.8), (6.0, 7.0), (3.0, 7.0)];
        let bottom: &[(f32, f32)] = &[(3.0, 3.0), (6.0, 3.0), (6.0, 3.2), (3.0, 3.2)];
        let back: &[(f32, f32)] = &[(5.8, 3.0), (6.0, 3.0), (6.0, 7.0), (5.8, 7.0)];
        let (r, path) = run(&[top, bottom, back], (4.0, 5.0), (9.0, 5.0));
        assert_eq!(r.status, DescentStatus::LocalMinimum);
        // It stopped inside the U, against its back.
        let last = path[r.path_cells - 1];
        let (x, y) = (last % 200, last / 200);
        assert!(
            (80..116).contains(&x) && (64..140).contains(&y),
            "({x},{y})"
        );
    }

    #[test]
    fn blocked_start_does_not_descend() {
        let block: &[(f32, f32)] = &[(1.0, 1.0), (3.0, 1.0), (3.0, 3.0), (1.0, 3.0)];
        let (r, _) = run(&[block], (1.0, 2.0), (8.0, 5.0));
        assert_eq!(
            r.status,
            DescentStatus::NotStarted(PlanStatusCode::StartBlocked)
        );
        assert_eq!(r.path_cells, 0);
    }
}
