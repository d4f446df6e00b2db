#[path = "../benches/grids/mod.rs"]
mod grids;
use pathfinding::prelude::*;
use std::collections::{BTreeMap, HashMap};
use twil_core::grid::Grid300;
use twil_core::plan::{
    PlanStatus, Planner, PlannerKind, DIAGONAL_COST as D, SCRATCH_WORDS_300, STRAIGHT_COST as S,
};
type Node = (i32, i32);
fn succ(g: &Grid300, &(x, y): &Node, unit: bool) -> Vec<(Node, u32)> {
    let free = |x: i32, y: i32| !g.is_occupied_xy(x, y);
    let (e, w, n, s) = (
        free(x + 1, y),
        free(x - 1, y),
        free(x, y + 1),
        free(x, y - 1),
    );
    let (a, b) = if unit { (1, 1) } else { (S, D) };
    let mut v = vec![];
    if e {
        v.push(((x + 1, y), a))
    }
    if w {
        v.push(((x - 1, y), a))
    }
    if n {
        v.push(((x, y + 1), a))
    }
    if s {
        v.push(((x, y - 1), a))
    }
    if n && e && free(x + 1, y + 1) {
        v.push(((x + 1, y + 1), b))
    }
    if n && w && free(x - 1, y + 1) {
        v.push(((x - 1, y + 1), b))
    }
    if s && w && free(x - 1, y - 1) {
        v.push(((x - 1, y - 1), b))
    }
    if s && e && free(x + 1, y - 1) {
        v.push(((x + 1, y - 1), b))
    }
    v
}
fn oct(a: Node, b: Node) -> u32 {
    let dx = a.0.abs_diff(b.0);
    let dy = a.1.abs_diff(b.1);
    let (lo, hi) = (dx.min(dy), dx.max(dy));
    D * lo + S * (hi - lo)
}
fn main() {
    let mut p: Box<Planner<SCRATCH_WORDS_300, 32768>> = Box::new(Planner::new());
    let (g, s, t) = grids::random_case(|g, s, t| {
        p.plan_cells(PlannerKind::Bfs, g, s, t).unwrap().status == PlanStatus::Found
    });
    let (s, t): (Node, Node) = ((s.x as i32, s.y as i32), (t.x as i32, t.y as i32));
    let mut gs: HashMap<Node, u32> = dijkstra_all(&s, |n| succ(&g, n, false))
        .into_iter()
        .map(|(k, v)| (k, v.1))
        .collect();
    gs.insert(s, 0);
    let mut gt: HashMap<Node, u32> = dijkstra_all(&t, |n| succ(&g, n, false))
        .into_iter()
        .map(|(k, v)| (k, v.1))
        .collect();
    gt.insert(t, 0);
    let mut kt: HashMap<Node, u32> = dijkstra_all(&t, |n| succ(&g, n, true))
        .into_iter()
        .map(|(k, v)| (k, v.1))
        .collect();
    kt.insert(t, 0);
    let c = gs[&t];
    println!(
        "C* = {c}, octile = {}, ratio {:.3}, free {}",
        oct(s, t),
        c as f64 / oct(s, t) as f64,
        gs.len()
    );
    let mut less = 0;
    let mut eq = 0;
    let mut levels = BTreeMap::new();
    let mut lessk = 0;
    let mut mm = 0;
    for (&n, &g0) in &gs {
        let f = g0 + oct(n, t);
        if f < c {
            less += 1;
            *levels.entry(f).or_insert(0) += 1;
        } else if f == c {
            eq += 1;
        }
        let k = kt[&n];
        let dx = n.0.abs_diff(t.0);
        let dy = n.1.abs_diff(t.1);
        let hk = (S * k + (D - S) * (dx + dy).saturating_sub(k)).max(oct(n, t));
        if g0 + hk < c {
            lessk += 1;
        }
        // MM: forward expands f_F < C and g_F < C/2; backward symmetric
        if g0 + oct(n, t) < c && 2 * g0 < c {
            mm += 1;
        }
        if gt[&n] + oct(n, s) < c && 2 * gt[&n] < c {
            mm += 1;
        }
    }
    for (name, hf) in [
        (
            "manhattan*D/2",
            Box::new(|n: Node| D * (n.0.abs_diff(t.0) + n.1.abs_diff(t.1)) / 2)
                as Box<dyn Fn(Node) -> u32>,
        ),
        (
            "cheb*S",
            Box::new(|n: Node| S * n.0.abs_diff(t.0).max(n.1.abs_diff(t.1))),
        ),
        ("octile", Box::new(|n: Node| oct(n, t))),
    ] {
        let cnt = gs.iter().filter(|(&n, &g0)| g0 + hf(n) < c).count();
        println!("{name}: f<C* {cnt}");
    }
    println!(
        "f<C*: {less}, f==C*: {eq}, distinct f<C*: {}, with bfs-step h: {lessk}, MM: {mm}",
        levels.len()
    );
    let mut sizes: Vec<u32> = levels.values().cloned().collect();
    sizes.sort();
    println!(
        "level sizes: median {} p90 {} max {}",
        sizes[sizes.len() / 2],
        sizes[sizes.len() * 9 / 10],
        sizes[sizes.len() - 1]
    );
    let r = p
        .plan_cells(
            PlannerKind::AStar,
            &g,
            twil_core::geom::Cell::new(s.0 as _, s.1 as _),
            twil_core::geom::Cell::new(t.0 as _, t.1 as _),
        )
        .unwrap();
    println!("ours expanded {} cost {}", r.expanded, r.cost);
}
