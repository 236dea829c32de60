//! Scalar functions over `f32`, the one door to libm (or micromath).
//!
//! `f32::min`, `f32::max` and `f32::clamp` are not used in the engine: their handling of
//! `±0` and NaN is not specified the same on every target, and `clamp` panics on NaN.
//! [`min`], [`max`] and [`clamp`] here are plain compares and selects.

/// Square root. IEEE 754 requires a correctly rounded result, so libm and hardware agree.
#[cfg(not(feature = "micromath"))]
#[inline]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// Square root (micromath approximation, a few ulp off).
#[cfg(feature = "micromath")]
#[inline]
pub fn sqrt(x: f32) -> f32 {
    if x <= 0.0 {
        return 0.0;
    }
    micromath::F32(x).sqrt().0
}

/// Sine of an angle in radians.
#[cfg(not(feature = "micromath"))]
#[inline]
pub fn sin(x: f32) -> f32 {
    libm::sinf(x)
}

/// Sine of an angle in radians (micromath approximation).
#[cfg(feature = "micromath")]
#[inline]
pub fn sin(x: f32) -> f32 {
    micromath::F32(x).sin().0
}

/// Cosine of an angle in radians.
#[cfg(not(feature = "micromath"))]
#[inline]
pub fn cos(x: f32) -> f32 {
    libm::cosf(x)
}

/// Cosine of an angle in radians (micromath approximation).
#[cfg(feature = "micromath")]
#[inline]
pub fn cos(x: f32) -> f32 {
    micromath::F32(x).cos().0
}

/// Four-quadrant arctangent of `y / x`, in radians.
#[cfg(not(feature = "micromath"))]
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    libm::atan2f(y, x)
}

/// Four-quadrant arctangent of `y / x`, in radians (micromath approximation).
#[cfg(feature = "micromath")]
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    micromath::F32(y).atan2(micromath::F32(x)).0
}

/// Absolute value (clears the sign bit; exact on every target).
#[inline]
pub fn abs(x: f32) -> f32 {
    f32::from_bits(x.to_bits() & 0x7fff_ffff)
}

/// The smaller of `a` and `b`; returns `b` when they compare equal or either is NaN.
#[inline]
pub fn min(a: f32, b: f32) -> f32 {
    if a < b {
        a
    } else {
        b
    }
}

/// The larger of `a` and `b`; returns `b` when they compare equal or either is NaN.
#[inline]
pub fn max(a: f32, b: f32) -> f32 {
    if a > b {
        a
    } else {
        b
    }
}

/// `x` limited to `[lo, hi]`; never panics (a NaN `x` gives `hi`).
#[inline]
pub fn clamp(x: f32, lo: f32, hi: f32) -> f32 {
    if x < lo {
        lo
    } else if x <= hi {
        x
    } else {
        hi
    }
}

/// `+1.0` for `x >= 0` (including `-0.0`), `-1.0` otherwise.
#[inline]
pub fn sign(x: f32) -> f32 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// `-0.0` becomes `+0.0`; every other value is unchanged. Used before hashing.
#[inline]
pub fn canonical(x: f32) -> f32 {
    if x == 0.0 {
        0.0
    } else {
        x
    }
}

/// True when `x` is neither infinite nor NaN.
#[inline]
pub fn is_finite(x: f32) -> bool {
    x.is_finite()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn min_max_clamp_are_total() {
        assert_eq!(min(1.0, 2.0), 1.0);
        assert_eq!(max(1.0, 2.0), 2.0);
        assert_eq!(clamp(f32::NAN, 0.0, 1.0), 1.0);
        assert_eq!(clamp(-3.0, 0.0, 1.0), 0.0);
        assert_eq!(clamp(0.5, 0.0, 1.0), 0.5);
        assert_eq!(canonical(-0.0).to_bits(), 0);
        assert_eq!(abs(-2.5), 2.5);
    }

    #[cfg(not(feature = "micromath"))]
    #[test]
    fn sqrt_is_exact_on_squares() {
        for i in 0..1000u32 {
            let x = i as f32;
            assert_eq!(sqrt(x * x), x);
        }
    }
}
