//! Stateless geometry: pure functions of (shape, pose) pairs.
//!
//! Every query takes world poses at the door, moves B into A's frame (`b_in_a`), works
//! there, and answers in the world frame. Nothing here knows about bodies or worlds.
//!
//! - [`distance`] (GJK): distance, closest points, separating normal.
//! - [`penetration`] (EPA): depth and normal of overlapping shapes.
//! - [`separation`]: both in one: the signed separation (distance apart, minus the depth
//!   overlapping), the normal and the witness points, whichever the case.
//! - [`contact`]: a contact manifold of up to 4 points with feature ids; [`contact_cached`]
//!   the same with a per-pair [`PairCache`] (box and hull pairs, and either against a
//!   triangle, by the separating axis test), [`contact_into`] the same into the caller's
//!   manifold, [`contact_gjk_epa`] the general GJK/EPA path for every pair.
//! - [`time_of_impact`]: when two moving shapes first touch.
//! - [`movement_bounds`]: the box a shape sweeps over a step.

pub(crate) mod analytic;
mod clip;
mod epa;
mod gjk;
mod gjk_f64;
mod manifold;
mod sat;
mod separation;
mod toi;

pub use analytic::segment_closest_points;
pub use epa::{penetration, EpaStatus, Penetration, MAX_EPA_FACES, MAX_EPA_VERTICES};
pub use gjk::{distance, intersects, DistanceOutput, GjkStatus, SimplexCache, MAX_GJK_ITERATIONS};
pub use manifold::{
    contact, contact_cached, contact_gjk_epa, contact_into, ContactId, Manifold, ManifoldPoint,
    MAX_MANIFOLD_POINTS,
};
pub use sat::{PairCache, SatAxis, EDGE_DEPTH_PREFERENCE, SAT_TOLERANCE};
pub use separation::{separation, Separation, SeparationStatus};
pub use toi::{
    movement_bounds, time_of_impact, Motion, Toi, MAX_TOI_ITERATIONS, TOI_SEARCH_SAMPLES,
};

pub(crate) use gjk::distance_in_a;
pub(crate) use manifold::{contact_cached_unchecked, sphere_pair};
pub(crate) use toi::time_of_impact_unchecked;

use crate::error::{Error, Input};
use crate::math::{Iso, Mat3, Quat, Vec3};
use crate::shape::Shape;

/// Check a pose given at a public door: a finite position within
/// ±[`crate::error::MAX_COORDINATE`], a finite unit rotation. A pose that passes (nearly
/// all) is told apart in one branch ([`pose_passes`]).
#[inline]
pub(crate) fn check_pose(pose: &Iso) -> Result<(), Error> {
    if pose_passes(pose) {
        return Ok(());
    }
    first_pose_error(pose)
}

/// [`check_pose`] one check at a time: the first failure's error.
#[cold]
fn first_pose_error(pose: &Iso) -> Result<(), Error> {
    crate::error::position(pose.position)?;
    if !pose.rotation.is_finite() {
        return Err(Error::NonFinite(Input::Rotation));
    }
    if !pose.rotation.is_unit() {
        return Err(Error::NotUnit(Input::Rotation));
    }
    Ok(())
}

/// `check_pose(pose).is_ok()` in four compares without a branch, for the doors' common
/// case: each compare is false for NaN and the infinities, so the finiteness checks are
/// implied (a rotation whose `|q|²` lies within the unit tolerance of 1 has finite
/// components). The first failing check, with its error, is [`first_pose_error`]'s.
#[inline]
pub(crate) fn pose_passes(pose: &Iso) -> bool {
    let p = pose.position;
    let within = |x: f32| crate::math::scalar::abs(x) <= crate::error::MAX_COORDINATE;
    let l2 = pose.rotation.length_squared();
    let unit = crate::math::scalar::abs(l2 - 1.0) <= crate::math::UNIT_TOLERANCE;
    within(p.x) & within(p.y) & within(p.z) & unit
}

/// B's pose in A's frame, with its rotation as a matrix: what a query in A's frame needs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Placement {
    /// The pose.
    pub iso: Iso,
    /// `iso`'s rotation as a matrix.
    pub rotation: Mat3,
}

impl Placement {
    /// `b_in_a` as it is, its matrix computed in f32 (the step's narrow phase).
    #[inline]
    pub fn new(b_in_a: &Iso) -> Placement {
        Placement {
            iso: *b_in_a,
            rotation: sat::rotation_matrix(b_in_a.rotation),
        }
    }

    /// `pose_a⁻¹ ∘ pose_b` for the public distance doors, composed in f64 and rounded
    /// once to f32.
    ///
    /// Why: in f32, the rotation matrix of a quaternion carries about two ulps in every
    /// entry and `Rᵀ (p_b − p_a)` a few ulps of `|p_b − p_a|`, so B's vertices land up to
    /// 1.2e-6 m off in A's frame for shapes 1.5 m apart (measured over 20 000 random
    /// poses): more than the touching gaps [`distance`] must resolve (1e-6 m, see
    /// `tests/touching.rs`). In f64 the relative rotation `qa* qb`, its matrix and the
    /// translation `R_aᵀ (p_b − p_a)` are exact to f64 rounding, and rounding them to f32
    /// leaves half an ulp per entry. About 100 f64 operations per query. Only `+ − × ÷`
    /// (IEEE, the same bits on every target); the rotations need not be unit: the matrix
    /// of `q` is built with `s = 2 / |q|²`, which is a rotation for any `q ≠ 0`.
    pub fn between(pose_a: &Iso, pose_b: &Iso) -> Placement {
        let ra = matrix_f64(quat_f64(pose_a.rotation));
        let d = [
            f64::from(pose_b.position.x) - f64::from(pose_a.position.x),
            f64::from(pose_b.position.y) - f64::from(pose_a.position.y),
            f64::from(pose_b.position.z) - f64::from(pose_a.position.z),
        ];
        let t = transpose_mul_f64(&ra, d);
        // The relative rotation `qa* qb` (products of f32s are exact in f64).
        let [ax, ay, az, aw] = quat_f64(pose_a.rotation);
        let [bx, by, bz, bw] = quat_f64(pose_b.rotation);
        let (ax, ay, az) = (-ax, -ay, -az);
        let q = [
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz,
        ];
        let [c0, c1, c2] = matrix_f64(q).map(to_f32);
        let relative = Quat::from_xyzw(q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32);
        Placement {
            iso: Iso::new(to_f32(t), relative.normalize()),
            rotation: Mat3::from_cols(c0, c1, c2),
        }
    }
}

/// `q`'s components `(x, y, z, w)` in f64.
fn quat_f64(q: Quat) -> [f64; 4] {
    [
        f64::from(q.x),
        f64::from(q.y),
        f64::from(q.z),
        f64::from(q.w),
    ]
}

/// The rotation matrix of `q = (x, y, z, w)` (any `q ≠ 0`) in f64, as three columns.
fn matrix_f64([x, y, z, w]: [f64; 4]) -> [[f64; 3]; 3] {
    let n = x * x + y * y + z * z + w * w;
    let s = if n > 0.0 { 2.0 / n } else { 0.0 };
    [
        [
            1.0 - s * (y * y + z * z),
            s * (x * y + w * z),
            s * (x * z - w * y),
        ],
        [
            s * (x * y - w * z),
            1.0 - s * (x * x + z * z),
            s * (y * z + w * x),
        ],
        [
            s * (x * z + w * y),
            s * (y * z - w * x),
            1.0 - s * (x * x + y * y),
        ],
    ]
}

/// `Mᵀ v` for the columns `m`.
fn transpose_mul_f64(m: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    m.map(|c| c[0] * v[0] + c[1] * v[1] + c[2] * v[2])
}

fn to_f32(v: [f64; 3]) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}

/// A shape placed in the query frame (A's frame): what GJK and EPA see. The pose's
/// rotation is kept as a matrix too (support points move through it twice per GJK step),
/// and a shape at the query frame's origin (A itself) skips the transforms altogether.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Proxy<'s, 'a> {
    /// The shape.
    pub shape: &'s Shape<'a>,
    /// Its pose in the query frame.
    pub pose: Iso,
    /// `pose`'s rotation as a matrix.
    rotation: crate::math::Mat3,
    /// True for the identity pose: points and directions are used as they are.
    identity: bool,
}

/// [`Shape::core_support`] with a hull's scan inlined here: GJK and EPA take a support
/// point per iteration, and the whole shape match is too large to inline.
#[inline(always)]
fn core_support(shape: &Shape<'_>, dir: Vec3) -> (Vec3, u32) {
    match shape {
        Shape::Hull(h) => h.core_support(dir),
        _ => shape.core_support(dir),
    }
}

impl<'s, 'a> Proxy<'s, 'a> {
    /// `shape` at `pose` (query frame).
    #[inline]
    pub fn new(shape: &'s Shape<'a>, pose: Iso) -> Proxy<'s, 'a> {
        Proxy {
            shape,
            pose,
            rotation: sat::rotation_matrix(pose.rotation),
            identity: false,
        }
    }

    /// `shape` at `placement` (query frame), with the placement's matrix.
    #[inline]
    pub fn placed(shape: &'s Shape<'a>, placement: &Placement) -> Proxy<'s, 'a> {
        Proxy {
            shape,
            pose: placement.iso,
            rotation: placement.rotation,
            identity: false,
        }
    }

    /// `shape` at the query frame's origin (A in its own frame).
    #[inline]
    pub fn at_origin(shape: &'s Shape<'a>) -> Proxy<'s, 'a> {
        Proxy {
            shape,
            pose: Iso::IDENTITY,
            rotation: crate::math::Mat3::IDENTITY,
            identity: true,
        }
    }

    /// Core support point along `dir` (query frame) and its vertex index.
    #[inline(always)]
    pub fn support(&self, dir: crate::math::Vec3) -> (crate::math::Vec3, u32) {
        if self.identity {
            return core_support(self.shape, dir);
        }
        let (p, i) = core_support(self.shape, self.rotation.transpose_mul_vec(dir));
        (self.rotation.mul_vec(p) + self.pose.position, i)
    }

    /// Core vertex `i` in the query frame.
    #[inline]
    pub fn vertex(&self, i: u32) -> crate::math::Vec3 {
        let p = self.shape.core_vertex(i);
        if self.identity {
            p
        } else {
            self.rotation.mul_vec(p) + self.pose.position
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::MAX_COORDINATE;

    /// `pose_passes` is `first_pose_error(..).is_ok()` (the checks one by one): over positions and rotations built from
    /// special values (NaN, the infinities, zeros, the coordinate bound and its
    /// neighbours, huge and tiny numbers) and random ones, including rotations just
    /// inside and outside the unit tolerance.
    #[test]
    fn pose_passes_exactly_when_check_pose_does() {
        let specials = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            MAX_COORDINATE,
            -MAX_COORDINATE,
            f32::from_bits(MAX_COORDINATE.to_bits() + 1),
            f32::from_bits(MAX_COORDINATE.to_bits() - 1),
            1.0e20,
            -3.0e38,
            f32::MIN_POSITIVE,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ];
        let mut rng = crate::rng::SplitMix64::new(5);
        let (mut passed, mut failed) = (0, 0);
        for i in 0..20_000u32 {
            let pick = |rng: &mut crate::rng::SplitMix64| {
                let k = (rng.next_u64() % 20) as usize;
                specials
                    .get(k)
                    .copied()
                    .unwrap_or_else(|| rng.range(-2.0e4, 2.0e4))
            };
            let position = Vec3::new(pick(&mut rng), pick(&mut rng), pick(&mut rng));
            let rotation = match i % 4 {
                // Unit, scaled to |q|² near the tolerance's edges, or from special values.
                0 => rng.rotation(),
                1 => {
                    let q = rng.rotation();
                    let s = crate::math::scalar::sqrt(1.0 + rng.range(-2.0e-3, 2.0e-3));
                    Quat::from_xyzw(q.x * s, q.y * s, q.z * s, q.w * s)
                }
                _ => Quat::from_xyzw(
                    pick(&mut rng),
                    pick(&mut rng),
                    pick(&mut rng),
                    pick(&mut rng),
                ),
            };
            let pose = Iso::new(position, rotation);
            let fast = pose_passes(&pose);
            assert_eq!(fast, first_pose_error(&pose).is_ok(), "{pose:?}");
            if fast {
                passed += 1;
            } else {
                failed += 1;
            }
        }
        assert!(passed > 1_000 && failed > 1_000, "{passed} {failed}");
    }
}
