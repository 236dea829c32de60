//! The cross-target narrow-phase workload: [`PAIRS`] seeded random pairs of spheres,
//! capsules, boxes and hulls through [`distance`] and [`contact`], every input pose and
//! every output number hashed. The host test, the Cortex-M firmware (under QEMU) and the
//! WASM build (under Node) all print its line, which `tests/golden/checksums.txt` holds:
//!
//! ```text
//! narrow 256 0x<16 hex digits>
//! ```
//!
//! One flipped bit in any result on any target changes the line.
//!
//! Canonical hashing: `-0.0` is hashed as `+0.0` (targets may differ in the sign of a zero
//! without differing in value), and every NaN as the one quiet NaN `0x7fc0_0000` (NaN
//! payloads are not portable, e.g. on wasm32). A NaN still changes the hash, so it is
//! still caught.
//!
//! This is the workload that lived in `demos/workload.rs`, moved unchanged: the draw order
//! and the hash stream are part of the golden line, so they must not change.

use crate::collide::{contact, distance, GjkStatus, Manifold, SimplexCache};
use crate::math::{Iso, Vec3};
use crate::rng::SplitMix64;
use crate::shape::{ConvexHull, Shape, Sphere};

/// Seed of the workload's generator (ASCII "carom!").
pub const SEED: u64 = 0x6361_726f_6d21;
/// Number of shape pairs the workload queries.
pub const PAIRS: u32 = 256;
/// Speculative margin passed to [`contact`] (m).
pub const MARGIN: f32 = 0.02;
/// Name of the workload's golden line.
pub const NAME: &str = "narrow";
/// Number of distinct hulls the pairs draw from.
const HULLS: usize = 4;
/// Points per hull, random on the unit sphere.
const HULL_POINTS: usize = 16;

/// Tags hashed in place of values that are not numbers (which branch a result took).
const TAG_ERR: u32 = 0xE000_0000;
const TAG_NONE: u32 = 0xA000_0000;
const TAG_SOME: u32 = 0xB000_0000;

/// FNV-1a, 64-bit (Fowler, Noll, Vo): `h = (h ^ byte) · 0x100000001b3` (wrapping), from
/// the offset basis `0xcbf29ce484222325`. Multi-byte values are fed little-endian, so the
/// hash does not depend on the target's byte order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fnv1a64(u64);

impl Default for Fnv1a64 {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv1a64 {
    /// A hash at the FNV offset basis.
    pub const fn new() -> Fnv1a64 {
        Fnv1a64(0xcbf2_9ce4_8422_2325)
    }

    /// Feed one byte.
    pub fn write_u8(&mut self, byte: u8) {
        self.0 = (self.0 ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
    }

    /// Feed a `u32`, little-endian.
    pub fn write_u32(&mut self, x: u32) {
        for b in x.to_le_bytes() {
            self.write_u8(b);
        }
    }

    /// Feed a `u64`, little-endian.
    pub fn write_u64(&mut self, x: u64) {
        for b in x.to_le_bytes() {
            self.write_u8(b);
        }
    }

    /// Feed the bits of `x`, with `-0.0` as `+0.0` and every NaN as `0x7fc0_0000`.
    pub fn write_f32(&mut self, x: f32) {
        let bits = if x.is_nan() {
            0x7fc0_0000
        } else if x == 0.0 {
            0
        } else {
            x.to_bits()
        };
        self.write_u32(bits);
    }

    /// Feed a vector: x, then y, then z.
    pub fn write_vec3(&mut self, v: Vec3) {
        self.write_f32(v.x);
        self.write_f32(v.y);
        self.write_f32(v.z);
    }

    /// Feed a pose: position, then the rotation's x, y, z, w.
    pub fn write_iso(&mut self, iso: &Iso) {
        self.write_vec3(iso.position);
        self.write_f32(iso.rotation.x);
        self.write_f32(iso.rotation.y);
        self.write_f32(iso.rotation.z);
        self.write_f32(iso.rotation.w);
    }

    /// The hash so far.
    pub const fn finish(&self) -> u64 {
        self.0
    }
}

/// What the workload did: how many pairs it ran and the hash of everything it saw.
/// `Display` prints its golden line: `narrow <count> 0x<hash>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NarrowResult {
    /// Pairs queried.
    pub count: u32,
    /// FNV-1a 64 of the inputs and results.
    pub hash: u64,
}

impl NarrowResult {
    /// The golden line of this result.
    pub fn line(&self) -> super::GoldenLine {
        super::GoldenLine {
            name: NAME,
            steps: self.count,
            checksum: self.hash,
        }
    }
}

impl core::fmt::Display for NarrowResult {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        self.line().fmt(f)
    }
}

/// The random hulls the pairs draw from, kept where the caller wants them ([`run_in`];
/// [`run`] keeps them on its stack): 16 points on the unit sphere each. A
/// hull that does not build (an error is a deterministic outcome too) is marked so, and
/// its pairs use a cube of half-extent 0.5 m instead; the workload hashes which.
#[derive(Clone, Debug)]
pub struct NarrowHulls {
    hulls: [ConvexHull; HULLS],
    built: [bool; HULLS],
}

impl NarrowHulls {
    /// Storage for the workload's hulls, none built yet (a constant, so a firmware's
    /// `static` holds it without staging it on the stack).
    pub const EMPTY: NarrowHulls = NarrowHulls {
        hulls: [ConvexHull::UNIT_TETRAHEDRON; HULLS],
        built: [false; HULLS],
    };

    /// Build every hull in place from `rng`'s points.
    fn build(&mut self, rng: &mut SplitMix64) {
        for (hull, built) in self.hulls.iter_mut().zip(self.built.iter_mut()) {
            let mut points = [Vec3::ZERO; HULL_POINTS];
            for p in points.iter_mut() {
                *p = rng.unit_vector();
            }
            *built = hull.rebuild(&points).is_ok();
        }
    }

    /// Hull `index`, if it built.
    fn get(&self, index: usize) -> Option<&ConvexHull> {
        match self.built.get(index) {
            Some(true) => self.hulls.get(index),
            _ => None,
        }
    }
}

/// A random shape: kind 0 sphere (r in [0.2, 0.8) m), 1 capsule (half height and radius
/// in [0.1, 0.5) m), 2 box (half-extents in [0.2, 0.8) m), 3 one of the hulls (about
/// unit radius). Constructor errors fall back to a 0.5 m sphere, hashing `TAG_ERR`.
fn random_shape<'h>(rng: &mut SplitMix64, hulls: &'h NarrowHulls, hash: &mut Fnv1a64) -> Shape<'h> {
    let kind = (rng.next_u64() % 4) as u32;
    hash.write_u32(kind);
    let built = match kind {
        0 => Shape::sphere(rng.range(0.2, 0.8)),
        1 => {
            let half_height = rng.range(0.1, 0.5);
            Shape::capsule(half_height, rng.range(0.1, 0.5))
        }
        2 => {
            let x = rng.range(0.2, 0.8);
            let y = rng.range(0.2, 0.8);
            Shape::cuboid(Vec3::new(x, y, rng.range(0.2, 0.8)))
        }
        _ => {
            let index = (rng.next_u64() % HULLS as u64) as usize;
            hash.write_u32(index as u32);
            match hulls.get(index) {
                Some(h) => Ok(Shape::hull(h)),
                None => Shape::cuboid(Vec3::splat(0.5)),
            }
        }
    };
    match built {
        Ok(shape) => shape,
        Err(_) => {
            hash.write_u32(TAG_ERR);
            Shape::Sphere(Sphere { radius: 0.5 })
        }
    }
}

/// GJK status as a number for hashing.
fn gjk_status_code(s: GjkStatus) -> u32 {
    match s {
        GjkStatus::Separated => 1,
        GjkStatus::Overlapping => 2,
        GjkStatus::IterationLimit => 3,
    }
}

/// Hash a manifold: normal, point count, then each point's numbers and feature ids.
fn hash_manifold(m: &Manifold, hash: &mut Fnv1a64) {
    hash.write_u32(TAG_SOME);
    hash.write_vec3(m.normal);
    hash.write_u32(u32::from(m.len));
    for p in m.points() {
        hash.write_vec3(p.point_a);
        hash.write_vec3(p.point_b);
        hash.write_vec3(p.local_a);
        hash.write_vec3(p.local_b);
        hash.write_f32(p.separation);
        hash.write_u64(p.id.key());
    }
}

/// Run the workload: [`PAIRS`] seeded random pairs of spheres, capsules, boxes and hulls,
/// A anywhere in a 4 m cube (world frame) with a random rotation, B at a centre distance
/// in [0.5, 2.0) m from A in a random direction with its own random rotation (from deep
/// overlap to well apart). For each pair: [`distance`] from a cold cache, then [`contact`]
/// with the [`MARGIN`]. Keeps its four hulls on the stack (about 20 KB): [`run_in`] takes
/// them in the caller's storage.
pub fn run() -> NarrowResult {
    let mut hulls = NarrowHulls::EMPTY;
    run_in(&mut hulls)
}

/// [`run`] with its hulls built into `hulls` (whatever it held: each is built again).
pub fn run_in(hulls: &mut NarrowHulls) -> NarrowResult {
    let mut rng = SplitMix64::new(SEED);
    let mut hash = Fnv1a64::new();
    hulls.build(&mut rng);
    let hulls = &*hulls;
    for i in 0..HULLS {
        hash.write_u32(match hulls.get(i) {
            Some(h) => h.vertices().len() as u32,
            None => TAG_ERR,
        });
    }
    let mut count = 0;
    for _ in 0..PAIRS {
        let a = random_shape(&mut rng, hulls, &mut hash);
        let b = random_shape(&mut rng, hulls, &mut hash);
        let pos_a = Vec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
        );
        let pose_a = Iso::new(pos_a, rng.rotation());
        let offset = rng.unit_vector() * rng.range(0.5, 2.0);
        let pose_b = Iso::new(pos_a + offset, rng.rotation());
        hash.write_iso(&pose_a);
        hash.write_iso(&pose_b);

        let mut cache = SimplexCache::default();
        match distance(&a, &pose_a, &b, &pose_b, &mut cache) {
            Ok(d) => {
                hash.write_f32(d.distance);
                hash.write_vec3(d.point_a);
                hash.write_vec3(d.point_b);
                hash.write_vec3(d.normal);
                hash.write_u32(d.iterations);
                hash.write_u32(gjk_status_code(d.status));
            }
            Err(_) => hash.write_u32(TAG_ERR),
        }
        match contact(&a, &pose_a, &b, &pose_b, MARGIN) {
            Ok(Some(m)) => hash_manifold(&m, &mut hash),
            Ok(None) => hash.write_u32(TAG_NONE),
            Err(_) => hash.write_u32(TAG_ERR),
        }
        count += 1;
    }
    NarrowResult {
        count,
        hash: hash.finish(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn fnv1a64_matches_the_published_test_vectors() {
        // Reference values from the FNV test suite (Noll): "" and "a" and "foobar".
        assert_eq!(Fnv1a64::new().finish(), 0xcbf2_9ce4_8422_2325);
        let mut h = Fnv1a64::new();
        h.write_u8(b'a');
        assert_eq!(h.finish(), 0xaf63_dc4c_8601_ec8c);
        let mut h = Fnv1a64::new();
        for b in b"foobar" {
            h.write_u8(*b);
        }
        assert_eq!(h.finish(), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn multi_byte_values_are_fed_little_endian() {
        let mut by_word = Fnv1a64::new();
        by_word.write_u32(0x0403_0201);
        let mut by_byte = Fnv1a64::new();
        for b in [1u8, 2, 3, 4] {
            by_byte.write_u8(b);
        }
        assert_eq!(by_word, by_byte);
    }

    #[test]
    fn negative_zero_and_nan_payloads_hash_canonically() {
        let hash_of = |x: f32| {
            let mut h = Fnv1a64::new();
            h.write_f32(x);
            h.finish()
        };
        assert_eq!(hash_of(-0.0), hash_of(0.0));
        assert_eq!(hash_of(f32::from_bits(0x7fc0_0001)), hash_of(f32::NAN));
        assert_eq!(hash_of(f32::from_bits(0xffc0_0000)), hash_of(f32::NAN));
        assert_ne!(hash_of(f32::NAN), hash_of(0.0));
        assert_ne!(hash_of(1.0), hash_of(-1.0));
    }

    #[test]
    fn the_workload_runs_every_pair_and_repeats_bit_for_bit() {
        let first = run();
        assert_eq!(first.count, PAIRS);
        assert_eq!(first, run());
        let line = first.to_string();
        assert!(line.starts_with("narrow 256 0x"), "{line}");
        assert_eq!(line.len(), "narrow 256 0x".len() + 16, "{line}");
    }

    /// `run_in` gives `run`'s result whatever its storage held: other hulls marked built,
    /// then its own from the run before.
    #[test]
    fn run_in_reused_storage_matches_run() {
        let mut hulls = NarrowHulls::EMPTY;
        let mut rng = SplitMix64::new(7);
        for (hull, built) in hulls.hulls.iter_mut().zip(hulls.built.iter_mut()) {
            let cloud: [Vec3; 8] = core::array::from_fn(|_| rng.unit_vector() * 3.0);
            *built = hull.rebuild(&cloud).is_ok();
        }
        assert!(hulls.built.iter().all(|&b| b));
        let expected = run();
        assert_eq!(run_in(&mut hulls), expected);
        assert_eq!(run_in(&mut hulls), expected);
    }
}
