//! Four lanes of `f32`: the arithmetic of the wide contact solver.
//!
//! Every operation is the scalar operation applied to each lane, in the same order, with
//! the same rounding (`+ − × ÷ √`, compares and selects; no fused multiply-add, no
//! reciprocal estimates, no horizontal sums). A compiler that vectorises these loops
//! (SSE2 on x86_64, NEON on aarch64, simd128 on wasm32 built with
//! `-C target-feature=+simd128`) and one that does not (a Cortex-M, a wasm32 build
//! without it) produce the same bits lane for lane, so the golden checksums hold across
//! targets. Written as plain arrays, no `unsafe`; the intrinsics are, on x86, the
//! square root ([`F4::sqrt`], `safe_arch`'s `sqrtps`: correctly rounded, the same bits)
//! and the equality mask ([`F4::eq_bits`], `cmpeqps` and `movmskps`: the same mask as
//! four compares), and on wasm32 with SIMD the square root (`core::arch::wasm32`'s
//! `f32x4_sqrt`, the IEEE root in each lane).

use core::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use super::{scalar, Mat3, Vec3};

/// Four `f32` lanes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct F4(pub [f32; 4]);

impl F4 {
    /// Zero in every lane.
    pub const ZERO: F4 = F4([0.0; 4]);

    /// `x` in every lane.
    #[inline]
    pub const fn splat(x: f32) -> F4 {
        F4([x; 4])
    }

    /// Lane `l` (0 for an index out of range).
    #[inline]
    pub fn lane(self, l: usize) -> f32 {
        self.0.get(l).copied().unwrap_or(0.0)
    }

    /// Set lane `l` (ignored out of range).
    #[inline]
    pub fn set(&mut self, l: usize, x: f32) {
        if let Some(v) = self.0.get_mut(l) {
            *v = x;
        }
    }

    /// `f` of the two lanes `l` of `self` and `o`, in each lane.
    #[inline(always)]
    fn lanewise(self, o: F4, f: impl Fn(f32, f32) -> f32) -> F4 {
        let [a0, a1, a2, a3] = self.0;
        let [b0, b1, b2, b3] = o.0;
        F4([f(a0, b0), f(a1, b1), f(a2, b2), f(a3, b3)])
    }

    /// Lane-wise [`scalar::min`].
    #[inline]
    pub fn min(self, o: F4) -> F4 {
        self.lanewise(o, scalar::min)
    }

    /// Lane-wise [`scalar::max`].
    #[inline]
    pub fn max(self, o: F4) -> F4 {
        self.lanewise(o, scalar::max)
    }

    /// Lane-wise [`scalar::clamp`] to `[lo, hi]`.
    #[inline]
    pub fn clamp(self, lo: F4, hi: F4) -> F4 {
        let [x0, x1, x2, x3] = self.0;
        let [l0, l1, l2, l3] = lo.0;
        let [h0, h1, h2, h3] = hi.0;
        F4([
            scalar::clamp(x0, l0, h0),
            scalar::clamp(x1, l1, h1),
            scalar::clamp(x2, l2, h2),
            scalar::clamp(x3, l3, h3),
        ])
    }

    /// Lane-wise `self / o`.
    #[inline]
    pub fn div(self, o: F4) -> F4 {
        let [a0, a1, a2, a3] = self.0;
        let [b0, b1, b2, b3] = o.0;
        F4([a0 / b0, a1 / b1, a2 / b2, a3 / b3])
    }

    /// Lane-wise `1 / self` where the lane is positive and finite, zero elsewhere (an
    /// effective mass from its inverse, `contact_solver::inverse_or_zero` in each lane):
    /// two selects around one division of all four lanes. (The lanes below infinity are
    /// kept first and the positive ones of those then inverted: tested together on the
    /// same value, the two compares became a scalar bit test per lane.)
    #[inline]
    pub fn recip_or_zero(self) -> F4 {
        let finite = F4::splat(f32::INFINITY).gt_select(self, self, F4::ZERO);
        finite.gt_select(F4::ZERO, F4::splat(1.0).div(finite), F4::ZERO)
    }

    /// Lane-wise [`scalar::sqrt`]: on x86 with SSE (every x86_64 build) one `sqrtps`
    /// through `safe_arch` (IEEE's correctly rounded root in each lane, so the bits of
    /// [`scalar::sqrt`]); elsewhere, and with `micromath`, [`scalar::sqrt`] per lane.
    #[cfg(all(
        not(feature = "micromath"),
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse"
    ))]
    #[inline]
    pub fn sqrt(self) -> F4 {
        F4(safe_arch::sqrt_m128(safe_arch::m128::from_array(self.0)).to_array())
    }

    /// Lane-wise [`scalar::sqrt`]: on wasm32 built with SIMD, one `f32x4.sqrt` (the IEEE
    /// root in each lane, as [`scalar::sqrt`] there).
    #[cfg(all(
        not(feature = "micromath"),
        target_arch = "wasm32",
        target_feature = "simd128"
    ))]
    #[inline]
    pub fn sqrt(self) -> F4 {
        use core::arch::wasm32::{f32x4, f32x4_extract_lane, f32x4_sqrt};
        let [a0, a1, a2, a3] = self.0;
        let r = f32x4_sqrt(f32x4(a0, a1, a2, a3));
        F4([
            f32x4_extract_lane::<0>(r),
            f32x4_extract_lane::<1>(r),
            f32x4_extract_lane::<2>(r),
            f32x4_extract_lane::<3>(r),
        ])
    }

    /// Lane-wise [`scalar::sqrt`].
    #[cfg(not(any(
        all(
            not(feature = "micromath"),
            any(target_arch = "x86", target_arch = "x86_64"),
            target_feature = "sse"
        ),
        all(
            not(feature = "micromath"),
            target_arch = "wasm32",
            target_feature = "simd128"
        )
    )))]
    #[inline]
    pub fn sqrt(self) -> F4 {
        let [a0, a1, a2, a3] = self.0;
        F4([
            scalar::sqrt(a0),
            scalar::sqrt(a1),
            scalar::sqrt(a2),
            scalar::sqrt(a3),
        ])
    }

    /// Lane-wise `if self > o { a } else { b }`.
    #[inline]
    pub fn gt_select(self, o: F4, a: F4, b: F4) -> F4 {
        let [x0, x1, x2, x3] = self.0;
        let [y0, y1, y2, y3] = o.0;
        b.blend([x0 > y0, x1 > y1, x2 > y2, x3 > y3], a)
    }

    /// Lane-wise `if self == o { a } else { b }`.
    #[inline]
    pub fn eq_select(self, o: F4, a: F4, b: F4) -> F4 {
        let [x0, x1, x2, x3] = self.0;
        let [y0, y1, y2, y3] = o.0;
        b.blend([x0 == y0, x1 == y1, x2 == y2, x3 == y3], a)
    }

    /// Lane-wise `self == o` as the bits of a 4-bit number, lane `k` in bit `k` (0 where
    /// either is NaN): on x86 with SSE one `cmpeqps` and one `movmskps` through
    /// `safe_arch` (the same bits: the compare's mask has its sign bit set exactly where
    /// the lanes are equal); elsewhere four compares. (Written as four compares on x86,
    /// the mask took ten more instructions per call where it was shifted into a wider
    /// one, as in `ConvexHull::core_support`.)
    #[cfg(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse"
    ))]
    #[inline]
    pub fn eq_bits(self, o: F4) -> u32 {
        let (a, b) = (
            safe_arch::m128::from_array(self.0),
            safe_arch::m128::from_array(o.0),
        );
        (safe_arch::move_mask_m128(safe_arch::cmp_eq_mask_m128(a, b)) & 0xf) as u32
    }

    /// Lane-wise `self == o` as the bits of a 4-bit number, lane `k` in bit `k` (0 where
    /// either is NaN).
    #[cfg(not(all(
        any(target_arch = "x86", target_arch = "x86_64"),
        target_feature = "sse"
    )))]
    #[inline]
    pub fn eq_bits(self, o: F4) -> u32 {
        let [x0, x1, x2, x3] = self.0;
        let [y0, y1, y2, y3] = o.0;
        u32::from(x0 == y0)
            | (u32::from(x1 == y1) << 1)
            | (u32::from(x2 == y2) << 2)
            | (u32::from(x3 == y3) << 3)
    }

    /// Lane-wise `if mask { a } else { self }`.
    #[inline]
    pub fn select_where(self, mask: [bool; 4], a: F4) -> F4 {
        self.blend(mask, a)
    }

    /// Lane-wise `if mask { a } else { self }` as a blend of bit patterns (all ones where
    /// `mask`, all zeros elsewhere): the bits of one input or the other, never arithmetic,
    /// written so that compilers emit a vector compare and blend instead of a branch per
    /// lane.
    #[inline]
    fn blend(self, mask: [bool; 4], a: F4) -> F4 {
        let [m0, m1, m2, m3] = mask.map(|m| 0u32.wrapping_sub(u32::from(m)));
        let [x0, x1, x2, x3] = self.0.map(f32::to_bits);
        let [y0, y1, y2, y3] = a.0.map(f32::to_bits);
        F4([
            f32::from_bits((y0 & m0) | (x0 & !m0)),
            f32::from_bits((y1 & m1) | (x1 & !m1)),
            f32::from_bits((y2 & m2) | (x2 & !m2)),
            f32::from_bits((y3 & m3) | (x3 & !m3)),
        ])
    }
}

impl Add for F4 {
    type Output = F4;
    #[inline]
    fn add(self, o: F4) -> F4 {
        let [a0, a1, a2, a3] = self.0;
        let [b0, b1, b2, b3] = o.0;
        F4([a0 + b0, a1 + b1, a2 + b2, a3 + b3])
    }
}

impl Sub for F4 {
    type Output = F4;
    #[inline]
    fn sub(self, o: F4) -> F4 {
        let [a0, a1, a2, a3] = self.0;
        let [b0, b1, b2, b3] = o.0;
        F4([a0 - b0, a1 - b1, a2 - b2, a3 - b3])
    }
}

impl Mul for F4 {
    type Output = F4;
    #[inline]
    fn mul(self, o: F4) -> F4 {
        let [a0, a1, a2, a3] = self.0;
        let [b0, b1, b2, b3] = o.0;
        F4([a0 * b0, a1 * b1, a2 * b2, a3 * b3])
    }
}

impl Neg for F4 {
    type Output = F4;
    #[inline]
    fn neg(self) -> F4 {
        let [a0, a1, a2, a3] = self.0;
        F4([-a0, -a1, -a2, -a3])
    }
}

impl AddAssign for F4 {
    #[inline]
    fn add_assign(&mut self, o: F4) {
        *self = *self + o;
    }
}

impl SubAssign for F4 {
    #[inline]
    fn sub_assign(&mut self, o: F4) {
        *self = *self - o;
    }
}

/// Four [`Vec3`] lanes, structure of arrays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct V4 {
    /// x of each lane.
    pub x: F4,
    /// y of each lane.
    pub y: F4,
    /// z of each lane.
    pub z: F4,
}

impl V4 {
    /// Zero in every lane.
    pub const ZERO: V4 = V4 {
        x: F4::ZERO,
        y: F4::ZERO,
        z: F4::ZERO,
    };

    /// `v` in every lane.
    #[inline]
    pub fn splat(v: Vec3) -> V4 {
        V4 {
            x: F4::splat(v.x),
            y: F4::splat(v.y),
            z: F4::splat(v.z),
        }
    }

    /// Lane `l` as a [`Vec3`].
    #[inline]
    pub fn lane(&self, l: usize) -> Vec3 {
        Vec3::new(self.x.lane(l), self.y.lane(l), self.z.lane(l))
    }

    /// Set lane `l`.
    #[inline]
    pub fn set(&mut self, l: usize, v: Vec3) {
        self.x.set(l, v.x);
        self.y.set(l, v.y);
        self.z.set(l, v.z);
    }

    /// Dot product per lane, `x·x + y·y + z·z` in that order (as [`Vec3::dot`]).
    #[inline]
    pub fn dot(&self, o: &V4) -> F4 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product per lane, as [`Vec3::cross`].
    #[inline]
    pub fn cross(&self, o: &V4) -> V4 {
        V4 {
            x: self.y * o.z - self.z * o.y,
            y: self.z * o.x - self.x * o.z,
            z: self.x * o.y - self.y * o.x,
        }
    }

    /// Every lane scaled by its `s`.
    #[inline]
    pub fn scale(&self, s: F4) -> V4 {
        V4 {
            x: self.x * s,
            y: self.y * s,
            z: self.z * s,
        }
    }

    /// Lane-wise sum.
    #[inline]
    pub fn add(&self, o: &V4) -> V4 {
        V4 {
            x: self.x + o.x,
            y: self.y + o.y,
            z: self.z + o.z,
        }
    }

    /// Lane-wise difference.
    #[inline]
    pub fn sub(&self, o: &V4) -> V4 {
        V4 {
            x: self.x - o.x,
            y: self.y - o.y,
            z: self.z - o.z,
        }
    }

    /// `self += o · s`.
    #[inline]
    pub fn add_scaled(&mut self, o: &V4, s: F4) {
        self.x += o.x * s;
        self.y += o.y * s;
        self.z += o.z * s;
    }

    /// `self −= o · s`.
    #[inline]
    pub fn sub_scaled(&mut self, o: &V4, s: F4) {
        self.x -= o.x * s;
        self.y -= o.y * s;
        self.z -= o.z * s;
    }
}

/// A 3×3 matrix per lane, by columns (as [`Mat3`]).
#[derive(Clone, Copy, Default)]
pub(crate) struct M4 {
    /// Column x of each lane.
    pub x: V4,
    /// Column y of each lane.
    pub y: V4,
    /// Column z of each lane.
    pub z: V4,
}

impl M4 {
    /// Set lane `l`.
    pub fn set(&mut self, l: usize, m: &Mat3) {
        self.x.set(l, m.x);
        self.y.set(l, m.y);
        self.z.set(l, m.z);
    }

    /// Lane `l` as a [`Mat3`].
    #[inline]
    pub fn lane(&self, l: usize) -> Mat3 {
        Mat3::from_cols(self.x.lane(l), self.y.lane(l), self.z.lane(l))
    }

    /// `M v`, as [`Mat3::mul_vec`]: `(x vₓ + y v_y) + z v_z`.
    #[inline(always)]
    pub fn mul_vec(&self, v: &V4) -> V4 {
        self.x
            .scale(v.x)
            .add(&self.y.scale(v.y))
            .add(&self.z.scale(v.z))
    }

    /// The rotation matrices of four quaternions given as lanes `[x, y, z, w]`: per lane
    /// exactly [`Mat3::from_quat`] (the same operations in the same order).
    #[inline(always)]
    pub fn from_quat(q: &[F4; 4]) -> M4 {
        let [x, y, z, w] = *q;
        let (one, two) = (F4::splat(1.0), F4::splat(2.0));
        let (x2, y2, z2) = (x * two, y * two, z * two);
        M4 {
            x: V4 {
                x: one + (y * -y2 - z * z2),
                y: z2 * w - x * -y2,
                z: -y2 * w + x * z2,
            },
            y: V4 {
                x: -z2 * w + y * x2,
                y: one + (z * -z2 - x * x2),
                z: x2 * w - y * -z2,
            },
            z: V4 {
                x: y2 * w - z * -x2,
                y: -x2 * w + z * y2,
                z: one + (x * -x2 - y * y2),
            },
        }
    }

    /// `Mᵀ v`, as [`Mat3::transpose_mul_vec`].
    #[inline]
    pub fn transpose_mul_vec(&self, v: &V4) -> V4 {
        V4 {
            x: self.x.dot(v),
            y: self.y.dot(v),
            z: self.z.dot(v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each lane gives the scalar operation's exact bits.
    #[test]
    fn lanes_match_the_scalar_operations() {
        let mut rng = crate::rng::SplitMix64::new(11);
        for _ in 0..1000 {
            let a: [Vec3; 4] = core::array::from_fn(|_| rng.unit_vector() * rng.range(-5.0, 5.0));
            let b: [Vec3; 4] = core::array::from_fn(|_| rng.unit_vector() * rng.range(-5.0, 5.0));
            let mut va = V4::default();
            let mut vb = V4::default();
            for l in 0..4 {
                va.set(l, a[l]);
                vb.set(l, b[l]);
            }
            let dot = va.dot(&vb);
            let s = dot.sqrt();
            for l in 0..4 {
                assert_eq!(dot.lane(l).to_bits(), a[l].dot(b[l]).to_bits());
                assert_eq!(s.lane(l).to_bits(), scalar::sqrt(a[l].dot(b[l])).to_bits());
            }
        }
    }

    /// `F4::sqrt` (one `sqrtps` on x86) is `scalar::sqrt` in each lane, to the bit, at the
    /// edges too: zeros of both signs, subnormals, the largest finite value, infinity;
    /// negative and NaN lanes give NaN in both.
    #[test]
    fn square_root_lanes_match_the_scalar_root() {
        let special = [
            0.0,
            -0.0,
            1.0e-45,
            1.0e-40,
            f32::MIN_POSITIVE,
            1.0,
            2.0,
            f32::MAX,
            f32::INFINITY,
            -1.0,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let mut rng = crate::rng::SplitMix64::new(29);
        for _ in 0..2000 {
            let x = F4(core::array::from_fn(|_| {
                if rng.next_u64().is_multiple_of(2) {
                    special[(rng.next_u64() % special.len() as u64) as usize]
                } else {
                    f32::from_bits((rng.next_u64() as u32) & 0x7f7f_ffff)
                }
            }));
            let r = x.sqrt();
            for l in 0..4 {
                let want = scalar::sqrt(x.lane(l));
                if want.is_nan() {
                    assert!(r.lane(l).is_nan(), "{}", x.lane(l));
                } else {
                    assert_eq!(r.lane(l).to_bits(), want.to_bits(), "{}", x.lane(l));
                }
            }
        }
    }

    /// The selects (and `min`, `max`) are blends of bit patterns: each lane is exactly
    /// one input's bits (NaN payloads and the sign of zero kept), chosen as the scalar
    /// `if` chooses, NaN compares false; `eq_bits` is the scalar `==` lane by lane.
    #[test]
    fn selects_pick_an_input_bit_for_bit_as_the_scalar_if() {
        let nan = f32::from_bits(0x7fc0_1234);
        let values = [
            0.0,
            -0.0,
            1.5,
            -2.0,
            f32::INFINITY,
            f32::NEG_INFINITY,
            nan,
            -nan,
        ];
        let mut rng = crate::rng::SplitMix64::new(5);
        let mut pick = || values[(rng.next_u64() % values.len() as u64) as usize];
        for _ in 0..2000 {
            let [x, y, a, b]: [F4; 4] =
                core::array::from_fn(|_| F4(core::array::from_fn(|_| pick())));
            let mask: [bool; 4] = core::array::from_fn(|l| x.0[l].to_bits() & 1 == 0);
            let gt = x.gt_select(y, a, b);
            let eq = x.eq_select(y, a, b);
            let sel = b.select_where(mask, a);
            let (low, high) = (x.min(y), x.max(y));
            let bits = x.eq_bits(y);
            assert_eq!(bits >> 4, 0);
            for (l, m) in mask.into_iter().enumerate() {
                let (xl, yl, al, bl) = (x.lane(l), y.lane(l), a.lane(l), b.lane(l));
                let want_gt = if xl > yl { al } else { bl };
                let want_eq = if xl == yl { al } else { bl };
                let want_sel = if m { al } else { bl };
                assert_eq!(gt.lane(l).to_bits(), want_gt.to_bits());
                assert_eq!(eq.lane(l).to_bits(), want_eq.to_bits());
                assert_eq!(sel.lane(l).to_bits(), want_sel.to_bits());
                // min and max: the second input on ties (either zero) and NaN.
                let want_low = if xl < yl { xl } else { yl };
                let want_high = if xl > yl { xl } else { yl };
                assert_eq!(low.lane(l).to_bits(), want_low.to_bits());
                assert_eq!(high.lane(l).to_bits(), want_high.to_bits());
                // The equality mask: lane l in bit l, as the scalar `==` (NaN unequal,
                // the two zeros equal).
                assert_eq!((bits >> l) & 1 == 1, xl == yl);
            }
        }
    }

    /// `recip_or_zero` is `inverse_or_zero` in each lane, to the bit: zero for zero,
    /// negative, infinite and NaN lanes.
    #[test]
    fn reciprocal_lanes_match_the_scalar_inverse() {
        let inverse_or_zero = crate::dynamics::contact_solver::inverse_or_zero;
        let special = [0.0, -0.0, -1.0, f32::INFINITY, f32::NEG_INFINITY, f32::NAN];
        let tiny = [f32::MIN_POSITIVE, 1.0e-40, f32::MAX, 3.0];
        let mut rng = crate::rng::SplitMix64::new(17);
        for _ in 0..1000 {
            let x = F4(core::array::from_fn(|_| match rng.next_u64() % 3 {
                0 => special[(rng.next_u64() % special.len() as u64) as usize],
                1 => tiny[(rng.next_u64() % tiny.len() as u64) as usize],
                _ => rng.range(-10.0, 1000.0),
            }));
            let r = x.recip_or_zero();
            for l in 0..4 {
                assert_eq!(r.lane(l).to_bits(), inverse_or_zero(x.lane(l)).to_bits());
            }
        }
    }
}
