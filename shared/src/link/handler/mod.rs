//! The device side of the link: the state a request acts on, and one reply per request.
//!
//! [`Handler`] owns everything in fixed-size fields: the grid (`GRID_WORDS` words), the stored
//! obstacles ([`Obstacles`]), the polygon being uploaded (at most [`MAX_PENDING_VERTICES`]) and
//! the last path. [`Handler::new`] is a `const fn`, so the firmware places the whole handler in a
//! `static` at compile time. The planner (its scratch and queue, the largest block of memory) is
//! passed to each call instead of owned, so that the firmware can place it in another memory
//! region than the rest (the STM32F405 has 112 + 16 KiB of SRAM and a separate 64 KiB CCM).
//!
//! [`Device`] puts a [`FrameDecoder`](crate::link::frame::FrameDecoder) in front: [`Device::receive`] takes bytes as they arrive
//! and emits one encoded reply frame per request frame (and one error frame per undecodable
//! frame).
//!
//! Time is not read here: the caller passes a clock (`FnMut() -> u64`, in instructions) that the
//! handler reads just before and just after the planner runs. The firmware reads SysTick; the
//! host passes `|| 0`.
//!
//! ## Files
//!
//! - this file: the state, the dispatch of each request, the session requests (`Hello`,
//!   `Ping`, `Status`) and the answer to a damaged frame;
//! - `map.rs`: the map requests (parameters, obstacle uploads, map words) and the marking
//!   budget;
//! - `planning.rs`: `Plan` and `ReadPath`;
//! - `device.rs`: [`Device`], the handler behind a frame decoder.

use heapless::Vec;

use super::frame::{FrameFault, MAX_FRAME_BYTES};
use super::message::*;
use crate::geom::PointM;
use crate::grid::{Grid, GridGeometry, DEFAULT_RESOLUTION_M};
use crate::plan::Planner;
use crate::raster::Work;
use crate::world::{Obstacles, MAX_POLYGONS, MAX_VERTICES};

mod device;
mod map;
mod planning;
#[cfg(test)]
mod tests;

pub use device::Device;
pub(crate) use map::upload_chunk;
pub use map::{marking_rows, MAX_MARKING_ROWS};

/// Vertices of one polygon being uploaded (a larger polygon is refused with
/// [`ErrorCode::TooManyVertices`]).
pub const MAX_PENDING_VERTICES: usize = 256;

/// Largest robot radius accepted by `SetParams`, metres (as the `.par` reader).
pub const MAX_ROBOT_RADIUS_M: f32 = 10.0;

/// The request handler and all the state it acts on.
pub struct Handler<const GRID_WORDS: usize> {
    info: DeviceInfo,
    params: MapParams,
    obstacles: Obstacles,
    pending: Vec<PointM, MAX_PENDING_VERTICES>,
    path_points: u16,
    requests: u32,
    frame_errors: u32,
    rx_dropped_bytes: u32,
    last_plan: LastPlan,
    reset_cause: crate::failsafe::ResetCause,
    /// Instructions of the last request handled (see [`DeviceStatus::last_request_instructions`]).
    last_request_instructions: u64,
    /// Marking work of the last request that marked obstacles (see [`crate::raster::Work`]).
    last_marking_work: Work,
}

/// What the status reports about the last plan.
#[derive(Clone, Copy, Default)]
struct LastPlan {
    instructions: u64,
    expanded: u32,
    queue_peak: u32,
}

impl<const GRID_WORDS: usize> Handler<GRID_WORDS> {
    /// Compile-time check: the grid holds at least one cell.
    const GRID_NOT_EMPTY: () = assert!(GRID_WORDS > 0, "the grid needs at least one word");

    /// A handler with an empty map: the seed's 300 x 300 cells of 0.05 m when the grid holds
    /// them, else one cell of 0.05 m (send `SetParams`). The capacities in `info` are filled in
    /// here; the caller sets `build` and `static_ram_bytes`.
    pub const fn new(info: DeviceInfo) -> Self {
        #[allow(clippy::let_unit_value)]
        let () = Self::GRID_NOT_EMPTY;
        let params = Self::initial_params();
        let mut info = info;
        info.protocol_version = PROTOCOL_VERSION;
        info.grid_capacity_cells = Grid::<GRID_WORDS>::CAPACITY_CELLS as u32;
        info.max_polygons = MAX_POLYGONS as u16;
        info.max_vertices = MAX_VERTICES as u16;
        info.max_frame_bytes = MAX_FRAME_BYTES as u16;
        Self {
            info,
            params,
            obstacles: Obstacles::new(),
            pending: Vec::new(),
            path_points: 0,
            requests: 0,
            frame_errors: 0,
            rx_dropped_bytes: 0,
            last_plan: LastPlan {
                instructions: 0,
                expanded: 0,
                queue_peak: 0,
            },
            reset_cause: crate::failsafe::ResetCause::Unknown,
            last_request_instructions: 0,
            last_marking_work: 0,
        }
    }

    /// The map a new handler starts with: the seed's 300 x 300 cells of 0.05 m when
    /// `Grid<GRID_WORDS>` holds them, else one cell of 0.05 m (send `SetParams`).
    pub const fn initial_params() -> MapParams {
        let side =
            if Grid::<GRID_WORDS>::CAPACITY_CELLS >= GridGeometry::seed_default().cell_count() {
                crate::grid::DEFAULT_SIDE_CELLS
            } else {
                1
            };
        MapParams {
            width_cells: side,
            height_cells: side,
            resolution_m: DEFAULT_RESOLUTION_M,
            robot_radius_m: 0.0,
        }
    }

    /// An empty map of [`Handler::initial_params`] (what a new handler's map must be).
    // Neither arm can be taken: `initial_params` picks the default side only when the grid holds
    // it, else one cell. A `const fn` cannot return the error to a `static` initializer; in
    // const evaluation (the firmware's statics) a panic would be a compile error.
    #[allow(clippy::panic)]
    pub const fn initial_grid() -> Grid<GRID_WORDS> {
        let p = Self::initial_params();
        let geometry =
            match GridGeometry::new(p.width_cells as u32, p.height_cells as u32, p.resolution_m) {
                Ok(g) => g,
                Err(_) => panic!("the initial geometry is valid"),
            };
        match Grid::new_const(geometry) {
            Ok(g) => g,
            Err(_) => panic!("the grid holds the initial geometry"),
        }
    }

    /// What [`Request::Hello`] answers.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }

    /// Set the statically allocated RAM reported by [`Request::Hello`] (firmware only).
    pub fn set_static_ram_bytes(&mut self, bytes: u32) {
        self.info.static_ram_bytes = bytes;
    }

    /// Set why the chip last reset (read at boot; `Status` reports it).
    pub fn set_reset_cause(&mut self, cause: crate::failsafe::ResetCause) {
        self.reset_cause = cause;
    }

    /// Set which program this is.
    pub fn set_build(&mut self, build: Build) {
        self.info.build = build;
    }

    /// The stored obstacles.
    pub fn obstacles(&self) -> &Obstacles {
        &self.obstacles
    }

    /// Vertices of the last path planned (0 unless the last plan found one); the path itself
    /// is the planner's [`Planner::path_cells`], read back by [`Request::ReadPath`].
    pub fn path_points(&self) -> u16 {
        self.path_points
    }

    /// The vertices of the polygon being uploaded (`ObstacleChunk`s not closed yet).
    pub fn pending(&self) -> &[PointM] {
        &self.pending
    }

    /// Forget the last path (the planner has been used for something else since).
    pub fn forget_path(&mut self) {
        self.path_points = 0;
    }

    /// Count bytes the receiver had to drop (reported by [`Request::Status`]).
    pub fn note_rx_dropped(&mut self, bytes: u32) {
        self.rx_dropped_bytes = self.rx_dropped_bytes.saturating_add(bytes);
    }

    /// Answer a frame that could not be decoded (counted in the status).
    pub fn fault_reply(&mut self, fault: FrameFault) -> (Option<u16>, Reply) {
        self.frame_errors = self.frame_errors.saturating_add(1);
        self.requests = self.requests.saturating_add(1);
        let max = MAX_FRAME_BYTES as u32;
        let (seq, error) = match fault {
            FrameFault::BadFrame => (None, ErrorReply::new(ErrorCode::BadFrame, 0, 0)),
            FrameFault::BadCrc => (None, ErrorReply::new(ErrorCode::BadCrc, 0, 0)),
            FrameFault::TooLong => (None, ErrorReply::new(ErrorCode::FrameTooLong, max, max)),
            FrameFault::BadMessage { seq } => (seq, ErrorReply::new(ErrorCode::BadMessage, 0, 0)),
        };
        (seq, Reply::Error(error))
    }

    /// Answer one request. `clock` returns a count of instructions (or cycles); it is read just
    /// before and after the planner runs. A request that fails answers [`Reply::Error`] and
    /// changes nothing.
    pub fn handle<const SCRATCH_WORDS: usize, const QUEUE: usize>(
        &mut self,
        request: &Request,
        grid: &mut Grid<GRID_WORDS>,
        planner: &mut Planner<SCRATCH_WORDS, QUEUE>,
        clock: &mut impl FnMut() -> u64,
    ) -> Reply {
        self.requests = self.requests.saturating_add(1);
        self.info.planner_capacity_cells = Planner::<SCRATCH_WORDS, QUEUE>::CAPACITY_CELLS as u32;
        let before = clock();
        let reply = match self.try_handle(request, grid, planner, clock) {
            Ok(reply) => reply,
            Err(error) => Reply::Error(error),
        };
        self.last_request_instructions = clock().saturating_sub(before);
        reply
    }

    fn try_handle<const SCRATCH_WORDS: usize, const QUEUE: usize>(
        &mut self,
        request: &Request,
        grid: &mut Grid<GRID_WORDS>,
        planner: &mut Planner<SCRATCH_WORDS, QUEUE>,
        clock: &mut impl FnMut() -> u64,
    ) -> Result<Reply, ErrorReply> {
        match request {
            Request::Hello { protocol_version } => {
                if *protocol_version != PROTOCOL_VERSION {
                    return Err(ErrorReply::new(
                        ErrorCode::VersionMismatch,
                        *protocol_version as u32,
                        PROTOCOL_VERSION as u32,
                    ));
                }
                Ok(Reply::Hello(self.info))
            }
            Request::Ping { nonce } => Ok(Reply::Pong { nonce: *nonce }),
            Request::SetParams(params) => self.set_params(*params, grid).map(|()| Reply::Ack),
            Request::ClearMap => self.clear_map(grid),
            Request::ObstacleChunk {
                first_vertex,
                vertices,
                last,
            } => self.obstacle_chunk(*first_vertex, vertices, *last, grid),
            Request::WriteMap {
                offset_words,
                words,
            } => self.write_map(*offset_words, words, grid),
            Request::Plan { kind, start, goal } => {
                self.plan(*kind, *start, *goal, grid, planner, clock)
            }
            Request::ReadPath { offset } => self.read_path(*offset, grid, planner),
            Request::ReadMap { offset_words } => self.read_map(*offset_words, grid),
            Request::Status => Ok(Reply::Status(self.status(grid))),
            // Missions and the real world are [`crate::link::RobotDevice`]'s; a plain handler (the
            // planning service) does not run them.
            Request::SetMission(_)
            | Request::WorldChunk { .. }
            | Request::ClearWorld
            | Request::StartMission
            | Request::PauseMission
            | Request::ResumeMission
            | Request::AbortMission
            | Request::EmergencyStop
            | Request::ClearEmergencyStop
            | Request::MissionStatus
            | Request::ParamList { .. }
            | Request::ParamGet { .. }
            | Request::ParamSet { .. }
            | Request::SelfTest
            | Request::SelfTestReport => Err(ErrorReply::new(ErrorCode::NotOnThisBuild, 0, 0)),
        }
    }

    /// The device state counters (`grid`: the map).
    pub fn status(&self, grid: &Grid<GRID_WORDS>) -> DeviceStatus {
        DeviceStatus {
            params: self.params,
            polygons: self.obstacles.len() as u16,
            vertices: self.obstacles.vertex_count() as u16,
            pending_vertices: self.pending.len() as u16,
            occupied_cells: grid.count_occupied() as u32,
            requests: self.requests,
            frame_errors: self.frame_errors,
            rx_dropped_bytes: self.rx_dropped_bytes,
            last_plan_instructions: self.last_plan.instructions,
            last_plan_expanded: self.last_plan.expanded,
            last_plan_queue_peak: self.last_plan.queue_peak,
            reset_cause: self.reset_cause,
            last_request_instructions: self.last_request_instructions,
        }
    }

    /// The map parameters in use.
    pub fn params(&self) -> MapParams {
        self.params
    }

    /// Count a request answered outside [`Handler::handle`] (by [`crate::link::RobotDevice`]).
    pub fn count_request(&mut self) {
        self.requests = self.requests.saturating_add(1);
    }
}
