//! Every float function the core uses, routed through `libm` so that native, wasm and
//! embedded targets compute the same bits (the core has no `std` to fall back on).

/// Square root.
#[inline]
pub(crate) fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// Square root in f64 (the pose bound's distance).
#[inline]
pub(crate) fn sqrt_f64(x: f64) -> f64 {
    libm::sqrt(x)
}

/// Cosine (the deringing windows, the gradient's stencil directions).
#[inline]
pub(crate) fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// Sine (the pose features' versine).
#[inline]
pub(crate) fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// Absolute value.
#[inline]
pub(crate) fn abs(x: f32) -> f32 {
    libm::fabsf(x)
}

/// Four-quadrant arc tangent of `y / x`, in f64 (rotation angles extracted from a matrix).
#[inline]
pub(crate) fn atan2_f64(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

/// Arc cosine in f64 (the horizon-clipped sphere light).
#[inline]
pub(crate) fn acos_f64(x: f64) -> f64 {
    libm::acos(x)
}

/// Arc cosine (the horizon-clipped occluder caps).
#[inline]
pub(crate) fn acos(x: f32) -> f32 {
    libm::acosf(x)
}

/// Four-quadrant arc tangent of `y / x` (the horizon-clipped occluder caps).
#[inline]
pub(crate) fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// `√(x² + y²)` without intermediate overflow, in f64.
#[inline]
pub(crate) fn hypot_f64(x: f64, y: f64) -> f64 {
    libm::hypot(x, y)
}

/// Sine and cosine of `x`, in f64.
#[inline]
pub(crate) fn sin_cos_f64(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// Square root for constant evaluation (`f64::sqrt` is not `const`), 0 for `x ≤ 0`: Newton's
/// iteration from an over-estimate decreases monotonically to ⌊√x⌋ or ⌈√x⌉ in f64, far below
/// f32 resolution, and stops there.
pub(crate) const fn const_sqrt(x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let mut y = if x > 1.0 { x } else { 1.0 };
    loop {
        let next = 0.5 * (y + x / y);
        if next >= y {
            return y;
        }
        y = next;
    }
}
