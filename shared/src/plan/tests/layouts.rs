//! The framed layout of the scratch against the flat one (windows, nibbles, whole searches).

use super::*;
use crate::grid::GridGeometry;
use crate::plan::layout::{CellMap, Flat, Framed, Interior, NIBBLE_WINDOWS};
use crate::plan::planner::Layout;

/// The framed copy of the map (rows padded to whole words, a frame of blocked cells): every
/// cell's nibble is the map's, and every cell's three windows, on the border too, equal the
/// flat layout's (which reads off-map neighbours as blocked), for all widths around the
/// multiples of 8 where the padding changes, with garbage in the scratch beforehand.
#[test]
fn framed_map_reads_like_the_flat_one() {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    for w in (1..=40u32).chain([63, 64, 65]) {
        for h in [1u32, 2, 3, 7, 24] {
            if (w * h) as usize > SMALL_CELLS {
                continue;
            }
            let seed = next_random(&mut state);
            let g: SmallGrid = random_grid(w, h, 30, seed);
            let geometry = *g.geometry();
            let mut framed_words = std::vec![0xA5A5_A5A5u32; SMALL_FRAMED];
            let mut framed = Framed::<SMALL_FRAMED>::new(&mut framed_words, &geometry).unwrap();
            framed.copy_map(&g);
            let mut p = Box::new(SmallPlanner::new());
            p.scratch.fill(0x5A5A_5A5A);
            p.copy_map(&g);
            let used = scratch_words_for_cells(geometry.cell_count());
            let flat = Flat {
                scratch: &mut p.scratch[..used],
                interior: Interior::new(&geometry),
            };
            for y in 0..h as usize {
                for x in 0..w as usize {
                    let (fi, ti) = (framed.index(x, y), flat.index(x, y));
                    assert_eq!(framed.nibble(fi), flat.nibble(ti), "{w}x{h} ({x}, {y})");
                    let mask = |(a, c, b): (u32, u32, u32)| {
                        let t = |v: u32| NIBBLE_WINDOWS[(v & 0xFFF) as usize];
                        (t(a), t(c), t(b))
                    };
                    assert_eq!(
                        mask(framed.windows(fi, x, y)),
                        mask(flat.windows(ti, x, y)),
                        "{w}x{h} ({x}, {y})"
                    );
                    assert_eq!(framed.interior(fi, x, y), flat.interior(ti, x, y));
                    if framed.interior(fi, x, y) {
                        assert_eq!(
                            mask(framed.interior_windows(fi)),
                            mask(flat.interior_windows(ti))
                        );
                    }
                }
            }
        }
    }
    // A map too large for the view is not framed.
    let g = SmallGrid::new(GridGeometry::new(40, 40, 0.1).unwrap()).unwrap();
    let mut words = std::vec![0u32; 129];
    assert!(Framed::<129>::new(&mut words, g.geometry()).is_none());
    assert!(Framed::<SMALL_FRAMED>::new(&mut words, g.geometry()).is_none());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// The cell-by-cell A* in the framed layout and in the flat one: the same search (cost,
    /// expansions, queue peak) and the same path, both of pathfinding's optimal cost.
    #[test]
    fn framed_and_flat_astar_agree((mut g, s, t) in arb_grid()) {
        g.set(s, false);
        g.set(t, false);
        if s == t {
            return Ok(());
        }
        let si = g.geometry().index(s);
        let mut framed = Box::new(Planner::<SMALL_FRAMED, 4096>::new());
        let a = framed.astar_in::<_, SMALL_FRAMED>(&g, si, t, true).unwrap();
        let is_framed = matches!(framed.layout, Layout::Framed { .. });
        prop_assert!(is_framed);
        let mut flat = Box::new(SmallPlanner::new());
        let b = flat.astar_in::<_, SMALL_FRAMED>(&g, si, t, false).unwrap();
        prop_assert_eq!(flat.layout, Layout::Flat);
        prop_assert_eq!((a.found, a.cost, a.expanded), (b.found, b.cost, b.expanded));
        // The framed search runs on rings: a different measure of the pool used.
        prop_assert!(framed.queue_peak() <= 4096);
        prop_assert_eq!(a.found.then_some(a.cost), oracle_astar(&g, s, t));
        if a.found {
            framed.rebuild_merged(g.geometry(), t, false);
            flat.rebuild_merged(g.geometry(), t, false);
            prop_assert_eq!(framed.path_cells(), flat.path_cells());
            prop_assert_eq!(steps_and_cost(framed.path_cells()).1, a.cost);
            assert_collision_free(&g, framed.path_cells());
        }
    }
}
