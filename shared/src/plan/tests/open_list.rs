//! The open lists of the cell-by-cell A*: the class queue against a reference, the rings
//! against the class queue, reclaiming and running out, the ring capacities.

use super::*;
use crate::grid::GridGeometry;
use crate::plan::class_queue::ClassQueue;
use crate::plan::goal::{reduced_cost_class, REDUCED_COSTS};
use crate::plan::layout::Framed;
use crate::plan::open_list::{OpenEntry, OpenList, NIL};
use crate::plan::planner::{Layout, Search};
use crate::plan::ring_queue::RingQueue;

/// The queue alone against a reference (an ordered set of `(key, node)`): random
/// interleavings of pushes (keys the last popped key plus 0 or a reduced cost, or any larger
/// key, also through the far list), pops and reclaims (`collect` of a random subset of nodes)
/// pop the reference's smallest key every time, each live node exactly once; a push is refused
/// exactly when the 64 entries are all live.
#[test]
fn class_queue_pops_keys_in_order_like_a_reference() {
    use std::collections::BTreeSet;
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    for round in 0..500 {
        let mut pool = std::vec![OpenEntry::ZERO; 64];
        let first = (next_random(&mut state) % 100_000) as u32;
        let (mut q, mut s) = ClassQueue::new(&mut pool, first);
        let mut reference = BTreeSet::new();
        let mut next_node = 0u32;
        let mut last = first;
        let steps = 20 + next_random(&mut state) % 400;
        for _ in 0..steps {
            let roll = next_random(&mut state) % 100;
            if roll < 55 {
                let r = match next_random(&mut state) % 8 {
                    0 | 1 => 0,
                    7 => 1 + (next_random(&mut state) % 40_000) as u32,
                    k => REDUCED_COSTS[(k - 2) as usize],
                };
                let key = last + r;
                let ok = if next_random(&mut state).is_multiple_of(4) {
                    q.push_far(&mut s, key, next_node)
                } else {
                    q.push(&mut s, key, next_node)
                };
                assert_eq!(ok, reference.len() < 64, "round {round}");
                if ok {
                    reference.insert((key, next_node));
                }
                next_node += 1;
            } else if roll < 97 {
                let got = Some(q.pop(&mut s))
                    .filter(|&n| n != NIL)
                    .map(|n| (s.last, n));
                let want = reference.first().map(|&(k, _)| k);
                assert_eq!(got.map(|(k, _)| k), want, "round {round}");
                if let Some((k, n)) = got {
                    assert!(
                        reference.remove(&(k, n)),
                        "round {round}: node {n} not live"
                    );
                    assert_eq!(s.last, k);
                    last = k;
                }
            } else {
                let m = 2 + (next_random(&mut state) % 3) as u32;
                let before = reference.len();
                let (after, freed) = q.collect(s, |n| n % m == 0);
                s = after;
                reference.retain(|&(_, n)| n % m != 0);
                assert_eq!(freed, before - reference.len(), "round {round}");
            }
        }
        // Drain: the rest comes out in order too.
        while let Some(&(k, _)) = reference.first() {
            let n = q.pop(&mut s);
            let gk = s.last;
            assert_eq!(gk, k, "round {round}");
            assert!(reference.remove(&(gk, n)));
        }
        assert_eq!(q.pop(&mut s), NIL);
        assert!(s.bump <= 64);
    }
}

/// The ring queue against the linked class queue, fed the same random interleavings of
/// pushes (all classes, the far list), pops and reclaims: while the rings accept the pushes,
/// every pop returns the same node with the same key (the same order, ties included), and a
/// reclaim drops the same number of entries. A push is refused only when its ring (or the far
/// array, or the stack) is full.
#[test]
fn ring_queue_pops_like_class_queue() {
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut refused = 0;
    for round in 0..500 {
        // Tiny pools too: some rings get no slot at all (always full).
        let size = [64usize, 200, 1024, 3, 6][round % 5];
        let mut ring_pool = std::vec![OpenEntry::ZERO; size];
        let mut list_pool = std::vec![OpenEntry::ZERO; 4 * size];
        let first = (next_random(&mut state) % 100_000) as u32;
        let (mut rq, mut rs) = <RingQueue as OpenList>::new(&mut ring_pool, first);
        let (mut lq, mut ls) = ClassQueue::new(&mut list_pool, first);
        let mut live = 0usize;
        let mut next_node = 0u32;
        let mut last = first;
        let steps = 20 + next_random(&mut state) % 2000;
        for _ in 0..steps {
            let roll = next_random(&mut state) % 100;
            if roll < 55 {
                let r = match next_random(&mut state) % 8 {
                    0 | 1 => 0,
                    7 => 1 + (next_random(&mut state) % 40_000) as u32,
                    k => REDUCED_COSTS[(k - 2) as usize],
                };
                let key = last + r;
                let far = next_random(&mut state).is_multiple_of(4);
                let ok = if far {
                    OpenList::push_far(&mut rq, &mut rs, key, next_node)
                } else {
                    OpenList::push(&mut rq, &mut rs, key, next_node)
                };
                if ok {
                    let pushed = if far {
                        lq.push_far(&mut ls, key, next_node)
                    } else {
                        lq.push(&mut ls, key, next_node)
                    };
                    assert!(pushed, "round {round}");
                    live += 1;
                } else {
                    refused += 1;
                    let full = match reduced_cost_class(key - last) {
                        _ if far => rq.far_len == rq.far_cap,
                        None => rq.far_len == rq.far_cap,
                        Some(0) => rs.stack as usize == size,
                        Some(c) => {
                            let (len, cap) = rq.ring_fill(c);
                            len == cap
                        }
                    };
                    assert!(full, "round {round}: refused while not full");
                }
                next_node += 1;
            } else if roll < 97 {
                let got = OpenList::pop(&mut rq, &mut rs);
                let want = lq.pop(&mut ls);
                assert_eq!((got, rs.last), (want, ls.last), "round {round}");
                if got != NIL {
                    live -= 1;
                    last = rs.last;
                }
            } else {
                let m = 2 + (next_random(&mut state) % 3) as u32;
                let freed = rq.collect(&mut rs, |n| n % m == 0);
                let (after, list_freed) = lq.collect(ls, |n| n % m == 0);
                ls = after;
                assert_eq!(freed, list_freed, "round {round}");
                live -= freed;
            }
        }
        for _ in 0..=live {
            let got = OpenList::pop(&mut rq, &mut rs);
            let want = lq.pop(&mut ls);
            assert_eq!((got, rs.last), (want, ls.last), "round {round}");
        }
        assert_eq!(OpenList::pop(&mut rq, &mut rs), NIL);
        assert!(OpenList::peak(&rq, &rs) as usize <= size);
    }
    // The small pools do fill their rings (the refusal test above ran).
    assert!(refused > 100, "{refused}");
}

/// The framed A* on rings and on the linked lists, run directly on the same maps with a
/// large and a small pool: when the rings do not give up, the same result, queue-independent
/// nibbles (every closed cell with the same parent step, i.e. the same pops in the same
/// order); when they do (`QueueFull`), the planner's answer (which then runs the linked
/// lists) is the linked lists' one. Both cases occur.
#[test]
fn ring_and_linked_astar_agree_and_fall_back() {
    let mut state = 0x1234_5678_9ABC_DEF1u64;
    let (mut ring_ok, mut ring_gave_up) = (0, 0);
    for round in 0..300 {
        let (w, h) = (
            8 + next_random(&mut state) % 24,
            8 + next_random(&mut state) % 24,
        );
        let mut g = SmallGrid::new(GridGeometry::new(w as u32, h as u32, 0.1).unwrap()).unwrap();
        let density = next_random(&mut state) % 40;
        for y in 0..h as u16 {
            for x in 0..w as u16 {
                if next_random(&mut state) % 100 < density {
                    g.set(Cell::new(x, y), true);
                }
            }
        }
        let s = Cell::new(0, 0);
        let t = Cell::new(w as u16 - 1, h as u16 - 1);
        g.set(s, false);
        g.set(t, false);
        let si = g.geometry().index(s);
        let used = scratch_words_for_cells(g.geometry().cell_count());
        let outcome = |r: &Result<Search, PlanError>| match r {
            Ok(s) => Ok((s.found, s.expanded, s.cost)),
            Err(e) => Err(*e),
        };
        let small = round % 2 == 1;
        let mut p = Box::new(Planner::<SMALL_FRAMED, 4096>::new());
        let pool = if small { 24 } else { 4096 };
        // The planner's answer (rings, else linked lists), which also fills the goal table.
        let planned = if small {
            let mut q = Box::new(Planner::<SMALL_FRAMED, 24>::new());
            let r = q.astar_in::<_, SMALL_FRAMED>(&g, si, t, true);
            assert!(matches!(q.layout, Layout::Framed { .. }));
            r
        } else {
            p.astar_in::<_, SMALL_FRAMED>(&g, si, t, true)
        };
        p.astar_in::<_, SMALL_FRAMED>(&g, si, t, true).ok();
        assert!(matches!(p.layout, Layout::Framed { .. }));
        let runs = |p: &mut Planner<SMALL_FRAMED, 4096>, ring: bool| {
            let mut map = Framed::<SMALL_FRAMED>::new(&mut p.scratch, g.geometry()).unwrap();
            map.copy_map(&g);
            let mut peak = 0;
            let queue = &mut p.queue[..pool];
            let r = if ring {
                astar_search::<_, RingQueue, true>(
                    &mut map,
                    queue,
                    &p.goal_axis,
                    (0, 0),
                    (t.x as u32, t.y as u32),
                    &mut peak,
                )
            } else {
                astar_search::<_, ClassQueue, true>(
                    &mut map,
                    queue,
                    &p.goal_axis,
                    (0, 0),
                    (t.x as u32, t.y as u32),
                    &mut peak,
                )
            };
            (r, p.scratch[..used].to_vec())
        };
        let (ring, ring_nibbles) = runs(&mut p, true);
        let (linked, linked_nibbles) = runs(&mut p, false);
        if matches!(ring, Err(PlanError::QueueFull { .. })) {
            ring_gave_up += 1;
        } else {
            ring_ok += 1;
            assert_eq!(outcome(&ring), outcome(&linked), "round {round}");
            assert!(ring_nibbles == linked_nibbles, "round {round}");
        }
        assert_eq!(outcome(&planned), outcome(&linked), "round {round}");
    }
    assert!(
        ring_ok > 50 && ring_gave_up > 10,
        "{ring_ok} {ring_gave_up}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// The cell-by-cell A* alone with a queue of 16 entries: reclaiming stale entries reorders
    /// the lists (a FIFO keeps its order, so its keys stay sorted), and the search finds the
    /// optimal cost or reports `QueueFull`, never another cost.
    #[test]
    fn cell_by_cell_astar_with_a_tiny_queue_is_exact_or_full((mut g, s, t) in arb_grid()) {
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 16>::new());
        g.set(s, false);
        g.set(t, false);
        if s == t {
            return Ok(());
        }
        let si = g.geometry().index(s);
        let expected = oracle_astar(&g, s, t);
        match p.astar(&g, si, t) {
            Ok(search) => {
                prop_assert_eq!(search.found, expected.is_some());
                if let Some(cost) = expected {
                    prop_assert_eq!(search.cost, cost);
                    p.rebuild_merged(g.geometry(), t, false);
                    prop_assert_eq!(steps_and_cost(p.path_cells()).1, cost);
                    assert_collision_free(&g, p.path_cells());
                }
                prop_assert!(p.queue_peak() <= 16);
            }
            Err(e) => prop_assert_eq!(e, PlanError::QueueFull { capacity: 16 }),
        }
    }
}

/// A tiny queue does run out and reclaim: corner to corner on 24 × 24 grids with 20 % random
/// obstacles, a few searches fill all 32 entries and still find the optimal cost (after a
/// reclaim), most end with `QueueFull`.
#[test]
fn tiny_queue_reclaims_and_runs_out_on_random_grids() {
    let (mut reclaimed, mut full) = (0, 0);
    for seed in 1..200u64 {
        let mut g: SmallGrid = random_grid(24, 24, 20, seed);
        let (s, t) = (Cell::new(0, 0), Cell::new(23, 23));
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(SMALL_CELLS) }, 32>::new());
        let si = g.geometry().index(s);
        match p.astar(&g, si, t) {
            Ok(search) => {
                let expected = oracle_astar(&g, s, t);
                assert_eq!(search.found, expected.is_some(), "seed {seed}");
                if let Some(cost) = expected {
                    assert_eq!(search.cost, cost, "seed {seed}");
                    if p.queue_peak() == 32 {
                        reclaimed += 1;
                    }
                }
            }
            Err(e) => {
                assert_eq!(e, PlanError::QueueFull { capacity: 32 });
                full += 1;
            }
        }
    }
    assert!(
        reclaimed > 0 && full > 0,
        "reclaimed {reclaimed}, full {full}"
    );
}

/// The ring capacities ([`RING_SHARES`]) fit the 20 % random benchmark grids with the MCU's
/// pool of 1 024 entries: on the benchmark's grid (seed 1) and three more seeds the rings
/// never give up (no second search), and they find what the linked lists find.
#[test]
fn rings_fit_random_grids_with_the_mcu_pool() {
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(rings_fit_random_grids)
        .unwrap()
        .join()
        .unwrap();
}

fn rings_fit_random_grids() {
    use crate::grid::Grid300;
    const WORDS: usize = 16385;
    let (s, t) = (Cell::new(2, 2), Cell::new(297, 297));
    for seed in 1u64..5 {
        // The generator of shared/benches/grids (xorshift64).
        let mut rng = 0x9E37_79B9_7F4A_7C15 ^ seed;
        let mut g = Grid300::new(GridGeometry::new(300, 300, 0.05).unwrap()).unwrap();
        for y in 0..300 {
            for x in 0..300 {
                rng ^= rng << 13;
                rng ^= rng >> 7;
                rng ^= rng << 17;
                if rng % 100 < 20 {
                    g.set_xy(x, y, true);
                }
            }
        }
        g.set(s, false);
        g.set(t, false);
        let mut p = Box::new(Planner::<{ scratch_words_for_cells(160_000) }, 1024>::new());
        let planned = p
            .astar_in::<_, WORDS>(&g, g.geometry().index(s), t, true)
            .unwrap();
        assert!(matches!(p.layout, Layout::Framed { .. }));
        let mut map = Framed::<WORDS>::new(&mut p.scratch, g.geometry()).unwrap();
        map.copy_map(&g);
        let mut peak = 0;
        let ring = astar_search::<_, RingQueue, true>(
            &mut map,
            &mut p.queue,
            &p.goal_axis,
            (s.x as u32, s.y as u32),
            (t.x as u32, t.y as u32),
            &mut peak,
        );
        let ring = ring.unwrap_or_else(|e| panic!("seed {seed}: the rings gave up: {e:?}"));
        assert!(ring.found, "seed {seed}");
        assert_eq!(
            (ring.expanded, ring.cost),
            (planned.expanded, planned.cost),
            "seed {seed}"
        );
        if seed == 1 {
            assert_eq!(ring.expanded, 28_823);
        }
    }
}
