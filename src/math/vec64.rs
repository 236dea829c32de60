//! A 3-vector of f64, for the few predicates f32 cannot resolve: the orientation tests of
//! the hull builder and the sub-algorithm that finishes an undecided GJK stop.
//!
//! An f32 vector converts to it exactly, `+ − × ÷` are correctly rounded IEEE operations
//! on every target (soft-float on an MCU), and nothing here fuses or reorders them, so the
//! results have the same bits everywhere. [`Vec64::rounded`] is the only way back to f32.

use super::Vec3;
use core::ops::{Add, Mul, Neg, Sub};

/// A point or direction in f64.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Vec64 {
    /// x component.
    pub x: f64,
    /// y component.
    pub y: f64,
    /// z component.
    pub z: f64,
}

impl Vec64 {
    /// The zero vector.
    pub const ZERO: Vec64 = Vec64 {
        x: 0.0,
        y: 0.0,
        z: 0.0,
    };

    /// The f32 vector, exactly.
    pub fn of(v: Vec3) -> Vec64 {
        Vec64 {
            x: f64::from(v.x),
            y: f64::from(v.y),
            z: f64::from(v.z),
        }
    }

    /// Rounded to the nearest f32 vector.
    #[allow(clippy::cast_possible_truncation)]
    pub fn rounded(self) -> Vec3 {
        Vec3::new(self.x as f32, self.y as f32, self.z as f32)
    }

    /// `self · o`, summed x, y, z.
    pub fn dot(self, o: Vec64) -> f64 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// `self × o`.
    pub fn cross(self, o: Vec64) -> Vec64 {
        Vec64 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    /// `|self|²`.
    pub fn length_squared(self) -> f64 {
        self.dot(self)
    }
}

impl Add for Vec64 {
    type Output = Vec64;
    fn add(self, o: Vec64) -> Vec64 {
        Vec64 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }
}

impl Sub for Vec64 {
    type Output = Vec64;
    fn sub(self, o: Vec64) -> Vec64 {
        Vec64 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }
}

impl Neg for Vec64 {
    type Output = Vec64;
    fn neg(self) -> Vec64 {
        Vec64 {
            x: -self.x,
            y: -self.y,
            z: -self.z,
        }
    }
}

impl Mul<f64> for Vec64 {
    type Output = Vec64;
    fn mul(self, s: f64) -> Vec64 {
        Vec64 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }
}

/// `√x` in f64, correctly rounded (IEEE `sqrt`, the same bits on every target): in an
/// AVX build on x86 the SSE2 square root as an intrinsic (`vsqrtsd`, see
/// `scalar::sqrt`), elsewhere libm's.
#[cfg(all(
    any(target_arch = "x86", target_arch = "x86_64"),
    target_feature = "avx"
))]
pub(crate) fn sqrt(x: f64) -> f64 {
    use safe_arch::{get_f64_from_m128d_s, set_m128d_s, sqrt_m128d_s};
    let v = set_m128d_s(x);
    get_f64_from_m128d_s(sqrt_m128d_s(v, v))
}

/// `√x` in f64 on wasm32 built with SIMD: WebAssembly's `f64x2.sqrt` of the value
/// splatted, lane 0 (the IEEE root; libm's is a software routine there, see
/// `scalar::sqrt`).
#[cfg(all(target_arch = "wasm32", target_feature = "simd128"))]
pub(crate) fn sqrt(x: f64) -> f64 {
    use core::arch::wasm32::{f64x2_extract_lane, f64x2_splat, f64x2_sqrt};
    f64x2_extract_lane::<0>(f64x2_sqrt(f64x2_splat(x)))
}

/// `√x` in f64, correctly rounded (IEEE `sqrt`, the same bits on every target).
#[cfg(not(any(
    all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "avx"
    ),
    all(target_arch = "wasm32", target_feature = "simd128")
)))]
pub(crate) fn sqrt(x: f64) -> f64 {
    libm::sqrt(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`sqrt`] is libm's, bit for bit (the x86 intrinsic in an AVX build; `.ci/run` runs
    /// this in its `x86-64-v3` build): across the exponents and the edges.
    #[test]
    fn sqrt_is_libms_bit_for_bit() {
        let mut bits = 0u64;
        while bits < 0x7ff0_0000_0000_0000 {
            let x = f64::from_bits(bits);
            assert_eq!(sqrt(x).to_bits(), libm::sqrt(x).to_bits(), "sqrt({x:e})");
            bits += 0x0000_3ff0_0000_0fff;
        }
        for x in [0.0, -0.0, f64::MIN_POSITIVE, 5.0e-324, f64::INFINITY] {
            assert_eq!(sqrt(x).to_bits(), libm::sqrt(x).to_bits());
        }
        assert!(sqrt(-1.0).is_nan() && sqrt(f64::NAN).is_nan());
    }

    #[test]
    fn converts_f32_exactly_and_rounds_back() {
        let v = Vec3::new(0.1, -3.0e-7, 12345.678);
        assert_eq!(Vec64::of(v).rounded(), v);
        let third = Vec64 {
            x: 1.0 / 3.0,
            y: 0.0,
            z: 0.0,
        };
        assert_eq!(third.rounded().x, 1.0f32 / 3.0);
    }

    #[test]
    fn cross_is_orthogonal_and_right_handed() {
        let x = Vec64::of(Vec3::new(1.0, 0.0, 0.0));
        let y = Vec64::of(Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(x.cross(y), Vec64::of(Vec3::new(0.0, 0.0, 1.0)));
        let a = Vec64::of(Vec3::new(1.5, -2.0, 0.25));
        let b = Vec64::of(Vec3::new(-0.5, 4.0, 3.0));
        let c = a.cross(b);
        assert_eq!(c.dot(a), 0.0);
        assert_eq!(c.dot(b), 0.0);
        assert_eq!((a - b + b) * 2.0, a + a);
        assert_eq!(-a + a, Vec64::ZERO);
        assert_eq!(
            sqrt(a.length_squared()),
            libm::sqrt(1.5 * 1.5 + 4.0 + 0.0625)
        );
    }
}
