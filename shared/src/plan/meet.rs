//! Where a layered BFS's two sides met ([`Meet`]): written by `bfs/`, read by the planner's
//! path rebuild. A leaf module so that neither imports the other for it.

/// Where the two sides of a layered search met: rows `rows.0 ..= rows.1` of word `word` hold
/// a cell of the other side that is a legal move away from a cell of the side that was
/// expanding its layer `layer`. One-sided: the goal's row and word.
#[derive(Clone, Copy, Debug)]
pub(in crate::plan) struct Meet {
    pub(in crate::plan) rows: (usize, usize),
    pub(in crate::plan) word: usize,
    /// The expanding side was the goal's.
    pub(in crate::plan) goal_side: bool,
    /// The expanding side's frontier layer.
    pub(in crate::plan) layer: u32,
    /// The other side's last layer.
    pub(in crate::plan) other_layer: u32,
    /// The search ran from the start only (no `SIDE` plane): `layer` is the goal's layer.
    pub(in crate::plan) one_sided: bool,
}
