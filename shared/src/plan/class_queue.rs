//! [`ClassQueue`]: the open list of the cell-by-cell A* by reduced-cost class, linked lists over
//! a fixed pool of entries. One LIFO stack for reduced cost 0, one FIFO per non-zero class
//! (sorted by construction, since popped keys never decrease), a sorted far list for corridor
//! walk ends; pushes are O(1), a pop compares at most six heads. Full pool: closed cells'
//! entries are reclaimed, `QueueFull` only when that frees less than 1/16. Measured effect
//! (branch `astar-fifo`, `cargo xtask mcu-bench`): 20 % random obstacles 7.55 M → 6.70 M
//! instructions against the former 512-bucket queue; see docs/planners-history.md,
//! "Cell-by-cell A\*: queue by reduced-cost class".

use super::goal::{CLASSES, CLASS_COSTS};
use super::open_list::{OpenEntry, OpenList, QueueState, NIL};

/// The open list of the cell-by-cell A*: lists by *reduced cost* over a fixed pool of entries.
///
/// With the octile heuristic (consistent), a child's key is its parent's plus the reduced cost
/// `r = cost + h(child) − h(parent)`, which takes only the six values of [`REDUCED_COSTS`](crate::plan::goal::REDUCED_COSTS)
/// (checked for every cell and step around goals in the tests). The parent's key is the last
/// key popped, and popped keys never decrease, so the children pushed with one `r` arrive with
/// non-decreasing keys: one FIFO list per non-zero `r` is sorted by construction, its head is
/// its smallest key. Entries with `r = 0` carry the last popped key itself, the smallest there
/// is: they go on a LIFO *stack*, popped first while it is not empty (ties pop the last pushed
/// first: the deeper entries, which on open floors keeps the search on one straight line). So
/// a push is O(1) (a link at the stack's head or a FIFO's tail), and a pop takes the stack's
/// head or the smallest of the five FIFO heads (their keys are kept in an array; ties go to
/// the smallest `r`, i.e. the latest parent). Keys that are not the last popped key plus one of
/// the six values (the ends of corridor walks) go to the *far list*, kept sorted by key
/// (insertion walks it; it holds a few entries), whose head is the sixth candidate of a pop.
///
/// Entries of cells closed meanwhile stay in the lists (lazy deletion) until popped, or until
/// [`ClassQueue::collect`] reclaims them when the pool is full.
pub(super) struct ClassQueue<'a> {
    pub(super) pool: &'a mut [OpenEntry],
    /// First and last entry of each FIFO class `1 ..= 5` (`NIL` when empty; index 0 and the
    /// two past the classes are unused, so that a 3-bit class indexes them).
    heads: [u32; 8],
    tails: [u32; 8],
    /// The key of each FIFO's head entry (`u32::MAX` when empty).
    head_keys: [u32; 8],
    /// Head of the far list (sorted by key, `NIL` when empty) and its key (`u32::MAX`).
    pub(super) far: u32,
    far_key: u32,
}

impl<'a> ClassQueue<'a> {
    pub(super) fn new(pool: &'a mut [OpenEntry], first_key: u32) -> (Self, QueueState) {
        (
            Self {
                pool,
                heads: [NIL; 8],
                tails: [NIL; 8],
                head_keys: [u32::MAX; 8],
                far: NIL,
                far_key: u32::MAX,
            },
            QueueState {
                stack: NIL,
                last: first_key,
                bump: 0,
                free: NIL,
                class: 1,
            },
        )
    }

    /// A free slot of the pool, taken off the free list or the unused end; `None` when full.
    #[inline(always)]
    fn alloc(&mut self, s: &mut QueueState) -> Option<u32> {
        if s.free != NIL {
            let slot = s.free;
            s.free = self.pool.get(slot as usize)?.next;
            Some(slot)
        } else if (s.bump as usize) < self.pool.len() {
            s.bump += 1;
            Some(s.bump - 1)
        } else {
            None
        }
    }

    /// Insert with the last popped key (class 0); `false` when the pool is full.
    #[inline(always)]
    pub(super) fn push_stack(&mut self, s: &mut QueueState, node: u32) -> bool {
        let Some(slot) = self.alloc(s) else {
            return false;
        };
        if let Some(e) = self.pool.get_mut(slot as usize) {
            *e = OpenEntry {
                f: s.last,
                node,
                next: s.stack,
            };
        }
        s.stack = slot;
        true
    }

    /// Insert with key `s.last + CLASS_COSTS[class]` at the tail of FIFO `class` (1 ..= 5);
    /// `false` when the pool is full.
    #[inline(always)]
    pub(super) fn push_class(&mut self, s: &mut QueueState, class: usize, node: u32) -> bool {
        let c = class & 7;
        let key = s.last.wrapping_add(CLASS_COSTS[c]);
        let Some(slot) = self.alloc(s) else {
            return false;
        };
        if let Some(e) = self.pool.get_mut(slot as usize) {
            *e = OpenEntry {
                f: key,
                node,
                next: NIL,
            };
        }
        match self.pool.get_mut(self.tails[c] as usize) {
            Some(t) => t.next = slot,
            None => {
                self.heads[c] = slot;
                self.head_keys[c] = key;
            }
        }
        self.tails[c] = slot;
        true
    }

    /// Insert any key not below `s.last` into the far list, sorted (before the entries of an
    /// equal key); `false` when the pool is full.
    #[inline(never)]
    pub(super) fn push_far(&mut self, s: &mut QueueState, key: u32, node: u32) -> bool {
        let Some(slot) = self.alloc(s) else {
            return false;
        };
        let (mut prev, mut at) = (NIL, self.far);
        while let Some(e) = self.pool.get(at as usize) {
            if e.f >= key {
                break;
            }
            (prev, at) = (at, e.next);
        }
        if let Some(e) = self.pool.get_mut(slot as usize) {
            *e = OpenEntry {
                f: key,
                node,
                next: at,
            };
        }
        match self.pool.get_mut(prev as usize) {
            Some(p) => p.next = slot,
            None => {
                self.far = slot;
                self.far_key = key;
            }
        }
        true
    }

    /// Remove an entry of the smallest key and return its node (`NIL` when the queue is
    /// empty); its key is then `s.last`.
    #[inline(always)]
    pub(super) fn pop(&mut self, s: &mut QueueState) -> u32 {
        if s.stack != NIL {
            // Its key is the last popped key: nothing is smaller.
            let slot = s.stack;
            let Some(e) = self.pool.get_mut(slot as usize) else {
                return NIL;
            };
            let node = e.node;
            s.stack = e.next;
            e.next = s.free;
            s.free = slot;
            return node;
        }
        // The FIFO popped last, when its head has the last popped key (runs of equal keys).
        let c = (s.class & 7) as usize;
        if self.head_keys[c] == s.last {
            return self.take(s, c);
        }
        self.pop_fifo(s)
    }

    /// Remove the head of FIFO `c` (1 ..= 5, not empty) and return its node.
    #[inline(always)]
    pub(super) fn take(&mut self, s: &mut QueueState, c: usize) -> u32 {
        let c = c & 7;
        let slot = self.heads[c];
        let Some(e) = self.pool.get_mut(slot as usize) else {
            return NIL;
        };
        let (key, node, next) = (e.f, e.node, e.next);
        e.next = s.free;
        s.free = slot;
        s.last = key;
        s.class = c as u32;
        self.heads[c] = next;
        match self.pool.get(next as usize) {
            Some(n) => self.head_keys[c] = n.f,
            None => {
                self.tails[c] = NIL;
                self.head_keys[c] = u32::MAX;
            }
        }
        node
    }

    /// Remove the smallest of the FIFO heads and the far list's head (the stack is empty) and
    /// return its node (`NIL` when all are empty).
    #[inline(never)]
    pub(super) fn pop_fifo(&mut self, s: &mut QueueState) -> u32 {
        let k = &self.head_keys;
        let (mut c, mut key) = (1, k[1]);
        if k[2] < key {
            (c, key) = (2, k[2]);
        }
        if k[3] < key {
            (c, key) = (3, k[3]);
        }
        if k[4] < key {
            (c, key) = (4, k[4]);
        }
        if k[5] < key {
            (c, key) = (5, k[5]);
        }
        if self.far_key <= key {
            return self.pop_far(s);
        }
        self.take(s, c)
    }

    /// Remove the head of the far list and return its node (`NIL` when it is empty).
    #[inline(always)]
    fn pop_far(&mut self, s: &mut QueueState) -> u32 {
        let slot = self.far;
        let Some(e) = self.pool.get_mut(slot as usize) else {
            return NIL;
        };
        let (f, node, next) = (e.f, e.node, e.next);
        e.next = s.free;
        s.free = slot;
        s.last = f;
        self.far = next;
        self.far_key = self.pool.get(next as usize).map_or(u32::MAX, |n| n.f);
        node
    }

    /// The pool is full: drop the entries of cells closed meanwhile (`closed(node)`) and push `(key, node)`; `None` (queue full) when that
    /// frees less than 1/16 of the pool (no thrashing) or the push still fails.
    #[cold]
    #[inline(never)]
    pub(super) fn reclaim_and_push(
        &mut self,
        s: QueueState,
        closed: impl Fn(u32) -> bool,
        key: u32,
        node: u32,
    ) -> Option<QueueState> {
        let (mut s, freed) = self.collect(s, closed);
        (freed >= (self.pool.len() / 16).max(1) && self.push(&mut s, key, node)).then_some(s)
    }

    /// Drop the entries for which `stale(node)` holds from the list starting at `head`,
    /// keeping the others in order. Returns the new head, the new tail and the slots freed.
    fn filter_list(
        &mut self,
        s: &mut QueueState,
        head: u32,
        stale: &impl Fn(u32) -> bool,
    ) -> (u32, u32, usize) {
        let (mut first, mut tail, mut slot, mut freed) = (NIL, NIL, head, 0);
        while let Some(e) = self.pool.get_mut(slot as usize) {
            let next = e.next;
            if stale(e.node) {
                e.next = s.free;
                s.free = slot;
                freed += 1;
            } else {
                e.next = NIL;
                match self.pool.get_mut(tail as usize) {
                    Some(t) => t.next = slot,
                    None => first = slot,
                }
                tail = slot;
            }
            slot = next;
        }
        (first, tail, freed)
    }

    /// Drop every entry for which `stale(node)` holds from the stack, the FIFOs and the far
    /// list (each keeps its order). Returns the new state and how many slots were freed.
    /// O(entries); used only when the pool is full.
    #[cold]
    #[inline(never)]
    pub(super) fn collect(
        &mut self,
        mut s: QueueState,
        stale: impl Fn(u32) -> bool,
    ) -> (QueueState, usize) {
        let stack_head = s.stack;
        let (stack, _, mut freed) = self.filter_list(&mut s, stack_head, &stale);
        s.stack = stack;
        for c in 1..CLASSES {
            let (head, tail, n) = self.filter_list(&mut s, self.heads[c], &stale);
            freed += n;
            self.heads[c] = head;
            self.tails[c] = tail;
            self.head_keys[c] = self.pool.get(head as usize).map_or(u32::MAX, |e| e.f);
        }
        let (far, _, n) = self.filter_list(&mut s, self.far, &stale);
        freed += n;
        self.far = far;
        self.far_key = self.pool.get(far as usize).map_or(u32::MAX, |e| e.f);
        (s, freed)
    }
}

impl<'a> OpenList<'a> for ClassQueue<'a> {
    #[inline(always)]
    fn new(pool: &'a mut [OpenEntry], first_key: u32) -> (Self, QueueState) {
        ClassQueue::new(pool, first_key)
    }
    #[inline(always)]
    fn capacity(&self) -> u32 {
        self.pool.len() as u32
    }
    #[inline(always)]
    fn peak(&self, s: &QueueState) -> u32 {
        s.bump
    }
    #[inline(always)]
    fn push_stack(&mut self, s: &mut QueueState, node: u32) -> bool {
        ClassQueue::push_stack(self, s, node)
    }
    #[inline(always)]
    fn push_class(&mut self, s: &mut QueueState, class: usize, node: u32) -> bool {
        ClassQueue::push_class(self, s, class, node)
    }
    #[inline(always)]
    fn push_far(&mut self, s: &mut QueueState, key: u32, node: u32) -> bool {
        ClassQueue::push_far(self, s, key, node)
    }
    #[inline(always)]
    fn pop(&mut self, s: &mut QueueState) -> u32 {
        ClassQueue::pop(self, s)
    }
    #[inline(always)]
    fn reclaim_and_push(
        &mut self,
        s: QueueState,
        closed: impl Fn(u32) -> bool,
        key: u32,
        node: u32,
    ) -> Option<QueueState> {
        ClassQueue::reclaim_and_push(self, s, closed, key, node)
    }
}
