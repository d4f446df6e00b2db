//! The open list as the cell-by-cell A* sees it: the [`OpenEntry`] (12 bytes) that every queue
//! shares, and the [`OpenList`] trait with its two implementations, [`ClassQueue`](crate::plan::class_queue::ClassQueue) (linked
//! lists, exact `QueueFull` semantics) and [`RingQueue`](crate::plan::ring_queue::RingQueue) (rings, faster; it gives up and the
//! search runs again on a `ClassQueue`). The search loop is generic over the trait: two
//! instances, the same pops in the same order (tested against each other on random grids).

use super::goal::reduced_cost_class;

/// The scalar state of a `ClassQueue` (or any [`OpenList`]), kept apart from its arrays so that the search loop
/// holds it in registers (it is passed by value to the queue's out-of-line parts).
#[derive(Clone, Copy)]
pub(super) struct QueueState {
    /// Head of the stack of entries whose key equals `last` (reduced cost 0).
    pub(super) stack: u32,
    /// The last key popped (every key in the queue is at least this).
    pub(super) last: u32,
    /// Entries of the pool ever used (the queue peak).
    pub(super) bump: u32,
    /// Head of the list of freed entries.
    pub(super) free: u32,
    /// The FIFO class of the last pop from a FIFO (1 ..= 5): its head is tried first.
    pub(super) class: u32,
}

/// One open-list / queue entry: 12 bytes.
#[derive(Clone, Copy, Debug)]
pub(super) struct OpenEntry {
    /// `g + h` (A*), unused by BFS.
    pub(super) f: u32,
    /// `cell_index << 4 | step code` (A*), `cell_index` (BFS).
    pub(super) node: u32,
    /// Next entry of the same list (A*), unused by BFS.
    pub(super) next: u32,
}

impl OpenEntry {
    pub(super) const ZERO: Self = Self {
        f: 0,
        node: 0,
        next: NIL,
    };
}

/// End of a list of the open list.
pub(super) const NIL: u32 = u32::MAX;

/// The open list as the search loop sees it: [`ClassQueue`](crate::plan::class_queue::ClassQueue) (linked lists over the pool, the
/// exact `QueueFull` semantics) or [`RingQueue`](crate::plan::ring_queue::RingQueue) (rings carved from the pool, faster; it gives
/// up when a ring stays full and the caller then runs the search again with a `ClassQueue`).
/// Both pop the same entries in the same order.
pub(super) trait OpenList<'a>: Sized {
    fn new(pool: &'a mut [OpenEntry], first_key: u32) -> (Self, QueueState);
    fn capacity(&self) -> u32;
    fn peak(&self, s: &QueueState) -> u32;
    /// Insert any key not below `s.last`: on the stack, a FIFO list or the far list by its
    /// reduced cost; `false` when there is no room.
    #[inline(never)]
    fn push(&mut self, s: &mut QueueState, key: u32, node: u32) -> bool {
        match reduced_cost_class(key.wrapping_sub(s.last)) {
            Some(0) => self.push_stack(s, node),
            Some(c) => self.push_class(s, c, node),
            None => self.push_far(s, key, node),
        }
    }
    fn push_stack(&mut self, s: &mut QueueState, node: u32) -> bool;
    fn push_class(&mut self, s: &mut QueueState, class: usize, node: u32) -> bool;
    fn push_far(&mut self, s: &mut QueueState, key: u32, node: u32) -> bool;
    fn pop(&mut self, s: &mut QueueState) -> u32;
    fn reclaim_and_push(
        &mut self,
        s: QueueState,
        closed: impl Fn(u32) -> bool,
        key: u32,
        node: u32,
    ) -> Option<QueueState>;
}
