//! Path planners on the occupancy grid: BFS (the seed's), A* (octile, optimal) and an any-angle
//! variant, plus the pruning of a plan to what the sonar has just seen.
//!
//! ## Contract
//!
//! - Neighbour rule (seed §IV.2, `gera_trajetoria`): the 4 side neighbours, plus a diagonal
//!   neighbour only when both side cells it passes between are free (no corner cutting).
//! - Costs: BFS counts steps (a diagonal step is one step; on maps that are not cluttered it is
//!   jump point search with unit costs, see "BFS by jump points"); A* uses the integer octile costs
//!   [`STRAIGHT_COST`] / [`DIAGONAL_COST`] (their ratio is √2 to 7 digits), so costs compare
//!   exactly with a reference implementation.
//! - Memory: a [`Planner`] owns all its scratch: 4 bits per cell and a queue of fixed capacity.
//!   Running out of queue or path capacity is a [`PlanError`], never a panic.
//! - Output: the path as a polyline in world metres (cell centres), from the start cell to the
//!   goal cell, with collinear cells merged; a [`PlanReport`] with the status, cost, length and the
//!   number of cells expanded. The same polyline as cells is [`Planner::path_cells`].
//!
//! ## Memory layout
//!
//! The scratch memory is `SCRATCH_WORDS` `u32` words: 4 bits per cell. A* and the scalar BFS
//! use it as one nibble per cell, 8 cells per word, row-major like the grid:
//!
//! | code      | meaning                                                        |
//! |-----------|----------------------------------------------------------------|
//! | 0         | free, not reached / not closed yet                             |
//! | 1 ..= 8   | reached, final; the code names the step *from* the parent      |
//! | 9         | the start cell (no parent)                                     |
//! | 10 ..= 14 | unused                                                         |
//! | 15        | occupied (scalar BFS and the cell-by-cell A* only)             |
//!
//! The scalar BFS (mazes, see below) and the cell-by-cell A* first copy the map into it
//! (occupied → 15, 8 cells per word from a 1 KB table), so one nibble read answers both "free?"
//! and "reached?". The jump point search reads the map's own bits and only clears the nibbles.
//!
//! The cell-by-cell A* uses a *framed* copy when it fits the first 2^14 + 1 words of the
//! scratch (300 × 300 cells take 11 477; so does any grid up to about 360 × 360, not the
//! [`Planner300`]'s 11 250-word scratch): rows padded to whole words with at least one blocked
//! nibble (`stride` = `width + 1` rounded up to 8 nibbles), a blocked row below and above the
//! map and one more blocked word, cell `(x, y)` at nibble `(y + 1) · stride + x + 1`. Every
//! cell's 3 × 3 neighbourhood is then three windows at one shift in three words a row apart,
//! border cells too, and the words are indexed through a mask, not bounds-tested (`Framed`;
//! `Flat` is the row-major layout above, used otherwise; both give the same search).
//!
//! The layered BFS uses the same words as bit planes, rows padded to `row_words = ⌈width /
//! 32⌉` words (`nodes = height × row_words`), stored *column by column*: bit `b` of word
//! `w · height + y` of a plane is cell `(32 w + b, y)`, so the words of one word column are
//! consecutive and the vertical-run kernel below slides along slices:
//!
//! | words                              | content                                             |
//! |------------------------------------|-----------------------------------------------------|
//! | `0 .. nodes`                       | `P0`: bit 0 of the cell's layer code                |
//! | `nodes .. 2 nodes`                 | `P1`: bit 1 of the layer code (code 0: not reached, |
//! |                                    | else `layer mod 3 + 1`)                             |
//! | `2 nodes .. 3 nodes`               | `SIDE`: 1 = reached from the goal (if it fits)      |
//! | `3 nodes .. 4 nodes`               | `FREE`: 1 = free (only if it fits, see below)       |
//! | then `2 × 2 × 2 row_words × set_words` | row sets per side and layer parity: per word    |
//! |                                    | column, the rows with frontier cells in it, then    |
//! |                                    | the rows with frontier cells at its edges           |
//! |                                    | (`set_words` = `⌈height / 32⌉` rounded up to a      |
//! |                                    | power of two)                                       |
//! | then `2 × 2 × ⌈2 row_words × set_words / 32⌉` | per side and parity, the non-empty row-set words |
//!
//! At 300 × 300 (`nodes` = 3 000, row sets 4 × 330 words): in the 20 000 words of the MCU's
//! 400 × 400 planner all four planes fit (13 320 words); in the 11 250 words of
//! [`Planner300`] `P0`, `P1`, `SIDE` and the row sets (10 320 words), and the free bits are
//! read from the grid's own packed bits instead (two reads and a funnel shift per word:
//! slower, same result). When `SIDE` does not fit either (narrow grids, where the padding to
//! whole words wastes most: e.g. 40 × 40 in `scratch_words_for_cells(1600)` = 200 words), BFS
//! searches from the start only, on `P0`, `P1` and the grid's bits; when not even those and
//! the row sets fit (grids narrower than about 18 cells in a scratch sized exactly for them),
//! BFS reports [`PlanError::ScratchTooSmall`] with the cells it would need.
//! `scratch_words_for_cells` is unchanged (4 bits per cell).
//!
//! For the seed's 300 × 300 grid that is **45 000 bytes** of scratch (`SCRATCH_WORDS = 11 250`,
//! [`SCRATCH_WORDS_300`]), plus the queue, 12 bytes per entry (`QUEUE = 3072` → 36 864 bytes),
//! plus the vertex buffer of [`MAX_PATH_POINTS`] cells (12 288 bytes), plus the cell-by-cell
//! A*'s goal table (2 560 bytes: per-axis words and a copy of `STEP_CLASSES`), plus a few
//! hundred bytes of bit sets on the stack during a jump point search (about 100 bytes of list
//! heads, tails and head keys in the cell-by-cell A*). Nothing else is allocated; the grid
//! itself is only read. The scalar BFS and the cell-by-cell A* share a constant 4 KB table
//! (`NIBBLE_WINDOWS`), the corridor walks read a 512-byte one, the A* step classes another
//! 512-byte one (`STEP_CLASSES`), `copy_map` a 1 KB one (read-only data: flash on the MCU).
//! [`Planner::queue_peak`] tells how much of the queue a search used. Measured on the 300 × 300
//! benchmark grids and the bundled worlds: the layered BFS needs no queue entries (its
//! `queue_peak` is the most frontier (row, word) pairs of one layer: at most 307); the scalar
//! BFS (mazes) 13; A* by jump points (open list plus records) 3 (open floor), 9 (corridor), 18
//! (office), 40 (pillars); BFS by jump points 3, 9, 20, 24; cell by cell (20 % random
//! obstacles, a maze of 1-cell corridors) 766 and 11. So 1 024 entries cover every benchmark
//! case.
//!
//! ## A*: jump point search without a g-table
//!
//! [`PlannerKind::AStar`] is *jump point search* (JPS) for the no-corner-cutting neighbour rule:
//! A* over *jump points* only, each reached by a straight or 45° scan, with the same optimal
//! octile cost as cell-by-cell A* (checked against the `pathfinding` crate by the property
//! tests). Scans, from a jump point, in the directions its arrival step leaves open (all 8 from
//! the start; after a diagonal step that diagonal and its two sides; after a side step that
//! side, both perpendiculars and the two forward diagonals):
//!
//! - a *side* scan stops with a jump point at the goal or at a cell with a *forced neighbour*:
//!   a cell beside the scan line that is free while the cell behind it, beside the previous
//!   cell of the scan, is occupied (the only way to reach it optimally is through this cell);
//!   it stops without one at an obstacle or the map edge. Along a row this tests 32 cells per
//!   step with a few word operations on the grid's bits (trailing / leading zeros); along a
//!   column it reads 3 bits per row.
//! - a *diagonal* scan moves only between two free side cells; a diagonal cell is a jump point
//!   when it is the goal or when its row or column scan finds one. (Without corner cutting a
//!   diagonal step has no forced neighbours.) The column scans of all the steps of one diagonal
//!   run together, row by row, over a bit set of the columns still scanning, so an open floor
//!   costs a few word operations per row instead of one read per cell.
//!
//! The open list is a binary heap of `(f, cell + step, parent record)` entries with *lazy
//! deletion*: a jump point may be pushed once per scan that finds it, and only its first pop
//! counts: the consistent octile heuristic makes that pop's cost the best over the jump point
//! graph, so the pop writes the arrival step into the nibble and later entries are skipped.
//! `g` is not stored: it is `f − h(cell)`. (Jump steps are longer than one cell, so the queue
//! of the cell-by-cell search, which relies on the six reduced costs of single steps, does not
//! apply; the heap holds few entries.)
//!
//! Every closed jump point also takes a *record* from the back of the queue: its cell and step
//! and the record of the jump point it was reached from. When the goal is closed, the records
//! of its chain give the jump points of the path exactly, and the cells between them get the
//! segment's step code, so the path is rebuilt cell by cell as for BFS. (Walking back along the
//! step code to the next closed cell is *not* exact: a cell on the segment may be a jump point
//! that another branch closed with a worse cost; the property tests found such cases.)
//!
//! *Choice.* On cluttered maps nearly every free cell becomes a jump point and scanning costs
//! more than it saves. Before searching, a clutter count (`cluttered`) reads one grid word in
//! sixteen over the rows between start and goal (16 rows of margin) and counts the runs of
//! occupied cells (a set bit after a clear one, `count_ones`): more than one run per 32 cells
//! (20 % random obstacles: about 1 per 6; a maze of 1-cell corridors: 1 per 4; the bundled
//! room worlds: fewer than 1 per 100) sends A* cell by cell at once. About 180 word reads
//! (≈ 1 000 instructions on an open floor) on a 300 × 300 grid.
//!
//! *Fallback.* When jump point search runs anyway and more than one cell in 256 (at least 256)
//! has been expanded as a jump point *and* the open list holds more than one entry per 16 of
//! them (a wide frontier), or when the queue runs out of entries for the heap and the records,
//! the search restarts as cell-by-cell A* below; `expanded` then counts the jump points and
//! the cells.
//!
//! ## BFS by jump points
//!
//! On maps that are not cluttered (the same clutter count as A*), [`PlannerKind::Bfs`] runs the
//! same jump point search with *unit costs*: a side step and a diagonal step both cost 1, the
//! heuristic is the Chebyshev distance `max(|dx|, |dy|)` (the octile formula with both costs
//! 1: admissible and consistent, since one step changes it by at most 1), so the first pop of
//! the goal has the fewest steps. The scans, the pruning rules and the record chain are those
//! of A*, chosen at compile time (`jump_points::<UNIT>`, so the octile search compiles as
//! before). Why the pruning stays exact with unit costs: every neighbour a jump point does not
//! scan towards is reachable from its parent, through free cells, in no more steps (after a
//! side step east from `p`: north is `p`'s diagonal neighbour when the cell north of `p` is
//! free, one step against two, and north-east is then two steps from `p` through that cell;
//! after a diagonal step north-east: west and south are `p`'s side neighbours, north-west and
//! south-east two side steps from `p`, against two steps through the cell). With octile costs
//! some of these were strict and are now ties; JPS's canonical-path argument allows ties (the
//! pruned paths are matched by diagonal-first ones the scans do follow). Checked, not assumed:
//! a property test runs the unit-cost search alone against `pathfinding::bfs` on 2 048 random
//! grids at 0–45 % obstacles (300 000 on grids up to 40 × 40 in a one-off run); dropping the
//! second side scan after a diagonal step, or the forward diagonal at a forced neighbour, makes
//! it fail.
//!
//! *Ties.* Many entries share one `f` with unit costs; the heap key is `f << 12 | h`, so among
//! equal `f` the entry nearest the goal (largest `g`) pops first: pillars 22 → 12 jump points
//! (the first `f` only order expanded the same 22 as A*). `h ≤ 4 095` on grids of at most 4 096
//! cells a side, so `g = (key >> 12) − h` is exact; a key whose `f` reaches 2²⁰ steps (only
//! on grids with paths of a million steps) ends the search with the fallback.
//!
//! `cost` is the number of steps (counted by the rebuild, equal to the search's `g`), `expanded`
//! the jump points expanded. *Fallback:* when more than 32 jump points
//! (`JPS_STEPS_MAX_EXPANSIONS`) have been expanded while the open list holds more than one
//! entry per 16 of them, or the queue runs out of entries, the layered BFS below runs and
//! `expanded` counts both. The bundled worlds need 8–15 jump points; sparse random obstacles
//! (1–3 %, not cluttered by the count) need hundreds at about 7 400 Cortex-M4 instructions
//! each, where giving up early is cheaper (A*'s limit of one cell in 256 cost 2.6 M
//! instructions before the layered search there).
//!
//! ## Cell-by-cell A*
//!
//! For cluttered maps (and as the fallback). The open list holds `(f, cell, step)` entries with
//! lazy deletion: a cell may be pushed more than once, and only its first pop counts (with a
//! consistent heuristic, its `g` is then optimal); `g` is not stored, it is `f − h(cell)`.
//!
//! *Arrival pruning.* A closed cell pushes only the neighbours that no other cell covers with a
//! key as small (the neighbour rule of jump point search without corner cutting, applied one
//! step at a time). After a side step, say east from parent `p`: the cell straight on (east);
//! the north neighbour only when the cell north of `p` is blocked (else `p` reached it
//! diagonally for `D < 2S`), and then also the north-east one (else the north neighbour covers
//! it at the same cost); likewise south. After a diagonal step, say north-east: east, north and
//! north-east (the west and south neighbours are `p`'s side neighbours, cheaper from `p`; the
//! north-west and south-east ones are reached through them for `2S < 2D`). The start tries all
//! eight. A neighbour is pushed only when its nibble is 0 (free, not closed), a diagonal only
//! when both side cells are free. By induction on the keys every pruned push is covered by an
//! entry of no larger key before the queue reaches it, so the first pop of every cell still
//! has the optimal `g`; the property tests compare the cost with `pathfinding` on 2 048 random
//! grids for the cell-by-cell search alone (and 200 000 in a one-off run). On 20 % random
//! obstacles the queue sees 0.84 pushes per expanded cell (1.46 when only the parent's own
//! moves were pruned, without the immediate expansion below).
//!
//! *Immediate expansion.* A target whose key equals the key just popped (reduced cost 0, see
//! below) would be the next pop (nothing in the queue is smaller; ties pop the last pushed
//! first): the first such target skips the queue and is expanded next (no closed test).
//!
//! *Hot loop.* The popped cell's 3 × 3 neighbourhood is read as three 12-bit windows (three
//! nibbles of a row, two 32-bit scratch reads each) and turned by a 4 KB table into an 18-bit
//! mask ("nibble 0" and "not blocked" per cell); one arm per arrival step tests its candidate
//! targets in that mask and pushes each with constant offsets (`y << 16 | x << 4 | code`
//! entries: a neighbour's entry is the cell's plus a constant). In the framed layout (see
//! "Memory layout") border cells need nothing special; in the flat one they read their
//! neighbours one by one. Neither `h` nor `g` is computed
//! per cell: the cell's *goal region* (signs of `dx`, `dy` and `|dx| − |dy|` saturated to
//! `−4 ..= 3`; on grids of at most 512 a side from two words of a per-axis table filled per
//! search, one subtraction and one saturation, about 11 instructions with the loads, see
//! `goal_axis_entry`) picks a word of `STEP_CLASSES` that gives every step's
//! reduced-cost class (3 bits per step), i.e. the list it goes to and its key, the last popped
//! key plus that reduced cost. `g` is needed only where a corridor walk ends (`f − h`) and at
//! the goal, where `h = 0` makes the key the cost.
//!
//! *Corridors.* A cell with at most two *legal* neighbours (8 moves, no corner cutting; then
//! both are side neighbours, since a legal diagonal brings its two side cells with it) is a
//! corridor cell, or a dead end with one. Every simple path through a corridor cell enters by
//! one neighbour and leaves by the other, so a chain of them is one edge between the cells at
//! its ends. When a popped cell reached by a side step is a corridor cell, the search *walks*
//! the chain instead of pushing its continuation: each next cell's 3 × 3 neighbourhood is read
//! as in the hot loop, a 512-byte table (`CORRIDOR_SIDES`, indexed by the nine "not blocked"
//! bits) says whether it is a corridor cell and which sides are open, and a corridor cell is
//! closed at once with its step as parent code and `g + STRAIGHT_COST`; the walk ends at a
//! cell that is not a corridor cell, the goal, or a cell on the map border (pushed with its
//! `f`, not closed), a dead end (closed, nothing pushed) or a cell already closed (nothing).
//! Why A* stays optimal: the walk starts at a cell closed with its optimal `g`; a walked cell
//! may get a worse `g` than the path from the chain's other end would give, but such a path
//! could only use it to reach cells further along the chain and finally the walk's own start,
//! which is closed already; the goal is never inside a walked stretch (it ends the walk), and
//! its end cell is pushed like any other child (an upper bound, lazy deletion). The arrival
//! pruning of the end cell is safe: its parent is a corridor cell, so every neighbour the rule
//! skips is blocked or the previous chain cell. Chains are walked whole from one end (a walk
//! from the other end finds its first cell closed), except at the goal. The walk's end may lie
//! far above the last popped key (a long chain away from the goal raises `f` by up to
//! `2 · STRAIGHT_COST` per cell), and its key is the last popped one plus a sum of reduced
//! costs, not one of them: walk ends go to a *far list* kept sorted by key (its head is
//! compared once per pop that does not come off the stack). Walks that close almost nothing
//! (20 % random obstacles: 0.15 cells per walk) are given up for the rest of the search once
//! 64 more walks than walked cells have been started: the search then goes on in a second,
//! out-of-line instance of its loop compiled without the walks (fewer live values, fewer
//! spills per expanded cell). In the 300 × 300 maze the search closes
//! the same cells but pops only 2 760 of them (6.0 M → 3.7 M Cortex-M4 instructions). Property
//! tests compare the cost with `pathfinding` on random mazes with loops and holes and on maps
//! carved from random 1-cell runs.
//!
//! *Queue by reduced-cost class* (see `ClassQueue` in the source): with the octile heuristic a
//! child's key is its parent's plus the *reduced cost* `r = cost + h(child) − h(parent)`, and
//! for octile steps `r` takes six values only: 0, `2S − D` = 3 363, `2D − 2S` = 4 756, `D` =
//! 8 119, `2S` = 11 482 and `2D` = 16 238 (S = [`STRAIGHT_COST`], D = [`DIAGONAL_COST`]; a
//! test checks every cell and step around goals in corners, on edges and in the middle). The
//! parent's key is the last popped key, and popped keys never decrease (consistent
//! heuristic), so the children pushed with one `r` come with non-decreasing keys: one FIFO list
//! per non-zero `r` is sorted by construction, and its head is its smallest key. Children with
//! `r = 0` carry the last popped key itself, the smallest there is: they go on a LIFO stack that
//! is popped first while it is not empty (ties pop the last pushed first, the deeper entries,
//! which on open floors keeps the search on one line). So a push is O(1) (a link at the
//! stack's head or a list's tail, key = last popped key + `r`), and a pop takes the stack's
//! head, else the head of the list popped last when its key is still the last popped key
//! (runs of equal keys: 84 % of the list pops in a QEMU profile of the benchmarks), else the
//! smallest of the five list heads (their keys are kept in an array; ties go to the smallest
//! `r`) and of the far list's head. The queue is exact: every entry is at least the last
//! popped key, the stack holds only that key, each list's head is its smallest key, the far
//! list is sorted. The queue's scalar state (stack head, last key, free list, peak, last list)
//! is a separate `Copy` value so that the loop keeps it in registers. (Before: a 512-bucket
//! queue with a 512-bit map and a summary word, 2.1 KB on the stack; with the step-class table
//! the class queue takes 20 % random obstacles from 7.55 M to 6.70 M instructions.)
//!
//! In the framed layout (the MCU's path) the same queue runs on *rings* (`RingQueue` in the
//! source): each FIFO class is a ring buffer of `(key, node)` in its own range of pool slots
//! (capacities from measured per-class peaks), the stack lives in the entries' `next` fields,
//! the far list is a short sorted array; no free list, no links (random 20 % obstacles: 5.39 M
//! → 4.99 M instructions). When a ring stays full after a reclaim, the search is run again on
//! the linked lists, so results never depend on the ring capacities.
//!
//! When the pool of entries is full, the queue first *reclaims* the entries of cells closed
//! since they were pushed (one pass over all lists) and carries on; only when that frees less
//! than 1/16 of the pool does the search end with [`PlanError::QueueFull`]. Entries are then
//! dropped in a different order, so an equal-cost path may differ from the one a larger queue
//! finds; the cost does not. (The jump point heap reclaims the same way before it gives up.)
//!
//! ## BFS: layered and bit-parallel, scalar in corridors
//!
//! On cluttered maps (and as the fallback of BFS by jump points), [`PlannerKind::Bfs`] expands
//! the search *layer by layer* on whole 32-cell words (module
//! `bfs`, memory layout above). The layer-`k` frontier is the set of cells whose layer code is
//! `k mod 3 + 1`: older cells with the same code (layers `k - 3`, `k - 6`, …) are inside the
//! reached region, all their legal neighbours are reached, so they add nothing and need no
//! separate frontier plane. For a target row `t`, word by word, with `F` the frontier and `M`
//! the free bits of a row:
//!
//! ```text
//! N[t] = M[t] & !reached[t] & ( F[t-1] & M[t] | F[t+1] & M[t] | east(F[t]) | west(F[t])
//!        | M[t-1] & spread(F[t-1] & M[t])      // diagonals from the row below
//!        | M[t+1] & spread(F[t+1] & M[t]) )    // diagonals from the row above
//! ```
//!
//! (`spread(x) = x << 1 | x >> 1`: a diagonal needs its two side cells free, the one in the
//! target row at the source column, `F & M[t]`, and the one in the source row at the target
//! column, `M[t∓1]`.) New cells get the next code (two ORs per word). Only the (row, word)
//! pairs that hold frontier cells are visited: per layer parity, per word column, a bit set of
//! the rows with frontier cells, and a summary of its non-empty words. Consecutive rows of one
//! column (up to 30; runs up to 6 rows apart join, `RUN_JOIN_GAP` in `bfs.rs`: the rows between
//! cost less than another call) are expanded as one *vertical run*, sliding a window of three
//! rows up the column, so each word is loaded once per layer; a single row reads its word and
//! the same word in the rows below and above. The run kernel walks column slices (the planes
//! are column-major) with zipped iterators, no index arithmetic or bounds test per row; it
//! takes the layer mod 3 as a compile-time parameter (the frontier and next-code masks are
//! constants) and is unrolled by three so that the window's rows change roles by name, not by
//! register moves (on the MCU: 95 instructions per row before, about 45 after). Moves across a
//! word edge (bit 31 of word `w` to bit 0 of `w + 1` and back) are rare (one cell pair per 32
//! columns): new cells at a word edge also put their row into the column's *edge set*, whose
//! rows are then expanded cell by cell across the edge with the same rule (out of line, as is
//! the single-row case: the layer loop keeps its registers). BFS needs no queue entries.
//!
//! *From both ends.* The search floods from the start (side A) and from the goal (side B),
//! one layer of one side at a time, alternating, so that on open floors each side floods a ball
//! of about half the distance (on the 300 × 300 open floor 46 345 cells instead of 88 803). A
//! third plane `SIDE` tells the sides apart (1 = reached from the goal): side X's frontier at
//! its layer `l` is "code `l mod 3 + 1` and `SIDE` = X", new cells get X's next code and `SIDE`
//! bit. Next to the new cells `N = reach & M & !reached` the kernel computes the *meetings*
//! `reach & reached & other side`. Why the first meeting gives the fewest steps: as long as
//! no layer met the other side, each side's marks are exactly its ball (`d_A ≤ a`, `d_B ≤ b`,
//! true distances) and the balls are disjoint and not joined by a move, so the distance `D`
//! is at least `a + b + 1`. When side X expands its layer `a` and reaches a cell `m` of side
//! Y, `d_Y(m) = b` (a Y cell of layer `≤ b - 1` next to X's frontier cell would have reached
//! that cell, or met it, when Y expanded that layer), so `a + 1 + b` steps join start and goal
//! and `D = a + b + 1`. The search ends after that layer; `cost` = `a + 1 + b` (counted by the
//! rebuild), `expanded` = cells reached by both sides (popcount of the code planes). It is
//! `Unreachable` when a layer adds no cell before any meeting (that side's region is all
//! reached and holds no cell of the other side). The path: the meeting move joins a cell of A
//! and a cell of B (the kernel notes the rows and word of the meeting; the rebuild finds the
//! pair there); each side is walked down its own layers (from a cell of layer `d` to a
//! neighbour of the same side with code `(d - 1) mod 3 + 1` that a legal move joins; its
//! neighbours have layers `d - 1 ..= d + 1`, which the code tells apart), preferring the
//! previous step's direction, then E, N, W, S, NE, NW, SW, SE; collinear cells are merged
//! across the join. When the `SIDE` plane does not fit in the scratch (narrow grids with
//! much row padding), the search runs from the start only and stops at the layer that
//! reaches the goal. While the two sides are far apart (the rectangles of 32-row × 32-column
//! blocks holding each side's cells, one grown by a block, do not meet) no word holds cells of
//! both and no meeting is possible: those layers run without `SIDE` (neither read nor
//! written), and before the first layer where the rectangles come near `SIDE` is set to the
//! reached cells of the goal side's rectangle. The scalar restart below is one-sided.
//!
//! *Narrow frontiers.* In a maze or a corridor the frontier holds 1–3 cells for thousands of
//! layers, and the per-layer and per-word costs outweigh the word parallelism (on the 300 × 300
//! maze: 8.3 M instructions on the MCU against 4.1 M cell by cell, measured before the last
//! optimisations of the layered search). So after 48 layers (`NARROW_CHECK_LAYER`), when the
//! frontier averaged fewer than 8 (row, word) pairs per layer (`NARROW_PAIRS_PER_LAYER`), BFS
//! starts again as the *scalar* queue BFS below (the false start costs about 0.12 M
//! instructions on the MCU: the plane set-up and 48 layers). It uses the queue (a ring buffer;
//! [`PlanError::QueueFull`] when it fills) and reports the cells taken off the queue as
//! `expanded`. A flood from a corner of an open floor averages about 30 pairs per layer by
//! then (one per row of its L-shaped front).
//!
//! The scalar BFS marks a cell (with its parent step) when it is first *discovered*: in a FIFO
//! queue the first discovery is by a fewest-steps parent, so every cell enters the ring buffer
//! at most once. Its hot loop reads a popped cell's 3 × 3 neighbourhood as three 12-bit
//! *windows* (three nibbles of a row, from two 32-bit scratch reads), looks each window up in a
//! 4 KB table built at compile time ("nibble 0?" and "not occupied?" for its three cells) and combines the three
//! answers into a mask of the targets with a few operations, so the side cells read for the side
//! moves also decide the diagonals. The targets are then tested in the fixed order E, N, W, S,
//! NE, NW, SW, SE with constant index offsets (a loop over the mask's bits had fewer
//! instructions but ran 25 % slower on x86-64: its store addresses come late, so the next
//! cell's reads of the same words wait). Border cells take a slower path that reads cells off
//! the map as occupied. Marking a new cell is one OR (its nibble is 0). The ring buffer is two
//! counters, pushed and popped (slot = counter mod capacity).
//!
//! Search loops carry cell coordinates in their queue entries (no division per cell) and test
//! the 8 neighbours with index arithmetic on the row-major nibble array.
//!
//! ## Complexity
//!
//! Layered BFS: `O(layers × frontier words + reached cells / 32)`; from both ends on the
//! 300 × 300 open floor (2 × 146 layers, 46 345 cells) 2.9 M Cortex-M4 instructions, 63 per
//! cell; 20 % random obstacles 4.9 M (53 055 cells, 92 per cell). Scalar BFS: `O(n)` for `n` cells, about 205 Cortex-M4 instructions per
//! cell (4.2 M in the 300 × 300 maze). Jump point
//! search (A*, and BFS on uncluttered maps): each expansion scans up to 8 rays; a row scan costs `O(length / 32)` word operations,
//! a column scan `O(length)` 3-bit reads, a diagonal run `O(rows × columns / 32)`; on the
//! seed's room maps a whole plan takes 0.9–2.9 M Cortex-M4 instructions for 9–22 jump points
//! (A*), 0.76–1.76 M for 8–15 (BFS, unit costs).
//! Keys are `u32`: a path may cost at most `u32::MAX` (more than 529 000 diagonal steps, which
//! only grids above about 727 × 727 cells can hold); beyond that the cell-by-cell search's keys
//! wrap and its result is undefined (but it does not panic).
//! Cell-by-cell A*: at most 8 pushes per expanded cell (typically fewer than one), each O(1)
//! (a walk's end: O(far list), a few entries), pops O(1); about 232 Cortex-M4 instructions per
//! expanded cell and about 100 (x86-64, measured) per corridor cell walked (6.7 M on 20 %
//! random obstacles, 3.8 M in the maze, 300 × 300). Rebuilding the path
//! walks the records and the steps back from the goal: `O(path cells)`, plus, for the
//! any-angle planner, one line-of-sight test per straight run not starting at the anchor and a
//! bisection in the runs where a shortcut ends (`O(runs × log(run) × segment length)`); a side-step turn with a
//! blocked inner corner right after a run from the anchor costs one cell read instead.
//!
//! ## Any-angle
//!
//! [`PlannerKind::AnyAngle`] runs A*, then pulls the string on the A* cell path, run by run
//! (maximal straight pieces), from the goal towards the start: if the far end of the next run
//! is visible from the anchor by [`line_of_sight`], the whole run is skipped; otherwise the last
//! visible cell of the run is found by bisection and becomes a vertex and the new anchor. Every
//! segment therefore passes the same no-corner-cutting line-of-sight test (a run that starts
//! at the anchor is made of A* moves and needs none), and by the triangle inequality the
//! polyline is never longer than the A* path it shortcuts. At a turn between two side-step
//! runs, when the anchor lies on the first one and the *inner corner* (the cell beside both
//! runs at the turn) is blocked, the first cell past the turn is hidden from the anchor (the
//! Bresenham line to it crosses that corner or steps diagonally past it), so the turn becomes a
//! vertex at once, without line-of-sight tests (the bisection would cut there too, unless a
//! farther cell of the run were visible again). In a maze of 1-cell corridors that is every
//! turn: any-angle 7.8 M → 4.1 M instructions there. [`line_of_sight`] steps a bit index
//! along the Bresenham cells (no per-cell bounds arithmetic), about 12 instructions per cell.
//!
//! ```
//! use twil_core::geom::PointM;
//! use twil_core::grid::{Grid, GridGeometry, words_for_cells};
//! use twil_core::plan::{PathM, Planner, PlannerKind, PlanStatus, scratch_words_for_cells};
//!
//! let geometry = GridGeometry::new(20, 10, 0.1).unwrap();
//! let mut grid = Grid::<{ words_for_cells(200) }>::new(geometry).unwrap();
//! for y in 0..8 {
//!     grid.set_xy(10, y, true); // a wall with a gap at the top
//! }
//! let mut planner = Planner::<{ scratch_words_for_cells(200) }, 256>::new();
//! let mut path = PathM::new();
//! let report = planner
//!     .plan(PlannerKind::AStar, &grid, PointM::new(0.15, 0.15), PointM::new(1.85, 0.15), &mut path)
//!     .unwrap();
//! assert_eq!(report.status, PlanStatus::Found);
//! assert_eq!(path.first(), Some(&PointM::new(0.15, 0.15)));
//! assert!(report.length_m > 1.7);
//! ```

mod bfs;
mod los;
mod prune;

#[cfg(test)]
mod tests;

pub use los::{line_of_sight, line_of_sight_m};
pub use prune::{needs_full_sweep, prune_visible_prefix, PruneEnd, Pruned, NORMAL_HALF_BAND_RAD};

use heapless::Vec;

use crate::geom::{Cell, PointM};
use crate::grid::{Grid, GridGeometry};

/// Cost of a side step in A* (integer octile costs: `DIAGONAL_COST / STRAIGHT_COST` ≈ √2).
pub const STRAIGHT_COST: u32 = 5741;
/// Cost of a diagonal step in A*.
pub const DIAGONAL_COST: u32 = 8119;

/// Largest number of vertices in a returned path polyline. The 300 x 300 benchmark maze (1-cell
/// corridors, 8 948 steps) needs 2 845; room worlds need a few dozen.
pub const MAX_PATH_POINTS: usize = 3072;

/// A path in world metres, first point = start cell centre, last = goal cell centre.
pub type PathM = Vec<PointM, MAX_PATH_POINTS>;

/// The same polyline as [`PathM`], as grid cells.
pub type PathCells = Vec<Cell, MAX_PATH_POINTS>;

/// Number of scratch words a [`Planner`] needs for `cells` cells (4 bits per cell).
pub const fn scratch_words_for_cells(cells: usize) -> usize {
    cells.div_ceil(8)
}

/// Scratch words for the seed's 300 × 300 grid (45 000 bytes).
pub const SCRATCH_WORDS_300: usize = scratch_words_for_cells(300 * 300);
/// Scratch words for a 400 × 400 grid (80 000 bytes).
pub const SCRATCH_WORDS_400: usize = scratch_words_for_cells(400 * 400);

/// The usual planner for the seed's 300 × 300 grid: 45 000 bytes of scratch, 3 072 queue
/// entries (36 864 bytes; jump point search uses at most 40 of them on the bundled worlds, the
/// cell-by-cell A* 766 on 20 % random obstacles), the 12 288-byte vertex buffer and the
/// cell-by-cell A*'s 2 560-byte goal table: about 97 KB in all.
pub type Planner300 = Planner<SCRATCH_WORDS_300, 3072>;

/// Which planner to run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlannerKind {
    /// Breadth-first search, the seed's planner: fewest steps.
    Bfs,
    /// A* with octile costs: shortest 8-connected path.
    #[default]
    AStar,
    /// A* followed by line-of-sight shortcuts: straight segments, never longer than A*.
    AnyAngle,
}

impl PlannerKind {
    /// The planner's name on the command line and in JSON: `bfs`, `astar`, `anyangle`.
    pub const fn as_str(self) -> &'static str {
        match self {
            PlannerKind::Bfs => "bfs",
            PlannerKind::AStar => "astar",
            PlannerKind::AnyAngle => "anyangle",
        }
    }
}

/// How a planning request ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanStatus {
    /// A path was found.
    Found,
    /// Start and goal are free but not connected.
    Unreachable,
    /// The start cell is occupied.
    StartBlocked,
    /// The goal cell is occupied.
    GoalBlocked,
    /// Start or goal lies outside the map.
    OutOfBounds,
}

impl PlanStatus {
    /// The status in snake case, as in the JSON of `twil plan`: `found`, `unreachable`,
    /// `start_blocked`, `goal_blocked`, `out_of_bounds`.
    pub const fn as_str(self) -> &'static str {
        match self {
            PlanStatus::Found => "found",
            PlanStatus::Unreachable => "unreachable",
            PlanStatus::StartBlocked => "start_blocked",
            PlanStatus::GoalBlocked => "goal_blocked",
            PlanStatus::OutOfBounds => "out_of_bounds",
        }
    }
}

/// A capacity ran out while planning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum PlanError {
    /// The grid has more cells than the planner's scratch memory covers.
    ScratchTooSmall {
        /// Cells in the grid.
        cells: u32,
        /// Cells the scratch covers.
        capacity: u32,
    },
    /// The open queue filled up.
    QueueFull {
        /// Queue capacity, entries.
        capacity: u32,
    },
    /// The path has more vertices than [`MAX_PATH_POINTS`]. The search itself succeeded:
    /// [`Planner::last_report`] has its cost, length and expansions.
    PathFull {
        /// Path capacity, vertices.
        capacity: u32,
    },
}

impl core::fmt::Display for PlanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            PlanError::ScratchTooSmall { cells, capacity } => write!(
                f,
                "grid has {cells} cells but the planner's scratch covers {capacity}"
            ),
            PlanError::QueueFull { capacity } => {
                write!(f, "planner queue full ({capacity} entries)")
            }
            PlanError::PathFull { capacity } => {
                write!(f, "path has more than {capacity} vertices")
            }
        }
    }
}

/// What a planning request produced (the path itself goes to the caller's [`PathM`]).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PlanReport {
    /// How it ended.
    pub status: PlanStatus,
    /// Nodes expanded: for BFS on uncluttered maps the jump points expanded (unit-cost jump
    /// point search), on cluttered ones the cells reached (layered search; the scalar one in
    /// narrow maps: the cells taken off its queue), both added when jump points gave up; jump
    /// points for A* and any-angle (plus the cells of the cell-by-cell search when it fell back
    /// to it: the cells it closed, those closed by corridor walks included).
    pub expanded: u32,
    /// BFS: steps; A* and any-angle: the A* cost in [`STRAIGHT_COST`] units. 0 unless found.
    pub cost: u32,
    /// Euclidean length of the returned polyline, metres. 0 unless found.
    pub length_m: f32,
}

impl PlanReport {
    const fn empty(status: PlanStatus) -> Self {
        Self {
            status,
            expanded: 0,
            cost: 0,
            length_m: 0.0,
        }
    }
}

/// One open-list / queue entry: 12 bytes.
#[derive(Clone, Copy, Debug)]
struct OpenEntry {
    /// `g + h` (A*), unused by BFS.
    f: u32,
    /// `cell_index << 4 | step code` (A*), `cell_index` (BFS).
    node: u32,
    /// Next entry of the same list (A*), unused by BFS.
    next: u32,
}

impl OpenEntry {
    const ZERO: Self = Self {
        f: 0,
        node: 0,
        next: NIL,
    };
}

/// Nibble code of the start cell.
const CODE_START: u32 = 9;
/// Nibble code of an occupied cell (copied from the map before a search).
const BLOCKED: u32 = 0xF;

/// Spread the 8 bits of `byte` to the low bit of 8 nibbles (bit k -> bit 4k).
#[inline(always)]
fn spread_bits_to_nibbles(byte: u32) -> u32 {
    let mut x = byte & 0xFF;
    x = (x | (x << 12)) & 0x000F_000F;
    x = (x | (x << 6)) & 0x0303_0303;
    (x | (x << 3)) & 0x1111_1111
}

/// [`BLOCKED`] in the nibble of each set bit of a byte (bit k -> nibble k): one table read
/// per 8 cells when [`Planner::copy_map`] copies the map. 1 KB of read-only data.
static BLOCKED_NIBBLES: [u32; 256] = {
    let mut table = [0u32; 256];
    let mut b = 0;
    while b < 256 {
        let mut k = 0;
        while k < 8 {
            if b & (1 << k) != 0 {
                table[b] |= BLOCKED << (4 * k);
            }
            k += 1;
        }
        b += 1;
    }
    table
};

/// Step of each code 1..=8 (index = code - 1): E, N, W, S, NE, NW, SW, SE.
const STEPS: [(i32, i32); 8] = [
    (1, 0),
    (0, 1),
    (-1, 0),
    (0, -1),
    (1, 1),
    (-1, 1),
    (-1, -1),
    (1, -1),
];
const E: u32 = 1;
const N: u32 = 2;
const W: u32 = 3;
const S: u32 = 4;
const NE: u32 = 5;
const NW: u32 = 6;
const SW: u32 = 7;
const SE: u32 = 8;

#[inline(always)]
fn nibble(scratch: &[u32], index: usize) -> u32 {
    match scratch.get(index >> 3) {
        Some(w) => (w >> ((index & 7) * 4)) & 0xF,
        None => 0xF,
    }
}

#[inline(always)]
fn set_nibble(scratch: &mut [u32], index: usize, code: u32) {
    if let Some(w) = scratch.get_mut(index >> 3) {
        let shift = (index & 7) * 4;
        *w = (*w & !(0xF << shift)) | (code << shift);
    }
}

/// The step code (1..=8) of the unit step `(dx, dy)`; 0 for `(0, 0)` or a non-unit step.
#[inline(always)]
const fn step_code(dx: i32, dy: i32) -> u32 {
    match (dx, dy) {
        (1, 0) => E,
        (0, 1) => N,
        (-1, 0) => W,
        (0, -1) => S,
        (1, 1) => NE,
        (-1, 1) => NW,
        (-1, -1) => SW,
        (1, -1) => SE,
        _ => 0,
    }
}

/// Octile distance in A* cost units (also used by the tables built at compile time).
#[inline(always)]
const fn octile(dx: u32, dy: u32) -> u32 {
    let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
    DIAGONAL_COST
        .saturating_mul(lo)
        .saturating_add(STRAIGHT_COST.saturating_mul(hi - lo))
}

/// Nibbles `j`, `j + 1`, `j + 2` of the scratch in bits 0..12 (beyond it: [`BLOCKED`]).
#[inline(always)]
pub(super) fn nibble_window(scratch: &[u32], j: usize) -> u32 {
    let w = j >> 3;
    match scratch.get(w..w.wrapping_add(2)) {
        Some(&[lo, hi]) => {
            let shift = ((j & 7) * 4) as u32;
            ((lo >> shift) | ((hi << 1) << (31 - shift))) & 0xFFF
        }
        _ => nibble(scratch, j) | nibble(scratch, j + 1) << 4 | nibble(scratch, j + 2) << 8,
    }
}

/// The map's interior for the nibble searches (scalar BFS, cell-by-cell A*): cells whose 3 × 3
/// neighbourhood lies on the map, i.e. `x` in `1 .. width - 1` and `index` in
/// `width .. cells - width`. Their neighbourhood is three [`nibble_window`]s at constant
/// offsets; border cells read nibble by nibble.
#[derive(Clone, Copy)]
pub(super) struct Interior {
    width: usize,
    height: usize,
    inner_x: usize,
    inner_span: usize,
}

impl Interior {
    pub(super) fn new(geometry: &GridGeometry) -> Self {
        let width = geometry.width() as usize;
        Self {
            width,
            height: geometry.height() as usize,
            inner_x: width.saturating_sub(2),
            inner_span: geometry.cell_count().saturating_sub(2 * width),
        }
    }

    /// Whether cell `index` (column `x`) is an interior cell.
    #[inline(always)]
    pub(super) fn contains(&self, index: usize, x: usize) -> bool {
        x.wrapping_sub(1) < self.inner_x && index.wrapping_sub(self.width) < self.inner_span
    }

    /// The 3 × 3 neighbourhood of cell `index` (column `x`) as three 12-bit windows, (row
    /// above, same row, row below), column `x - 1` in bits 0..4 of each. Off-map cells read as
    /// [`BLOCKED`]. `y` is called on border cells only (so a caller without the row at hand
    /// divides there only).
    #[inline(always)]
    pub(super) fn neighbourhood(
        &self,
        scratch: &[u32],
        index: usize,
        x: usize,
        y: impl FnOnce() -> usize,
    ) -> (u32, u32, u32) {
        let width = self.width;
        if self.contains(index, x) {
            return (
                nibble_window(scratch, index + width - 1),
                nibble_window(scratch, index - 1),
                nibble_window(scratch, index - width - 1),
            );
        }
        let y = y();
        // Nibble of (x + sx - 1, y + sy - 1), BLOCKED off the map.
        let at = |sx: usize, sy: usize| -> u32 {
            let (nx, ny) = ((x + sx).wrapping_sub(1), (y + sy).wrapping_sub(1));
            if nx < width && ny < self.height {
                nibble(scratch, ny * width + nx)
            } else {
                BLOCKED
            }
        };
        let row = |sy: usize| at(0, sy) | at(1, sy) << 4 | at(2, sy) << 8;
        (row(2), row(1), row(0))
    }
}

/// The nibble scratch as the cell-by-cell A* and its corridor walks read it. Two layouts with
/// the same contents and the same search on top ([`Flat`], [`Framed`]): a search gives the same
/// result, expansions and path in either.
trait CellMap {
    /// Scratch index of cell `(x, y)` (a cell of the map).
    fn index(&self, x: usize, y: usize) -> usize;
    /// Index step of one row up.
    fn row_step(&self) -> usize;
    /// The nibble at `index` ([`BLOCKED`] beyond the scratch).
    fn nibble(&self, index: usize) -> u32;
    /// OR `code` into the nibble at `index` (a nibble known to be 0).
    fn mark(&mut self, index: usize, code: u32);
    /// Close the cell at `index` with `code` if its nibble is 0 (free, not closed); whether it
    /// was.
    fn close(&mut self, index: usize, code: u32) -> bool;
    /// Whether cell `(x, y)` at `index` is an interior cell: its 3 × 3 neighbourhood lies on
    /// the map (corridor walks stop at the others, in both layouts).
    fn interior(&self, index: usize, x: usize, y: usize) -> bool;
    /// The 3 × 3 neighbourhood of an interior cell as three 12-bit windows (row above, same
    /// row, row below), column `x - 1` in bits 0..4 of each.
    fn interior_windows(&self, index: usize) -> (u32, u32, u32);
    /// The same for any cell of the map (off-map cells read as [`BLOCKED`]).
    fn windows(&self, index: usize, x: usize, y: usize) -> (u32, u32, u32);
}

/// The flat layout: one nibble per cell, row-major like the grid (as the scalar BFS and jump
/// point search use the scratch). Cells on the map border read their neighbours one by one.
struct Flat<'a> {
    scratch: &'a mut [u32],
    interior: Interior,
}

impl CellMap for Flat<'_> {
    #[inline(always)]
    fn index(&self, x: usize, y: usize) -> usize {
        y * self.interior.width + x
    }
    #[inline(always)]
    fn row_step(&self) -> usize {
        self.interior.width
    }
    #[inline(always)]
    fn nibble(&self, index: usize) -> u32 {
        nibble(self.scratch, index)
    }
    #[inline(always)]
    fn mark(&mut self, index: usize, code: u32) {
        if let Some(word) = self.scratch.get_mut(index >> 3) {
            *word |= code << ((index & 7) * 4);
        }
    }
    #[inline(always)]
    fn close(&mut self, index: usize, code: u32) -> bool {
        let Some(word) = self.scratch.get_mut(index >> 3) else {
            return false;
        };
        let shift = (index & 7) * 4;
        let open = (*word >> shift) & 0xF == 0;
        if open {
            *word |= code << shift;
        }
        open
    }
    #[inline(always)]
    fn interior(&self, index: usize, x: usize, _y: usize) -> bool {
        self.interior.contains(index, x)
    }
    #[inline(always)]
    fn interior_windows(&self, index: usize) -> (u32, u32, u32) {
        let width = self.interior.width;
        (
            nibble_window(self.scratch, index + width - 1),
            nibble_window(self.scratch, index - 1),
            nibble_window(self.scratch, index - width - 1),
        )
    }
    #[inline(always)]
    fn windows(&self, index: usize, x: usize, y: usize) -> (u32, u32, u32) {
        self.interior.neighbourhood(self.scratch, index, x, || y)
    }
}

/// Words of the [`Framed`] layout's view of the MCU-sized scratch: `2^14` words a mask can
/// index, plus one so that the second word of a window needs no bounds test either.
const FRAMED_WORDS: usize = (1 << 14) + 1;

/// The least scratch (32-bit words) with which the cell-by-cell A* uses its framed layout
/// (grids up to about 360 × 360 cells; see the module docs): the MCU's planner size.
pub const FRAMED_SCRATCH_WORDS: usize = FRAMED_WORDS;

/// The framed layout: rows padded to whole words with at least one [`BLOCKED`] nibble (the
/// row stride is `width + 1` rounded up to 8 nibbles), cell `(x, y)` at nibble `(y + 1) ·
/// stride + x + 1`, and a row of blocked nibbles below and above the map. So every cell, on
/// the border too, has its 3 × 3 neighbourhood in three windows at the same shift in three
/// words a row apart, and the words are indexed through a mask (the view is `WORDS` words,
/// `WORDS − 1` a power of two) instead of bounds tests. 300 × 300 cells take 304 / 8 × 302 =
/// 11 477 words.
struct Framed<'a, const WORDS: usize> {
    words: &'a mut [u32; WORDS],
    /// Row stride, nibbles (a multiple of 8) and words.
    stride: usize,
    row_words: usize,
    width: usize,
    height: usize,
}

impl<'a, const WORDS: usize> Framed<'a, WORDS> {
    /// Word indices are masked with this (`WORDS − 2`: `WORDS − 1` is a power of two).
    const MASK: usize = {
        assert!(WORDS > 2 && (WORDS - 1).is_power_of_two());
        WORDS - 2
    };

    /// Scratch words the layout needs for `geometry`: the rows, the frame rows and one more
    /// blocked word (the north-east neighbour of the last cell when `width + 1` is a multiple
    /// of 8 lies just past the upper frame row).
    const fn words_for(geometry: &GridGeometry) -> usize {
        Self::row_words(geometry) * (geometry.height() as usize + 2) + 1
    }

    /// Words of a padded row: `width + 1` nibbles (at least one blocked) rounded up.
    const fn row_words(geometry: &GridGeometry) -> usize {
        (geometry.width() as usize + 1).div_ceil(8)
    }

    /// The layout over the first `WORDS` words of `scratch`, when they hold the framed map of
    /// `geometry` (`None`: use [`Flat`]).
    fn new(scratch: &'a mut [u32], geometry: &GridGeometry) -> Option<Self> {
        if Self::words_for(geometry) > Self::MASK + 1 {
            return None;
        }
        let words = scratch.first_chunk_mut::<WORDS>()?;
        let row_words = Self::row_words(geometry);
        Some(Self {
            words,
            stride: row_words * 8,
            row_words,
            width: geometry.width() as usize,
            height: geometry.height() as usize,
        })
    }

    /// Copy the map into the layout: occupied cells and the frame [`BLOCKED`], free cells 0.
    /// Per row, 32 cells (four scratch words) per funnel shift of two grid words, then the
    /// row's padding nibbles are set.
    fn copy_map<const GW: usize>(&mut self, grid: &Grid<GW>) {
        let bits = grid.words();
        let (width, row_words) = (self.width, self.row_words);
        for y in [0, self.height + 1] {
            for w in 0..row_words {
                self.words[(y * row_words + w) & Self::MASK] = u32::MAX;
            }
        }
        self.words[((self.height + 2) * row_words) & Self::MASK] = u32::MAX;
        // The nibbles past the row's last cell in its last word (none when `width + 1` is a
        // multiple of 8: the next row's left padding follows at once).
        let right_padding = match (width + 1) % 8 {
            0 => 0,
            n => u32::MAX << (4 * n),
        };
        for y in 0..self.height {
            let row = (y + 1) * row_words;
            let Some(dst) = self.words.get_mut(row..row + row_words) else {
                continue;
            };
            // Nibble n of the row is cell x = n − 1, grid bit y · width + n − 1. Counted from
            // 32 bits earlier, with a word of set bits before the grid's first, that is bit
            // `at` of the sequence (set word, grid words…, set words).
            let at = y * width + 31;
            let (k, shift) = (at / 32, (at % 32) as u32);
            let nibbles =
                |cells: u32, j: u32| BLOCKED_NIBBLES[((cells >> (8 * j)) & 0xFF) as usize];
            let funnel = |lo: u32, hi: u32| (lo >> shift) | ((hi << 1) << (31 - shift));
            let chunks = row_words.div_ceil(4);
            // Grid words k − 1 ..= k − 1 + chunks, when they are all on the grid (every row
            // but the first and the last, usually): a slice, read in pairs without tests.
            match k.checked_sub(1).and_then(|i| bits.get(i..=i + chunks)) {
                Some(source) => {
                    let mut quads = dst.chunks_exact_mut(4);
                    let mut pairs = source.windows(2);
                    for (quad, pair) in (&mut quads).zip(&mut pairs) {
                        if let ([a, b, c, d], &[lo, hi]) = (quad, pair) {
                            // Written out: the compiler does not unroll at opt-level "s".
                            let cells = funnel(lo, hi);
                            (*a, *b, *c, *d) = (
                                nibbles(cells, 0),
                                nibbles(cells, 1),
                                nibbles(cells, 2),
                                nibbles(cells, 3),
                            );
                        }
                    }
                    if let Some(&[lo, hi]) = pairs.next() {
                        let cells = funnel(lo, hi);
                        for (j, word) in quads.into_remainder().iter_mut().enumerate() {
                            *word = nibbles(cells, j as u32);
                        }
                    }
                }
                None => {
                    // The first or last row: word by word, a set word before and past the grid.
                    let word = |i: usize| match i.checked_sub(1) {
                        Some(i) => bits.get(i).copied().unwrap_or(u32::MAX),
                        None => u32::MAX,
                    };
                    for (j, out) in dst.iter_mut().enumerate() {
                        let cells = funnel(word(k + j / 4), word(k + j / 4 + 1));
                        *out = nibbles(cells, (j % 4) as u32);
                    }
                }
            }
            if let Some(word) = dst.first_mut() {
                *word |= BLOCKED; // the left padding
            }
            if let Some(word) = dst.last_mut() {
                *word |= right_padding;
            }
        }
    }

    /// Nibbles `j ..= j + 2` in bits 0..12 (higher bits: garbage), `j` not past the map.
    #[inline(always)]
    fn window_at(&self, w: usize, shift: u32) -> u32 {
        let w = w & Self::MASK;
        let (lo, hi) = (self.words[w], self.words[w + 1]);
        (lo >> shift) | ((hi << 1) << (31 - shift))
    }
}

impl<const WORDS: usize> CellMap for Framed<'_, WORDS> {
    #[inline(always)]
    fn index(&self, x: usize, y: usize) -> usize {
        (y + 1) * self.stride + x + 1
    }
    #[inline(always)]
    fn row_step(&self) -> usize {
        self.stride
    }
    #[inline(always)]
    fn nibble(&self, index: usize) -> u32 {
        (self.words[(index >> 3) & Self::MASK] >> ((index & 7) * 4)) & 0xF
    }
    #[inline(always)]
    fn mark(&mut self, index: usize, code: u32) {
        self.words[(index >> 3) & Self::MASK] |= code << ((index & 7) * 4);
    }
    #[inline(always)]
    fn close(&mut self, index: usize, code: u32) -> bool {
        let word = &mut self.words[(index >> 3) & Self::MASK];
        let shift = (index & 7) * 4;
        let open = (*word >> shift) & 0xF == 0;
        if open {
            *word |= code << shift;
        }
        open
    }
    #[inline(always)]
    fn interior(&self, _index: usize, x: usize, y: usize) -> bool {
        x.wrapping_sub(1) < self.width.wrapping_sub(2)
            && y.wrapping_sub(1) < self.height.wrapping_sub(2)
    }
    #[inline(always)]
    fn interior_windows(&self, index: usize) -> (u32, u32, u32) {
        let j = index.wrapping_sub(1);
        let (w, shift) = (j >> 3, ((j & 7) * 4) as u32);
        (
            self.window_at(w.wrapping_add(self.row_words), shift) & 0xFFF,
            self.window_at(w, shift) & 0xFFF,
            self.window_at(w.wrapping_sub(self.row_words), shift) & 0xFFF,
        )
    }
    #[inline(always)]
    fn windows(&self, index: usize, _x: usize, _y: usize) -> (u32, u32, u32) {
        self.interior_windows(index)
    }
}

/// For each 12-bit window of three nibbles (a row of a 3 × 3 neighbourhood, for the scalar BFS
/// and the cell-by-cell A*): bit `k` (k = 0, 1, 2) set when nibble `k` is 0 (free, not reached
/// or closed), bit `3 + k` when it is not [`BLOCKED`]. 4 KB of read-only data, built at compile
/// time.
pub(super) static NIBBLE_WINDOWS: [u8; 4096] = {
    let mut table = [0u8; 4096];
    let mut v = 0;
    while v < 4096 {
        let mut m = 0u8;
        let mut k = 0;
        while k < 3 {
            let code = (v >> (4 * k)) & 0xF;
            if code == 0 {
                m |= 1 << k;
            }
            if code != BLOCKED as usize {
                m |= 8 << k;
            }
            k += 1;
        }
        table[v] = m;
        v += 1;
    }
    table
};

// The 18-bit neighbourhood mask of the cell-by-cell A*: three rows of [`NIBBLE_WINDOWS`]
// entries (below, same, above; 6 bits each). `Z_*`: the neighbour's nibble is 0 (a possible
// target); `O_*`: the neighbour is not blocked (a side cell a diagonal step may pass).
const Z_SW: u32 = 0;
const Z_S: u32 = 1;
const Z_SE: u32 = 2;
const Z_W: u32 = 6;
const Z_E: u32 = 8;
const Z_NW: u32 = 12;
const Z_N: u32 = 13;
const Z_NE: u32 = 14;
const O_SW: u32 = 3;
const O_S: u32 = 4;
const O_SE: u32 = 5;
const O_W: u32 = 9;
const O_E: u32 = 11;
const O_NW: u32 = 15;
const O_N: u32 = 16;
const O_NE: u32 = 17;

/// Corridor test of the cell-by-cell A*, indexed by the nine "not blocked" bits of a 3 × 3
/// neighbourhood (bits 0..3: the row below, W to E; 3..6: the cell's row; 6..9: the row above;
/// see [`corridor_index`]): the side neighbours (bit 0 E, 1 N, 2 W, 3 S) when the centre has
/// one or two *legal* neighbours under the no-corner-cutting rule (a dead end or a corridor
/// cell), else 0. A legal diagonal needs both its side cells free, so a cell with at most two
/// legal neighbours has side neighbours only. 512 bytes of read-only data.
static CORRIDOR_SIDES: [u8; 512] = {
    let mut table = [0u8; 512];
    let mut v = 0;
    while v < 512 {
        // Sides: E (row 1, col 2), N (row 2, col 1), W (row 1, col 0), S (row 0, col 1).
        let (e, n, w, s) = ((v >> 5) & 1, (v >> 7) & 1, (v >> 3) & 1, (v >> 1) & 1);
        let (ne, nw, sw, se) = ((v >> 8) & 1, (v >> 6) & 1, v & 1, (v >> 2) & 1);
        let legal = e + n + w + s + (ne & n & e) + (nw & n & w) + (sw & s & w) + (se & s & e);
        if legal == 1 || legal == 2 {
            table[v] = (e | n << 1 | w << 2 | s << 3) as u8;
        }
        v += 1;
    }
    table
};

/// The index into [`CORRIDOR_SIDES`] of an 18-bit neighbourhood mask (the `O_*` bits).
#[inline(always)]
fn corridor_index(m: u32) -> usize {
    (((m >> 3) & 7) | ((m >> 6) & 0x38) | ((m >> 9) & 0x1C0)) as usize
}

/// The cell-by-cell A* stops starting corridor walks when they have closed this many cells
/// fewer than the walks started (short chains on cluttered, roomy maps: 20 % random obstacles
/// walk about 0.15 cells per walk, a maze of 1-cell corridors dozens).
const WALK_GIVE_UP_CREDIT: i32 = -64;

/// End of a list of the open list.
/// End of a list of the open list.
const NIL: u32 = u32::MAX;

/// The reduced costs `r = cost + h(child) − h(parent)` of an octile step under the octile
/// heuristic, in increasing order: 0, `2S − D`, `2D − 2S`, `D`, `2S`, `2D` (S =
/// [`STRAIGHT_COST`], D = [`DIAGONAL_COST`]); the index is the step's *class*. A child's key is
/// its parent's plus one of these, see [`ClassQueue`].
const REDUCED_COSTS: [u32; CLASSES] = [
    0,
    2 * STRAIGHT_COST - DIAGONAL_COST,
    2 * DIAGONAL_COST - 2 * STRAIGHT_COST,
    DIAGONAL_COST,
    2 * STRAIGHT_COST,
    2 * DIAGONAL_COST,
];
/// Classes of reduced cost: 0 (the stack) and one FIFO list per non-zero value.
const CLASSES: usize = 6;
/// [`REDUCED_COSTS`] padded to 8 entries, for class numbers read from 3-bit fields.
const CLASS_COSTS: [u32; 8] = {
    let mut t = [0; 8];
    let mut c = 0;
    while c < CLASSES {
        t[c] = REDUCED_COSTS[c];
        c += 1;
    }
    t
};
/// The class of a reduced cost `r` by `r >> 10` (`r < 16 384`), `NO_CLASS` for none; the six
/// reduced costs fall into six different slots (0, 3, 4, 7, 11, 15).
const CLASS_BY_KILO: [u8; 16] = {
    let mut table = [NO_CLASS; 16];
    let mut c = 0;
    while c < CLASSES {
        table[(REDUCED_COSTS[c] >> 10) as usize] = c as u8;
        c += 1;
    }
    table
};
const NO_CLASS: u8 = 0xFF;

/// The class of reduced cost `r` (`key − last popped key`), `None` when `r` is not an octile
/// step's reduced cost.
#[inline(always)]
fn reduced_cost_class(r: u32) -> Option<usize> {
    let c = *CLASS_BY_KILO.get((r >> 10) as usize)? as usize;
    (REDUCED_COSTS.get(c) == Some(&r)).then_some(c)
}

/// Regions of [`goal_region`].
const REGIONS: usize = 128;

/// The *region* of a cell relative to the goal, `(dx, dy)` = cell − goal, as `0 .. 128`: the
/// *sign code* `3 (sgn dx + 1) + (sgn dy + 1)` (`0 ..= 8`) in bits 0..4 and `|dx| − |dy|`
/// clamped to `−4 ..= 3`, plus 4, in bits 4..7. The octile heuristic is linear in
/// `(|dx|, |dy|)` on each side of `|dx| = |dy|`, a step changes `|dx|` and `|dy|` by at most
/// one each in a way the signs fix, and it crosses that line only from `|dx| − |dy| = ±1`; so
/// the reduced cost of every step from a cell depends on its region only (checked against
/// `h` for every cell and step around many goals in the tests). The search computes the same
/// number from two per-axis table entries ([`goal_axis_entry`], [`axis_region`]) on grids of
/// at most [`GOAL_AXIS_CELLS`] a side and with this function on larger ones.
#[inline(always)]
fn goal_region(dx: i32, dy: i32) -> usize {
    let d = (dx.unsigned_abs().wrapping_sub(dy.unsigned_abs()) as i32).clamp(-4, 3) + 4;
    let code = 3 * (dx.signum() + 1) + dy.signum() + 1;
    ((code as u32 | (d as u32) << 4) & (REGIONS as u32 - 1)) as usize
}

/// Grid sides (cells) up to which the cell-by-cell A* takes each cell's [`goal_region`] from
/// a per-axis table of this many words filled once per search ([`goal_axis_entry`]; 2 KB in
/// the [`Planner`]); larger grids compute it per cell.
const GOAL_AXIS_CELLS: usize = 512;

/// Sign code of `i − g`: 0 below, 1 equal, 2 above.
#[inline(always)]
const fn axis_sign_code(i: u32, g: u32) -> u32 {
    (i > g) as u32 + (i >= g) as u32
}

/// Entry `i` of the per-axis goal table for the goal `(gx, gy)`, `i < GOAL_AXIS_CELLS`: in the
/// high half the column value `16 (|i − gx| + 4) + 3 sx + 2`, in the low half the row value
/// `16 |i − gy| + 2 − sy` (`sx`, `sy` the [`axis_sign_code`]s; both below 2^14). The column
/// value of `x` minus the row value of `y` is `16 (|dx| − |dy| + 4) + 3 sx + sy`: the sign
/// code in the low nibble (never a borrow: `3 sx + 2 ≥ 2 − sy`) and the unclamped difference
/// above it.
#[inline(always)]
const fn goal_axis_entry(i: u32, gx: u32, gy: u32) -> u32 {
    let col = ((i.abs_diff(gx) + 4) << 4) + 3 * axis_sign_code(i, gx) + 2;
    let row = (i.abs_diff(gy) << 4) + 2 - axis_sign_code(i, gy);
    (col << 16) | row
}

/// The [`goal_region`] of the cell of queue entry `node` (`y << 16 | x << 4 | code`; its column
/// `x` is passed too, as the search holds it already; `x` and `y` below [`GOAL_AXIS_CELLS`])
/// from the per-axis table `axis` ([`goal_axis_entry`]): one subtraction of the two entries'
/// halves (`a − (b << 16)`: the column value of `x` minus the row value of `y` in the high half,
/// `16 (|dx| − |dy| + 4) + sign code`, with `|dx| − |dy| + 4` in `−507 ..= 515`), one
/// saturation (`usat`) and one insert. With the loads of the two entries and of the step
/// classes about 11 Cortex-M4 instructions (`STEP_CLASSES` sits at the end of the same table).
#[inline(always)]
fn axis_region(axis: &[u32; GOAL_TABLE_WORDS], x: usize, node: u32) -> usize {
    // Masked indices into a fixed-size array: never out of range.
    let a = axis[x & (GOAL_AXIS_CELLS - 1)];
    let b = axis[(node >> 16) as usize & (GOAL_AXIS_CELLS - 1)];
    let v = a.wrapping_sub(b << 16) as i32;
    let d = (v >> 20).clamp(0, 7) as u32;
    (((v as u32 >> 16) & 15) | d << 4) as usize
}

/// Words of the [`Planner`]'s goal table: the per-axis entries, then a copy of
/// [`STEP_CLASSES`] (in RAM next to them, the search addresses both from one base).
const GOAL_TABLE_WORDS: usize = GOAL_AXIS_CELLS + REGIONS;

/// Flag of the [`STEP_CLASSES`] word of the goal's region (above the eight 3-bit classes).
const AT_GOAL: u32 = 1 << 31;

/// Per [`goal_region`]: the class (index into [`REDUCED_COSTS`]) of each step, in bits
/// `3 (code − 1) ..` for step code `code` (1 ..= 8). 512 bytes of read-only data, built at
/// compile time from one cell of each region (0 for the sign codes 9 ..= 15, which do not
/// occur). The goal's own region (sign code 4: `dx = dy = 0`, no other cell) also has
/// [`AT_GOAL`] set, so that the search tests for the goal on the word it loads anyway.
static STEP_CLASSES: [u32; REGIONS] = {
    let mut table = [0u32; REGIONS];
    let mut region = 0;
    while region < REGIONS {
        let d = (region >> 4) as i32 - 4;
        let code = (region & 15) as i32;
        let (sx, sy) = (code / 3 - 1, code % 3 - 1);
        // A cell of the region: |dx|, |dy| in 0..12 with those signs and that clamped
        // difference.
        let mut found = None;
        let mut a = 0;
        while a < 12 && found.is_none() && code < 9 {
            let mut b = 0;
            while b < 12 && found.is_none() {
                let diff = a - b;
                let dc = if diff < -4 {
                    -4
                } else if diff > 3 {
                    3
                } else {
                    diff
                };
                if (a == 0) == (sx == 0) && (b == 0) == (sy == 0) && dc == d {
                    found = Some((a * sx, b * sy));
                }
                b += 1;
            }
            a += 1;
        }
        if let Some((dx, dy)) = found {
            let mut word = 0u32;
            let mut k = 0;
            while k < 8 {
                let (mx, my) = STEPS[k];
                let cost = if k >= 4 { DIAGONAL_COST } else { STRAIGHT_COST };
                let r = cost + octile((dx + mx).unsigned_abs(), (dy + my).unsigned_abs())
                    - octile(dx.unsigned_abs(), dy.unsigned_abs());
                let mut c = 0;
                while c < CLASSES && REDUCED_COSTS[c] != r {
                    c += 1;
                }
                assert!(c < CLASSES, "not a reduced cost");
                word |= (c as u32) << (3 * k);
                k += 1;
            }
            if dx == 0 && dy == 0 {
                word |= AT_GOAL;
            }
            table[region] = word;
        }
        region += 1;
    }
    table
};

/// The scalar state of a [`ClassQueue`], kept apart from its arrays so that the search loop
/// holds it in registers (it is passed by value to the queue's out-of-line parts).
#[derive(Clone, Copy)]
struct QueueState {
    /// Head of the stack of entries whose key equals `last` (reduced cost 0).
    stack: u32,
    /// The last key popped (every key in the queue is at least this).
    last: u32,
    /// Entries of the pool ever used (the queue peak).
    bump: u32,
    /// Head of the list of freed entries.
    free: u32,
    /// The FIFO class of the last pop from a FIFO (1 ..= 5): its head is tried first.
    class: u32,
}

/// The open list of the cell-by-cell A*: lists by *reduced cost* over a fixed pool of entries.
///
/// With the octile heuristic (consistent), a child's key is its parent's plus the reduced cost
/// `r = cost + h(child) − h(parent)`, which takes only the six values of [`REDUCED_COSTS`]
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
struct ClassQueue<'a> {
    pool: &'a mut [OpenEntry],
    /// First and last entry of each FIFO class `1 ..= 5` (`NIL` when empty; index 0 and the
    /// two past the classes are unused, so that a 3-bit class indexes them).
    heads: [u32; 8],
    tails: [u32; 8],
    /// The key of each FIFO's head entry (`u32::MAX` when empty).
    head_keys: [u32; 8],
    /// Head of the far list (sorted by key, `NIL` when empty) and its key (`u32::MAX`).
    far: u32,
    far_key: u32,
}

impl<'a> ClassQueue<'a> {
    fn new(pool: &'a mut [OpenEntry], first_key: u32) -> (Self, QueueState) {
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
    fn push_stack(&mut self, s: &mut QueueState, node: u32) -> bool {
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
    fn push_class(&mut self, s: &mut QueueState, class: usize, node: u32) -> bool {
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
    fn push_far(&mut self, s: &mut QueueState, key: u32, node: u32) -> bool {
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
    fn pop(&mut self, s: &mut QueueState) -> u32 {
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
    fn take(&mut self, s: &mut QueueState, c: usize) -> u32 {
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
    fn pop_fifo(&mut self, s: &mut QueueState) -> u32 {
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
    fn reclaim_and_push(
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
    fn collect(&mut self, mut s: QueueState, stale: impl Fn(u32) -> bool) -> (QueueState, usize) {
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

/// The open list as the search loop sees it: [`ClassQueue`] (linked lists over the pool, the
/// exact `QueueFull` semantics) or [`RingQueue`] (rings carved from the pool, faster; it gives
/// up when a ring stays full and the caller then runs the search again with a `ClassQueue`).
/// Both pop the same entries in the same order.
trait OpenList<'a>: Sized {
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

/// Share of the pool per FIFO class `2 ..= 5` of a [`RingQueue`], in 256ths of what the far
/// list leaves (the rest goes to class 1). Most entries at once on 20 % random obstacles
/// (300 × 300, four seeds): class 1 304–371, class 2 13–16, class 3 62–97, class 4 310–359,
/// class 5 4–5; with a pool of 1 024 the rings hold 426, 30, 115, 402 and 14 entries.
const RING_SHARES: [u32; CLASSES] = [0, 0, 8, 30, 104, 4];
/// Entries of the far list of a [`RingQueue`], in 64ths of the pool (at least one entry).
const RING_FAR_SHARE: u32 = 2;

/// The open list of [`ClassQueue`] (same classes, same order of pops) on fixed *rings* instead
/// of linked lists: FIFO class `c` is a ring buffer of `(key, node)` in the `f` and `node`
/// fields of its own range of pool slots (capacities by [`RING_SHARES`]), the stack of class 0
/// lives in the `next` fields of the pool (up to one entry per slot), the far list is a sorted
/// array at the pool's front (smallest key last). No free list, no links: a push writes one
/// slot and moves a tail, a pop reads one slot and moves a head. When a ring (or the far
/// array) is full, the entries of closed cells are dropped from all (each keeps its order); if
/// the ring is then still more than 7/8 full the queue gives up (`reclaim_and_push` returns
/// `None`) and the caller runs the search again with a [`ClassQueue`], so results never depend
/// on the ring capacities.
/// One ring of a [`RingQueue`]: next slot to pop (`head`), next slot to write (`tail`;
/// `head == tail`: empty, and one slot stays unused so that a full ring is told apart), the
/// end of its slots and its reduced cost (a pushed key is the last popped key plus `cost`).
#[derive(Clone, Copy)]
struct Ring {
    head: u32,
    tail: u32,
    end: u32,
    cost: u32,
}

struct RingQueue<'a> {
    pool: &'a mut [OpenEntry],
    /// The hot state of ring `c` in one place (one base address for the loop).
    rings: [Ring; 8],
    /// Ring `c`'s slots are `starts[c] .. rings[c].end`.
    starts: [u32; 8],
    /// Entries of the far list: slots `0 .. far_len`, sorted by key, the smallest (and of
    /// equal keys the last pushed) last; `far_cap` slots.
    far_len: u32,
    far_cap: u32,
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
    fn take(&mut self, s: &mut QueueState, c: usize) -> u32 {
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
    /// empty) and return its node (`NIL` when all are empty). Ties as in [`ClassQueue`].
    #[inline(never)]
    fn pop_fifo(&mut self, s: &mut QueueState) -> u32 {
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
    fn collect(&mut self, s: &mut QueueState, stale: impl Fn(u32) -> bool) -> usize {
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
    fn ring_fill(&self, c: usize) -> (u32, u32) {
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
    /// `(key, node)`; `None` (give up: the caller runs a [`ClassQueue`]) when the push still
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

/// Walk a chain of corridor cells (see "Corridors" in the module docs) from the closed cell
/// `index` (entry `node`, interior) along its open side `rest` (bit `code - 1`, at most one
/// bit; 0 for a dead end): each corridor cell is closed with its step code. Returns the entry
/// of the cell to push at the end (`NIL` when nothing is to be pushed: a dead end or a closed
/// cell), the number of steps to it and the number of cells closed. Out of line so that the
/// search loop's registers are not spent on it.
#[inline(never)]
fn walk_corridor<M: CellMap>(
    map: &mut M,
    goal: usize,
    mut wi: usize,
    mut wnode: u32,
    mut rest: u32,
) -> (u32, u32, u32) {
    let row = map.row_step();
    // Index and entry steps of the side codes E, N, W, S.
    let index_step = [1, row, usize::MAX, row.wrapping_neg()];
    const WALK_NODE_STEP: [u32; 4] = [
        1 << 4,
        1 << 16,
        (1u32 << 4).wrapping_neg(),
        (1u32 << 16).wrapping_neg(),
    ];
    let (mut steps, mut closed) = (0u32, 0u32);
    while rest != 0 {
        let c = rest.trailing_zeros() + 1;
        let k = (c - 1) as usize & 3;
        wi = wi.wrapping_add(index_step[k]);
        wnode = (wnode & !0xF).wrapping_add(WALK_NODE_STEP[k]) | c;
        steps += 1;
        let (wx, wy) = (((wnode >> 4) & 0xFFF) as usize, (wnode >> 16) as usize);
        if wi == goal || !map.interior(wi, wx, wy) {
            // Pushed, not walked (a closed cell must not be pushed: it could be expanded at
            // once by the immediate expansion).
            let end = if map.nibble(wi) == 0 { wnode } else { NIL };
            return (end, steps, closed);
        }
        let window = |w: u32| u32::from(NIBBLE_WINDOWS[w as usize & 0xFFF]);
        let (above, cur, below) = map.interior_windows(wi);
        let wc = window(cur);
        if wc & 2 == 0 {
            return (NIL, steps, closed); // closed already
        }
        let wm = window(below) | wc << 6 | window(above) << 12;
        let t = u32::from(CORRIDOR_SIDES[corridor_index(wm)]);
        if t == 0 {
            return (wnode, steps, closed); // not a corridor cell
        }
        map.mark(wi, c);
        closed += 1;
        rest = t & !(1 << ((c + 1) & 3));
    }
    (NIL, steps, closed) // a dead end
}

/// Euclidean length of the segment between two cells, in cells.
#[inline]
fn cells_distance(a: Cell, b: Cell) -> f32 {
    let dx = a.x as f32 - b.x as f32;
    let dy = a.y as f32 - b.y as f32;
    crate::math::hypot(dx, dy)
}

/// The jump scans of [`Planner::jps`], on the grid's packed occupancy bits (1 = occupied):
/// side scans along a row test 32 cells per step with a few word operations; scans along a
/// column read 3 bits per row. Cells off the map count as occupied.
struct JumpScan<'a> {
    words: &'a [u32],
    width: i32,
    height: i32,
    goal_x: i32,
    goal_y: i32,
}

impl JumpScan<'_> {
    /// Occupancy of the 32 cells `c0 .. c0 + 32` of row `y` (bit k = column `c0 + k`), cells off
    /// the map set.
    #[inline(always)]
    fn row_bits(&self, y: i32, c0: i32) -> u32 {
        if (y as u32) >= self.height as u32 || c0 >= self.width || c0 <= -32 {
            return u32::MAX;
        }
        let from = c0.max(0);
        let i = (y * self.width + from) as usize;
        let lo = self.words.get(i >> 5).copied().unwrap_or(u32::MAX) as u64;
        let hi = self.words.get((i >> 5) + 1).copied().unwrap_or(u32::MAX) as u64;
        let mut bits = ((lo | (hi << 32)) >> (i & 31)) as u32;
        let valid = self.width - from; // columns of the row from `from` on
        if valid < 32 {
            bits |= u32::MAX << valid;
        }
        if c0 < 0 {
            let s = (-c0) as u32;
            bits = (bits << s) | ((1u32 << s) - 1);
        }
        bits
    }

    #[inline(always)]
    fn free(&self, x: i32, y: i32) -> bool {
        (x as u32) < self.width as u32
            && (y as u32) < self.height as u32
            && self.row_bits(y, x) & 1 == 0
    }

    /// Scan from `(x, y)` in the side direction `(dx, dy)` (one of them 0). Returns the first
    /// jump point `(x, y, steps)`: the goal, or a cell with a forced neighbour (a side cell
    /// that is free while the cell behind it, next to the previous cell of the scan, is
    /// occupied). `None` when the scan runs into an obstacle or off the map first.
    #[inline]
    fn straight(&self, x: i32, y: i32, dx: i32, dy: i32) -> Option<(i32, i32, u32)> {
        if dy == 0 {
            self.along_row(x, y, dx)
        } else {
            self.along_column(x, y, dy)
        }
    }

    fn along_row(&self, x: i32, y: i32, dx: i32) -> Option<(i32, i32, u32)> {
        let goal_in_row = self.goal_y == y;
        // The cells behind each side cell (one column back) come from shifting the side rows'
        // words, with the bit carried over from the previous word.
        let mut up_carry = self.row_bits(y + 1, x) & 1;
        let mut down_carry = self.row_bits(y - 1, x) & 1;
        if dx > 0 {
            let mut c0 = x + 1;
            loop {
                let cur = self.row_bits(y, c0);
                let up = self.row_bits(y + 1, c0);
                let down = self.row_bits(y - 1, c0);
                let up_back = (up << 1) | up_carry;
                let down_back = (down << 1) | down_carry;
                let mut hit = (!up & up_back) | (!down & down_back);
                if goal_in_row && self.goal_x >= c0 && self.goal_x < c0 + 32 {
                    hit |= 1 << (self.goal_x - c0);
                }
                if cur | hit != 0 {
                    let stop = cur.trailing_zeros();
                    let jump = hit.trailing_zeros();
                    if jump < stop {
                        let jx = c0 + jump as i32;
                        return Some((jx, y, (jx - x) as u32));
                    }
                    return None;
                }
                up_carry = up >> 31;
                down_carry = down >> 31;
                c0 += 32;
            }
        } else {
            // Columns c0 .. c0 + 32 with the scan going down from c0 + 31.
            let mut c0 = x - 32;
            loop {
                let cur = self.row_bits(y, c0);
                let up = self.row_bits(y + 1, c0);
                let down = self.row_bits(y - 1, c0);
                let up_back = (up >> 1) | (up_carry << 31);
                let down_back = (down >> 1) | (down_carry << 31);
                let mut hit = (!up & up_back) | (!down & down_back);
                if goal_in_row && self.goal_x >= c0 && self.goal_x < c0 + 32 {
                    hit |= 1 << (self.goal_x - c0);
                }
                if cur | hit != 0 {
                    let stop = cur.leading_zeros();
                    let jump = hit.leading_zeros();
                    if jump < stop {
                        let jx = c0 + 31 - jump as i32;
                        return Some((jx, y, (x - jx) as u32));
                    }
                    return None;
                }
                up_carry = up & 1;
                down_carry = down & 1;
                c0 -= 32;
            }
        }
    }

    /// Occupancy of cells `j - 1`, `j`, `j + 1` (bits 0, 1, 2) of the row-major bit array.
    /// `j ≥ 1`; words past the end read as occupied.
    #[inline(always)]
    fn three_bits(&self, j: usize) -> u32 {
        let i = j - 1;
        let lo = self.words.get(i >> 5).copied().unwrap_or(u32::MAX) as u64;
        let hi = self.words.get((i >> 5) + 1).copied().unwrap_or(u32::MAX) as u64;
        (((lo | (hi << 32)) >> (i & 31)) as u32) & 7
    }

    fn along_column(&self, x: i32, mut y: i32, dy: i32) -> Option<(i32, i32, u32)> {
        // Bits 0, 1, 2 = columns x - 1, x, x + 1; columns off the map read as occupied.
        let width = self.width as usize;
        let edge = u32::from(x == 0) | (u32::from(x == self.width - 1) << 2);
        // In column 0, read from index j (not j - 1) and shift: column -1 is `edge`.
        let read = |j: usize| -> u32 {
            if x == 0 {
                ((self.three_bits(j + 1) << 1) & 7) | edge
            } else {
                self.three_bits(j) | edge
            }
        };
        let mut j = (y * self.width + x) as usize;
        let mut behind = read(j);
        let mut steps = 0u32;
        loop {
            y += dy;
            if (y as u32) >= self.height as u32 {
                return None;
            }
            j = if dy > 0 { j + width } else { j - width };
            let here = read(j);
            if here & 2 != 0 {
                return None;
            }
            steps += 1;
            if (!here & behind) & 5 != 0 || (x == self.goal_x && y == self.goal_y) {
                return Some((x, y, steps));
            }
            behind = here;
        }
    }

    /// Scan from `(x, y)` in the diagonal direction `(dx, dy)`, each step only between two
    /// free side cells (no corner cutting). Returns the first diagonal cell that is the goal or
    /// from which a side scan along `dx` or `dy` finds a jump point; `None` when blocked first.
    ///
    /// The row scans run step by step (32 cells per word operation); the column scans of all
    /// steps are run together, row by row over a bit set of the columns still scanning
    /// ([`JumpScan::diagonal_columns`]), so an open floor costs a few word operations per row
    /// instead of one read per cell.
    #[inline]
    fn diagonal(&self, x: i32, y: i32, dx: i32, dy: i32) -> Option<(i32, i32, u32)> {
        let (mut cx, mut cy) = (x, y);
        let mut steps = 0u32;
        let mut row_hit = None;
        while self.free(cx + dx, cy) && self.free(cx, cy + dy) && self.free(cx + dx, cy + dy) {
            cx += dx;
            cy += dy;
            steps += 1;
            if (cx == self.goal_x && cy == self.goal_y) || self.along_row(cx, cy, dx).is_some() {
                row_hit = Some(steps);
                break;
            }
        }
        let last = match row_hit {
            Some(i) => i - 1,
            None => steps,
        };
        let i = self.diagonal_columns(x, y, dx, dy, last).or(row_hit)?;
        Some((x + dx * i as i32, y + dy * i as i32, i))
    }

    /// The smallest step `i` in `1..=last` of the diagonal from `(x, y)` whose column scan
    /// (from `(x + dx·i, y + dy·i)` along `dy`) finds a jump point; all diagonal cells up to
    /// `last` are free.
    fn diagonal_columns(&self, x: i32, y: i32, dx: i32, dy: i32, last: u32) -> Option<u32> {
        // Up to 512 columns (the 300 and 400 cell grids); wider grids scan column by column.
        const MAX_WORDS: usize = 16;
        if last == 0 {
            return None;
        }
        if (self.width as usize).div_ceil(32) > MAX_WORDS {
            return (1..=last).find(|&i| {
                self.along_column(x + dx * i as i32, y + dy * i as i32, dy)
                    .is_some()
            });
        }
        let mut alive = [0u32; MAX_WORDS];
        // Occupancy words of the current row and the row behind it, at index `word + 1` (so
        // the words just outside the columns in play fit), valid over `cached`.
        let mut rows = [[u32::MAX; MAX_WORDS + 2]; 2];
        let mut cached: Option<(i32, i32)> = None;
        let mut best = last + 1; // steps at or beyond `best` no longer matter
        let mut any_alive = false;
        let mut k = 1u32;
        loop {
            let row = y + dy * k as i32;
            if any_alive {
                if (row as u32) >= self.height as u32 {
                    break;
                }
                let behind = row - dy;
                // Columns of the steps joined so far: 1 ..= min(k - 1, last).
                let span = (k - 1).min(last) as i32;
                let (lo, hi) = if dx > 0 {
                    (x + 1, x + span)
                } else {
                    (x - span, x - 1)
                };
                let (wlo, whi) = ((lo >> 5) - 1, (hi >> 5) + 1);
                let (cur_rows, behind_rows) = rows.split_at_mut(1);
                let (cur, back) = (&mut cur_rows[0], &mut behind_rows[0]);
                // `back` holds the previous row over `cached`; fill the rest of the range.
                for w in wlo..=whi {
                    let fresh = match cached {
                        Some((a, b)) => w < a || w > b,
                        None => true,
                    };
                    if fresh {
                        if let Some(slot) = back.get_mut((w + 1) as usize) {
                            *slot = self.row_bits(behind, w * 32);
                        }
                    }
                    if let Some(slot) = cur.get_mut((w + 1) as usize) {
                        *slot = self.row_bits(row, w * 32);
                    }
                }
                let at = |v: &[u32; MAX_WORDS + 2], w: i32| -> u32 {
                    v.get((w + 1) as usize).copied().unwrap_or(u32::MAX)
                };
                let mut any = false;
                let mut hit_step = None::<u32>;
                for w in wlo + 1..whi {
                    let Some(a) = alive.get_mut(w as usize) else {
                        break;
                    };
                    if *a == 0 {
                        continue;
                    }
                    let c0 = w * 32;
                    let (c_prev, c_here, c_next) = (at(cur, w - 1), at(cur, w), at(cur, w + 1));
                    let (b_prev, b_here, b_next) = (at(back, w - 1), at(back, w), at(back, w + 1));
                    *a &= !c_here;
                    let right_c = (c_here >> 1) | (c_next << 31);
                    let right_b = (b_here >> 1) | (b_next << 31);
                    let left_c = (c_here << 1) | (c_prev >> 31);
                    let left_b = (b_here << 1) | (b_prev >> 31);
                    let mut hit = *a & ((!right_c & right_b) | (!left_c & left_b));
                    if row == self.goal_y && self.goal_x >= c0 && self.goal_x < c0 + 32 {
                        hit |= *a & (1 << (self.goal_x - c0));
                    }
                    if hit != 0 {
                        // The step nearest the start among this word's hits.
                        let c = if dx > 0 {
                            c0 + hit.trailing_zeros() as i32
                        } else {
                            c0 + 31 - hit.leading_zeros() as i32
                        };
                        let i = ((c - x) * dx) as u32;
                        hit_step = Some(hit_step.map_or(i, |h| h.min(i)));
                    }
                    any |= *a != 0;
                }
                rows.swap(0, 1);
                cached = Some((wlo, whi));
                if let Some(i) = hit_step {
                    best = best.min(i);
                    // Drop the columns of steps at or beyond `best`.
                    any = false;
                    for w in (lo >> 5) as usize..=(hi >> 5) as usize {
                        let Some(a) = alive.get_mut(w) else {
                            break;
                        };
                        let c0 = (w * 32) as i32;
                        for bit in 0..32 {
                            let i = (c0 + bit - x) * dx;
                            if i >= best as i32 {
                                *a &= !(1u32 << bit);
                            }
                        }
                        any |= *a != 0;
                    }
                }
                any_alive = any;
            } else {
                cached = None; // rows were skipped: the cached row is not the one behind
            }
            // The column of step k starts scanning from its diagonal cell.
            if k <= last && k < best {
                let c = x + dx * k as i32;
                if let Some(a) = alive.get_mut((c >> 5) as usize) {
                    *a |= 1 << (c & 31);
                    any_alive = true;
                }
            } else if !any_alive {
                break;
            }
            k += 1;
        }
        (best <= last).then_some(best)
    }
}

/// Jump point search gives up (and A* runs cell by cell) when more than one cell in this many
/// (at least 256 cells) became a jump point: on cluttered maps such as 20 % random obstacles
/// nearly every free cell is one, and scanning costs more than the cell-by-cell search ...
const JPS_MAX_EXPANSIONS_PER_CELLS: usize = 256;
/// ... but only while the open list holds more than one entry per this many jump points
/// expanded (a wide frontier: 269 open entries after 1 024 jump points on 20 % random
/// obstacles, 2 in a maze of 1-cell corridors, where jump point search stays 3x ahead).
const JPS_WIDE_FRONTIER: usize = 16;

/// Unit-cost jump point search (BFS) gives up, and the layered BFS runs, past this many jump
/// points (with the wide-frontier test of [`JPS_WIDE_FRONTIER`]): the bundled worlds need 8–15,
/// sparse random obstacles (1–3 %, not cluttered by the count) hundreds, at about 7 400
/// Cortex-M4 instructions each, which the layered BFS (about 4 M on 300 × 300) does not repay.
const JPS_STEPS_MAX_EXPANSIONS: u32 = 32;

/// A* runs cell by cell straight away (no jump point search) when the rows between start and
/// goal (plus [`CLUTTER_MARGIN_ROWS`] on each side) hold more than one obstacle run per this
/// many cells: 20 % random obstacles have about 1 in 6, a maze of 1-cell corridors 1 in 4, the
/// bundled room worlds fewer than 1 in 100.
const CLUTTER_CELLS_PER_RUN: usize = 32;
/// [`cluttered`] reads one word in this many (of 32 cells each).
const CLUTTER_SAMPLE_STRIDE: usize = 16;
/// Rows beyond the start and goal rows that [`cluttered`] also counts.
const CLUTTER_MARGIN_ROWS: u32 = 16;

/// `true` when the map around start and goal is cluttered (see [`CLUTTER_CELLS_PER_RUN`]): it
/// counts the runs of occupied cells (a set bit after a clear one) in a sample of the grid's
/// words (one in [`CLUTTER_SAMPLE_STRIDE`]) over the rows from the lower of the two rows to the
/// higher, widened by [`CLUTTER_MARGIN_ROWS`]: about 180 word reads on a 300 × 300 grid.
fn cluttered(words: &[u32], geometry: &GridGeometry, start: Cell, goal: Cell) -> bool {
    let width = geometry.width() as usize;
    let (lo, hi) = if start.y < goal.y {
        (start.y, goal.y)
    } else {
        (goal.y, start.y)
    };
    let first_row = (lo as u32).saturating_sub(CLUTTER_MARGIN_ROWS) as usize;
    let last_row =
        ((hi as u32) + CLUTTER_MARGIN_ROWS).min((geometry.height() as u32).saturating_sub(1));
    let (first_word, end_word) = (
        first_row * width / 32,
        ((last_row as usize + 1) * width).div_ceil(32),
    );
    // Every `CLUTTER_SAMPLE_STRIDE`-th word; a run that enters a sampled word counts as starting
    // there.
    let mut runs = 0usize;
    let mut sampled = 0usize;
    for &w in words
        .get(first_word..end_word)
        .unwrap_or(&[])
        .iter()
        .step_by(CLUTTER_SAMPLE_STRIDE)
    {
        if w != 0 {
            runs += (w & !(w << 1)).count_ones() as usize;
        }
        sampled += 1;
    }
    let cells = sampled * 32;
    runs * CLUTTER_CELLS_PER_RUN > cells
}

/// Unit-cost jump point search ([`Planner::jps_steps`]): the heap key is
/// `f << UNIT_KEY_SHIFT | h`.
const UNIT_KEY_SHIFT: u32 = 12;
/// The heuristic's bits in a unit-cost key (at most 4 095 on grids of at most 4 096 a side).
const UNIT_H_MASK: u32 = (1 << UNIT_KEY_SHIFT) - 1;
/// The largest `f` a unit-cost key holds.
const UNIT_MAX_F: u32 = u32::MAX >> UNIT_KEY_SHIFT;

/// Binary min-heap over a fixed slice of entries, ordered by `f`.
#[inline(always)]
fn heap_before(a: &OpenEntry, b: &OpenEntry) -> bool {
    a.f < b.f
}

fn heap_sift_up(heap: &mut [OpenEntry], mut i: usize) {
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

fn heap_sift_down(heap: &mut [OpenEntry], mut i: usize) {
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

/// Outcome of the search phase, before the path is rebuilt.
struct Search {
    found: bool,
    expanded: u32,
    cost: u32,
}

/// A planner with its scratch memory: `SCRATCH_WORDS` 32-bit words hold 8 cells each (4 bits
/// per cell, see [`scratch_words_for_cells`]), `QUEUE` is the open-list capacity in entries
/// (12 bytes each).
///
/// A planner is reusable: every call clears the scratch of the cells it uses. It is large
/// (`4 × SCRATCH_WORDS + 12 × QUEUE + 12 288 + 2 560` bytes: the vertex buffer and the
/// cell-by-cell A*'s goal table), so keep it in a `static` or a `Box`, not on a small stack.
pub struct Planner<const SCRATCH_WORDS: usize, const QUEUE: usize> {
    scratch: [u32; SCRATCH_WORDS],
    queue: [OpenEntry; QUEUE],
    cells: PathCells,
    /// The per-axis goal table of the cell-by-cell A* ([`goal_axis_entry`]), refilled by
    /// every search on a grid of at most [`GOAL_AXIS_CELLS`] a side.
    goal_axis: [u32; GOAL_TABLE_WORDS],
    last: Option<PlanReport>,
    queue_peak: u32,
    /// Where the last search left each cell's nibble (read by the path rebuild).
    layout: Layout,
}

/// Where the nibble of a cell is in the scratch after a search.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layout {
    /// Row-major, `width` nibbles a row (jump points, scalar BFS, [`Flat`] A*).
    Flat,
    /// [`Framed`] A*: rows of `stride` nibbles, one frame row and column before the map.
    Framed { stride: usize },
}

impl Layout {
    /// The scratch index of `cell` (a cell of the map).
    fn index(self, geometry: &GridGeometry, cell: Cell) -> usize {
        match self {
            Layout::Flat => geometry.index(cell),
            Layout::Framed { stride } => (cell.y as usize + 1) * stride + cell.x as usize + 1,
        }
    }

    /// The scratch index step of one row up.
    fn row_step(self, geometry: &GridGeometry) -> usize {
        match self {
            Layout::Flat => geometry.width() as usize,
            Layout::Framed { stride } => stride,
        }
    }
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Planner<SCRATCH_WORDS, QUEUE> {
    /// Cells the scratch memory covers.
    pub const CAPACITY_CELLS: usize = SCRATCH_WORDS * 8;

    /// A planner with cleared scratch.
    pub const fn new() -> Self {
        Self {
            scratch: [0; SCRATCH_WORDS],
            queue: [OpenEntry::ZERO; QUEUE],
            cells: Vec::new(),
            goal_axis: [0; GOAL_TABLE_WORDS],
            last: None,
            queue_peak: 0,
            layout: Layout::Flat,
        }
    }

    /// Plan from `start` to `goal` on `grid`, writing the polyline to `path` (cleared first).
    ///
    /// Start and goal are snapped to the cells that contain them; the path runs from the start
    /// cell's centre to the goal cell's centre. A start or goal off the map or not finite gives
    /// `Ok` with [`PlanStatus::OutOfBounds`]; occupied ones [`PlanStatus::StartBlocked`] /
    /// [`PlanStatus::GoalBlocked`] (checked in that order); `start` and `goal` in the same free
    /// cell give [`PlanStatus::Found`] with a one-point path. `path` is empty unless found.
    ///
    /// Errors: [`PlanError::ScratchTooSmall`] when the grid has more cells than the scratch,
    /// [`PlanError::QueueFull`] when the open list overflows, [`PlanError::PathFull`] when the
    /// polyline has more vertices than `path` holds (at most [`MAX_PATH_POINTS`]: `path` then
    /// holds nothing and
    /// [`Planner::last_report`] has the search's result).
    pub fn plan<const W: usize, const P: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: PointM,
        goal: PointM,
        path: &mut Vec<PointM, P>,
    ) -> Result<PlanReport, PlanError> {
        path.clear();
        let report = self.plan_at(kind, grid, start, goal)?;
        let geometry = *grid.geometry();
        for &c in self.cells.iter() {
            if path.push(geometry.center_of(c)).is_err() {
                path.clear();
                return Err(PlanError::PathFull {
                    capacity: P.min(MAX_PATH_POINTS) as u32,
                });
            }
        }
        Ok(report)
    }

    /// [`Planner::plan`] without the polyline in metres: it stays in [`Planner::path_cells`]
    /// (until the next plan), so a caller that only reads it back needs no path buffer of its
    /// own.
    pub fn plan_at<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: PointM,
        goal: PointM,
    ) -> Result<PlanReport, PlanError> {
        self.last = None;
        let geometry = *grid.geometry();
        let (Ok(start_cell), Ok(goal_cell)) = (geometry.cell_of(start), geometry.cell_of(goal))
        else {
            self.check_scratch(&geometry)?;
            self.cells.clear();
            let report = PlanReport::empty(PlanStatus::OutOfBounds);
            self.last = Some(report);
            return Ok(report);
        };
        self.plan_cells(kind, grid, start_cell, goal_cell)
    }

    /// Plan between two cells; the polyline (as cells) is then [`Planner::path_cells`].
    ///
    /// Same contract as [`Planner::plan`]; cells outside the grid give
    /// [`PlanStatus::OutOfBounds`].
    pub fn plan_cells<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: Cell,
        goal: Cell,
    ) -> Result<PlanReport, PlanError> {
        self.plan_cells_with(kind, grid, start, goal, true)
    }

    /// [`Planner::plan_cells`]; with `bfs_jump_points` false BFS always runs the layered search
    /// (the tests check it on maps where the planner would run jump points).
    fn plan_cells_with<const W: usize>(
        &mut self,
        kind: PlannerKind,
        grid: &Grid<W>,
        start: Cell,
        goal: Cell,
        bfs_jump_points: bool,
    ) -> Result<PlanReport, PlanError> {
        // The last path stays until this plan has a result: an error (scratch, queue or path
        // capacity) leaves it as it was.
        self.last = None;
        self.queue_peak = 0;
        self.layout = Layout::Flat;
        let geometry = *grid.geometry();
        self.check_scratch(&geometry)?;
        let inside = |c: Cell| geometry.contains_xy(c.x as i32, c.y as i32);
        let status = if !inside(start) || !inside(goal) {
            Some(PlanStatus::OutOfBounds)
        } else if grid.is_occupied(start) {
            Some(PlanStatus::StartBlocked)
        } else if grid.is_occupied(goal) {
            Some(PlanStatus::GoalBlocked)
        } else {
            None
        };
        if let Some(status) = status {
            self.cells.clear();
            let report = PlanReport::empty(status);
            self.last = Some(report);
            return Ok(report);
        }
        // Jump point search (A* and any-angle with octile costs, BFS with unit costs) reads
        // the map's own bits and needs cleared nibbles only (its fallbacks set up their own
        // scratch). On a cluttered map (nearly every free cell would be a jump point) A* runs
        // cell by cell at once, from a copy of the map, and BFS runs the layered search, which
        // sets up its own bit planes (or, in narrow maps, a copy of the map).
        let used_words = scratch_words_for_cells(geometry.cell_count());
        let jump_points = (kind != PlannerKind::Bfs || bfs_jump_points)
            && !cluttered(grid.words(), &geometry, start, goal);
        match kind {
            _ if jump_points => self
                .scratch
                .get_mut(..used_words)
                .unwrap_or(&mut [])
                .fill(0),
            // The layered BFS sets up its own bit planes, cell-by-cell A* its copy of the map.
            _ => {}
        }
        let start_index = geometry.index(start);
        let goal_index = geometry.index(goal);
        // Where the layered BFS met (else, when found, the scalar BFS left its path in the
        // nibbles).
        let mut bfs_meet = None;
        let search = if start_index == goal_index {
            set_nibble(&mut self.scratch, start_index, CODE_START);
            Search {
                found: true,
                expanded: 0,
                cost: 0,
            }
        } else {
            match kind {
                PlannerKind::Bfs if jump_points => {
                    match self.jps_steps(
                        grid,
                        start_index,
                        goal,
                        goal_index,
                        JPS_STEPS_MAX_EXPANSIONS,
                    ) {
                        Ok(search) => search,
                        Err(jps_expanded) => {
                            // Jump points turned out too many, or the queue ran out of entries
                            // for them: the layered BFS.
                            let (search, meet) = self.bfs(grid, start, goal)?;
                            bfs_meet = meet;
                            Search {
                                expanded: search.expanded.saturating_add(jps_expanded),
                                ..search
                            }
                        }
                    }
                }
                PlannerKind::Bfs => {
                    let (search, meet) = self.bfs(grid, start, goal)?;
                    bfs_meet = meet;
                    search
                }
                PlannerKind::AStar | PlannerKind::AnyAngle if !jump_points => {
                    self.astar(grid, start_index, goal)?
                }
                PlannerKind::AStar | PlannerKind::AnyAngle => {
                    match self.jps(grid, start_index, goal, goal_index) {
                        Ok(search) => search,
                        Err(jps_expanded) => {
                            // Cluttered map (JPS scans more than it saves) or the queue ran
                            // out of entries for jump points and their records: cell-by-cell
                            // A*, which also reclaims stale entries more finely.
                            let plain = self.astar(grid, start_index, goal)?;
                            Search {
                                expanded: plain.expanded.saturating_add(jps_expanded),
                                ..plain
                            }
                        }
                    }
                }
            }
        };
        if !search.found {
            self.cells.clear();
            let report = PlanReport {
                status: PlanStatus::Unreachable,
                expanded: search.expanded,
                cost: 0,
                length_m: 0.0,
            };
            self.last = Some(report);
            return Ok(report);
        }
        // `PathFull` must keep the last path. Only long paths may not fit: a path of `steps`
        // moves has at most `steps + 2` vertices (any-angle adds at most one per run of the
        // A* path, and the final one). For those the last path is first put aside in the
        // queue, free once the search is over (the firmware's 1 024 entries hold all 3 072
        // vertices, 3 a entry), and put back if the new one does not fit; a planner whose
        // queue is too small counts the new path before writing it (its rebuild twice).
        let steps_bound = match kind {
            PlannerKind::Bfs if search.cost > 0 => search.cost,
            PlannerKind::Bfs => u32::MAX, // the layered BFS does not count its steps
            _ => search.cost / STRAIGHT_COST,
        };
        let may_overflow = steps_bound.saturating_add(2) as usize > MAX_PATH_POINTS;
        let rebuild = |planner: &mut Self, count_only: bool| match kind {
            PlannerKind::AnyAngle => planner.rebuild_any_angle(grid, goal, count_only),
            PlannerKind::Bfs => match bfs_meet {
                Some(meet) => planner.bfs_rebuild(grid, goal, meet, count_only),
                None => planner.rebuild_merged(&geometry, goal, count_only),
            },
            _ => planner.rebuild_merged(&geometry, goal, count_only),
        };
        let last_path = self.cells.len();
        let kept = match may_overflow && last_path > 0 {
            false => Kept::Nothing,
            true if self.stash_path() => Kept::InQueue(last_path),
            true => Kept::Counted,
        };
        let counted = match kept {
            Kept::Counted => Some(rebuild(self, true)),
            _ => None,
        };
        let (length_cells, steps, fits) = match counted {
            Some(counted) if !counted.2 => counted,
            _ => {
                self.cells.clear();
                rebuild(self, false)
            }
        };
        if !fits {
            match kept {
                Kept::InQueue(n) => self.unstash_path(n),
                Kept::Counted => {} // not written
                Kept::Nothing => self.cells.clear(),
            }
        }
        let report = PlanReport {
            status: PlanStatus::Found,
            expanded: search.expanded,
            cost: match kind {
                PlannerKind::Bfs => steps,
                _ => search.cost,
            },
            length_m: length_cells * geometry.resolution_m(),
        };
        self.last = Some(report);
        if !fits {
            return Err(PlanError::PathFull {
                capacity: MAX_PATH_POINTS as u32,
            });
        }
        Ok(report)
    }

    /// The polyline of the last successful plan, as cells (start cell first). Empty after a
    /// plan that found no path; an error ([`PlanError`]) leaves the previous path.
    pub fn path_cells(&self) -> &[Cell] {
        &self.cells
    }

    /// Copy the last path into the queue (3 cells an entry); `false` when it does not fit.
    /// Only after a search: the queue is free until the next one.
    fn stash_path(&mut self) -> bool {
        if self.cells.len().div_ceil(3) > QUEUE {
            return false;
        }
        let pack = |c: Option<&Cell>| c.map_or(0, |c| (c.x as u32) << 16 | c.y as u32);
        for (entry, chunk) in self.queue.iter_mut().zip(self.cells.chunks(3)) {
            entry.f = pack(chunk.first());
            entry.node = pack(chunk.get(1));
            entry.next = pack(chunk.get(2));
        }
        true
    }

    /// Put back the `n` cells of the path [`Planner::stash_path`] copied.
    fn unstash_path(&mut self, n: usize) {
        self.cells.clear();
        for entry in self.queue.iter().take(n.div_ceil(3)) {
            for word in [entry.f, entry.node, entry.next] {
                if self.cells.len() < n {
                    let _ = self.cells.push(Cell::new((word >> 16) as u16, word as u16));
                }
            }
        }
    }

    /// The report of the last planning request, also when it ended in
    /// [`PlanError::PathFull`] (then `status` is `Found` and cost/length/expanded are those of
    /// the path that did not fit). `None` before the first request and after the other errors.
    pub fn last_report(&self) -> Option<PlanReport> {
        self.last
    }

    /// Most queue entries in use at once during the last search (A*: open-list entries, stale
    /// ones included; scalar BFS: ring-buffer entries). Size `QUEUE` from this on your maps. The
    /// layered BFS uses no queue entries: there it is the most frontier (row, word) pairs of one
    /// layer.
    pub fn queue_peak(&self) -> u32 {
        self.queue_peak
    }

    fn check_scratch(&self, geometry: &GridGeometry) -> Result<(), PlanError> {
        if geometry.cell_count() > Self::CAPACITY_CELLS {
            return Err(PlanError::ScratchTooSmall {
                cells: geometry.cell_count() as u32,
                capacity: Self::CAPACITY_CELLS as u32,
            });
        }
        Ok(())
    }

    /// Copy the map into the scratch: occupied cells [`BLOCKED`], free cells 0.
    fn copy_map<const GW: usize>(&mut self, grid: &Grid<GW>) {
        let used_words = scratch_words_for_cells(grid.geometry().cell_count());
        let used = self.scratch.get_mut(..used_words).unwrap_or(&mut []);
        let mut quads = used.chunks_exact_mut(4);
        let mut bits = grid.words().iter();
        for (quad, &b) in (&mut quads).zip(&mut bits) {
            if let [w0, w1, w2, w3] = quad {
                *w0 = BLOCKED_NIBBLES[(b & 0xFF) as usize];
                *w1 = BLOCKED_NIBBLES[((b >> 8) & 0xFF) as usize];
                *w2 = BLOCKED_NIBBLES[((b >> 16) & 0xFF) as usize];
                *w3 = BLOCKED_NIBBLES[(b >> 24) as usize];
            }
        }
        // The last grid word may cover fewer than four scratch words.
        if let Some(&b) = bits.next() {
            for (k, word) in quads.into_remainder().iter_mut().enumerate() {
                *word = spread_bits_to_nibbles(b >> (8 * k)) * BLOCKED;
            }
        }
    }

    /// Cell-by-cell A* (see [`astar_search`]) on a copy of the map, in the [`Framed`] layout
    /// when it fits the first [`FRAMED_WORDS`] words of the scratch, else the [`Flat`] one, with
    /// the goal regions from the per-axis table on grids of at most [`GOAL_AXIS_CELLS`] a side.
    /// `start`: the flat cell index.
    fn astar<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
    ) -> Result<Search, PlanError> {
        self.astar_in::<GW, FRAMED_WORDS, true>(grid, start, goal_cell, true)
    }

    /// [`Planner::astar`] with a framed view of `WORDS` words (`WORDS − 1` a power of two), or
    /// in the flat layout when `framed` is false or the framed map does not fit; with
    /// `AXIS_TABLE` the goal regions come from the per-axis table ([`axis_region`]; on grids
    /// larger than [`GOAL_AXIS_CELLS`] a side the search runs without it, flat), else they are
    /// computed per cell ([`goal_region`]; the tests run both on the same maps).
    fn astar_in<const GW: usize, const WORDS: usize, const AXIS_TABLE: bool>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        framed: bool,
    ) -> Result<Search, PlanError> {
        let geometry = *grid.geometry();
        let width = geometry.width() as usize;
        let start_xy = ((start % width) as u32, (start / width) as u32);
        let goal_xy = (goal_cell.x as u32, goal_cell.y as u32);
        if AXIS_TABLE {
            let side = width.max(geometry.height() as usize);
            if side > GOAL_AXIS_CELLS {
                return self.astar_in::<GW, WORDS, false>(grid, start, goal_cell, false);
            }
            let (axis, classes) = self.goal_axis.split_at_mut(GOAL_AXIS_CELLS);
            for (i, entry) in (0u32..).zip(axis.iter_mut().take(side)) {
                *entry = goal_axis_entry(i, goal_xy.0, goal_xy.1);
            }
            classes.copy_from_slice(&STEP_CLASSES);
        }
        if framed && AXIS_TABLE {
            if let Some(mut map) = Framed::<WORDS>::new(&mut self.scratch, &geometry) {
                map.copy_map(grid);
                self.layout = Layout::Framed { stride: map.stride };
                // Rings first; when one stays full, again with the linked lists (exact
                // `QueueFull` semantics; the same pops in the same order).
                let ring = astar_search::<_, RingQueue, AXIS_TABLE>(
                    &mut map,
                    &mut self.queue,
                    &self.goal_axis,
                    start_xy,
                    goal_xy,
                    &mut self.queue_peak,
                );
                if !matches!(ring, Err(PlanError::QueueFull { .. })) {
                    return ring;
                }
                map.copy_map(grid);
                return astar_search::<_, ClassQueue, AXIS_TABLE>(
                    &mut map,
                    &mut self.queue,
                    &self.goal_axis,
                    start_xy,
                    goal_xy,
                    &mut self.queue_peak,
                );
            }
        }
        self.copy_map(grid);
        self.layout = Layout::Flat;
        let used_words = scratch_words_for_cells(geometry.cell_count());
        let mut map = Flat {
            scratch: self.scratch.get_mut(..used_words).unwrap_or(&mut []),
            interior: Interior::new(&geometry),
        };
        astar_search::<_, ClassQueue, AXIS_TABLE>(
            &mut map,
            &mut self.queue,
            &self.goal_axis,
            start_xy,
            goal_xy,
            &mut self.queue_peak,
        )
    }

    /// A* by Jump Point Search (no corner cutting) with the octile heuristic and a
    /// lazy-deletion binary heap of jump points. Optimal octile cost, same as plain A*.
    ///
    /// The queue's entries are shared by the heap (from the front) and the records of the
    /// closed jump points (from the back: the cell, its step code and the record of the jump
    /// point it was reached from), so that on success the path is rebuilt exactly, segment by
    /// segment, by [`Planner::write_jump_chain`]. `Err(expanded)` when the entries run out or
    /// the map is cluttered (see [`JPS_MAX_EXPANSIONS_PER_CELLS`] and [`JPS_WIDE_FRONTIER`]):
    /// the caller then falls back to cell-by-cell A*.
    fn jps<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        goal: usize,
    ) -> Result<Search, u32> {
        let max_expanded = (grid.geometry().cell_count() / JPS_MAX_EXPANSIONS_PER_CELLS).max(256);
        self.jump_points::<GW, false>(grid, start, goal_cell, goal, max_expanded as u32)
    }

    /// Jump point search with unit costs (a side step and a diagonal step both cost 1, the
    /// Chebyshev heuristic): BFS's fewest steps on uncluttered maps. `Search::cost` is the
    /// number of steps. `Err(expanded)` (the caller then runs the layered BFS) when the entries
    /// run out, when more than `max_expanded` jump points were expanded with a wide open list
    /// (the planner passes [`JPS_STEPS_MAX_EXPANSIONS`]), or when a key would not fit (`f ≥ 2²⁰`
    /// steps).
    fn jps_steps<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        goal: usize,
        max_expanded: u32,
    ) -> Result<Search, u32> {
        self.jump_points::<GW, true>(grid, start, goal_cell, goal, max_expanded)
    }

    /// The jump point search of [`Planner::jps`] (`UNIT = false`: octile costs and heuristic)
    /// and [`Planner::jps_steps`] (`UNIT = true`: unit costs, Chebyshev heuristic). With unit
    /// costs many entries share one `f`, so the heap key is `f << 12 | h` ([`UNIT_KEY_SHIFT`]):
    /// equal `f` pops the smallest `h`, i.e. the largest `g`, first (towards the goal); `h` is at
    /// most 4 095 on grids of at most [`crate::grid::MAX_SIDE_CELLS`] a side, and `f` must stay
    /// below 2²⁰ (else the search gives up).
    fn jump_points<const GW: usize, const UNIT: bool>(
        &mut self,
        grid: &Grid<GW>,
        start: usize,
        goal_cell: Cell,
        goal: usize,
        max_expanded: u32,
    ) -> Result<Search, u32> {
        let geometry = grid.geometry();
        let width = geometry.width() as i32;
        let height = geometry.height() as i32;
        let (gx, gy) = (goal_cell.x as i32, goal_cell.y as i32);
        let h = |x: i32, y: i32| {
            if UNIT {
                x.abs_diff(gx).max(y.abs_diff(gy))
            } else {
                octile(x.abs_diff(gx), y.abs_diff(gy))
            }
        };
        // Heap key of an entry with cost `g` to the cell of heuristic `hc`; `None` when a unit
        // key does not fit.
        let key = |g: u32, hc: u32| -> Option<u32> {
            if UNIT {
                let f = g.checked_add(hc)?;
                (f <= UNIT_MAX_F && hc <= UNIT_H_MASK).then_some(f << UNIT_KEY_SHIFT | hc)
            } else {
                Some(g.saturating_add(hc))
            }
        };
        // `g` of a popped key at a cell of heuristic `hc`.
        let g_of = |k: u32, hc: u32| {
            if UNIT {
                (k >> UNIT_KEY_SHIFT).wrapping_sub(hc)
            } else {
                k.wrapping_sub(hc)
            }
        };
        let (straight_cost, diagonal_cost) = if UNIT {
            (1, 1)
        } else {
            (STRAIGHT_COST, DIAGONAL_COST)
        };
        let pack = |x: i32, y: i32, code: u32| ((y as u32) << 16) | ((x as u32) << 4) | code;
        let pool = &mut self.queue[..];
        let capacity = pool.len();
        let (sx, sy) = (start as i32 % width, start as i32 / width);
        let mut len = match pool.first_mut() {
            Some(slot) => {
                *slot = OpenEntry {
                    f: match key(0, h(sx, sy)) {
                        Some(k) => k,
                        None => return Err(0),
                    },
                    node: pack(sx, sy, CODE_START),
                    next: NIL,
                };
                1usize
            }
            None => return Err(0),
        };
        // Closed jump points: record r lives at `pool[capacity - 1 - r]`.
        let mut records = 0usize;
        let mut peak = len;
        let mut expanded = 0u32;

        while len > 0 {
            let top = pool[0];
            len -= 1;
            pool[0] = pool[len];
            heap_sift_down(&mut pool[..len], 0);

            let x = ((top.node >> 4) & 0xFFF) as i32;
            let y = (top.node >> 16) as i32;
            let index = (y * width + x) as usize;
            if nibble(&self.scratch, index) != 0 {
                continue; // already closed by a cheaper entry
            }
            let code = top.node & 0xF;
            set_nibble(&mut self.scratch, index, code);
            expanded += 1;
            if expanded > max_expanded && len * JPS_WIDE_FRONTIER > expanded as usize {
                self.queue_peak = peak as u32;
                return Err(expanded);
            }
            // The popped entry freed a slot, so the record always fits.
            let record = records as u32;
            pool[capacity - 1 - records] = OpenEntry {
                f: 0,
                node: top.node,
                next: top.next,
            };
            records += 1;
            let g = g_of(top.f, h(x, y));
            if index == goal {
                self.queue_peak = peak as u32;
                self.write_jump_chain(width, record as usize);
                return Ok(Search {
                    found: true,
                    expanded,
                    cost: g,
                });
            }
            let scan = JumpScan {
                words: grid.words(),
                width,
                height,
                goal_x: gx,
                goal_y: gy,
            };
            // Directions to scan, by the step that reached this jump point: from the start all
            // 8; after a diagonal step its two sides and itself; after a side step itself and,
            // for each forced side cell, that side and the forward diagonal next to it.
            let mut dirs = [0u32; 8];
            let n = match code {
                E | N | W | S => {
                    let (dx, dy) = STEPS[(code - 1) as usize];
                    dirs[0] = code;
                    let mut n = 1;
                    for (px, py) in [(dy, dx), (-dy, -dx)] {
                        // Forced: the side cell is free, the one behind it occupied.
                        if scan.free(x + px, y + py) && !scan.free(x + px - dx, y + py - dy) {
                            dirs[n] = step_code(px, py);
                            dirs[n + 1] = step_code(dx + px, dy + py);
                            n += 2;
                        }
                    }
                    n
                }
                NE | NW | SW | SE => {
                    let (dx, dy) = STEPS[(code - 1) as usize];
                    dirs[..3].copy_from_slice(&[code, step_code(dx, 0), step_code(0, dy)]);
                    3
                }
                _ => {
                    dirs = [E, N, W, S, NE, NW, SW, SE];
                    8
                }
            };
            for &d in &dirs[..n] {
                let Some(&(dx, dy)) = STEPS.get((d as usize).wrapping_sub(1)) else {
                    continue;
                };
                let found = if dx == 0 || dy == 0 {
                    scan.straight(x, y, dx, dy)
                        .map(|(jx, jy, k)| (jx, jy, k * straight_cost))
                } else {
                    scan.diagonal(x, y, dx, dy)
                        .map(|(jx, jy, k)| (jx, jy, k * diagonal_cost))
                };
                let Some((jx, jy, cost)) = found else {
                    continue;
                };
                if nibble(&self.scratch, (jy * width + jx) as usize) != 0 {
                    continue; // closed already
                }
                let Some(f) = key(g.saturating_add(cost), h(jx, jy)) else {
                    self.queue_peak = peak as u32;
                    return Err(expanded);
                };
                let entry = OpenEntry {
                    f,
                    node: pack(jx, jy, d),
                    next: record,
                };
                if len + records == capacity {
                    // Full: drop the entries of cells closed meanwhile, unless that frees too
                    // little to be worth it (no thrashing).
                    let before = len;
                    let mut kept = 0usize;
                    for i in 0..len {
                        let e = pool[i];
                        let cell = (e.node >> 16) as i32 * width + ((e.node >> 4) & 0xFFF) as i32;
                        if nibble(&self.scratch, cell as usize) == 0 {
                            pool[kept] = e;
                            kept += 1;
                        }
                    }
                    len = kept;
                    for i in (0..len / 2).rev() {
                        heap_sift_down(&mut pool[..len], i);
                    }
                    if before - len < (capacity / 16).max(1) {
                        self.queue_peak = peak as u32;
                        return Err(expanded);
                    }
                }
                pool[len] = entry;
                len += 1;
                heap_sift_up(&mut pool[..len], len - 1);
                peak = peak.max(len + records);
            }
        }
        self.queue_peak = peak as u32;
        Ok(Search {
            found: false,
            expanded,
            cost: 0,
        })
    }

    /// Write the step codes along the chain of jump point records that ends at `record` (the
    /// goal's), so that the path can be rebuilt cell by cell from the goal. Each segment between
    /// two jump points is a straight or 45° scan, so every cell strictly between them gets the
    /// segment's step code (the path is a shortest one, so it crosses no cell twice).
    fn write_jump_chain(&mut self, width: i32, mut record: usize) {
        let capacity = self.queue.len();
        // Each record's parent was closed before it, so indices fall; the bound is a guard.
        for _ in 0..capacity {
            let Some(&child) = self.queue.get(capacity.wrapping_sub(1 + record)) else {
                return;
            };
            let Some(&parent) = self
                .queue
                .get(capacity.wrapping_sub(1 + child.next as usize))
            else {
                return; // the start
            };
            if child.next as usize >= record {
                return;
            }
            let code = child.node & 0xF;
            let Some(&(dx, dy)) = STEPS.get((code as usize).wrapping_sub(1)) else {
                return;
            };
            let (mut x, mut y) = (
                ((child.node >> 4) & 0xFFF) as i32,
                (child.node >> 16) as i32,
            );
            let (px, py) = (
                ((parent.node >> 4) & 0xFFF) as i32,
                (parent.node >> 16) as i32,
            );
            for _ in 0..4096 {
                x -= dx;
                y -= dy;
                if (x, y) == (px, py) || x < 0 || y < 0 {
                    break;
                }
                set_nibble(&mut self.scratch, (y * width + x) as usize, code);
            }
            record = child.next as usize;
        }
    }

    /// The parent of `cell` by its nibble, or `None` at the start (or on a corrupt code).
    #[inline]
    fn parent(&self, geometry: &GridGeometry, cell: Cell) -> Option<(Cell, u32)> {
        let code = nibble(&self.scratch, self.layout.index(geometry, cell));
        let &(dx, dy) = STEPS.get((code as usize).wrapping_sub(1))?;
        let parent = geometry.cell_xy(cell.x as i32 - dx, cell.y as i32 - dy)?;
        Some((parent, code))
    }

    /// The run of parent steps of code `code` that goes on back from `cell` (the parent of a
    /// cell reached with `code`): the first cell back whose own code is not `code` (the run's
    /// far end) and the number of steps to it. Walks the scratch index, a few instructions per
    /// cell (the parent chain of a search's nibbles never leaves the map; the bound only guards
    /// against a corrupt one).
    fn run_back(&self, geometry: &GridGeometry, cell: Cell, code: u32) -> (Cell, u32) {
        let Some(&(dx, dy)) = STEPS.get((code as usize).wrapping_sub(1)) else {
            return (cell, 0);
        };
        let offset = (dy as isize)
            .wrapping_mul(self.layout.row_step(geometry) as isize)
            .wrapping_add(dx as isize) as usize;
        let mut index = self.layout.index(geometry, cell);
        let longest = geometry.width().max(geometry.height()) as u32;
        let mut steps = 0u32;
        while steps < longest && nibble(&self.scratch, index) == code {
            index = index.wrapping_sub(offset);
            steps += 1;
        }
        let end = geometry.cell_xy(
            cell.x as i32 - dx * steps as i32,
            cell.y as i32 - dy * steps as i32,
        );
        end.map_or((cell, 0), |end| (end, steps))
    }

    /// Rebuild the BFS / A* path from the parent steps, run by run ([`Planner::run_back`]), so
    /// collinear cells are merged. Returns the length in cells, the number of steps and whether
    /// every vertex fitted.
    ///
    /// With `count_only` the cells are counted, not written (`fits` and the figures are the
    /// same).
    fn rebuild_merged(
        &mut self,
        geometry: &GridGeometry,
        goal: Cell,
        count_only: bool,
    ) -> (f32, u32, bool) {
        let mut out = PathOut::new(count_only);
        let mut fits = out.push(&mut self.cells, goal);
        let (mut straight, mut diagonal) = (0u32, 0u32);
        let mut cell = goal;
        // A parent chain never revisits a cell; the bound only guards against a corrupt one.
        for _ in 0..geometry.cell_count() {
            let Some((parent, code)) = self.parent(geometry, cell) else {
                break;
            };
            let (end, more) = self.run_back(geometry, parent, code);
            if code >= NE {
                diagonal += 1 + more;
            } else {
                straight += 1 + more;
            }
            cell = end;
            fits &= out.push(&mut self.cells, cell);
        }
        out.reverse(&mut self.cells);
        let length = straight as f32 + diagonal as f32 * core::f32::consts::SQRT_2;
        (length, straight + diagonal, fits)
    }

    /// Rebuild the A* path and pull the string with line-of-sight shortcuts. Returns the length
    /// in cells, the number of A* steps and whether every vertex fitted.
    ///
    /// Works run by run (maximal straight pieces of the A* path), from the goal back: if the far
    /// end of the next run is visible from the anchor, the whole run is skipped; otherwise the
    /// last visible cell of the run is found by bisection and becomes a vertex and the new
    /// anchor. Every emitted segment has been tested with [`line_of_sight`].
    fn rebuild_any_angle<const GW: usize>(
        &mut self,
        grid: &Grid<GW>,
        goal: Cell,
        count_only: bool,
    ) -> (f32, u32, bool) {
        let geometry = *grid.geometry();
        let mut out = PathOut::new(count_only);
        let mut fits = out.push(&mut self.cells, goal);
        let mut length = 0.0f32;
        let mut anchor = goal;
        let mut cur = goal;
        let mut steps = 0u32;
        // The code of the run just taken from the anchor (the anchor lies on its line behind
        // `cur`), else 0.
        let mut prev_code = 0u32;
        // Each pass either moves `cur` towards the start or moves the anchor forward; the
        // bound only guards against a corrupt parent chain.
        for _ in 0..2 * geometry.cell_count() {
            // The run that ends at `cur`: `run` steps of `code`, back to `end`.
            let Some((mut end, code)) = self.parent(&geometry, cur) else {
                break;
            };
            let (far, more) = self.run_back(&geometry, end, code);
            end = far;
            let run = 1 + more;
            // From the anchor itself the run is an A* move sequence: visible without a test.
            if cur == anchor {
                cur = end;
                steps += run;
                prev_code = code;
                continue;
            }
            // A side-step turn after a run from the anchor, whose inner corner (the cell
            // beside the previous run and the next one) is blocked: no cell of the next run is
            // visible past it (the Bresenham line to the first one crosses that corner or
            // steps diagonally past it), so `cur` is the vertex, with no line-of-sight test.
            if prev_code != 0 && prev_code <= S && code <= S && (prev_code ^ code) & 1 == 1 {
                let (Some(&(px, py)), Some(&(dx, dy))) = (
                    STEPS.get(prev_code as usize - 1),
                    STEPS.get(code as usize - 1),
                ) else {
                    break;
                };
                if grid.is_occupied_xy(cur.x as i32 + px - dx, cur.y as i32 + py - dy) {
                    fits &= out.push(&mut self.cells, cur);
                    length += cells_distance(anchor, cur);
                    anchor = cur;
                    cur = end;
                    steps += run;
                    prev_code = code;
                    continue;
                }
            }
            prev_code = 0;
            if line_of_sight(grid, anchor, end) {
                cur = end;
                steps += run;
                continue;
            }
            // `cur` is visible, `end` is not: bisect for the last visible cell of the run.
            let Some(&(dx, dy)) = STEPS.get(code as usize - 1) else {
                break;
            };
            let at = |i: u32| {
                Cell::new(
                    (cur.x as i32 - dx * i as i32) as u16,
                    (cur.y as i32 - dy * i as i32) as u16,
                )
            };
            let (mut lo, mut hi) = (0u32, run);
            while hi - lo > 1 {
                let mid = lo + (hi - lo) / 2;
                if line_of_sight(grid, anchor, at(mid)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            // The step after the anchor is an A* move, always visible; never stall.
            let cut = if lo == 0 && cur == anchor { 1 } else { lo };
            let vertex = at(cut);
            fits &= out.push(&mut self.cells, vertex);
            length += cells_distance(anchor, vertex);
            anchor = vertex;
            cur = vertex;
            steps += cut;
        }
        if cur != anchor {
            fits &= out.push(&mut self.cells, cur);
            length += cells_distance(anchor, cur);
        }
        out.reverse(&mut self.cells);
        (length, steps, fits)
    }
}

/// How a plan that may overflow the path keeps the last one.
#[derive(Clone, Copy, Debug)]
enum Kept {
    /// No last path, or the new one surely fits.
    Nothing,
    /// Copied into the queue: this many cells.
    InQueue(usize),
    /// The new path is counted before it is written.
    Counted,
}

/// Where a path rebuild puts its vertices: the planner's cells, or only a count of them (to
/// learn whether a path fits before the last one is overwritten).
#[derive(Clone, Copy, Debug)]
pub(super) struct PathOut {
    count_only: bool,
    count: usize,
}

impl PathOut {
    pub(super) fn new(count_only: bool) -> Self {
        Self {
            count_only,
            count: 0,
        }
    }

    /// Add a vertex; `false` when it does not fit.
    pub(super) fn push(&mut self, cells: &mut PathCells, cell: Cell) -> bool {
        self.count += 1;
        if self.count_only {
            self.count <= MAX_PATH_POINTS
        } else {
            cells.push(cell).is_ok()
        }
    }

    /// Vertices added so far.
    pub(super) fn count(&self) -> usize {
        self.count
    }

    /// Only counting.
    pub(super) fn is_counting(&self) -> bool {
        self.count_only
    }

    /// Turn the written path round (nothing to do when counting).
    pub(super) fn reverse(&self, cells: &mut PathCells) {
        if !self.count_only {
            cells.reverse();
        }
    }
}

/// Cell-by-cell A* with the octile heuristic, a lazy-deletion queue by reduced-cost class
/// ([`ClassQueue`]) and the
/// *arrival pruning* of successors (see the module docs): a closed cell pushes only the
/// neighbours that no other cell covers with a key no larger. The scratch must hold the map
/// ([`Planner::copy_map`]).
///
/// Hot loop: the popped cell's 3 × 3 neighbourhood is read as three 12-bit windows (three
/// nibbles of a row from two scratch words) and turned by [`NIBBLE_WINDOWS`] into an 18-bit
/// mask ("nibble 0" and "not blocked" per cell); one arm per arrival step tests its
/// candidate targets in the mask and pushes them with constant offsets. Cells on the map
/// border read their neighbours one by one.
fn astar_search<'p, M: CellMap, Q: OpenList<'p>, const AXIS_TABLE: bool>(
    map: &mut M,
    pool: &'p mut [OpenEntry],
    goal_axis: &[u32; GOAL_TABLE_WORDS],
    (sx, sy): (u32, u32),
    (gx, gy): (u32, u32),
    peak: &mut u32,
) -> Result<Search, PlanError> {
    // Octile distance to the goal; sides are at most 4096 cells, so no overflow.
    let h = |x: u32, y: u32| {
        let (dx, dy) = (x.abs_diff(gx), y.abs_diff(gy));
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        DIAGONAL_COST * lo + STRAIGHT_COST * (hi - lo)
    };
    let goal = map.index(gx as usize, gy as usize);
    let (mut open, mut state) = Q::new(pool, h(sx, sy));
    let full = PlanError::QueueFull {
        capacity: open.capacity(),
    };
    let mut expanded = 0u32;

    // Entries carry `y << 16 | x << 4 | step code` (sides are at most 4096 cells), so the
    // loop never divides, and a neighbour's entry is the cell's plus a constant.
    if !open.push(&mut state, h(sx, sy), (sy << 16) | (sx << 4) | CODE_START) {
        return Err(full);
    }

    // A target whose key equals the key just popped (class 0) is the next pop anyway
    // (nothing in the queue is below it): one such target skips the queue and is expanded
    // next (`next_node`, NIL when none). The key of the cell being expanded is always
    // `state.last`; `g` is not carried: it is `state.last − h` where needed (at the goal
    // `h` is 0).
    let mut next_node = NIL;
    // With corridor walks until they are given up on this map (random clutter), then in a
    // second instance of the loop without them: its registers are not spent on the walks.
    match astar_loop::<M, Q, AXIS_TABLE, true>(
        map,
        &mut open,
        &mut state,
        &mut next_node,
        &mut expanded,
        goal_axis,
        (gx, gy),
        goal,
        peak,
    ) {
        Some(end) => end,
        None => astar_loop::<M, Q, AXIS_TABLE, false>(
            map,
            &mut open,
            &mut state,
            &mut next_node,
            &mut expanded,
            goal_axis,
            (gx, gy),
            goal,
            peak,
        )
        .unwrap_or(Err(full)),
    }
}

/// The expansion loop of [`astar_search`] from the queue `open` / `state`, the immediate
/// target `next_node` and the count `expanded`: the search's result, or with `WALKS` `None`
/// when the corridor walks are given up (the state is written back; the search goes on without
/// them). Without `WALKS` it never returns `None`.
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn astar_loop<'p, M: CellMap, Q: OpenList<'p>, const AXIS_TABLE: bool, const WALKS: bool>(
    map: &mut M,
    open: &mut Q,
    queue_state: &mut QueueState,
    next_target: &mut u32,
    expanded_cells: &mut u32,
    goal_axis: &[u32; GOAL_TABLE_WORDS],
    (gx, gy): (u32, u32),
    goal: usize,
    peak: &mut u32,
) -> Option<Result<Search, PlanError>> {
    let h = |x: u32, y: u32| {
        let (dx, dy) = (x.abs_diff(gx), y.abs_diff(gy));
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        DIAGONAL_COST * lo + STRAIGHT_COST * (hi - lo)
    };
    let full = PlanError::QueueFull {
        capacity: open.capacity(),
    };
    let (gxi, gyi) = (gx as i32, gy as i32);
    let (mut state, mut next_node, mut expanded) = (*queue_state, *next_target, *expanded_cells);
    // The balance of cells closed by corridor walks minus walks started.
    let mut walk_credit = 0i32;
    loop {
        // Close the cell: its nibble gets the arrival step (it was 0).
        let (node, x, y, index) = if next_node != NIL {
            // A target of the cell just expanded: not closed (its nibble was 0 then).
            let node = next_node;
            next_node = NIL;
            let (x, y) = (((node >> 4) & 0xFFF) as usize, (node >> 16) as usize);
            let index = map.index(x, y);
            map.mark(index, node & 0xF);
            (node, x, y, index)
        } else {
            let mut found = None;
            loop {
                let node = open.pop(&mut state);
                if node == NIL {
                    break;
                }
                let (x, y) = (((node >> 4) & 0xFFF) as usize, (node >> 16) as usize);
                let index = map.index(x, y);
                if map.close(index, node & 0xF) {
                    found = Some((node, x, y, index));
                    break;
                }
                // Otherwise already closed by a cheaper entry.
            }
            match found {
                Some(entry) => entry,
                None => break,
            }
        };
        let code = node & 0xF;
        expanded += 1;

        let (above, cur, below) = map.windows(index, x, y);
        let window = |w: u32| u32::from(NIBBLE_WINDOWS[(w & 0xFFF) as usize]);
        let m = window(below) | window(cur) << 6 | window(above) << 12;
        // The targets by arrival step (arrival pruning, see the module docs), each tested
        // and pushed with constant offsets: straight on, plus the forced side and diagonal
        // neighbours after a side step; the two sides and the diagonal after a diagonal
        // step; all eight from the start.
        let base = node & !0xF;
        // The class of each step's reduced cost (its key is `state.last` plus the class's
        // reduced cost), 3 bits per step code.
        let classes = if AXIS_TABLE {
            // In range: a region is below 128 by construction (no bounds check emitted).
            let region = axis_region(goal_axis, x, node);
            goal_axis[GOAL_AXIS_CELLS + region]
        } else {
            let region = goal_region(x as i32 - gxi, y as i32 - gyi);
            STEP_CLASSES.get(region).copied().unwrap_or(0)
        };
        // The goal: the only cell of its region, flagged in the class word.
        if classes & AT_GOAL != 0 {
            *peak = open.peak(&state);
            // h(goal) = 0: the key is the cost.
            return Some(Ok(Search {
                found: true,
                expanded,
                cost: state.last,
            }));
        }
        // The pool is full: reclaim and push `(key, child)`, or end with QueueFull.
        macro_rules! reclaim {
            ($key:expr, $child:expr) => {{
                let closed = |n: u32| {
                    map.nibble(map.index(((n >> 4) & 0xFFF) as usize, (n >> 16) as usize)) != 0
                };
                match open.reclaim_and_push(state, closed, $key, $child) {
                    Some(after) => state = after,
                    None => {
                        *peak = open.peak(&state);
                        return Some(Err(full));
                    }
                }
            }};
        }
        macro_rules! visit {
            ($z:expr, $code:expr) => {{
                if m & (1 << $z) != 0 {
                    let (dx, dy) = STEPS[$code as usize - 1];
                    let child = base.wrapping_add(((dy << 16) + (dx << 4)) as u32 + $code);
                    let class = ((classes >> (3 * ($code - 1))) & 7) as usize;
                    if class != 0 {
                        if !open.push_class(&mut state, class, child) {
                            reclaim!(state.last.wrapping_add(CLASS_COSTS[class]), child);
                        }
                    } else if next_node == NIL {
                        next_node = child;
                    } else if !open.push_stack(&mut state, child) {
                        reclaim!(state.last, child);
                    }
                }
            }};
        }
        // Corridor contraction (see "Corridors" in the module docs): a cell with one or
        // two legal neighbours, reached by a side step, has at most one continuation. Walk
        // along the chain of such cells, closing each with its step, up to the first cell
        // that is not one (pushed), the goal or a cell on the map border (pushed), a dead
        // end (closed, nothing pushed) or a closed cell (nothing pushed).
        let sides = if WALKS && code <= S {
            u32::from(CORRIDOR_SIDES[corridor_index(m)])
        } else {
            0
        };
        if sides != 0 {
            // Side bit `code - 1`; the side behind a step of code `c` is bit `(c + 1) & 3`.
            let rest = sides & !(1 << ((code + 1) & 3));
            let (end, steps, closed) = walk_corridor(map, goal, index, node, rest);
            expanded += closed;
            if end != NIL {
                // Plain adds: keys are u32 (see "Complexity" in the module docs).
                let g = state.last.wrapping_sub(h(x as u32, y as u32));
                let wg = g.wrapping_add(steps.wrapping_mul(STRAIGHT_COST));
                let key = wg.wrapping_add(h((end >> 4) & 0xFFF, end >> 16));
                if key == state.last && next_node == NIL {
                    next_node = end;
                } else if !open.push_far(&mut state, key, end) {
                    reclaim!(key, end);
                }
            }
            // Walks that close (nearly) nothing cost more than the arms' pushes.
            walk_credit += closed as i32 - 1;
            if walk_credit < WALK_GIVE_UP_CREDIT {
                (*queue_state, *next_target, *expanded_cells) = (state, next_node, expanded);
                return None;
            }
            continue;
        }
        macro_rules! diagonal {
            ($z:expr, $code:expr, $o1:expr, $o2:expr) => {{
                if m & ((1 << $o1) | (1 << $o2)) == (1 << $o1) | (1 << $o2) {
                    visit!($z, $code);
                }
            }};
        }
        macro_rules! forced {
            ($o_back:expr, $z:expr, $code:expr, $zd:expr, $dcode:expr, $o1:expr, $o2:expr) => {{
                if m & (1 << $o_back) == 0 {
                    visit!($z, $code);
                    diagonal!($zd, $dcode, $o1, $o2);
                }
            }};
        }
        match code {
            E => {
                visit!(Z_E, E);
                forced!(O_NW, Z_N, N, Z_NE, NE, O_N, O_E);
                forced!(O_SW, Z_S, S, Z_SE, SE, O_S, O_E);
            }
            W => {
                visit!(Z_W, W);
                forced!(O_NE, Z_N, N, Z_NW, NW, O_N, O_W);
                forced!(O_SE, Z_S, S, Z_SW, SW, O_S, O_W);
            }
            N => {
                visit!(Z_N, N);
                forced!(O_SE, Z_E, E, Z_NE, NE, O_E, O_N);
                forced!(O_SW, Z_W, W, Z_NW, NW, O_W, O_N);
            }
            S => {
                visit!(Z_S, S);
                forced!(O_NE, Z_E, E, Z_SE, SE, O_E, O_S);
                forced!(O_NW, Z_W, W, Z_SW, SW, O_W, O_S);
            }
            NE => {
                visit!(Z_E, E);
                visit!(Z_N, N);
                diagonal!(Z_NE, NE, O_N, O_E);
            }
            NW => {
                visit!(Z_W, W);
                visit!(Z_N, N);
                diagonal!(Z_NW, NW, O_N, O_W);
            }
            SW => {
                visit!(Z_W, W);
                visit!(Z_S, S);
                diagonal!(Z_SW, SW, O_S, O_W);
            }
            SE => {
                visit!(Z_E, E);
                visit!(Z_S, S);
                diagonal!(Z_SE, SE, O_S, O_E);
            }
            _ => {
                visit!(Z_E, E);
                visit!(Z_N, N);
                visit!(Z_W, W);
                visit!(Z_S, S);
                diagonal!(Z_NE, NE, O_N, O_E);
                diagonal!(Z_NW, NW, O_N, O_W);
                diagonal!(Z_SW, SW, O_S, O_W);
                diagonal!(Z_SE, SE, O_S, O_E);
            }
        }
    }
    *peak = open.peak(&state);
    Some(Ok(Search {
        found: false,
        expanded,
        cost: 0,
    }))
}

impl<const SCRATCH_WORDS: usize, const QUEUE: usize> Default for Planner<SCRATCH_WORDS, QUEUE> {
    fn default() -> Self {
        Self::new()
    }
}
