//! The only floating-point functions the core uses beyond `+ - * /`.
//!
//! They all go through `micromath`, called by path, never by method syntax: on a host build a
//! method call such as `x.sqrt()` silently resolves to `std`'s inherent function instead, and the
//! simulator would then compute different numbers from the firmware. Calling these wrappers keeps
//! the host, the tests and the MCU bit-for-bit on the same code.

use micromath::F32Ext;

/// Square root (micromath's fast approximation).
#[inline]
pub fn sqrt(x: f32) -> f32 {
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

/// `e` raised to `x` (micromath's approximation).
#[inline]
pub fn exp(x: f32) -> f32 {
    F32Ext::exp(x)
}

/// Natural logarithm (micromath's approximation); `NaN` for negative `x`.
#[inline]
pub fn ln(x: f32) -> f32 {
    F32Ext::ln(x)
}

/// Square root to nearly full `f32` precision: micromath's [`sqrt`] (a bit-level estimate,
/// off by up to ~6 %) refined by two Newton steps. Plain `+ - * /`, so the host and the MCU
/// still compute bit-identical results. Negative or NaN input gives NaN; `+inf` gives `+inf`.
///
/// ```
/// let r = twil_core::math::sqrt_precise(0.01);
/// assert!((r - 0.1).abs() < 1e-6);
/// ```
#[inline]
pub fn sqrt_precise(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x == 0.0 || x == f32::INFINITY {
        return x;
    }
    let mut y = sqrt(x);
    y = 0.5 * (y + x / y);
    y = 0.5 * (y + x / y);
    y
}

/// Hypotenuse with [`sqrt_precise`].
#[inline]
pub fn hypot_precise(x: f32, y: f32) -> f32 {
    sqrt_precise(x * x + y * y)
}
