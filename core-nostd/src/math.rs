//! Every float function the core uses, routed through `libm` so that native, wasm and
//! embedded targets compute the same bits (the core has no `std` to fall back on).

/// Square root.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// Cosine.
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// Sine.
#[inline]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// Arc cosine, with the argument clamped to [-1, 1] so rounding never yields NaN.
#[inline]
pub fn acos(x: f32) -> f32 {
    libm::acosf(x.clamp(-1.0, 1.0))
}

/// Four-quadrant arc tangent of `y / x`.
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// Absolute value.
#[inline]
pub fn abs(x: f32) -> f32 {
    libm::fabsf(x)
}

/// Four-quadrant arc tangent of `y / x`, in f64 (rotation angles extracted from a matrix).
#[inline]
pub fn atan2_f64(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// `√(x² + y²)` without intermediate overflow, in f64.
#[inline]
pub fn hypot_f64(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// Sine and cosine of `x`, in f64.
#[inline]
pub fn sin_cos_f64(x: f64) -> (f64, f64) {
    libm::sincos(x)
}
