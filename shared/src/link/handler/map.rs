//! The map requests: `SetParams`, `ClearMap`, `ObstacleChunk` (a polygon uploaded in
//! chunks, marked when it closes), `WriteMap` and `ReadMap`, and the budget that keeps marking
//! a bounded request.
//!
//! Every request checks everything before it changes anything, so that a refused request
//! leaves the map, the stored obstacles and the polygon being uploaded as they were
//! ([`upload_chunk`] is shared with the robot's world upload, `RobotDevice`).

use heapless::Vec;

use super::Handler;
use crate::geom::PointM;
use crate::grid::{words_for_cells, Grid, GridError, GridGeometry};
use crate::link::message::{ErrorCode, ErrorReply, MapParams, Reply, MAP_CHUNK_WORDS};
use crate::raster::{mark_polygon, Work};
use crate::world::{PolygonSet, PolygonSetError, MAX_VERTICES};

use super::MAX_ROBOT_RADIUS_M;

/// Most map rows one request may have the marker visit: stored obstacle vertices × map height
/// (each edge visits at most every row of the map, see [`crate::raster::edge_work_bound`]).
///
/// Marking costs about 140 instructions per row visited on the MCU (`cargo xtask mcu-bench`,
/// tests/firmware_requests.rs), so this bound keeps the worst marking request near 43 M
/// instructions (0.26 s at 168 MHz): far inside the 1 s the watchdog gives the mission task, and
/// exactly what the seed's 300 × 300 map with [`MAX_VERTICES`] vertices needs. A tall map holds
/// fewer vertices (21 × 4 096 cells: 75), instead of a request that keeps the device busy for
/// seconds (it measured 613 M instructions, 3.6 s, before this bound).
pub const MAX_MARKING_ROWS: u32 = MAX_VERTICES as u32 * 300;

/// Rows the marker may visit for `vertices` obstacle vertices on a map `height_cells` tall.
pub fn marking_rows(vertices: usize, height_cells: u32) -> u32 {
    u32::try_from(vertices)
        .unwrap_or(u32::MAX)
        .saturating_mul(height_cells)
}

/// [`ErrorCode::MarkingBudget`] unless `vertices` on a map `height_cells` tall are within
/// [`MAX_MARKING_ROWS`].
fn check_marking_budget(vertices: usize, height_cells: u32) -> Result<(), ErrorReply> {
    let rows = marking_rows(vertices, height_cells);
    if rows > MAX_MARKING_ROWS {
        return Err(ErrorReply::new(
            ErrorCode::MarkingBudget,
            rows,
            MAX_MARKING_ROWS,
        ));
    }
    Ok(())
}

impl<const GRID_WORDS: usize> Handler<GRID_WORDS> {
    /// `ClearMap`: forget every obstacle, the polygon being uploaded and the path.
    pub(super) fn clear_map(&mut self, grid: &mut Grid<GRID_WORDS>) -> Result<Reply, ErrorReply> {
        self.obstacles.clear();
        self.pending.clear();
        self.path_points = 0;
        grid.clear();
        Ok(Reply::Ack)
    }

    pub(super) fn set_params(
        &mut self,
        params: MapParams,
        grid: &mut Grid<GRID_WORDS>,
    ) -> Result<(), ErrorReply> {
        let r = params.robot_radius_m;
        if !(r.is_finite() && (0.0..=MAX_ROBOT_RADIUS_M).contains(&r)) {
            return Err(ErrorReply::new(ErrorCode::BadArgument, 3, 0));
        }
        let geometry = GridGeometry::new(
            params.width_cells as u32,
            params.height_cells as u32,
            params.resolution_m,
        )
        .map_err(|e| match e {
            GridError::BadResolution { .. } => ErrorReply::new(ErrorCode::BadArgument, 2, 0),
            _ => ErrorReply::new(
                ErrorCode::BadGeometry,
                params.width_cells as u32,
                params.height_cells as u32,
            ),
        })?;
        // Re-marking every stored obstacle must stay a bounded request (checked before the
        // grid changes: a refused request changes nothing).
        check_marking_budget(self.obstacles.vertex_count(), u32::from(geometry.height()))?;
        grid.reset(geometry).map_err(|e| match e {
            GridError::CapacityExceeded { cells, capacity } => {
                ErrorReply::new(ErrorCode::GridCapacity, cells, capacity)
            }
            _ => ErrorReply::new(
                ErrorCode::BadGeometry,
                params.width_cells as u32,
                params.height_cells as u32,
            ),
        })?;
        self.params = params;
        self.path_points = 0;
        self.last_marking_work = self.mark_all(grid);
        Ok(())
    }

    /// Mark every stored obstacle on `grid` with the current radius. The work is at most
    /// [`crate::raster::polygon_work_bound`] for the stored vertices: the map's, not the
    /// coordinates' nor the radius'.
    pub fn mark_all(&self, grid: &mut Grid<GRID_WORDS>) -> Work {
        let half = grid.geometry().expansion_cells(self.params.robot_radius_m);
        self.obstacles
            .iter()
            .map(|polygon| mark_polygon(grid, polygon, half))
            .sum()
    }

    /// Marking work of the last `SetParams` or polygon-closing `ObstacleChunk`.
    pub fn last_marking_work(&self) -> Work {
        self.last_marking_work
    }

    /// `ObstacleChunk`: add the chunk; a closing chunk stores the polygon and marks it.
    pub(super) fn obstacle_chunk(
        &mut self,
        first_vertex: u16,
        vertices: &[PointM],
        last: bool,
        grid: &mut Grid<GRID_WORDS>,
    ) -> Result<Reply, ErrorReply> {
        let already = if first_vertex == 0 {
            0
        } else {
            self.pending.len()
        };
        if first_vertex as usize == already {
            check_marking_budget(
                self.obstacles.vertex_count() + already + vertices.len(),
                u32::from(grid.geometry().height()),
            )?;
        }
        if upload_chunk(
            &mut self.obstacles,
            &mut self.pending,
            first_vertex,
            vertices,
            last,
        )? {
            // The polygon closed: it is the last one stored.
            let half = grid.geometry().expansion_cells(self.params.robot_radius_m);
            if let Some(polygon) = self
                .obstacles
                .polygon(self.obstacles.len().saturating_sub(1))
            {
                self.last_marking_work = mark_polygon(grid, polygon, half);
            }
            self.path_points = 0;
        }
        Ok(Reply::Obstacles {
            polygons: self.obstacles.len() as u16,
            vertices: self.obstacles.vertex_count() as u16,
            pending_vertices: self.pending.len() as u16,
        })
    }

    /// `WriteMap`: overwrite the map's words from `offset_words` (the host's own map).
    pub(super) fn write_map(
        &mut self,
        offset_words: u32,
        words: &[u32],
        grid: &mut Grid<GRID_WORDS>,
    ) -> Result<Reply, ErrorReply> {
        let used = words_for_cells(grid.geometry().cell_count());
        grid.write_words(offset_words as usize, words)
            .map_err(|_| {
                ErrorReply::new(
                    ErrorCode::OutOfRange,
                    offset_words.saturating_add(words.len() as u32),
                    used as u32,
                )
            })?;
        self.path_points = 0;
        Ok(Reply::Ack)
    }

    /// `ReadMap`: up to [`MAP_CHUNK_WORDS`] words of the map from `offset_words`.
    pub(super) fn read_map(
        &self,
        offset_words: u32,
        grid: &Grid<GRID_WORDS>,
    ) -> Result<Reply, ErrorReply> {
        let all = grid.words();
        let start = offset_words as usize;
        let chunk = all
            .get(start..)
            .ok_or(ErrorReply::new(
                ErrorCode::OutOfRange,
                start as u32,
                all.len() as u32,
            ))?
            .iter()
            .take(MAP_CHUNK_WORDS);
        let mut words = Vec::new();
        for w in chunk {
            let _ = words.push(*w); // at most MAP_CHUNK_WORDS: cannot fail
        }
        let g = grid.geometry();
        Ok(Reply::MapChunk {
            offset_words,
            total_words: all.len() as u32,
            width_cells: g.width(),
            height_cells: g.height(),
            words,
        })
    }
}

/// Add one chunk of a polygon being uploaded to `pending`; the `last` chunk stores the polygon
/// in `obstacles` and returns `true`. Checks everything first: on error nothing changes.
pub(crate) fn upload_chunk<const V: usize, const P: usize, const N: usize>(
    obstacles: &mut PolygonSet<V, P>,
    pending: &mut Vec<PointM, N>,
    first_vertex: u16,
    vertices: &[PointM],
    last: bool,
) -> Result<bool, ErrorReply> {
    let already = if first_vertex == 0 { 0 } else { pending.len() };
    if first_vertex as usize != already {
        return Err(ErrorReply::new(
            ErrorCode::ChunkOutOfOrder,
            first_vertex as u32,
            already as u32,
        ));
    }
    if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
        return Err(ErrorReply::new(
            ErrorCode::BadArgument,
            first_vertex as u32 + i as u32,
            0,
        ));
    }
    let needed = already + vertices.len();
    let left = V.saturating_sub(obstacles.vertex_count()).min(N);
    if needed > left {
        return Err(ErrorReply::new(
            ErrorCode::TooManyVertices,
            needed as u32,
            left as u32,
        ));
    }
    if obstacles.len() >= P {
        return Err(ErrorReply::new(
            ErrorCode::TooManyPolygons,
            obstacles.len() as u32 + 1,
            P as u32,
        ));
    }
    if last && needed == 0 {
        return Err(ErrorReply::new(ErrorCode::EmptyPolygon, 0, 0));
    }
    // All checks passed: from here nothing can fail.
    if first_vertex == 0 {
        pending.clear();
    }
    let _ = pending.extend_from_slice(vertices);
    if !last {
        return Ok(false);
    }
    match obstacles.push(pending) {
        Ok(()) => {}
        Err(PolygonSetError::TooManyPolygons { capacity }) => {
            return Err(ErrorReply::new(
                ErrorCode::TooManyPolygons,
                capacity as u32 + 1,
                capacity as u32,
            ))
        }
        Err(PolygonSetError::TooManyVertices { capacity_left }) => {
            return Err(ErrorReply::new(
                ErrorCode::TooManyVertices,
                pending.len() as u32,
                capacity_left as u32,
            ))
        }
        Err(PolygonSetError::Empty) => return Err(ErrorReply::new(ErrorCode::EmptyPolygon, 0, 0)),
    }
    pending.clear();
    Ok(true)
}
