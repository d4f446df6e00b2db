//! Host adapter of the potential field (`twil_core::classic::potential`, seed 003 §III.3,
//! seed 004 §2.2.3): runs the grid descent with [`PotentialParams::DEFAULT`] and the `.par`
//! robot radius, and fills a [`Run`]: the path as far as the descent got, `local_minimum` when
//! it stopped short of the goal (the stop cell is drawn as a node), and the parameters used.
//!
//! Memory: the distance transform (site 4 bytes, distance 2 bytes a cell) and the path buffer
//! (4 bytes a cell); the field itself is never stored.

use anyhow::Context;
use twil_core::classic::potential::{self, DescentStatus, PlanStatusCode, PotentialParams};

use super::voronoi::cells_to_path;
use super::{polyline_length_m, Method, Run, Status};
use crate::planning::World;

/// Run the potential field on `world`.
pub fn run(world: &World) -> anyhow::Result<Run> {
    let g = *world.grid.geometry();
    let n = g.cell_count();
    let params = PotentialParams {
        robot_radius_m: world.params.robot_radius_m,
        ..PotentialParams::DEFAULT
    };
    let mut sites = vec![0u32; n];
    let mut dist = vec![0u16; n];
    let mut path = vec![0u32; n];
    let report = potential::descend(
        &world.grid,
        &world.raw,
        world.params.start,
        world.params.goal,
        &params,
        &mut sites,
        &mut dist,
        &mut path,
    )
    .context("planner potential")?;
    let status = match report.status {
        DescentStatus::Reached => Status::Found,
        DescentStatus::LocalMinimum => Status::LocalMinimum,
        DescentStatus::NotStarted(PlanStatusCode::StartBlocked) => Status::StartBlocked,
        DescentStatus::NotStarted(PlanStatusCode::GoalBlocked) => Status::GoalBlocked,
        DescentStatus::NotStarted(PlanStatusCode::OutOfBounds) => Status::OutOfBounds,
    };
    let mut run = Run::empty(Method::Potential, status, "descent steps");
    let cells = &path[..report.path_cells];
    match status {
        Status::Found => run.path = cells_to_path(world, cells),
        Status::LocalMinimum => {
            // As far as it got: the exact start, then the cells' centres.
            let mut pts = vec![world.params.start];
            pts.extend(
                cells
                    .iter()
                    .skip(1)
                    .map(|&c| g.center_of(g.cell_at(c as usize))),
            );
            run.path = super::voronoi::simplify_collinear(&pts);
            if let Some(&last) = run.path.last() {
                run.overlay.nodes.push(last);
                run.overlay.node_label = "local minimum";
            }
        }
        _ => {}
    }
    run.length_m = polyline_length_m(&run.path);
    run.expanded = report.steps as u64;
    run.memory_bytes = n * (4 + 2 + 4);
    let e = &mut run.extra;
    e.insert("attraction".into(), params.attraction.into());
    e.insert("repulsion".into(), params.repulsion.into());
    e.insert("influence_m".into(), params.influence_m.into());
    e.insert("steps".into(), report.steps.into());
    e.insert("evaluations".into(), report.evaluations.into());
    Ok(run)
}
