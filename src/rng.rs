//! SplitMix64: a tiny, portable, seeded generator for building the standard scenes and
//! test inputs identically on every target. Not for cryptography.

use crate::math::{scalar, Quat, Vec3};

/// The SplitMix64 generator (Steele, Lea and Flood 2014).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    /// A generator from a seed.
    pub const fn new(seed: u64) -> SplitMix64 {
        SplitMix64 { state: seed }
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `[0, 1)`, from the top 24 bits (exact in `f32`).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / 16_777_216.0)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }

    /// Uniform on the unit sphere (rejection sampling in the cube, bounded to 64 tries).
    pub fn unit_vector(&mut self) -> Vec3 {
        for _ in 0..64 {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            let l2 = v.length_squared();
            if l2 > 1.0e-4 && l2 <= 1.0 {
                return v * (1.0 / scalar::sqrt(l2));
            }
        }
        Vec3::Y
    }

    /// A uniformly random rotation (Shoemake's method).
    pub fn rotation(&mut self) -> Quat {
        let u1 = self.next_f32();
        let u2 = self.range(0.0, core::f32::consts::TAU);
        let u3 = self.range(0.0, core::f32::consts::TAU);
        let a = scalar::sqrt(1.0 - u1);
        let b = scalar::sqrt(u1);
        Quat::from_xyzw(
            a * scalar::sin(u2),
            a * scalar::cos(u2),
            b * scalar::sin(u3),
            b * scalar::cos(u3),
        )
        .normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_outputs_match_the_reference_sequence() {
        // Reference values of SplitMix64 seeded with 0.
        let mut r = SplitMix64::new(0);
        assert_eq!(r.next_u64(), 0xE220_A839_7B1D_CDAF);
        assert_eq!(r.next_u64(), 0x6E78_9E6A_A1B9_65F4);
    }

    #[test]
    fn floats_stay_in_range() {
        let mut r = SplitMix64::new(7);
        for _ in 0..10_000 {
            let x = r.range(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
            assert!((r.unit_vector().length() - 1.0).abs() < 1e-5);
        }
    }
}
