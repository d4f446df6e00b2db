//! A binary min-heap over a slice the caller provides: the priority queue of the classic
//! methods' searches (Dijkstra on Voronoi ridge cells, on quadtree leaves).
//!
//! Entries are `(key, item)` pairs packed in one `u64` (key in the high half), so the order is
//! by key, then by item: deterministic. Decrease-key is done lazily (push again, skip stale
//! entries when popped), so a search may push one entry per relaxation; a full slice is an
//! error value, never a reallocation or a panic. Not from a seed: plumbing.

/// The heap's slice is full.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct HeapFull {
    /// Entries the slice holds.
    pub capacity: usize,
}

/// A min-heap of `(key, item)` pairs stored in a borrowed slice.
#[derive(Debug)]
pub struct CellHeap<'a> {
    entries: &'a mut [u64],
    len: usize,
    peak: usize,
}

impl<'a> CellHeap<'a> {
    /// An empty heap that can hold `entries.len()` pairs.
    pub fn new(entries: &'a mut [u64]) -> Self {
        Self {
            entries,
            len: 0,
            peak: 0,
        }
    }

    /// Entries held now.
    pub fn len(&self) -> usize {
        self.len
    }

    /// `true` when empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Most entries held at once since [`CellHeap::new`].
    pub fn peak(&self) -> usize {
        self.peak
    }

    /// Forget every entry (the peak stays).
    pub fn clear(&mut self) {
        self.len = 0;
    }

    /// Add `item` with priority `key` (smaller first).
    pub fn push(&mut self, key: u32, item: u32) -> Result<(), HeapFull> {
        let capacity = self.entries.len();
        let Some(slot) = self.entries.get_mut(self.len) else {
            return Err(HeapFull { capacity });
        };
        *slot = (key as u64) << 32 | item as u64;
        let mut i = self.len;
        self.len += 1;
        self.peak = self.peak.max(self.len);
        while i > 0 {
            let parent = (i - 1) / 2;
            if self.entries[parent] <= self.entries[i] {
                break;
            }
            self.entries.swap(parent, i);
            i = parent;
        }
        Ok(())
    }

    /// Remove and return the pair with the smallest key.
    pub fn pop(&mut self) -> Option<(u32, u32)> {
        if self.len == 0 {
            return None;
        }
        let top = self.entries[0];
        self.len -= 1;
        self.entries.swap(0, self.len);
        let mut i = 0;
        loop {
            let (l, r) = (2 * i + 1, 2 * i + 2);
            let mut smallest = i;
            if l < self.len && self.entries[l] < self.entries[smallest] {
                smallest = l;
            }
            if r < self.len && self.entries[r] < self.entries[smallest] {
                smallest = r;
            }
            if smallest == i {
                break;
            }
            self.entries.swap(i, smallest);
            i = smallest;
        }
        Some(((top >> 32) as u32, top as u32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pops_in_key_order_and_reports_full() {
        let mut buf = [0u64; 6];
        let mut heap = CellHeap::new(&mut buf);
        for (k, item) in [(5, 1), (3, 2), (9, 3), (1, 4), (3, 0), (7, 5)] {
            heap.push(k, item).unwrap();
        }
        assert_eq!(heap.push(0, 9), Err(HeapFull { capacity: 6 }));
        let mut out = [(0, 0); 6];
        for o in out.iter_mut() {
            *o = heap.pop().unwrap();
        }
        assert_eq!(out, [(1, 4), (3, 0), (3, 2), (5, 1), (7, 5), (9, 3)]);
        assert_eq!(heap.pop(), None);
        assert_eq!(heap.peak(), 6);
    }
}
