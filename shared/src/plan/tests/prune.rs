//! Pruning a plan to what the sonar sees, the sweep-band check and the line-of-sight walk.

use super::*;
use crate::grid::GridGeometry;

fn along_path_length(path: &[PointM]) -> f64 {
    path.windows(2)
        .map(|p| ((p[1].x_m - p[0].x_m) as f64).hypot((p[1].y_m - p[0].y_m) as f64))
        .sum()
}

#[test]
fn prune_cuts_at_range_mid_segment() {
    let g = SmallGrid::new(GridGeometry::new(40, 40, 0.1).unwrap()).unwrap();
    let path = [
        PointM::new(0.55, 0.55),
        PointM::new(2.55, 0.55),
        PointM::new(2.55, 3.55),
    ];
    let mut out = PathM::new();
    let pruned = prune_visible_prefix(&g, &path, 3.0, &mut out);
    assert_eq!(pruned.end, PruneEnd::Range);
    assert_eq!(out.len(), 3);
    assert_eq!(&out[..2], &path[..2]);
    assert!((out[2].x_m - 2.55).abs() < 1e-5);
    assert!((out[2].y_m - 1.55).abs() < 1e-4, "{:?}", out[2]);
    assert!((pruned.length_m - 3.0).abs() < 1e-5);

    let pruned = prune_visible_prefix(&g, &path, 100.0, &mut out);
    assert_eq!(pruned.end, PruneEnd::PathEnd);
    assert_eq!(out.as_slice(), &path);
    assert!((pruned.length_m - 5.0).abs() < 1e-4);
}

#[test]
fn prune_stops_where_a_wall_hides_the_path() {
    // A wall along x = 2.0 m from y = 1.5 m upwards; the path runs south, east below the wall's
    // end, then north behind it. The part behind the wall is hidden from the start.
    let mut g = SmallGrid::new(GridGeometry::new(40, 40, 0.1).unwrap()).unwrap();
    for y in 15..40 {
        g.set_xy(20, y, true);
    }
    let path = [
        PointM::new(0.55, 2.55),
        PointM::new(0.55, 0.55),
        PointM::new(2.55, 0.55),
        PointM::new(2.55, 3.55),
    ];
    let mut out = PathM::new();
    let pruned = prune_visible_prefix(&g, &path, 100.0, &mut out);
    assert_eq!(pruned.end, PruneEnd::Hidden);
    assert_eq!(&out[..3], &path[..3]);
    assert_eq!(out.len(), 4);
    let cut = out[3];
    assert!((cut.x_m - 2.55).abs() < 1e-5);
    assert!(cut.y_m > 0.55 && cut.y_m < 3.55, "{cut:?}");
    for p in out.iter() {
        assert!(line_of_sight_m(&g, out[0], *p), "{p:?} not visible");
    }
    // A little further along the last segment is no longer visible.
    let beyond = PointM::new(2.55, cut.y_m + 0.1);
    assert!(!line_of_sight_m(&g, out[0], beyond));
    assert!((pruned.length_m as f64 - along_path_length(&out)).abs() < 1e-4);
}

#[test]
fn prune_degenerate_inputs() {
    let mut g = SmallGrid::new(GridGeometry::new(10, 10, 0.1).unwrap()).unwrap();
    let mut out = PathM::new();
    let p = prune_visible_prefix(&g, &[], 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::PathEnd, 0));
    let path = [PointM::new(0.15, 0.15), PointM::new(0.85, 0.15)];
    for range in [0.0, -1.0, f32::NAN, f32::NEG_INFINITY] {
        let p = prune_visible_prefix(&g, &path, range, &mut out);
        assert_eq!((p.end, out.as_slice()), (PruneEnd::Range, &path[..1]));
    }
    let p = prune_visible_prefix(&g, &[PointM::new(-1.0, 0.0), path[1]], 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::Hidden, 1));
    let p = prune_visible_prefix(&g, &[path[0], PointM::new(f32::NAN, 0.1)], 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::Hidden, 1));
    // Repeated points are skipped, not emitted twice.
    let p = prune_visible_prefix(&g, &[path[0], path[0], path[1]], 3.0, &mut out);
    assert_eq!((p.end, out.as_slice()), (PruneEnd::PathEnd, &path[..]));
    g.set_xy(1, 1, true);
    let p = prune_visible_prefix(&g, &path, 3.0, &mut out);
    assert_eq!((p.end, out.len()), (PruneEnd::Hidden, 1));
    // An absurd range on a long path cannot hang: samples are capped.
    let far = [PointM::new(0.15, 0.15), PointM::new(0.15, 1.0e30)];
    let p = prune_visible_prefix(&g, &far, f32::MAX, &mut out);
    assert_eq!(p.end, PruneEnd::Hidden);
}

#[test]
fn band_check_matches_the_seed_rule() {
    let pose = PointM::new(5.0, 5.0);
    let at = |deg: f32| {
        let r = deg.to_radians();
        PointM::new(5.0 + r.cos(), 5.0 + r.sin())
    };
    let band = NORMAL_HALF_BAND_RAD;
    assert!(!needs_full_sweep(
        &[pose, at(0.0), at(90.0), at(-94.0)],
        pose,
        0.0,
        band
    ));
    assert!(needs_full_sweep(
        &[pose, at(0.0), at(96.0)],
        pose,
        0.0,
        band
    ));
    assert!(needs_full_sweep(&[at(-170.0)], pose, 0.0, band));
    // Heading 180°: behind is now ahead; wrap-around at ±π.
    assert!(!needs_full_sweep(
        &[at(170.0), at(-170.0)],
        pose,
        core::f32::consts::PI,
        band
    ));
    assert!(needs_full_sweep(
        &[at(0.0)],
        pose,
        core::f32::consts::PI,
        band
    ));
    // The robot's own position has no direction.
    assert!(!needs_full_sweep(&[pose], pose, 0.0, band));
    assert!(!needs_full_sweep(&[], pose, 0.0, band));
    assert!(needs_full_sweep(&[at(0.0)], pose, f32::NAN, band));
    assert!(needs_full_sweep(
        &[PointM::new(f32::NAN, 0.0)],
        pose,
        0.0,
        band
    ));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn pruned_prefix_is_visible_and_in_range((g, s, t) in arb_grid(), range_m in 0.05f32..3.0) {
        let mut p = Box::new(SmallPlanner::new());
        let mut path = PathM::new();
        let geometry = *g.geometry();
        let r = p.plan(PlannerKind::AnyAngle, &g, geometry.center_of(s), geometry.center_of(t), &mut path).unwrap();
        prop_assume!(r.status == PlanStatus::Found);
        let mut out = PathM::new();
        let pruned = prune_visible_prefix(&g, &path, range_m, &mut out);
        prop_assert!(!out.is_empty());
        prop_assert_eq!(out[0], path[0]);
        // A prefix: all but the last kept point are path vertices, in order.
        let n = out.len();
        prop_assert_eq!(&out[..n - 1], &path[..n - 1]);
        for q in out.iter() {
            prop_assert!(line_of_sight_m(&g, out[0], *q), "{:?} hidden", q);
        }
        let along = along_path_length(&out);
        prop_assert!(along <= range_m as f64 + 1e-4, "{} > {}", along, range_m);
        prop_assert!((pruned.length_m as f64 - along).abs() < 1e-3);
        if pruned.end == PruneEnd::PathEnd {
            prop_assert_eq!(out.as_slice(), path.as_slice());
        }
    }
}

/// The line of sight walked with [`crate::raster::BresenhamLine`] and the grid's checked
/// accessors, cell by cell: the reference for the index-stepping [`line_of_sight`].
fn line_of_sight_reference<const W: usize>(grid: &Grid<W>, a: Cell, b: Cell) -> bool {
    let (from, to) = if (a.y, a.x) <= (b.y, b.x) {
        (a, b)
    } else {
        (b, a)
    };
    let (mut px, mut py) = (from.x as i32, from.y as i32);
    for (x, y) in crate::raster::BresenhamLine::new((px, py), (to.x as i32, to.y as i32)) {
        if grid.is_occupied_xy(x, y) {
            return false;
        }
        if x != px && y != py && (grid.is_occupied_xy(x, py) || grid.is_occupied_xy(px, y)) {
            return false;
        }
        px = x;
        py = y;
    }
    true
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    #[test]
    fn line_of_sight_equals_the_cell_by_cell_walk(
        (g, s, t) in arb_grid(),
        off in 0u16..3,
    ) {
        // `off` moves the far end off the map now and then.
        let t = Cell::new(t.x + off * 20, t.y);
        prop_assert_eq!(line_of_sight(&g, s, t), line_of_sight_reference(&g, s, t));
        prop_assert_eq!(line_of_sight(&g, t, s), line_of_sight_reference(&g, s, t));
    }
}
