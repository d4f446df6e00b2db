//! The only floating-point functions the core uses beyond `+ - * /`.
//!
//! They all go through `micromath`, called by path, never by method syntax: on a host build a
//! method call such as `x.sqrt()` silently resolves to `std`'s inherent function instead, and the
//! simulator would then compute different numbers from the firmware. Calling these wrappers keeps
//! the host, the tests and the MCU bit-for-bit on the same code.

use micromath::F32Ext;

/// micromath's fast square-root estimate: the starting point of [`sqrt`].
#[inline]
fn sqrt_estimate(x: f32) -> f32 {
    F32Ext::sqrt(x)
}

/// Sine of an angle in radians.
#[inline]
pub fn sin(angle_rad: f32) -> f32 {
    F32Ext::sin(angle_rad)
}

/// Cosine of an angle in radians.
#[inline]
pub fn cos(angle_rad: f32) -> f32 {
    F32Ext::cos(angle_rad)
}

/// Four-quadrant arctangent of `y / x`, radians in `(-π, π]`.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    F32Ext::atan2(y, x)
}

/// Hypotenuse `sqrt(x² + y²)`.
#[inline]
pub fn hypot(x: f32, y: f32) -> f32 {
    sqrt(x * x + y * y)
}

/// Absolute value.
#[inline]
pub fn abs(x: f32) -> f32 {
    F32Ext::abs(x)
}

/// Largest integer not above `x` (as `f32`).
#[inline]
pub fn floor(x: f32) -> f32 {
    F32Ext::floor(x)
}

/// Smallest integer not below `x` (as `f32`).
#[inline]
pub fn ceil(x: f32) -> f32 {
    F32Ext::ceil(x)
}

/// Wrap an angle to `(-π, π]`.
#[inline]
pub fn wrap_angle_rad(angle_rad: f32) -> f32 {
    use core::f32::consts::PI;
    // Most angles are in range already: the remainder is a software `fmodf` on the MCU (the
    // Thales rule wraps a bearing per reading per cell; it was a quarter of its cost).
    if angle_rad > -PI && angle_rad <= PI {
        return angle_rad;
    }
    // Within one turn of the range the remainder is the angle itself: the same bits without it.
    if angle_rad > PI && angle_rad < 2.0 * PI {
        return angle_rad - 2.0 * PI;
    }
    if angle_rad <= -PI && angle_rad > -2.0 * PI {
        return angle_rad + 2.0 * PI;
    }
    wrap_by_remainder(angle_rad)
}

/// [`wrap_angle_rad`] by the remainder alone (its definition; the shortcuts above must give
/// the same bits: `tests::wrapping_gives_the_remainders_bits`). Non-finite angles give 0.
fn wrap_by_remainder(angle_rad: f32) -> f32 {
    use core::f32::consts::PI;
    if !angle_rad.is_finite() {
        return 0.0;
    }
    let mut a = angle_rad % (2.0 * PI);
    if a > PI {
        a -= 2.0 * PI;
    } else if a <= -PI {
        a += 2.0 * PI;
    }
    a
}

/// `e` raised to `x`, relative error below 1e-6 (range reduction by powers of two and a
/// degree-7 series; plain arithmetic, so every target gets the same bits). Underflows to 0
/// below −87, overflows to `+∞` above 88; `NaN` stays `NaN`.
pub fn exp(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    if x > 88.0 {
        return f32::INFINITY;
    }
    if x < -87.0 {
        return 0.0;
    }
    let ln2 = core::f32::consts::LN_2;
    let k = floor(x / ln2 + 0.5);
    // ln 2 in two parts (Cody-Waite) so k·ln2 is subtracted without rounding loss.
    let r = (x - k * 0.693_145_75) - k * 1.428_606_8e-6; // |r| <= ln2 / 2
    let mut term = 1.0f32;
    let mut sum = 1.0f32;
    for n in 1..=7 {
        term *= r / n as f32;
        sum += term;
    }
    // 2^k as bits: k is in [-126, 127] here.
    let scale = f32::from_bits(((k as i32 + 127) as u32) << 23);
    sum * scale
}

/// Natural logarithm, absolute error below 1e-6; `NaN` for negative or `NaN` `x`, `−∞` at 0.
/// (micromath's `ln` is off by up to a few percent, too much for settle times.) Splits
/// `x = m · 2^e` with `m` in `[√½, √2)` and sums `2·atanh((m−1)/(m+1))`.
pub fn ln(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x == 0.0 {
        return f32::NEG_INFINITY;
    }
    if x.is_infinite() {
        return x;
    }
    // Subnormals: scale up first.
    let (x, extra) = if x < f32::MIN_POSITIVE {
        (x * 16_777_216.0, -24i32)
    } else {
        (x, 0)
    };
    let bits = x.to_bits();
    let mut e = ((bits >> 23) & 0xff) as i32 - 127 + extra;
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000); // [1, 2)
    if m > core::f32::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0); // |s| < 0.172
    let s2 = s * s;
    let series =
        s * (2.0 + s2 * (2.0 / 3.0 + s2 * (2.0 / 5.0 + s2 * (2.0 / 7.0 + s2 * (2.0 / 9.0)))));
    series + e as f32 * core::f32::consts::LN_2
}

/// Square root to full `f32` precision (within an ulp): micromath's square root is a fast estimate
/// that can be 6 % off (`sqrt(2.25)` gives 1.5625), refined here by three Newton steps, which
/// are plain arithmetic and so identical on every target. `NaN` for negative or `NaN` input.
pub fn sqrt(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x == 0.0 || x.is_infinite() {
        return x;
    }
    // Subnormals: scale by 2^24 (the root by 2^12) so the estimate is meaningful.
    let (v, unscale) = if x < f32::MIN_POSITIVE {
        (x * 16_777_216.0, 1.0 / 4096.0)
    } else {
        (x, 1.0)
    };
    let mut y = sqrt_estimate(v);
    if !(y.is_finite() && y > 0.0) {
        y = v;
    }
    for _ in 0..3 {
        y = 0.5 * (y + v / y);
    }
    y * unscale
}

#[cfg(test)]
mod tests {
    extern crate std;

    proptest::proptest! {
        /// The shortcuts for angles within a turn of the range give the remainder's bits.
        #[test]
        fn wrapping_gives_the_remainders_bits(a in proptest::prop_oneof![
            -7.0f32..7.0, proptest::num::f32::ANY,
        ]) {
            let (got, want) = (super::wrap_angle_rad(a), super::wrap_by_remainder(a));
            proptest::prop_assert_eq!(got.to_bits(), want.to_bits(), "{}", a);
        }
    }

    #[test]
    fn wrapping_keeps_the_range_ends_and_non_numbers_apart() {
        use core::f32::consts::PI;
        assert_eq!(super::wrap_angle_rad(PI), PI);
        assert_eq!(super::wrap_angle_rad(-PI), super::wrap_by_remainder(-PI));
        assert_eq!(super::wrap_angle_rad(f32::NAN), 0.0);
        assert_eq!(super::wrap_angle_rad(f32::INFINITY), 0.0);
    }

    #[test]
    fn exp_and_ln_are_accurate() {
        for i in -800..800 {
            let x = i as f32 * 0.1;
            let e = super::exp(x) as f64;
            let exact = (x as f64).exp();
            assert!(
                ((e - exact) / exact).abs() < 2e-6,
                "exp({x}) = {e} vs {exact}"
            );
        }
        for i in 1..2000 {
            let x = i as f32 * 0.0123;
            let l = super::ln(x) as f64;
            assert!((l - (x as f64).ln()).abs() < 2e-6, "ln({x}) = {l}");
        }
        assert!((super::ln(1.0e-40) as f64 - (1.0e-40f64).ln()).abs() < 1e-4);
        assert!(super::ln(-1.0).is_nan());
        assert_eq!(super::ln(0.0), f32::NEG_INFINITY);
        assert_eq!(super::exp(100.0), f32::INFINITY);
        assert_eq!(super::exp(-100.0), 0.0);
        assert!(super::exp(f32::NAN).is_nan());
    }

    #[test]
    fn sqrt_is_precise() {
        for i in 0..100_000 {
            let x = i as f32 * 0.013 + 1.0e-3;
            let r = super::sqrt(x) as f64;
            let exact = (x as f64).sqrt();
            assert!(((r - exact) / exact).abs() < 2e-7, "sqrt({x}) = {r}");
        }
        assert_eq!(super::sqrt(2.25), 1.5);
        assert!((super::sqrt(1.0e-40) as f64 - 1.0e-20).abs() < 1e-25);
        assert!(super::sqrt(-1.0).is_nan());
        assert_eq!(super::sqrt(f32::INFINITY), f32::INFINITY);
        assert_eq!(super::hypot(3.0, 4.0), 5.0);
    }
}
