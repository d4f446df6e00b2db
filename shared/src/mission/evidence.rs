//! The evidence map: two bits per cell (unknown, free evidence, tentative occupied, confirmed
//! occupied), kept as two bit planes of the grid's geometry.
//!
//! Why: a 1-bit "seen" grid cannot tell an echo's reflector from silence, nor take a mark back.
//! An ultrasonic reading says three different things (seed 003 §IV.5 marks only the first):
//! a reflector somewhere on the arc of its range (one per run of constant depth: Leonard &
//! Durrant-Whyte 1991), space nearer than the echo along the beam that sound crossed (Moravec &
//! Elfes 1985, Elfes 1989), and for silence, only that nothing *facing* the sensor was in the
//! cone: a smooth wall met obliquely is silent (Kuc & Siegel 1987), so silence marks nothing
//! here. The counts are a two-bit saturating counter in the spirit of HIMM (Borenstein & Koren
//! 1991: +3/−1 on 0..15, the axis cell only), cut to what the mission decides with.
//!
//! | `free` | `occupied` | state                                                     |
//! |--------|------------|-----------------------------------------------------------|
//! | 0      | 0          | [`CellEvidence::Unknown`]                                  |
//! | 1      | 0          | [`CellEvidence::Free`] (a ray crossed it before its echo)  |
//! | 0      | 1          | [`CellEvidence::Tentative`] (one reflector, or a suspect)  |
//! | 1      | 1          | [`CellEvidence::Confirmed`] (a reflector marked twice)     |
//!
//! Transitions: a reflector moves unknown/free → tentative → confirmed (saturates); free
//! evidence moves unknown → free and takes a tentative mark back (tentative → free); a confirmed
//! mark is never taken back by it (a specular wall crossed obliquely by a later beam is silent,
//! so a ray's free evidence through it proves nothing about it). A cell a standing sweep
//! vouches for by the Thales rule ([`EvidenceMap::observe_vouched_xy`]) steps down one state
//! instead: confirmed → tentative → free (a wall through it would have echoed). A suspect ([`EvidenceMap::suspect_xy`])
//! only turns unknown into tentative.
//!
//! Memory: `2 × W` words, 22 500 B at 300 × 300 (the 1-bit "seen" grid it replaces was half
//! that). Every operation is O(1) per cell except [`EvidenceMap::mark_ray_free`], bounded by the
//! ray's length in cells, and [`EvidenceMap::reset`], one pass over the planes.
//! Measured: see `docs/mapping.md`.

use crate::geom::PointM;
use crate::grid::{Grid, GridError, GridGeometry};
use crate::raster::BresenhamLine;

/// What the map holds about one cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellEvidence {
    /// Nothing heard about it (also every cell off the map).
    Unknown,
    /// A ray crossed it before its echo.
    Free,
    /// One reflector was placed here (or it is a suspect): the planner avoids it, a later ray
    /// crossing it takes it back.
    Tentative,
    /// Reflectors placed here by two readings or more: kept.
    Confirmed,
}

/// What an observation did to a cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Change {
    /// The cell's state did not change.
    None,
    /// It changed, and its occupancy (tentative or confirmed vs not) did not.
    Evidence,
    /// It became occupied (tentative) from unknown or free.
    NowOccupied,
    /// A tentative mark was taken back: it is free now.
    TakenBack,
}

/// Two bit planes of one geometry: see the module documentation.
///
/// The free plane holds `W` words, the occupied plane `E`: a build that has no room for the
/// second plane (the MCU's, see `docs/mapping.md`) gives it one word, and then the map holds
/// free evidence only ([`EvidenceMap::has_occupied_plane`] is `false`).
#[derive(Clone, Debug, PartialEq)]
pub struct EvidenceMap<const W: usize, const E: usize = W> {
    free: Grid<W>,
    occupied: Grid<E>,
}

/// The geometry a plane of `E` words gets when `geometry` does not fit it.
const PLACEHOLDER: GridGeometry = match GridGeometry::new(1, 1, crate::grid::DEFAULT_RESOLUTION_M) {
    Ok(g) => g,
    Err(_) => panic!("a 1 x 1 geometry is valid"),
};

impl<const W: usize, const E: usize> EvidenceMap<W, E> {
    /// An all-unknown map, as a `const fn` (for `static`s on the MCU). Errors as [`Grid::new`]
    /// when the free plane cannot hold `geometry`; an occupied plane too small for it is left
    /// out (see [`EvidenceMap::has_occupied_plane`]).
    pub const fn new_const(geometry: GridGeometry) -> Result<Self, GridError> {
        let free = match Grid::<W>::new_const(geometry) {
            Ok(g) => g,
            Err(e) => return Err(e),
        };
        let occupied = match Grid::<E>::new_const(geometry) {
            Ok(g) => g,
            Err(_) => match Grid::<E>::new_const(PLACEHOLDER) {
                Ok(g) => g,
                Err(e) => return Err(e),
            },
        };
        Ok(Self { free, occupied })
    }

    /// All unknown, on `geometry`. On error (the free plane cannot hold it) nothing changes.
    pub fn reset(&mut self, geometry: GridGeometry) -> Result<(), GridError> {
        self.free.reset(geometry)?;
        if self.occupied.reset(geometry).is_err() {
            self.occupied.reset(PLACEHOLDER)?;
        }
        Ok(())
    }

    /// Cells the occupied plane can hold.
    pub const OCCUPIED_CAPACITY_CELLS: usize = Grid::<E>::CAPACITY_CELLS;

    /// The map has its occupied plane (it holds the free plane's geometry).
    pub fn has_occupied_plane(&self) -> bool {
        self.occupied.geometry() == self.free.geometry()
    }

    /// The geometry of both planes.
    pub fn geometry(&self) -> &GridGeometry {
        self.free.geometry()
    }

    /// The free-evidence plane (bit set: some ray crossed the cell before its echo). Without the
    /// evidence map this plane is the mission's "seen" grid.
    pub fn free_plane(&self) -> &Grid<W> {
        &self.free
    }

    /// The free-evidence plane, to write (the mission's "seen" marking without the evidence map).
    pub fn free_plane_mut(&mut self) -> &mut Grid<W> {
        &mut self.free
    }

    /// The state of the cell at (`x`, `y`); off the map [`CellEvidence::Unknown`].
    pub fn get_xy(&self, x: i32, y: i32) -> CellEvidence {
        if !self.geometry().contains_xy(x, y) {
            return CellEvidence::Unknown;
        }
        match (self.free.is_occupied_xy(x, y), self.is_occupied_xy(x, y)) {
            (false, false) => CellEvidence::Unknown,
            (true, false) => CellEvidence::Free,
            (false, true) => CellEvidence::Tentative,
            (true, true) => CellEvidence::Confirmed,
        }
    }

    /// The state of the cell holding `p` (off the map: unknown).
    pub fn get(&self, p: PointM) -> CellEvidence {
        match self.geometry().cell_xy_on_map(p) {
            Some((x, y)) => self.get_xy(x, y),
            None => CellEvidence::Unknown,
        }
    }

    /// Free evidence, and only that (not occupied).
    pub fn is_free_xy(&self, x: i32, y: i32) -> bool {
        self.get_xy(x, y) == CellEvidence::Free
    }

    /// Tentative or confirmed occupied.
    pub fn is_occupied_xy(&self, x: i32, y: i32) -> bool {
        self.has_occupied_plane()
            && self.geometry().contains_xy(x, y)
            && self.occupied.is_occupied_xy(x, y)
    }

    fn set(&mut self, x: i32, y: i32, state: CellEvidence) {
        let (f, o) = match state {
            CellEvidence::Unknown => (false, false),
            CellEvidence::Free => (true, false),
            CellEvidence::Tentative => (false, true),
            CellEvidence::Confirmed => (true, true),
        };
        self.free.set_xy(x, y, f);
        if self.has_occupied_plane() {
            self.occupied.set_xy(x, y, o);
        }
    }

    /// A reflector at (`x`, `y`): unknown or free → tentative, tentative → confirmed. Without
    /// the occupied plane nothing changes.
    pub fn observe_occupied_xy(&mut self, x: i32, y: i32) -> Change {
        if !self.geometry().contains_xy(x, y) || !self.has_occupied_plane() {
            return Change::None;
        }
        let (next, change) = match self.get_xy(x, y) {
            CellEvidence::Unknown | CellEvidence::Free => {
                (CellEvidence::Tentative, Change::NowOccupied)
            }
            CellEvidence::Tentative => (CellEvidence::Confirmed, Change::Evidence),
            CellEvidence::Confirmed => return Change::None,
        };
        self.set(x, y, next);
        change
    }

    /// A reflector that may lie elsewhere on its arc (not a region of constant depth):
    /// unknown or free → tentative; a mark already there stays as it is (it never confirms).
    pub fn observe_arc_xy(&mut self, x: i32, y: i32) -> Change {
        match self.get_xy(x, y) {
            CellEvidence::Unknown | CellEvidence::Free => self.observe_occupied_xy(x, y),
            CellEvidence::Tentative | CellEvidence::Confirmed => Change::None,
        }
    }

    /// A ray crossed (`x`, `y`) before its echo: unknown → free, tentative → free (taken
    /// back); a confirmed mark stays.
    pub fn observe_free_xy(&mut self, x: i32, y: i32) -> Change {
        if !self.geometry().contains_xy(x, y) {
            return Change::None;
        }
        match self.get_xy(x, y) {
            CellEvidence::Unknown => {
                self.set(x, y, CellEvidence::Free);
                Change::Evidence
            }
            CellEvidence::Tentative => {
                self.set(x, y, CellEvidence::Free);
                Change::TakenBack
            }
            CellEvidence::Free | CellEvidence::Confirmed => Change::None,
        }
    }

    /// A standing sweep vouches for (`x`, `y`) by the Thales rule (`swept`): a wall through
    /// the cell would have echoed, so every mark there is one step less sure (HIMM's −1):
    /// confirmed → tentative, tentative → free (taken back), unknown → free.
    pub fn observe_vouched_xy(&mut self, x: i32, y: i32) -> Change {
        if self.get_xy(x, y) == CellEvidence::Confirmed {
            self.set(x, y, CellEvidence::Tentative);
            return Change::Evidence;
        }
        self.observe_free_xy(x, y)
    }

    /// A cell of an obstacle known a priori (`Mission::add_known_polygon`): confirmed, as if
    /// heard from two places, so that a proof or a take-back, which redraw the grid from the
    /// marks, keep it. Off the map, or without the occupied plane, nothing changes.
    pub fn known_xy(&mut self, x: i32, y: i32) -> Change {
        if !self.geometry().contains_xy(x, y) || !self.has_occupied_plane() {
            return Change::None;
        }
        let before = self.get_xy(x, y);
        self.set(x, y, CellEvidence::Confirmed);
        match before {
            CellEvidence::Confirmed => Change::None,
            CellEvidence::Tentative => Change::Evidence,
            _ => Change::NowOccupied,
        }
    }

    /// A cell nobody vouched for beside the robot: unknown → tentative; anything else stays.
    pub fn suspect_xy(&mut self, x: i32, y: i32) -> Change {
        if self.get_xy(x, y) != CellEvidence::Unknown
            || !self.geometry().contains_xy(x, y)
            || !self.has_occupied_plane()
        {
            return Change::None;
        }
        self.set(x, y, CellEvidence::Tentative);
        Change::NowOccupied
    }

    /// Free evidence along the ray from `from` to `to` (both ends included, off-map cells
    /// skipped), and call `taken_back` with each cell whose tentative mark it took back.
    /// Bounded by the ray's length in cells; a ray starting off the map marks nothing.
    pub fn mark_ray_free(
        &mut self,
        from: PointM,
        to: PointM,
        mut taken_back: impl FnMut(i32, i32),
    ) -> u32 {
        let g = *self.geometry();
        let (Some(a), Some(b)) = (g.cell_xy_of(from), g.cell_xy_of(to)) else {
            return 0;
        };
        if !g.contains_xy(a.0, a.1) {
            return 0;
        }
        let mut cells = 0;
        for (x, y) in BresenhamLine::new(a, b) {
            if !g.contains_xy(x, y) {
                break;
            }
            cells += 1;
            if self.observe_free_xy(x, y) == Change::TakenBack {
                taken_back(x, y);
            }
        }
        cells
    }

    /// Count of cells in each state, for reports: (free, tentative, confirmed). One pass.
    pub fn counts(&self) -> (u32, u32, u32) {
        let g = *self.geometry();
        let (mut free, mut tentative, mut confirmed) = (0, 0, 0);
        for i in 0..g.cell_count() {
            let occupied = self.has_occupied_plane() && self.occupied.bit(i);
            match (self.free.bit(i), occupied) {
                (true, false) => free += 1,
                (false, true) => tentative += 1,
                (true, true) => confirmed += 1,
                (false, false) => {}
            }
        }
        (free, tentative, confirmed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::words_for_cells;

    type Map = EvidenceMap<{ words_for_cells(40 * 40) }>;

    fn map() -> Map {
        Map::new_const(GridGeometry::new(40, 40, 0.05).unwrap()).unwrap()
    }

    #[test]
    fn a_reflector_is_tentative_then_confirmed_and_saturates() {
        let mut m = map();
        assert_eq!(m.get_xy(3, 4), CellEvidence::Unknown);
        assert_eq!(m.observe_occupied_xy(3, 4), Change::NowOccupied);
        assert_eq!(m.get_xy(3, 4), CellEvidence::Tentative);
        assert_eq!(m.observe_occupied_xy(3, 4), Change::Evidence);
        assert_eq!(m.get_xy(3, 4), CellEvidence::Confirmed);
        assert_eq!(m.observe_occupied_xy(3, 4), Change::None);
        assert_eq!(m.get_xy(3, 4), CellEvidence::Confirmed);
        assert!(m.is_occupied_xy(3, 4));
        assert_eq!(m.get_xy(3, 5), CellEvidence::Unknown, "one cell only");
    }

    #[test]
    fn free_evidence_takes_a_tentative_mark_back_but_not_a_confirmed_one() {
        let mut m = map();
        m.observe_occupied_xy(10, 0);
        m.observe_occupied_xy(20, 0);
        m.observe_occupied_xy(20, 0);
        let mut back = heapless::Vec::<(i32, i32), 4>::new();
        let from = PointM::new(0.025, 0.025);
        let to = PointM::new(1.325, 0.025); // cells 0..=26 of row 0
        let cells = m.mark_ray_free(from, to, |x, y| {
            let _ = back.push((x, y));
        });
        assert_eq!(cells, 27);
        assert_eq!(back.as_slice(), &[(10, 0)]);
        assert_eq!(m.get_xy(10, 0), CellEvidence::Free);
        assert_eq!(m.get_xy(20, 0), CellEvidence::Confirmed);
        assert_eq!(m.get_xy(26, 0), CellEvidence::Free);
        assert_eq!(m.get_xy(27, 0), CellEvidence::Unknown);
        // A reflector on free evidence is tentative again.
        assert_eq!(m.observe_occupied_xy(10, 0), Change::NowOccupied);
        assert_eq!(m.counts(), (25, 1, 1));
    }

    #[test]
    fn an_arc_marks_but_never_confirms() {
        let mut m = map();
        assert_eq!(m.observe_arc_xy(7, 7), Change::NowOccupied);
        assert_eq!(m.observe_arc_xy(7, 7), Change::None);
        assert_eq!(m.get_xy(7, 7), CellEvidence::Tentative);
        assert_eq!(m.observe_occupied_xy(7, 7), Change::Evidence);
        assert_eq!(m.get_xy(7, 7), CellEvidence::Confirmed);
    }

    #[test]
    fn vouching_steps_a_confirmed_mark_down_one_state_at_a_time() {
        let mut m = map();
        m.observe_occupied_xy(5, 5);
        m.observe_occupied_xy(5, 5);
        assert_eq!(m.observe_vouched_xy(5, 5), Change::Evidence);
        assert_eq!(m.get_xy(5, 5), CellEvidence::Tentative);
        assert_eq!(m.observe_vouched_xy(5, 5), Change::TakenBack);
        assert_eq!(m.get_xy(5, 5), CellEvidence::Free);
        assert_eq!(m.observe_vouched_xy(6, 5), Change::Evidence);
        assert_eq!(m.get_xy(6, 5), CellEvidence::Free);
    }

    #[test]
    fn a_suspect_only_fills_the_unknown() {
        let mut m = map();
        m.observe_free_xy(1, 1);
        assert_eq!(m.suspect_xy(1, 1), Change::None);
        assert_eq!(m.get_xy(1, 1), CellEvidence::Free);
        assert_eq!(m.suspect_xy(2, 1), Change::NowOccupied);
        assert_eq!(m.get_xy(2, 1), CellEvidence::Tentative);
        // Suspects are tentative: free evidence takes them back.
        assert_eq!(m.observe_free_xy(2, 1), Change::TakenBack);
    }

    #[test]
    fn off_the_map_is_unknown_and_never_written() {
        let mut m = map();
        assert_eq!(m.observe_occupied_xy(-1, 0), Change::None);
        assert_eq!(m.observe_free_xy(40, 0), Change::None);
        assert_eq!(m.suspect_xy(0, 40), Change::None);
        assert_eq!(m.get_xy(-1, 0), CellEvidence::Unknown);
        assert_eq!(m.get(PointM::new(-5.0, 0.0)), CellEvidence::Unknown);
        assert_eq!(m.counts(), (0, 0, 0));
    }

    #[test]
    fn a_ray_is_bounded_by_the_map_whatever_its_ends() {
        let mut m = map();
        // From off the map: nothing.
        let n = m.mark_ray_free(PointM::new(-1.0, 0.0), PointM::new(1.0, 0.0), |_, _| {});
        assert_eq!(n, 0);
        // To a point a kilometre away: stops at the map's edge (40 cells).
        let n = m.mark_ray_free(PointM::new(0.025, 0.5), PointM::new(1000.0, 0.5), |_, _| {});
        assert_eq!(n, 40);
        // Non-finite ends mark nothing.
        let n = m.mark_ray_free(PointM::new(f32::NAN, 0.5), PointM::new(1.0, 0.5), |_, _| {});
        assert_eq!(n, 0);
    }

    #[test]
    fn without_room_for_the_occupied_plane_it_holds_free_evidence_only() {
        let mut m = EvidenceMap::<{ words_for_cells(40 * 40) }, 1>::new_const(
            GridGeometry::new(40, 40, 0.05).unwrap(),
        )
        .unwrap();
        assert!(!m.has_occupied_plane());
        assert_eq!(m.observe_occupied_xy(3, 3), Change::None);
        assert_eq!(m.get_xy(3, 3), CellEvidence::Unknown);
        assert_eq!(m.observe_free_xy(3, 3), Change::Evidence);
        assert_eq!(m.get_xy(3, 3), CellEvidence::Free);
        assert!(map().has_occupied_plane());
    }

    #[test]
    fn reset_checks_the_capacity_and_clears() {
        let mut m = map();
        m.observe_occupied_xy(1, 1);
        let too_big = GridGeometry::new(100, 100, 0.05).unwrap();
        assert!(m.reset(too_big).is_err());
        assert_eq!(
            m.get_xy(1, 1),
            CellEvidence::Tentative,
            "an error changes nothing"
        );
        m.reset(GridGeometry::new(20, 20, 0.05).unwrap()).unwrap();
        assert_eq!(m.get_xy(1, 1), CellEvidence::Unknown);
        assert_eq!(m.geometry().width(), 20);
    }
}
