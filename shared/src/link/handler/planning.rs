//! The planning requests: `Plan` runs the planner on the map (timed with the caller's clock,
//! for the status), `ReadPath` reads its path back in chunks.
//!
//! The path stays in the planner ([`Planner::path_cells`]); the handler only keeps its
//! length, so a device needs no second path buffer.

use heapless::Vec;

use super::{Handler, LastPlan};
use crate::geom::PointM;
use crate::grid::Grid;
use crate::link::message::{ErrorCode, ErrorReply, PlanSummary, Reply, PATH_CHUNK_POINTS};
use crate::plan::{PlanError, Planner, PlannerKind};

impl<const GRID_WORDS: usize> Handler<GRID_WORDS> {
    /// `Plan`: run the planner from `start` to `goal`.
    pub(super) fn plan<const SCRATCH_WORDS: usize, const QUEUE: usize>(
        &mut self,
        kind: PlannerKind,
        start: PointM,
        goal: PointM,
        grid: &Grid<GRID_WORDS>,
        planner: &mut Planner<SCRATCH_WORDS, QUEUE>,
        clock: &mut impl FnMut() -> u64,
    ) -> Result<Reply, ErrorReply> {
        // A NaN or infinite point is a bad argument (field 1 start, 2 goal of `Plan`), not a
        // point off the map: refused before the planner runs, so the last plan's figures stay.
        for (field, point) in [(1, start), (2, goal)] {
            if !point.is_finite() {
                return Err(ErrorReply::new(ErrorCode::BadArgument, field, 0));
            }
        }
        let before = clock();
        let result = planner.plan_at(kind, grid, start, goal);
        let after = clock();
        self.last_plan = LastPlan {
            instructions: after.saturating_sub(before),
            expanded: planner.last_report().map(|r| r.expanded).unwrap_or(0),
            queue_peak: planner.queue_peak(),
        };
        // A planner error keeps the last path in the planner (and its count here).
        let report = result.map_err(plan_error)?;
        self.path_points = if report.status == crate::plan::PlanStatus::Found {
            planner.path_cells().len().min(u16::MAX as usize) as u16
        } else {
            0
        };
        Ok(Reply::Plan(PlanSummary {
            status: report.status,
            expanded: report.expanded,
            cost: report.cost,
            length_m: report.length_m,
            points: self.path_points,
            mcu_instructions: after.saturating_sub(before),
        }))
    }

    /// `ReadPath`: up to [`PATH_CHUNK_POINTS`] points of the last path from `offset`.
    pub(super) fn read_path<const SCRATCH_WORDS: usize, const QUEUE: usize>(
        &self,
        offset: u16,
        grid: &Grid<GRID_WORDS>,
        planner: &Planner<SCRATCH_WORDS, QUEUE>,
    ) -> Result<Reply, ErrorReply> {
        let cells = planner.path_cells();
        let total = (self.path_points as usize).min(cells.len());
        let start = offset as usize;
        let chunk = cells
            .get(start..total)
            .ok_or(ErrorReply::new(
                ErrorCode::OutOfRange,
                start as u32,
                total as u32,
            ))?
            .iter()
            .take(PATH_CHUNK_POINTS);
        let geometry = grid.geometry();
        let mut points = Vec::new();
        for c in chunk {
            // at most PATH_CHUNK_POINTS: cannot fail
            let _ = points.push(geometry.center_of(*c));
        }
        Ok(Reply::PathChunk {
            offset,
            total: total as u16,
            points,
        })
    }
}

/// A planner capacity error as the link reports it.
fn plan_error(e: PlanError) -> ErrorReply {
    let (value, limit, detail) = match e {
        PlanError::ScratchTooSmall { cells, capacity } => (cells, capacity, 0),
        PlanError::QueueFull { capacity } => (capacity.saturating_add(1), capacity, 1),
        PlanError::PathFull { capacity } => (capacity.saturating_add(1), capacity, 2),
    };
    ErrorReply {
        code: ErrorCode::PlannerCapacity,
        value,
        limit,
        detail,
    }
}
