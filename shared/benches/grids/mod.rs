//! The 300 × 300 benchmark grids (open floor, 20 % random obstacles, a maze), shared by the
//! planner benchmark (`shared/benches/planners.rs`) and the instruction count under QEMU
//! (`tests/firmware_qemu.rs`, `cargo xtask mcu-bench`) so that both measure the same grids.
#![allow(dead_code)]

use twil_core::geom::Cell;
use twil_core::grid::{Grid300, GridGeometry};

/// Side of every benchmark grid, cells.
pub const SIDE: u16 = 300;

/// Deterministic xorshift64 generator (no `rand` crate needed).
pub struct Rng(pub u64);
impl Rng {
    /// The next pseudo-random number.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// An empty 300 × 300 grid of 0.05 m cells.
pub fn empty() -> Grid300 {
    Grid300::new(GridGeometry::new(SIDE as u32, SIDE as u32, 0.05).expect("geometry"))
        .expect("grid")
}

/// Open floor, start and goal near opposite corners.
pub fn open_case() -> (Grid300, Cell, Cell) {
    (empty(), Cell::new(3, 5), Cell::new(296, 291))
}

/// 20 % of the cells occupied at random (seeded); the seed is advanced until `connected` says
/// start and goal are joined, so the case always has a path.
pub fn random_case(
    mut connected: impl FnMut(&Grid300, Cell, Cell) -> bool,
) -> (Grid300, Cell, Cell) {
    let (s, t) = (Cell::new(2, 2), Cell::new(297, 297));
    for seed in 1u64.. {
        let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ seed);
        let mut g = empty();
        for y in 0..SIDE as i32 {
            for x in 0..SIDE as i32 {
                if rng.next_u64() % 100 < 20 {
                    g.set_xy(x, y, true);
                }
            }
        }
        g.set(s, false);
        g.set(t, false);
        if connected(&g, s, t) {
            return (g, s, t);
        }
    }
    unreachable!("some seed gives a connected grid")
}

/// A perfect maze (recursive backtracker, seeded) with 1-cell corridors: rooms on odd
/// coordinates, walls elsewhere. Start and goal are opposite corners.
pub fn maze_case() -> (Grid300, Cell, Cell) {
    let mut g = empty();
    for y in 0..SIDE as i32 {
        g.fill_row(y, 0, SIDE as i32 - 1);
    }
    let rooms = (SIDE as i32 - 1) / 2; // 149 x 149 rooms
    let mut visited = vec![false; (rooms * rooms) as usize];
    let mut stack = vec![(0i32, 0i32)];
    visited[0] = true;
    g.set_xy(1, 1, false);
    let mut rng = Rng(0xDEAD_BEEF_CAFE_F00D);
    while let Some(&(rx, ry)) = stack.last() {
        let mut options = [(0i32, 0i32); 4];
        let mut n = 0;
        for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
            let (nx, ny) = (rx + dx, ry + dy);
            if nx >= 0
                && ny >= 0
                && nx < rooms
                && ny < rooms
                && !visited[(ny * rooms + nx) as usize]
            {
                options[n] = (dx, dy);
                n += 1;
            }
        }
        if n == 0 {
            stack.pop();
            continue;
        }
        let (dx, dy) = options[(rng.next_u64() % n as u64) as usize];
        let (nx, ny) = (rx + dx, ry + dy);
        visited[(ny * rooms + nx) as usize] = true;
        g.set_xy(2 * rx + 1 + dx, 2 * ry + 1 + dy, false);
        g.set_xy(2 * nx + 1, 2 * ny + 1, false);
        stack.push((nx, ny));
    }
    let far = (2 * (rooms - 1) + 1) as u16;
    (g, Cell::new(1, 1), Cell::new(far, far))
}
