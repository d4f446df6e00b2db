//! The binary min-heap of the jump point search, over a fixed slice of [`OpenEntry`] ordered by
//! `f` (lazy deletion: a jump point may be pushed once per scan that finds it, its first pop
//! counts). Jump steps break the six reduced costs the cell-by-cell queue relies on, and the
//! heap holds few entries (3–40 on the benchmark maps and bundled worlds, `queue_peak`).

use super::open_list::OpenEntry;

/// Binary min-heap over a fixed slice of entries, ordered by `f`.
#[inline(always)]
fn heap_before(a: &OpenEntry, b: &OpenEntry) -> bool {
    a.f < b.f
}

pub(super) fn heap_sift_up(heap: &mut [OpenEntry], mut i: usize) {
    let Some(&item) = heap.get(i) else {
        return;
    };
    while i > 0 {
        let parent = (i - 1) / 2;
        match heap.get(parent) {
            Some(p) if heap_before(&item, p) => {
                heap[i] = *p;
                i = parent;
            }
            _ => break,
        }
    }
    heap[i] = item;
}

pub(super) fn heap_sift_down(heap: &mut [OpenEntry], mut i: usize) {
    let len = heap.len();
    let Some(&item) = heap.get(i) else {
        return;
    };
    loop {
        let left = 2 * i + 1;
        if left >= len {
            break;
        }
        let right = left + 1;
        let child = if right < len && heap_before(&heap[right], &heap[left]) {
            right
        } else {
            left
        };
        if heap_before(&heap[child], &item) {
            heap[i] = heap[child];
            i = child;
        } else {
            break;
        }
    }
    heap[i] = item;
}
