//! [`RingQueue`]: the same classes and order of pops as [`ClassQueue`](crate::plan::class_queue::ClassQueue) on fixed rings carved
//! from the pool (capacities by [`RING_SHARES`], from measured per-class peaks), the stack in
//! the entries' `next` fields, the far list a short sorted array: no free list, no links. When
//! a ring stays full after a reclaim the queue gives up and the search runs again with a
//! `ClassQueue`, so results never depend on the ring capacities. Used in the framed layout
//! (the MCU's path). Measured effect (branch `astar-queue`, `cargo xtask mcu-bench`): 20 %
//! random obstacles 5.39 M → 4.99 M instructions; see docs/planners-history.md,
//! "Cell-by-cell A\*: open list on rings".

use super::goal::{reduced_cost_class, CLASSES, CLASS_COSTS};
use super::open_list::QueueState;
use super::open_list::{OpenEntry, OpenList, NIL};

/// Share of the pool per FIFO class `2 ..= 5` of a [`RingQueue`], in 256ths of what the far
/// list leaves (the rest goes to class 1). Most entries at once on 20 % random obstacles
/// (300 × 300, four seeds): class 1 304–371, class 2 13–16, class 3 62–97, class 4 310–359,
/// class 5 4–5; with a pool of 1 024 the rings hold 426, 30, 115, 402 and 14 entries.
const RING_SHARES: [u32; CLASSES] = [0, 0, 8, 30, 104, 4];
/// Entries of the far list of a [`RingQueue`], in 64ths of the pool (at least one entry).
const RING_FAR_SHARE: u32 = 2;

/// One ring of a [`RingQueue`]: next slot to pop (`head`), next slot to write (`tail`;
/// `head == tail`: empty, and one slot stays unused so that a full ring is told apart), the
/// end of its slots and its reduced cost (a pushed key is the last popped key plus `cost`).
#[derive(Clone, Copy)]
struct Ring {
    pub(super) head: u32,
    pub(super) tail: u32,
    pub(super) end: u32,
    pub(super) cost: u32,
}

/// The open list of [`ClassQueue`](crate::plan::class_queue::ClassQueue) (same classes, same order of pops) on fixed *rings* instead
/// of linked lists: FIFO class `c` is a ring buffer of `(key, node)` in the `f` and `node`
/// fields of its own range of pool slots (capacities by [`RING_SHARES`]), the stack of class 0
/// lives in the `next` fields of the pool (up to one entry per slot), the far list is a sorted
/// array at the pool's front (smallest key last). No free list, no links: a push writes one
/// slot and moves a tail, a pop reads one slot and moves a head. When a ring (or the far
/// array) is full, the entries of closed cells are dropped from all (each keeps its order); if
/// the ring is then still more than 7/8 full the queue gives up (`reclaim_and_push` returns
/// `None`) and the caller runs the search again with a [`ClassQueue`](crate::plan::class_queue::ClassQueue), so results never depend
/// on the ring capacities.
pub(super) struct RingQueue<'a> {
    pub(super) pool: &'a mut [OpenEntry],
    /// The hot state of ring `c` in one place (one base address for the loop).
    rings: [Ring; 8],
    /// Ring `c`'s slots are `starts[c] .. rings[c].end`.
    starts: [u32; 8],
    /// Entries of the far list: slots `0 .. far_len`, sorted by key, the smallest (and of
    /// equal keys the last pushed) last; `far_cap` slots.
    pub(super) far_len: u32,
    pub(super) far_cap: u32,
    /// Bit `c`: ring `c` has wrapped around (for the peak); bit 0: the stack was used.
    wrapped: u32,
    far_peak: u32,
}

impl RingQueue<'_> {
    /// The key at the head of ring `c` (`u32::MAX` when empty).
    #[inline(always)]
    fn head_key(&self, c: usize) -> u32 {
        let c = c & 7;
        let h = self.rings[c].head;
        if h == self.rings[c].tail {
            return u32::MAX;
        }
        self.pool.get(h as usize).map_or(u32::MAX, |e| e.f)
    }

    /// Remove the head of ring `c` (1 ..= 5, not empty) and return its node; its key becomes
    /// `s.last`.
    #[inline(always)]
    pub(super) fn take(&mut self, s: &mut QueueState, c: usize) -> u32 {
        let c = c & 7;
        let h = self.rings[c].head;
        let Some(e) = self.pool.get(h as usize) else {
            return NIL;
        };
        s.last = e.f;
        s.class = c as u32;
        let node = e.node;
        let mut n = h + 1;
        if n == self.rings[c].end {
            n = self.starts[c];
        }
        self.rings[c].head = n;
        node
    }

    /// Remove the smallest of the ring heads and the far list's last entry (the stack is
    /// empty) and return its node (`NIL` when all are empty). Ties as in [`ClassQueue`](crate::plan::class_queue::ClassQueue).
    #[inline(never)]
    pub(super) fn pop_fifo(&mut self, s: &mut QueueState) -> u32 {
        let (mut c, mut key) = (1, self.head_key(1));
        for k in 2..CLASSES {
            let kk = self.head_key(k);
            if kk < key {
                (c, key) = (k, kk);
            }
        }
        let far = self.far_len.wrapping_sub(1);
        let far_key = self.pool.get(far as usize).map_or(u32::MAX, |e| e.f);
        if far_key <= key {
            let Some(e) = self.pool.get(far as usize) else {
                return NIL;
            };
            s.last = e.f;
            self.far_len = far;
            return e.node;
        }
        self.take(s, c)
    }

    /// Keep the entries of ring `c` for which `stale(node)` is false, in order; returns how
    /// many were dropped.
    fn filter_ring(&mut self, c: usize, stale: &impl Fn(u32) -> bool) -> usize {
        let c = c & 7;
        let (start, end) = (self.starts[c], self.rings[c].end);
        let (mut read, mut write, tail) =
            (self.rings[c].head, self.rings[c].head, self.rings[c].tail);
        let mut dropped = 0;
        while read != tail {
            let Some(e) = self.pool.get(read as usize).copied() else {
                break;
            };
            if stale(e.node) {
                dropped += 1;
            } else {
                if let Some(w) = self.pool.get_mut(write as usize) {
                    w.f = e.f;
                    w.node = e.node;
                }
                write += 1;
                if write == end {
                    write = start;
                }
            }
            read += 1;
            if read == end {
                read = start;
            }
        }
        self.rings[c].tail = write;
        dropped
    }

    /// Drop every entry for which `stale(node)` holds from the stack, the rings and the far
    /// list (each keeps its order). Returns how many were dropped. O(entries).
    #[cold]
    #[inline(never)]
    pub(super) fn collect(&mut self, s: &mut QueueState, stale: impl Fn(u32) -> bool) -> usize {
        let mut dropped = 0;
        let mut write = 0u32;
        for read in 0..s.stack {
            let Some(node) = self.pool.get(read as usize).map(|e| e.next) else {
                break;
            };
            if stale(node) {
                dropped += 1;
            } else {
                if let Some(w) = self.pool.get_mut(write as usize) {
                    w.next = node;
                }
                write += 1;
            }
        }
        s.stack = write;
        for c in 1..CLASSES {
            dropped += self.filter_ring(c, &stale);
        }
        let mut write = 0u32;
        for read in 0..self.far_len {
            let Some(e) = self.pool.get(read as usize).copied() else {
                break;
            };
            if stale(e.node) {
                dropped += 1;
            } else {
                if let Some(w) = self.pool.get_mut(write as usize) {
                    w.f = e.f;
                    w.node = e.node;
                }
                write += 1;
            }
        }
        self.far_len = write;
        dropped
    }

    /// Entries in ring `c` and its capacity (one slot less than its slots).
    pub(super) fn ring_fill(&self, c: usize) -> (u32, u32) {
        let c = c & 7;
        let slots = self.rings[c].end - self.starts[c];
        let (h, t) = (self.rings[c].head, self.rings[c].tail);
        let len = if t >= h { t - h } else { t + slots - h };
        (len, slots.saturating_sub(1))
    }
}

/// The slots `starts[c] .. ends[c]` of the rings of a [`RingQueue`] over `len` pool slots
/// whose first `far_cap` slots are the far array: classes 2 ..= 5 by [`RING_SHARES`] (at least
/// one slot each when the pool allows; a ring of one slot holds nothing), class 1 the rest. A
/// ring left without a slot (pools of a few entries) gets the one "slot" `len`, past the pool:
/// its tail's successor is its head, so it is always full and never written. Out of line:
/// computed in `new`, the empty-ring fix changed the search loop's registers (+0.05..0.19 M).
#[inline(never)]
fn ring_layout(len: u32, far_cap: u32) -> ([u32; 8], [u32; 8]) {
    let rest = len - far_cap;
    let (mut starts, mut ends) = ([far_cap; 8], [far_cap; 8]);
    let mut at = far_cap;
    for c in [2usize, 3, 4, 5] {
        let share = u64::from(rest) * u64::from(RING_SHARES[c]) / 256;
        let n = (share as u32).max(1).min(len - at);
        starts[c] = at;
        at += n;
        ends[c] = at;
    }
    starts[1] = at;
    ends[1] = len;
    for c in 1..CLASSES {
        if starts[c] == ends[c] {
            (starts[c], ends[c]) = (len, len + 1);
        }
    }
    (starts, ends)
}

impl<'a> OpenList<'a> for RingQueue<'a> {
    fn new(pool: &'a mut [OpenEntry], first_key: u32) -> (Self, QueueState) {
        let len = pool.len().min(u32::MAX as usize / 2) as u32;
        let far_cap = (len * RING_FAR_SHARE / 64).max(1).min(len);
        let (starts, ends) = ring_layout(len, far_cap);
        (
            Self {
                pool,
                rings: core::array::from_fn(|c| Ring {
                    head: starts[c],
                    tail: starts[c],
                    end: ends[c],
                    cost: CLASS_COSTS[c],
                }),
                starts,
                far_len: 0,
                far_cap,
                wrapped: 0,
                far_peak: 0,
            },
            QueueState {
                stack: 0,
                last: first_key,
                bump: 0,
                free: NIL,
                class: 1,
            },
        )
    }

    fn capacity(&self) -> u32 {
        self.pool.len() as u32
    }

    /// Slots of the pool ever written by the rings and the far list (the stack lives in the
    /// `next` fields and takes no slot of its own).
    #[inline(never)]
    fn peak(&self, _s: &QueueState) -> u32 {
        let mut used = self.far_peak;
        for c in 1..CLASSES {
            used += if self.wrapped & (1 << c) != 0 {
                // (A ring without a slot "wraps" at once: it counts 0.)
                let end = self.rings[c].end.min(self.pool.len() as u32);
                end.saturating_sub(self.starts[c])
            } else {
                self.rings[c].tail.max(self.rings[c].head) - self.starts[c]
            };
        }
        used
    }

    #[inline(always)]
    fn push_stack(&mut self, s: &mut QueueState, node: u32) -> bool {
        match self.pool.get_mut(s.stack as usize) {
            Some(e) => {
                e.next = node;
                s.stack += 1;
                true
            }
            None => false,
        }
    }

    #[inline(always)]
    fn push_class(&mut self, s: &mut QueueState, class: usize, node: u32) -> bool {
        let c = class & 7;
        let ring = &mut self.rings[c];
        let key = s.last.wrapping_add(ring.cost);
        let t = ring.tail;
        let mut n = t + 1;
        if n == ring.end {
            n = self.starts[c];
            self.wrapped |= 1 << c;
        }
        if n == ring.head {
            return false;
        }
        if let Some(e) = self.pool.get_mut(t as usize) {
            e.f = key;
            e.node = node;
        }
        self.rings[c].tail = n;
        true
    }

    #[inline(never)]
    fn push_far(&mut self, _s: &mut QueueState, key: u32, node: u32) -> bool {
        if self.far_len >= self.far_cap {
            return false;
        }
        // Shift the entries of smaller keys up by one (they are popped first).
        let mut i = self.far_len;
        while i > 0 {
            let Some(below) = self.pool.get((i - 1) as usize).copied() else {
                return false;
            };
            if below.f >= key {
                break;
            }
            if let Some(e) = self.pool.get_mut(i as usize) {
                e.f = below.f;
                e.node = below.node;
            }
            i -= 1;
        }
        if let Some(e) = self.pool.get_mut(i as usize) {
            e.f = key;
            e.node = node;
        }
        self.far_len += 1;
        self.far_peak = self.far_peak.max(self.far_len);
        true
    }

    #[inline(always)]
    fn pop(&mut self, s: &mut QueueState) -> u32 {
        if s.stack != 0 {
            // Its key is the last popped key: nothing is smaller.
            s.stack -= 1;
            return self.pool.get(s.stack as usize).map_or(NIL, |e| e.next);
        }
        // The ring popped last, when its head has the last popped key (runs of equal keys).
        let c = (s.class & 7) as usize;
        let h = self.rings[c].head;
        if h != self.rings[c].tail {
            if let Some(e) = self.pool.get(h as usize) {
                if e.f == s.last {
                    let node = e.node;
                    let mut n = h + 1;
                    if n == self.rings[c].end {
                        n = self.starts[c];
                    }
                    self.rings[c].head = n;
                    return node;
                }
            }
        }
        self.pop_fifo(s)
    }

    /// A ring, the far list or the stack is full: drop the entries of closed cells and push
    /// `(key, node)`; `None` (give up: the caller runs a [`ClassQueue`](crate::plan::class_queue::ClassQueue)) when the push still
    /// fails or leaves its ring more than 7/8 full (no thrashing).
    #[cold]
    #[inline(never)]
    fn reclaim_and_push(
        &mut self,
        mut s: QueueState,
        closed: impl Fn(u32) -> bool,
        key: u32,
        node: u32,
    ) -> Option<QueueState> {
        self.collect(&mut s, closed);
        if !self.push(&mut s, key, node) {
            return None;
        }
        let roomy = match reduced_cost_class(key.wrapping_sub(s.last)) {
            Some(0) => true,
            Some(c) => {
                let (len, cap) = self.ring_fill(c);
                len <= cap - cap / 8
            }
            None => self.far_len <= self.far_cap - self.far_cap / 8,
        };
        roomy.then_some(s)
    }
}
