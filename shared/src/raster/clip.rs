//! Exact clipping of a Bresenham line to a rectangle of cells, in integers.
//!
//! The cells of [`super::BresenhamLine`] have a closed form. Call the axis with the larger
//! difference the major one (x when the differences are equal), `b` its absolute difference
//! and `a` the minor one's. Step `k` (`0..=b`) moves the major coordinate `k` cells and the
//! minor one `floor((2·a·k + b) / (2·b))` cells (proved by induction on the walk's error term,
//! checked against the walk by the tests). Both are monotone in `k`, so the steps whose cell
//! lies in a rectangle form one interval, found with four divisions: a Liang–Barsky clip done
//! on the discrete line rather than the segment, so the clipped walk visits exactly the cells
//! the whole walk would have visited inside the rectangle. Everything is `i64`: the
//! coordinates are within ±1 000 000 cells, so no product exceeds 10^13.

/// A Bresenham line in closed form (coordinates already clamped as the walk clamps them).
#[derive(Clone, Copy, Debug)]
pub(super) struct LineSteps {
    /// The first cell.
    pub(super) from: (i64, i64),
    /// +1 or -1 per axis, as the walk steps.
    pub(super) sign: (i64, i64),
    /// Absolute differences, x and y.
    pub(super) delta: (i64, i64),
}

impl LineSteps {
    pub(super) fn new(from: (i32, i32), to: (i32, i32)) -> Self {
        let (x0, y0, x1, y1) = (from.0 as i64, from.1 as i64, to.0 as i64, to.1 as i64);
        // The walk steps -1 along an axis whose difference is zero; keep its convention.
        let sign = |a: i64, b: i64| if a < b { 1 } else { -1 };
        Self {
            from: (x0, y0),
            sign: (sign(x0, x1), sign(y0, y1)),
            delta: ((x1 - x0).abs(), (y1 - y0).abs()),
        }
    }

    /// `true` when x is the major axis (the walk steps x at every step).
    pub(super) fn x_major(&self) -> bool {
        self.delta.0 >= self.delta.1
    }

    /// Index of the last step (the number of cells minus one).
    pub(super) fn last_step(&self) -> i64 {
        self.delta.0.max(self.delta.1)
    }

    /// Cells moved along the minor axis after `k` steps.
    fn minor_moves(&self, k: i64) -> i64 {
        let (b, a) = self.major_minor_delta();
        if b == 0 {
            return 0;
        }
        (2 * a * k + b).div_euclid(2 * b)
    }

    /// (major, minor) absolute differences.
    fn major_minor_delta(&self) -> (i64, i64) {
        if self.x_major() {
            self.delta
        } else {
            (self.delta.1, self.delta.0)
        }
    }

    /// Cells moved along x and y after `k` steps.
    pub(super) fn moves(&self, k: i64) -> (i64, i64) {
        let minor = self.minor_moves(k);
        if self.x_major() {
            (k, minor)
        } else {
            (minor, k)
        }
    }

    /// The cell at step `k`.
    pub(super) fn cell(&self, k: i64) -> (i64, i64) {
        let (mx, my) = self.moves(k);
        (
            self.from.0 + self.sign.0 * mx,
            self.from.1 + self.sign.1 * my,
        )
    }

    /// The walk's error term after `k` steps (see [`super::BresenhamLine`]):
    /// `|dx|·(1 + y moves) − |dy|·(1 + x moves)`. It lies between `|dx|/2 − |dy|` and
    /// `3|dx|/2 − |dy|` (x major) or the mirror (y major), so it fits an `i32`.
    pub(super) fn error_at(&self, k: i64) -> i64 {
        let (mx, my) = self.moves(k);
        self.delta.0 * (1 + my) - self.delta.1 * (1 + mx)
    }

    /// The steps whose cell lies in `x_range` × `y_range` (inclusive bounds), as an inclusive
    /// interval, or `None` when there are none.
    pub(super) fn steps_within(
        &self,
        x_range: (i64, i64),
        y_range: (i64, i64),
    ) -> Option<(i64, i64)> {
        let (mut lo, mut hi) = (0, self.last_step());
        let (major_range, minor_range, major_sign, minor_sign, major_from, minor_from) =
            if self.x_major() {
                (
                    x_range,
                    y_range,
                    self.sign.0,
                    self.sign.1,
                    self.from.0,
                    self.from.1,
                )
            } else {
                (
                    y_range,
                    x_range,
                    self.sign.1,
                    self.sign.0,
                    self.from.1,
                    self.from.0,
                )
            };
        // Major axis: coordinate = from + sign·k.
        let (k_lo, k_hi) = moves_range(major_range, major_from, major_sign);
        lo = lo.max(k_lo);
        hi = hi.min(k_hi);
        // Minor axis: coordinate = from + sign·n(k), n non-decreasing.
        let (t_lo, t_hi) = moves_range(minor_range, minor_from, minor_sign);
        let (b, a) = self.major_minor_delta();
        if a == 0 {
            // The minor coordinate never moves.
            if !(t_lo <= 0 && 0 <= t_hi) {
                return None;
            }
        } else {
            // n(k) ≥ t  ⇔  2ak + b ≥ 2bt  ⇔  k ≥ ceil((2bt − b) / 2a).
            lo = lo.max(ceil_div(2 * b * t_lo - b, 2 * a));
            // n(k) ≤ t  ⇔  2ak + b < 2b(t + 1)  ⇔  k ≤ floor((2bt + b − 1) / 2a).
            hi = hi.min((2 * b * t_hi + b - 1).div_euclid(2 * a));
        }
        (lo <= hi).then_some((lo, hi))
    }
}

/// The moves `m` for which `from + sign·m` lies in `range` (inclusive), as an inclusive range
/// (empty when its start exceeds its end).
fn moves_range(range: (i64, i64), from: i64, sign: i64) -> (i64, i64) {
    if sign > 0 {
        (range.0 - from, range.1 - from)
    } else {
        (from - range.1, from - range.0)
    }
}

/// `ceil(p / q)` for `q > 0`.
fn ceil_div(p: i64, q: i64) -> i64 {
    -((-p).div_euclid(q))
}
