//! Scalar functions over `f32`, the one door to libm (or micromath).
//!
//! `f32::min`, `f32::max` and `f32::clamp` are not used in the engine: their handling of
//! `±0` and NaN is not specified the same on every target, and `clamp` panics on NaN.
//! [`min`], [`max`] and [`clamp`] here are plain compares and selects.

/// Square root. IEEE 754 requires a correctly rounded result, so libm and hardware agree.
///
/// In a build that enables AVX on x86 (`-C target-cpu=x86-64-v3`, `native`), the square
/// root through `safe_arch` (`_mm_sqrt_ss`), which the compiler emits as `vsqrtss`.
/// libm's x86 `sqrtf` is a legacy-encoded `sqrtss` in inline assembly, and an AVX build
/// paid the processor's SSE-to-AVX transition at each one: the whole step took 1.5 to 2.6
/// times as long as the default `x86-64` build's. Elsewhere libm's (hardware where the
/// target has it): in the default x86-64 build the intrinsic gave the same bits, but the
/// solve passes compiled to 18 % more instructions (`spheres`).
#[cfg(all(
    not(feature = "micromath"),
    any(target_arch = "x86", target_arch = "x86_64"),
    target_feature = "avx"
))]
#[inline]
pub fn sqrt(x: f32) -> f32 {
    use safe_arch::{get_f32_from_m128_s, set_m128_s, sqrt_m128_s};
    get_f32_from_m128_s(sqrt_m128_s(set_m128_s(x)))
}

/// Square root. IEEE 754 requires a correctly rounded result, so libm and hardware agree.
///
/// On wasm32 built with SIMD (`-C target-feature=+simd128`), WebAssembly's `f32x4.sqrt`
/// of the value splatted, lane 0: the IEEE root, which V8 runs as one instruction. libm's
/// `sqrtf` is its software routine on wasm32 (the scalar `f32.sqrt` intrinsic is not in
/// stable Rust), a tenth of a `boxes` step under Node.
#[cfg(all(
    not(feature = "micromath"),
    target_arch = "wasm32",
    target_feature = "simd128"
))]
#[inline]
pub fn sqrt(x: f32) -> f32 {
    use core::arch::wasm32::{f32x4_extract_lane, f32x4_splat, f32x4_sqrt};
    f32x4_extract_lane::<0>(f32x4_sqrt(f32x4_splat(x)))
}

/// Square root. IEEE 754 requires a correctly rounded result, so libm and hardware agree.
#[cfg(all(
    not(feature = "micromath"),
    not(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "avx"
    )),
    not(all(target_arch = "wasm32", target_feature = "simd128"))
))]
#[inline]
pub fn sqrt(x: f32) -> f32 {
    libm::sqrtf(x)
}

/// Square root without a division: micromath's inverse square root estimate (the
/// bit-level "magic constant" guess, up to 3.4 % off), two Newton steps on `1/√x` and one
/// on `√x`, all in `+ − ×`; within 1 ulp of the correctly rounded root (tested). A
/// non-positive or NaN `x` gives 0, `+∞` gives `+∞`.
///
/// micromath's own `sqrt` (a halved exponent, up to 6 % off) is not used: it left
/// normalised quaternions and normals outside carom's unit checks and put the same
/// relative error into every distance. Each step is plain IEEE arithmetic in a fixed
/// order (no `mul_add`), so the result is bit-identical on every target, soft-float
/// included.
///
/// Not inlined: its ~15 operations at each of the engine's square roots would add about
/// 14 KiB of flash to the minimal Cortex-M4F firmware for no measurable speed (the call
/// costs a few instructions against the dozens of the root).
#[cfg(feature = "micromath")]
#[inline(never)]
pub fn sqrt(x: f32) -> f32 {
    /// 2^24 and 2^-12: subnormal inputs are scaled into the normal range (exactly) and
    /// the root scaled back, so the estimate starts within its 3.4 %.
    const SCALE_UP: f32 = 16_777_216.0;
    const SCALE_DOWN: f32 = 1.0 / 4096.0;
    if x > 0.0 {
        if x == f32::INFINITY {
            x
        } else if x < f32::MIN_POSITIVE {
            refined_sqrt(x * SCALE_UP) * SCALE_DOWN
        } else {
            refined_sqrt(x)
        }
    } else {
        0.0 // zero, negative or NaN
    }
}

/// `√x` for a positive normal finite `x` (see [`sqrt`]).
#[cfg(feature = "micromath")]
#[inline]
fn refined_sqrt(x: f32) -> f32 {
    let half = 0.5 * x;
    // y ≈ 1/√x: relative error ≤ 3.4 %, then ≤ 1.8e-3, then ≤ 5e-6 (each Newton step
    // y ← y (3/2 − x y²/2) squares the error and multiplies it by 3/2).
    let mut y = micromath::F32(x).invsqrt().0;
    y = y * (1.5 - half * y * y);
    y = y * (1.5 - half * y * y);
    // s ≈ √x, then one Newton step on s² = x using the inverse already at hand:
    // s ← s + (x − s²) y/2, whose error is the square of the last (about 1e-11) plus
    // rounding.
    let s = x * y;
    s + (x - s * s) * (0.5 * y)
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

    /// The root the default backend takes (the x86 intrinsic in a build that enables AVX,
    /// libm's elsewhere) is libm's, bit for bit: over every exponent, 2^15 mantissas each,
    /// and the edges (signed zeros, subnormals, infinities, negatives and NaN give NaN).
    /// Run by `.ci/run` in the `x86-64-v3` build too, where the two differ in code.
    #[cfg(not(feature = "micromath"))]
    #[test]
    fn sqrt_is_libms_bit_for_bit() {
        let mut bits = 0u32;
        let mut checked = 0u32;
        while bits < 0x8000_0000 {
            for x in [f32::from_bits(bits), -f32::from_bits(bits)] {
                let (got, want) = (sqrt(x), libm::sqrtf(x));
                if want.is_nan() {
                    assert!(got.is_nan(), "sqrt({x:e}) = {got:e}, want NaN");
                } else {
                    assert_eq!(got.to_bits(), want.to_bits(), "sqrt({x:e})");
                }
                checked += 1;
            }
            bits += 0xff;
        }
        for x in [
            0.0,
            -0.0,
            f32::MIN_POSITIVE,
            1.0e-45,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ] {
            let (got, want) = (sqrt(x), libm::sqrtf(x));
            assert!(got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()));
        }
        assert!(sqrt(f32::NAN).is_nan());
        assert!(checked > 8_000_000, "{checked}");
    }

    #[cfg(feature = "micromath")]
    #[test]
    fn micromath_sqrt_is_within_one_ulp() {
        // Every exponent, 2^15 mantissas each, plus subnormals and the edges.
        let mut worst = 0u32;
        let mut bits = 0x0000_0001u32;
        while bits < 0x7f80_0000 {
            let x = f32::from_bits(bits);
            let exact = libm::sqrtf(x);
            let got = sqrt(x);
            let ulps = got.to_bits().abs_diff(exact.to_bits());
            assert!(ulps <= 1, "sqrt({x:e}) = {got:e}, want {exact:e}");
            worst = worst.max(ulps);
            bits += 0xff;
        }
        assert_eq!(sqrt(0.0), 0.0);
        assert_eq!(sqrt(-0.0), 0.0);
        assert_eq!(sqrt(-4.0), 0.0);
        assert_eq!(sqrt(f32::NAN), 0.0);
        assert_eq!(sqrt(f32::INFINITY), f32::INFINITY);
        assert_eq!(sqrt(f32::MAX).to_bits(), libm::sqrtf(f32::MAX).to_bits());
        assert!(worst <= 1);
    }

    #[cfg(feature = "micromath")]
    #[test]
    fn micromath_sqrt_is_exact_on_most_squares() {
        let mut exact = 0;
        for i in 1..1000u32 {
            let x = i as f32;
            if sqrt(x * x) == x {
                exact += 1;
            }
        }
        assert!(exact >= 990, "{exact} of 999 squares exact");
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
