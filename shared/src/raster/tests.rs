//! Tests of the rasterizer: the walk, the clipping, the marking against the reference.

extern crate std;

use super::*;
use crate::grid::{Grid300, GridGeometry};

fn line(a: (i32, i32), b: (i32, i32)) -> heapless::Vec<(i32, i32), 64> {
    BresenhamLine::new(a, b).collect()
}

#[test]
fn bresenham_covers_all_octants_end_to_end() {
    for &(dx, dy) in &[
        (5, 2),
        (2, 5),
        (-5, 2),
        (-2, 5),
        (5, -2),
        (2, -5),
        (-5, -2),
        (-2, -5),
        (0, 0),
        (7, 0),
        (0, -7),
        (4, 4),
    ] {
        let cells = line((10, 10), (10 + dx, 10 + dy));
        assert_eq!(cells.first(), Some(&(10, 10)));
        assert_eq!(cells.last(), Some(&(10 + dx, 10 + dy)));
        assert_eq!(cells.len() as i32, dx.abs().max(dy.abs()) + 1);
        for w in cells.windows(2) {
            assert!((w[0].0 - w[1].0).abs() <= 1 && (w[0].1 - w[1].1).abs() <= 1);
        }
    }
}

#[test]
fn square_is_clipped_at_the_border() {
    let mut grid = Grid300::new(GridGeometry::new(10, 10, 0.1).unwrap()).unwrap();
    mark_square(&mut grid, 0, 0, 2);
    assert_eq!(grid.count_occupied(), 9);
    mark_square(&mut grid, -100, 5, 3);
    assert_eq!(grid.count_occupied(), 9);
    mark_square(&mut grid, i32::MAX, i32::MIN, u16::MAX);
    assert_eq!(grid.count_occupied(), 9);
}

#[test]
fn polygon_outline_is_grown() {
    let mut grid = Grid300::new(GridGeometry::new(100, 100, 0.1).unwrap()).unwrap();
    let square = [
        PointM::new(3.0, 3.0),
        PointM::new(6.0, 3.0),
        PointM::new(6.0, 6.0),
        PointM::new(3.0, 6.0),
    ];
    mark_polygon(&mut grid, &square, 1);
    // The outline from cell 30 to 60 grown by one cell: a 33x33 ring, 3 cells thick.
    assert_eq!(grid.count_occupied(), 33 * 33 - 27 * 27);
    assert!(
        !grid.is_occupied_xy(45, 45),
        "inside of the outline stays free"
    );
    assert!(grid.is_occupied_xy(29, 45));
    assert!(!grid.is_occupied_xy(28, 45));
}

#[test]
fn polygon_far_outside_marks_nothing_and_terminates() {
    let mut grid = Grid300::new(GridGeometry::new(10, 10, 0.1).unwrap()).unwrap();
    mark_polygon(
        &mut grid,
        &[
            PointM::new(-1.0e9, 5.0),
            PointM::new(-1.0e9, 6.0),
            PointM::new(f32::NAN, 1.0),
        ],
        3,
    );
    assert_eq!(grid.count_occupied(), 0);
}

mod properties {
    use super::super::clip::LineSteps;
    use super::super::reference;
    use super::*;
    use crate::grid::words_for_cells;
    use proptest::prelude::*;

    type SmallGrid = Grid<{ words_for_cells(100 * 100) }>;

    fn grid(width: u32, height: u32) -> SmallGrid {
        SmallGrid::new(GridGeometry::new(width, height, 0.1).unwrap()).unwrap()
    }

    /// Half-sides: mostly small, sometimes past the grid.
    fn half_side() -> impl Strategy<Value = u16> {
        prop_oneof![4 => 0u16..12, 1 => 12u16..130]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn closed_form_is_the_walk(
            from in (-300i32..300, -300i32..300),
            to in (-300i32..300, -300i32..300),
        ) {
            let steps = LineSteps::new(from, to);
            let mut walk = BresenhamLine::new(from, to);
            let mut k = 0i64;
            loop {
                let err = walk.err as i64;
                let Some(cell) = walk.next() else { break };
                prop_assert_eq!(steps.cell(k), (cell.0 as i64, cell.1 as i64), "step {}", k);
                prop_assert_eq!(steps.error_at(k), err, "error at step {}", k);
                k += 1;
            }
            prop_assert_eq!(k, steps.last_step() + 1);
        }

        #[test]
        fn clipped_walk_is_the_walk_inside(
            from in (-300i32..300, -300i32..300),
            to in (-300i32..300, -300i32..300),
            x in (-200i32..200, 0i32..150),
            y in (-200i32..200, 0i32..150),
        ) {
            let (x_range, y_range) = ((x.0, x.0 + x.1), (y.0, y.0 + y.1));
            let inside = |c: &(i32, i32)| {
                (x_range.0..=x_range.1).contains(&c.0) && (y_range.0..=y_range.1).contains(&c.1)
            };
            let expected: std::vec::Vec<_> = BresenhamLine::new(from, to).filter(inside).collect();
            let got: std::vec::Vec<_> = BresenhamLine::clipped(from, to, x_range, y_range)
                .into_iter()
                .flatten()
                .collect();
            prop_assert_eq!(got, expected);
        }

        #[test]
        fn marking_equals_the_reference(
            size in (1u32..100, 1u32..100),
            from in (-160i32..260, -160i32..260),
            to in (-160i32..260, -160i32..260),
            half in half_side(),
        ) {
            let (mut fast, mut slow) = (grid(size.0, size.1), grid(size.0, size.1));
            let work = mark_line(&mut fast, from, to, half);
            reference::mark_line(&mut slow, from, to, half);
            prop_assert!(fast == slow, "edge {:?} -> {:?}, half-side {}", from, to, half);
            prop_assert!(work <= edge_work_bound(fast.geometry()));
            let (mut fast, mut slow) = (grid(size.0, size.1), grid(size.0, size.1));
            mark_square(&mut fast, from.0, from.1, half);
            reference::mark_square(&mut slow, from.0, from.1, half);
            prop_assert!(fast == slow, "square at {:?}, half-side {}", from, half);
        }

        #[test]
        fn polygons_equal_the_reference(
            size in (1u32..100, 1u32..100),
            vertices in proptest::collection::vec((-6.0f32..16.0, -6.0f32..16.0), 1..8),
            half in half_side(),
        ) {
            let vertices: std::vec::Vec<PointM> =
                vertices.iter().map(|&(x, y)| PointM::new(x, y)).collect();
            let (mut fast, mut slow) = (grid(size.0, size.1), grid(size.0, size.1));
            let work = mark_polygon(&mut fast, &vertices, half);
            reference::mark_polygon(&mut slow, &vertices, half);
            prop_assert!(fast == slow);
            prop_assert!(work <= polygon_work_bound(fast.geometry(), vertices.len()));
        }
    }

    /// Any `f32`: ordinary, huge, infinite or NaN.
    fn coordinate() -> impl Strategy<Value = f32> {
        prop_oneof![
            3 => -20.0f32..40.0,
            1 => -1.0e30f32..1.0e30,
            1 => prop::sample::select(std::vec![f32::NAN, f32::INFINITY, f32::NEG_INFINITY, 1.0e9, -1.0e9, f32::MAX]),
            1 => proptest::num::f32::ANY,
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// The input-cost property: whatever the numbers, a polygon of `n` vertices costs at
        /// most `n · edge_work_bound` (the grid only).
        #[test]
        fn work_is_bounded_by_the_map(
            size in (1u32..100, 1u32..100),
            vertices in proptest::collection::vec((coordinate(), coordinate()), 1..40),
            radius_m in prop_oneof![0.0f32..2.0, proptest::num::f32::ANY],
        ) {
            let mut g = grid(size.0, size.1);
            let half = g.geometry().expansion_cells(radius_m);
            let vertices: std::vec::Vec<PointM> =
                vertices.iter().map(|&(x, y)| PointM::new(x, y)).collect();
            let work = mark_polygon(&mut g, &vertices, half);
            prop_assert!(work <= polygon_work_bound(g.geometry(), vertices.len()));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// Far edges (the whole ±1e6-cell walk) clip to what the whole walk marks.
        #[test]
        fn far_edges_equal_the_reference(
            from in (-2_000_000i32..2_000_000, -2_000_000i32..2_000_000),
            to in (-2_000_000i32..2_000_000, -2_000_000i32..2_000_000),
            through in (0i32..60, 0i32..60),
            half in 0u16..6,
        ) {
            // Half the cases pass through the grid: `to` mirrored through a grid cell.
            let to = if through.0 % 2 == 0 { to } else {
                (2 * through.0 - from.0.clamp(-1_000_000, 1_000_000),
                 2 * through.1 - from.1.clamp(-1_000_000, 1_000_000))
            };
            let (mut fast, mut slow) = (grid(60, 60), grid(60, 60));
            mark_line(&mut fast, from, to, half);
            // The reference's cost is the walk's length (up to 4e6 cells), not the squares.
            for (x, y) in BresenhamLine::new(from, to) {
                if (-6..66).contains(&x) && (-6..66).contains(&y) {
                    reference::mark_square(&mut slow, x, y, half);
                }
            }
            prop_assert!(fast == slow);
        }
    }
}

/// Every short line against every single clip bound (each side of the rectangle at each
/// position): the off-by-one cases of the closed form that random rectangles rarely hit.
#[test]
fn clipping_is_exact_at_every_bound() {
    for tx in -10..=10 {
        for ty in -10..=10 {
            for t in -11..=11 {
                let wide = (-100, 100);
                for (x_range, y_range) in [
                    ((t, 100), wide),
                    ((-100, t), wide),
                    (wide, (t, 100)),
                    (wide, (-100, t)),
                ] {
                    let inside = |c: &(i32, i32)| {
                        (x_range.0..=x_range.1).contains(&c.0)
                            && (y_range.0..=y_range.1).contains(&c.1)
                    };
                    let expected: heapless::Vec<(i32, i32), 32> =
                        BresenhamLine::new((0, 0), (tx, ty))
                            .filter(inside)
                            .collect();
                    let got: heapless::Vec<(i32, i32), 32> =
                        BresenhamLine::clipped((0, 0), (tx, ty), x_range, y_range)
                            .into_iter()
                            .flatten()
                            .collect();
                    assert_eq!(
                        got, expected,
                        "to ({tx}, {ty}), x {x_range:?}, y {y_range:?}"
                    );
                }
            }
        }
    }
}

/// The tester's case: a 4-vertex polygon at x = ±1e9 m, radius 10 m on the seed's map.
#[test]
fn polygon_at_a_billion_metres_costs_the_map_not_the_numbers() {
    let geometry = GridGeometry::seed_default();
    let mut grid = Grid300::new(geometry).unwrap();
    let half = geometry.expansion_cells(10.0);
    assert_eq!(half, 200);
    let polygon = [
        PointM::new(-1.0e9, 5.0),
        PointM::new(1.0e9, 5.0),
        PointM::new(1.0e9, 6.0),
        PointM::new(-1.0e9, 6.0),
    ];
    let work = mark_polygon(&mut grid, &polygon, half);
    // Rows 100 and 120 grown by 200 cover the map.
    assert_eq!(grid.count_occupied(), 300 * 300);
    let bound = polygon_work_bound(&geometry, 4);
    assert!(work <= bound, "work {work} > bound {bound}");
    assert!(work < 20_000, "work {work}");
}
