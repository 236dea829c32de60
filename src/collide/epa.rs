//! EPA: penetration depth and normal of two overlapping convex shapes, on a fixed-size
//! polytope.
//!
//! Like GJK ([`super::gjk`]) it works in A's frame on the cores' Minkowski difference
//! `D = B − A`. When the cores are apart but closer than `ra + rb`, GJK's answer is exact:
//! `depth = ra + rb − core distance` along GJK's normal. When the cores overlap, the
//! Expanding Polytope Algorithm (van den Bergen 2001, "Proximity queries and penetration
//! depth computation on 3D game objects") grows a polytope inside `D` around the origin
//! until its face closest to the origin lies on the boundary of `D`: that face's outward
//! normal `m` and distance `d` give the smallest translation `−d m` of B (in `D`, a
//! translation `t` of B moves the origin to `−t`) that separates the cores. The normal
//! from A towards B is therefore `−m`; the radii are added to the depth at the end.
//!
//! Departures from the textbook:
//! - Fixed arrays of [`MAX_EPA_VERTICES`] vertices and [`MAX_EPA_FACES`] faces, no heap.
//! - The visible region is found by a flood fill from the closest face over faces sharing
//!   an edge (so it is connected), and the horizon is the bounded list of its boundary
//!   edges. A new face whose vertices are collinear (no usable normal) is refused; the
//!   expansion is then redone with the faces the new point lies on (within the
//!   tolerance) counted as visible, which removes the collinear vertex instead; likewise
//!   when a new face would lie on a kept neighbour's plane turned the other way (an
//!   inside-out fold). The polytope is changed only after every new face proved valid
//!   and fit.
//! - Face normals are computed at the corner opposite the longest edge
//!   ([`gjk::triangle_normal`]), so sliver faces of `D` keep an accurate plane.
//! - The seed is GJK's final simplex, blown up to a tetrahedron with support points. When
//!   `D` is flat through the origin (crossing segments, a point on a triangle) the core
//!   depth is exactly 0 along the flat normal: that is returned at once.
//! - A support point that is already a vertex but lies beyond the closest face by more
//!   than the tolerance means the face's plane is off by rounding (a thin triangle). The
//!   face is the answer only when the smallest upper bound seen (EPA's faces and SAT) is
//!   within the tolerance of its distance; otherwise it is set aside and the next closest
//!   face is expanded. (The textbook stops at once and reports that face.)
//! - Every exit short of convergence ([`EpaStatus::PolytopeFull`],
//!   [`EpaStatus::IterationLimit`], [`EpaStatus::Degenerate`]) answers with the smallest
//!   *upper bound* `h_D(m) = max_{x∈D} m·x` seen, over EPA's faces and over the face
//!   normals of both shapes (SAT): moving B by that depth along the normal always
//!   separates the shapes. The points are then the two supports along the normal.

use super::gjk::{self, GjkStatus, Simplex, SimplexCache, SimplexVertex, MAX_GJK_ITERATIONS};
use super::{check_pose, Placement, Proxy};
use crate::error::Error;
use crate::math::{scalar, Iso, Vec3};
use crate::shape::Shape;

/// Most vertices of the EPA polytope.
pub const MAX_EPA_VERTICES: usize = 64;
/// Most faces of the EPA polytope.
pub const MAX_EPA_FACES: usize = 2 * MAX_EPA_VERTICES;

/// Iteration cap of the EPA loop: each iteration adds one vertex, so this also bounds the
/// polytope to `4 + MAX_EPA_ITERATIONS` vertices. Box and hull pairs converge in well
/// under 20.
pub(crate) const MAX_EPA_ITERATIONS: u32 = 48;

/// EPA stops when the support along the closest face's normal is within
/// `EPA_RELATIVE_TOLERANCE · scale` of that face (`scale`: the largest extent of `D`
/// along the six axes). Rounding in a face plane built from points of size `scale` is a
/// few ulps of it (about 1e-7 relative); 1e-5 leaves two orders of magnitude.
pub(crate) const EPA_RELATIVE_TOLERANCE: f32 = 1.0e-5;

/// A triangle whose doubled area `|(b − a) × (c − a)|` is at most this fraction of its
/// longest edge squared (its height over that edge below 1e-5 of the edge) has no usable
/// normal: for three collinear points the cross product is pure rounding, a few ulps of
/// the edge lengths squared (about 1e-7 relative), and points in any direction. 1e-5
/// leaves two orders of magnitude above that noise.
const EPA_FLAT_FACE: f32 = 1.0e-5;

/// How far (in units of EPA's tolerance) the converged face's closest point may lie from
/// `depth · normal` for its barycentric witnesses to be called converged.
const WITNESS_MISS: f32 = 10.0;

/// Faces whose unit normals differ by less than this in `1 − cos` (about 0.5°) count
/// as coplanar when the converged face's witnesses are looked up.
const EPA_COPLANAR_COS: f32 = 1.0e-4;

/// Most boundary edges of one visible region: one per face is more than a region of
/// faces can have (`horizon <= faces + 2`, and a region never holds every face).
const MAX_HORIZON_EDGES: usize = MAX_EPA_FACES;

/// How EPA ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EpaStatus {
    /// Converged to the tolerance.
    Converged,
    /// The polytope filled up; the answer is the best found so far.
    PolytopeFull,
    /// The iteration cap was hit; the answer is the best found so far.
    IterationLimit,
    /// The Minkowski difference was too thin to expand, or too flat at the converged face
    /// for its witness points, or the closest face stalled with its depth certified by an
    /// upper bound while the support along its own normal lies far beyond that depth (a
    /// sliver, not a true face); a fallback (depth and normal bound the overlap, the
    /// points are the supports along the normal) was given.
    Degenerate,
}

/// How far two shapes overlap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Penetration {
    /// Penetration depth (m), `>= 0`: moving B by `depth · normal` separates them.
    pub depth: f32,
    /// Unit normal from A towards B (world frame).
    pub normal: Vec3,
    /// Deepest point of B inside A, on A's surface (world frame).
    pub point_a: Vec3,
    /// Deepest point of A inside B, on B's surface (world frame).
    pub point_b: Vec3,
    /// How EPA ended.
    pub status: EpaStatus,
    /// EPA iterations used (0 when GJK or a closed form answered).
    pub iterations: u32,
}

/// Penetration of `a` at `pose_a` and `b` at `pose_b` (world frame), or `None` when they
/// do not overlap (distance `> 0`; touching shapes give depth 0). Two half-spaces have no
/// finite depth: `None`. Fails only on an invalid pose.
///
/// `point_b − point_a = −depth · normal` when EPA converged or a closed form answered.
///
/// # Examples
///
/// ```
/// use carom::collide::penetration;
/// use carom::{Iso, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// let a = Shape::cuboid(Vec3::splat(0.5))?;
/// let b = Shape::cuboid(Vec3::splat(0.5))?;
/// let pose_b = Iso::from_position(Vec3::new(0.8, 0.0, 0.0)); // 0.2 m into a along x
/// let p = penetration(&a, &Iso::IDENTITY, &b, &pose_b)?.expect("overlapping");
/// assert!((p.depth - 0.2).abs() < 1e-5);
/// assert!((p.normal - Vec3::X).length() < 1e-5);
/// assert!(penetration(&a, &Iso::IDENTITY, &b, &Iso::from_position(Vec3::new(2.0, 0.0, 0.0)))?.is_none());
/// # Ok(())
/// # }
/// ```
pub fn penetration(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
) -> Result<Option<Penetration>, Error> {
    check_pose(pose_a)?;
    check_pose(pose_b)?;
    a.check_convex()?;
    b.check_convex()?;
    let placement = Placement::between(pose_a, pose_b);
    Ok(
        penetration_placed(a, b, &placement, EpaCaps::DEFAULT).map(|p| {
            let world = Penetration {
                normal: pose_a.transform_vector(p.normal),
                point_a: pose_a.transform_point(p.point_a),
                point_b: pose_a.transform_point(p.point_b),
                ..p
            };
            // Only coordinates near f32::MAX can overflow here.
            sanitized(world, pose_a.position, pose_b.position)
        }),
    )
}

/// The bounds of one EPA run.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct EpaCaps {
    /// Most polytope vertices, clamped to `4..=MAX_EPA_VERTICES`.
    pub vertices: usize,
    /// Most iterations.
    pub iterations: u32,
}

impl EpaCaps {
    /// The engine's bounds.
    pub const DEFAULT: EpaCaps = EpaCaps {
        vertices: MAX_EPA_VERTICES,
        iterations: MAX_EPA_ITERATIONS,
    };
}

/// [`penetration`] in A's frame, B's matrix in f32 (unit tests).
#[cfg(test)]
pub(crate) fn penetration_in_a(a: &Shape, b: &Shape, b_in_a: &Iso) -> Option<Penetration> {
    penetration_in_a_capped(a, b, b_in_a, EpaCaps::DEFAULT)
}

/// [`penetration_in_a`] with explicit bounds (tests force the bounded exits with it).
#[cfg(test)]
pub(crate) fn penetration_in_a_capped(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    caps: EpaCaps,
) -> Option<Penetration> {
    penetration_placed(a, b, &Placement::new(b_in_a), caps)
}

/// [`penetration`] in A's frame, with B's placement (pose and matrix) given and explicit
/// bounds.
pub(crate) fn penetration_placed(
    a: &Shape,
    b: &Shape,
    placement: &Placement,
    caps: EpaCaps,
) -> Option<Penetration> {
    let b_in_a = &placement.iso;
    let pa = Proxy::at_origin(a);
    let pb = Proxy::placed(b, placement);
    let (ra, rb) = (a.radius(), b.radius());
    let p = match (a, b) {
        (Shape::HalfSpace(_), Shape::HalfSpace(_)) => return None,
        (Shape::HalfSpace(h), _) => half_space_vs_core(h.normal, &pb, rb)?,
        (_, Shape::HalfSpace(h)) => {
            core_vs_half_space(&pa, ra, b_in_a.transform_vector(h.normal), b_in_a.position)?
        }
        _ => {
            let mut cache = SimplexCache::default();
            let core = gjk::gjk_cores(&pa, &pb, &mut cache, MAX_GJK_ITERATIONS);
            return penetration_from_gjk(&pa, &pb, &core, caps);
        }
    };
    Some(sanitized(p, Vec3::ZERO, b_in_a.position))
}

/// The penetration of two cores (neither a half-space; `pa` at the identity, `pb` at B's
/// pose in A's frame) from the answer of GJK on them (`core`, run from any cache): when
/// the cores overlap, EPA seeded with GJK's final simplex, so a caller that already ran
/// GJK does not run it again; when they are apart, GJK's distance against the radii.
/// `None` when the full shapes do not overlap. The same answer as `penetration_in_a`
/// when `core` came from a fresh cache.
pub(crate) fn penetration_from_gjk(
    pa: &Proxy,
    pb: &Proxy,
    core: &gjk::CoreDistance,
    caps: EpaCaps,
) -> Option<Penetration> {
    let (ra, rb) = (pa.shape.radius(), pb.shape.radius());
    // Whether the shapes overlap is decided by the f32 search, as `distance` decides it.
    let f32_gap = gjk::radius_gap(core.distance, ra, rb);
    // Cores apart by little on a long simplex: the witnesses and the normal are the
    // answer here, so the search is finished in f64 (`gjk::refined_near`).
    let refined = if f32_gap <= 0.0 {
        gjk::refined_near(pa, pb, core)
    } else {
        None
    };
    let core = refined.as_ref().unwrap_or(core);
    let gap = gjk::radius_gap(core.distance, ra, rb);
    // Cores apart by less than the rounding of a vertex's or an edge's direction (see
    // `gjk::GJK_DIRECTION_TOLERANCE`) but overlapping through the radii: GJK's normal is
    // noise, so EPA on the touching cores gives it (a normal of a face of `D`), at a depth
    // at most that tolerance deeper than the exact one.
    let touching_cores = core.ambiguous && gap <= 0.0;
    let p = if core.status == GjkStatus::Overlapping || touching_cores {
        let c = epa_cores(pa, pb, &core.simplex, caps);
        inflated(c, ra, rb)
    } else {
        // Cores apart: GJK's answer is exact (an upper bound on the core distance,
        // so a lower bound on the depth, when GJK hit its cap). Shapes that touch in
        // f32 but part by a rounding in f64 touch, at depth 0.
        if f32_gap > 0.0 {
            return None;
        }
        let n = core.normal;
        Penetration {
            depth: scalar::max(-gap, 0.0),
            normal: n,
            point_a: core.point_a + n * ra,
            point_b: core.point_b - n * rb,
            status: if core.status == GjkStatus::IterationLimit {
                EpaStatus::IterationLimit
            } else {
                EpaStatus::Converged
            },
            iterations: 0,
        }
    };
    Some(sanitized(p, Vec3::ZERO, pb.pose.position))
}

/// The normal (A's frame, from A towards B) that EPA finds for cores GJK left apart by
/// less than the rounding of its direction ([`gjk::CoreDistance::ambiguous`]): EPA run on
/// them as touching cores, seeded with GJK's simplex. A normal of a face of `D` next to
/// the closest vertex or edge, a direction that separates the cores as well as GJK's
/// within that rounding.
pub(crate) fn touching_normal(
    pa: &Proxy,
    pb: &Proxy,
    core: &gjk::CoreDistance,
    caps: EpaCaps,
) -> Vec3 {
    epa_cores(pa, pb, &core.simplex, caps).normal
}

/// The full-shape answer from the cores' answer: depth plus both radii, points moved out
/// along the normal by their radius.
fn inflated(c: CorePenetration, ra: f32, rb: f32) -> Penetration {
    Penetration {
        depth: c.depth + ra + rb,
        normal: c.normal,
        point_a: c.point_a + c.normal * ra,
        point_b: c.point_b - c.normal * rb,
        status: c.status,
        iterations: c.iterations,
    }
}

/// Guarantee the contract whatever f32 did: finite depth `>= 0`, unit normal, finite
/// points (else `origin_a`, `origin_b`, or zero). Only overflowing inputs ever need it;
/// they are flagged [`EpaStatus::Degenerate`].
fn sanitized(p: Penetration, origin_a: Vec3, origin_b: Vec3) -> Penetration {
    let mut out = p;
    if !(p.depth >= 0.0 && p.depth.is_finite()) {
        out.depth = if p.depth > 0.0 { f32::MAX } else { 0.0 };
        out.status = EpaStatus::Degenerate;
    }
    out.normal = p.normal.normalize_or(Vec3::Y);
    if !(p.point_a.is_finite() && p.point_b.is_finite()) {
        let or_zero = |q: Vec3| if q.is_finite() { q } else { Vec3::ZERO };
        out.point_a = or_zero(origin_a);
        out.point_b = or_zero(origin_b);
        out.status = EpaStatus::Degenerate;
    }
    out
}

// ---------------------------------------------------------------------------------------
// Half-spaces: closed forms.
// ---------------------------------------------------------------------------------------

/// A is the half-space `{p : n·p <= 0}`. B's deepest core point `p` along `−n` sits at
/// height `s = n·p`; the depth is `rb − s` (`None` when negative), the normal `n`.
fn half_space_vs_core(n: Vec3, pb: &Proxy, rb: f32) -> Option<Penetration> {
    let (p, _) = pb.support(-n);
    let s = n.dot(p);
    let gap = gjk::radius_gap(s, 0.0, rb);
    if gap > 0.0 {
        return None;
    }
    let point_b = p - n * rb;
    Some(Penetration {
        depth: -gap,
        normal: n,
        point_a: point_b - n * n.dot(point_b),
        point_b,
        status: EpaStatus::Converged,
        iterations: 0,
    })
}

/// B is the half-space `{p : n·(p − c) <= 0}` (A's frame). A's deepest core point along
/// `−n` at height `s = n·(p − c)`; depth `ra − s`, normal from A towards B `−n`.
fn core_vs_half_space(pa: &Proxy, ra: f32, n: Vec3, c: Vec3) -> Option<Penetration> {
    let (p, _) = pa.support(-n);
    let s = n.dot(p - c);
    let gap = gjk::radius_gap(s, ra, 0.0);
    if gap > 0.0 {
        return None;
    }
    let point_a = p - n * ra;
    Some(Penetration {
        depth: -gap,
        normal: -n,
        point_a,
        point_b: point_a - n * n.dot(point_a - c),
        status: EpaStatus::Converged,
        iterations: 0,
    })
}

// ---------------------------------------------------------------------------------------
// EPA on the cores.
// ---------------------------------------------------------------------------------------

/// The cores' answer, before the radii (query frame).
#[derive(Clone, Copy, Debug)]
struct CorePenetration {
    /// Core depth (m), `>= 0`.
    depth: f32,
    /// Unit normal from A towards B.
    normal: Vec3,
    /// Point on A's core.
    point_a: Vec3,
    /// Point on B's core.
    point_b: Vec3,
    status: EpaStatus,
    iterations: u32,
}

/// A triangle of the polytope: vertex indices counter-clockwise seen from outside, its
/// outward unit normal `m` and the signed distance `d = m·w₀` of its plane from the
/// origin (positive while the origin is inside).
#[derive(Clone, Copy, Debug, Default)]
struct EpaFace {
    v: [u8; 3],
    normal: Vec3,
    distance: f32,
    /// Set aside: its support point was already a vertex but its plane, tilted by
    /// rounding, could not be certified (see [`stall_is_certified`]). No longer a
    /// candidate for the closest face.
    stalled: bool,
}

impl EpaFace {
    /// The three directed edges `(v₀ v₁), (v₁ v₂), (v₂ v₀)`.
    fn edges(&self) -> [(u8, u8); 3] {
        let [a, b, c] = self.v;
        [(a, b), (b, c), (c, a)]
    }
}

/// Why an expansion was refused (the polytope is left unchanged).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Refused {
    /// Not enough room for the new vertex, faces or horizon.
    Full,
    /// A new face would have no usable normal.
    Degenerate,
}

/// The polytope: fixed-capacity lists (`heapless::Vec`: the storage is not initialised up
/// front, so a polytope costs nothing to make; it lives on [`epa_cores`]'s stack, about
/// 6 KiB, and is built there in place).
struct Polytope {
    vertices: heapless::Vec<SimplexVertex, MAX_EPA_VERTICES>,
    faces: heapless::Vec<EpaFace, MAX_EPA_FACES>,
}

impl Polytope {
    /// An empty polytope.
    const fn new() -> Polytope {
        Polytope {
            vertices: heapless::Vec::new(),
            faces: heapless::Vec::new(),
        }
    }

    fn vertex(&self, i: u8) -> SimplexVertex {
        self.vertices.get(i as usize).copied().unwrap_or_default()
    }

    fn used_faces(&self) -> &[EpaFace] {
        &self.faces
    }

    fn contains(&self, v: &SimplexVertex) -> bool {
        self.vertices.iter().any(|u| u.same_as(v))
    }

    /// The face on vertices `i j k` (in that order), or `None` when it has no normal: its
    /// vertices are collinear or coincident within [`EPA_FLAT_FACE`].
    fn make_face(&self, i: u8, j: u8, k: u8) -> Option<EpaFace> {
        let (a, b, c) = (self.vertex(i).w, self.vertex(j).w, self.vertex(k).w);
        let longest2 = scalar::max(
            (b - a).length_squared(),
            scalar::max((c - b).length_squared(), (a - c).length_squared()),
        );
        let (normal, area2) = gjk::triangle_normal(a, b, c).normalize_and_length()?;
        // False for a NaN too: such a face counts as flat.
        let sound = area2 > EPA_FLAT_FACE * longest2;
        sound.then_some(EpaFace {
            v: [i, j, k],
            normal,
            distance: normal.dot(a),
            stalled: false,
        })
    }

    /// True when the new face `fresh` is turned back onto the kept face `kept` across their
    /// shared edge: normals within [`EPA_COPLANAR_COS`] of opposite, and `kept`'s third
    /// vertex not behind `fresh` by more than `tol` (m). The polytope would fold inside out
    /// there: `w` lay on `kept`'s plane and the sign of rounding kept the face. A thin
    /// but convex wedge of `D` (two crossing triangles 0.01 rad apart) also has nearly
    /// opposite normals on its sharp edge, but there each face's third vertex lies
    /// clearly behind the other.
    fn folds_onto(&self, fresh: &EpaFace, kept: &EpaFace, tol: f32) -> bool {
        let opposite = fresh.normal.dot(kept.normal) < -1.0 + EPA_COPLANAR_COS;
        let [i, ..] = fresh.v;
        let third = kept.v.into_iter().find(|k| !fresh.v.contains(k));
        let behind =
            third.is_some_and(|k| fresh.normal.dot(self.vertex(k).w - self.vertex(i).w) < -tol);
        opposite && !behind
    }

    /// Index of the face closest to the origin (lowest index on ties), stalled faces
    /// aside; `None` when every face has stalled.
    fn closest_face(&self) -> Option<usize> {
        let mut best: Option<(usize, f32)> = None;
        for (i, f) in self.used_faces().iter().enumerate() {
            if !f.stalled && best.is_none_or(|(_, d)| f.distance < d) {
                best = Some((i, f.distance));
            }
        }
        best.map(|(i, _)| i)
    }

    /// The face holding the directed edge `from → to`.
    fn face_with_edge(&self, from: u8, to: u8) -> Option<usize> {
        self.used_faces()
            .iter()
            .position(|f| f.edges().contains(&(from, to)))
    }

    /// Add `w`, seen from outside face `start`: remove the connected region of faces that
    /// `w` is in front of or within `coplanar` (m) of the plane of, and fan new faces from
    /// its boundary (the horizon) to `w`.
    ///
    /// With `coplanar = 0` a `w` on the plane of a neighbour face (several vertices of `D`
    /// on one face of `D`, common for boxes) keeps that face or not on the sign of
    /// rounding noise. When it is kept, the new face on the shared edge is coplanar with
    /// it and, if `w` and the edge are collinear (a vertex of the polytope on an edge of
    /// `D`, as GJK's seed often is), has no normal: [`Refused::Degenerate`], and the
    /// caller retries with `coplanar > 0` so the neighbour goes too. The same happens when
    /// a kept neighbour is in the plane of `w` and a new face on its edge lies in that
    /// plane turned the other way (an inside-out fold: two concentric boxes tilted by
    /// 1 mrad put several corners of `D` on one face plane). Removing a face that `w` is
    /// behind by at most `coplanar` dents the polytope by at most that much. `tol` (m) is
    /// EPA's tolerance, for the fold test ([`Polytope::folds_onto`]).
    fn expand(
        &mut self,
        start: usize,
        w: SimplexVertex,
        coplanar: f32,
        tol: f32,
    ) -> Result<(), Refused> {
        let new_index = self.vertices.len();
        if new_index >= MAX_EPA_VERTICES {
            return Err(Refused::Full);
        }
        // Flood fill of the visible region; every face is pushed at most once.
        let mut removed = [false; MAX_EPA_FACES];
        // Face indices are below MAX_EPA_FACES = 128: a byte each.
        let mut stack = [0u8; MAX_EPA_FACES];
        let mut top = 0;
        // Boundary edges `(i, j)` of the removed region, with the kept face across each.
        let mut horizon: heapless::Vec<(u8, u8, Option<usize>), MAX_HORIZON_EDGES> =
            heapless::Vec::new();
        if let (Some(r), Some(s), Ok(id)) = (
            removed.get_mut(start),
            stack.get_mut(0),
            u8::try_from(start),
        ) {
            *r = true;
            *s = id;
            top = 1;
        }
        for _ in 0..MAX_EPA_FACES {
            if top == 0 {
                break;
            }
            top -= 1;
            let f = stack.get(top).map_or(start, |&f| usize::from(f));
            let face = self.faces.get(f).copied().unwrap_or_default();
            for (i, j) in face.edges() {
                let neighbour = self.face_with_edge(j, i);
                let visible_neighbour = neighbour.and_then(|g| {
                    let nf = self.faces.get(g)?;
                    let seen = nf.normal.dot(w.w - self.vertex(nf.v[0]).w) > -coplanar;
                    seen.then_some(g)
                });
                match visible_neighbour {
                    Some(g) if removed.get(g).copied().unwrap_or(true) => {}
                    Some(g) => {
                        if let (Some(r), Some(s), Ok(id)) =
                            (removed.get_mut(g), stack.get_mut(top), u8::try_from(g))
                        {
                            *r = true;
                            *s = id;
                            top += 1;
                        } else {
                            return Err(Refused::Full);
                        }
                    }
                    None => horizon.push((i, j, neighbour)).map_err(|_| Refused::Full)?,
                }
            }
        }
        let removed_count = removed.iter().filter(|r| **r).count();
        if self.faces.len().saturating_sub(removed_count) + horizon.len() > MAX_EPA_FACES {
            return Err(Refused::Full);
        }
        // Build the new faces first (with `w` in place as vertex `new_index`); commit only
        // if all of them are sound, else take `w` back out.
        self.vertices.push(w).map_err(|_| Refused::Full)?;
        let k = new_index as u8;
        let mut fresh: heapless::Vec<EpaFace, MAX_HORIZON_EDGES> = heapless::Vec::new();
        for &(i, j, kept) in &horizon {
            let face = self.make_face(i, j, k);
            let folded = face.is_some_and(|face| {
                kept.and_then(|g| self.faces.get(g))
                    .is_some_and(|g| self.folds_onto(&face, g, tol))
            });
            match face {
                Some(face) if !folded => {
                    // Cannot be full: one new face per horizon edge.
                    let _ = fresh.push(face);
                }
                _ => {
                    self.vertices.truncate(new_index);
                    return Err(Refused::Degenerate);
                }
            }
        }
        let mut kept = 0;
        for f in 0..self.faces.len() {
            if !removed.get(f).copied().unwrap_or(true) {
                if let Some(face) = self.faces.get(f).copied() {
                    if let Some(dst) = self.faces.get_mut(kept) {
                        *dst = face;
                    }
                    kept += 1;
                }
            }
        }
        self.faces.truncate(kept);
        for face in &fresh {
            // Room was checked above: kept + horizon <= MAX_EPA_FACES.
            let _ = self.faces.push(*face);
        }
        Ok(())
    }
}

/// How the seed came out.
enum Seed {
    /// A tetrahedron with positive volume, around (or touching) the origin.
    Tetrahedron([SimplexVertex; 4]),
    /// `D` is flat through the origin, with this unit normal: the core depth is 0.
    Flat(Vec3),
}

/// The support points of `D` along ±X, ±Y, ±Z and the largest extent among them.
fn axis_supports(pa: &Proxy, pb: &Proxy) -> ([SimplexVertex; 6], f32) {
    let dirs = [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let s = dirs.map(|d| gjk::support(pa, pb, d));
    let mut scale2 = 0.0;
    for v in &s {
        scale2 = scalar::max(scale2, v.w.length_squared());
    }
    (s, scalar::sqrt(scale2))
}

/// The candidate of `cands` farthest from `measure` (first on ties), if farther than
/// `tol`.
fn farthest(
    cands: &[SimplexVertex],
    tol: f32,
    measure: impl Fn(Vec3) -> f32,
) -> Option<SimplexVertex> {
    let mut best: Option<(SimplexVertex, f32)> = None;
    for c in cands {
        let d = measure(c.w);
        if d > tol && best.is_none_or(|(_, bd)| d > bd) {
            best = Some((*c, d));
        }
    }
    best.map(|(c, _)| c)
}

/// Grow GJK's simplex (which holds the origin) into a tetrahedron with support points,
/// dropping vertices that are degenerate within `tol` (van den Bergen's blow-up, at most 8 steps).
fn seed(
    pa: &Proxy,
    pb: &Proxy,
    gjk_simplex: &Simplex,
    axes: &[SimplexVertex; 6],
    tol: f32,
) -> Seed {
    let mut s = *gjk_simplex;
    for _ in 0..8 {
        let [w0, w1, w2, w3] = s.vertices.map(|v| v.w);
        match s.count {
            0 => {
                s.push(axes[0]);
            }
            1 => match farthest(axes, tol, |w| (w - w0).length()) {
                Some(v) => {
                    s.push(v);
                }
                None => return Seed::Flat(Vec3::Y),
            },
            2 => {
                let Some((e, _)) = (w1 - w0).normalize_and_length().filter(|(_, l)| *l > tol)
                else {
                    s.count = 1;
                    continue;
                };
                let p1 = e.any_perpendicular();
                let p2 = e.cross(p1);
                let cands = [p1, -p1, p2, -p2].map(|d| gjk::support(pa, pb, d));
                let off_line = |w: Vec3| {
                    let r = w - w0;
                    (r - e * r.dot(e)).length()
                };
                match farthest(&cands, tol, off_line) {
                    Some(v) => {
                        s.push(v);
                    }
                    None => return Seed::Flat(p1),
                }
            }
            3 => {
                let Some((n, _)) = gjk::triangle_normal(w0, w1, w2).normalize_and_length() else {
                    s.count = 2;
                    continue;
                };
                let e = (w1 - w0).normalize_or(Vec3::X);
                let r = w2 - w0;
                let apart = (r - e * r.dot(e)).length() > tol;
                if !apart {
                    s.count = 2;
                    continue;
                }
                // A support point that is already a vertex of the triangle lies in its
                // plane, whatever rounding says its height is: it stands in as w0 (height
                // 0), so only a new point can lift the seed off the plane.
                let known = |v: SimplexVertex| s.used().iter().any(|u| u.same_as(&v));
                let cands = [gjk::support(pa, pb, n), gjk::support(pa, pb, -n)].map(|v| {
                    if known(v) {
                        s.vertices[0]
                    } else {
                        v
                    }
                });
                match farthest(&cands, tol, |w| scalar::abs(n.dot(w - w0))) {
                    Some(v) => {
                        s.push(v);
                    }
                    None => return Seed::Flat(n),
                }
            }
            _ => {
                let height = gjk::triangle_normal(w0, w1, w2)
                    .normalize_and_length()
                    .map(|(n, _)| scalar::abs(n.dot(w3 - w0)))
                    .unwrap_or(0.0);
                if height > tol && !s.used().iter().take(3).any(|v| v.same_as(&s.vertices[3])) {
                    return Seed::Tetrahedron(s.vertices);
                }
                s.count = 3;
            }
        }
    }
    Seed::Flat(Vec3::Y)
}

/// The initial polytope from a tetrahedron, built in `p` (emptied first): faces wound so
/// their normals point out. False (and `p` unspecified) when a face has no normal.
fn tetrahedron(p: &mut Polytope, t: [SimplexVertex; 4]) -> bool {
    let mut t = t;
    let orient = (t[1].w - t[0].w)
        .cross(t[2].w - t[0].w)
        .dot(t[3].w - t[0].w);
    if orient < 0.0 {
        t.swap(1, 2);
    }
    p.vertices.clear();
    p.faces.clear();
    for v in t {
        // Cannot be full: 4 of MAX_EPA_VERTICES.
        let _ = p.vertices.push(v);
    }
    // With (w1 − w0) × (w2 − w0) · (w3 − w0) > 0, face 0 1 2 faces w3: reverse it.
    let faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let mut built = [EpaFace::default(); 4];
    for (dst, [i, j, k]) in built.iter_mut().zip(faces) {
        let Some(face) = p.make_face(i, j, k) else {
            return false;
        };
        *dst = face;
    }
    for face in built {
        let _ = p.faces.push(face);
    }
    true
}

/// Flip `n` (a direction in `D`) so the normal `−n` points from A's origin to B's.
fn outward_towards_a(n: Vec3, pa: &Proxy, pb: &Proxy) -> Vec3 {
    let c = pb.pose.position - pa.pose.position;
    if n.dot(c) > 0.0 {
        -n
    } else {
        n
    }
}

/// The witness points of cores that touch through a flat `D` (thinner than EPA's
/// tolerance along its normal `n`): the point of GJK's simplex over the origin, seen
/// along `n`, as a convex combination of its vertices, so the two points differ along
/// `n` only (by at most the thickness of `D`). GJK's own barycentric coordinates cannot
/// serve: on a tetrahedron that flat they are ill-conditioned, and a witness pair came
/// out 16 m apart across the normal (fuzz finding
/// `sphere-in-a-thin-box-flat-difference-03da1638`: a ball's centre inside a 2.4 mm
/// thick, 1 km wide box).
///
/// In the plane across `n`: the widest of the simplex's triangles that holds the origin
/// gives barycentric coordinates; when none does (the origin on the edge of the
/// projection, within rounding), the closest point of its edges and vertices.
fn flat_witnesses(simplex: &Simplex, n: Vec3) -> (Vec3, Vec3) {
    let used = simplex.used();
    let u = n.any_perpendicular();
    let v = n.cross(u);
    // 2D coordinates of the vertices across `n`.
    let at = |i: usize| used.get(i).map_or((0.0, 0.0), |p| (p.w.dot(u), p.w.dot(v)));
    let cross = |p: (f32, f32), q: (f32, f32)| p.0 * q.1 - p.1 * q.0;
    let sub = |p: (f32, f32), q: (f32, f32)| (p.0 - q.0, p.1 - q.1);
    let mut best: Option<([f32; 4], f32)> = None;
    for (i, j, k) in [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)] {
        if k >= used.len() {
            continue;
        }
        let (p0, p1, p2) = (at(i), at(j), at(k));
        let (e1, e2) = (sub(p1, p0), sub(p2, p0));
        let area = cross(e1, e2);
        if area == 0.0 || !area.is_finite() {
            continue;
        }
        let o = (-p0.0, -p0.1);
        let l1 = cross(o, e2) / area;
        let l2 = cross(e1, o) / area;
        let l0 = 1.0 - l1 - l2;
        let inside = l0 >= 0.0 && l1 >= 0.0 && l2 >= 0.0;
        if inside && best.is_none_or(|(_, a)| scalar::abs(area) > a) {
            let mut w = [0.0; 4];
            for (slot, l) in [(i, l0), (j, l1), (k, l2)] {
                if let Some(x) = w.get_mut(slot) {
                    *x = l;
                }
            }
            best = Some((w, scalar::abs(area)));
        }
    }
    let weights = best.map(|(w, _)| w).unwrap_or_else(|| {
        // The closest point of the edges (or the one vertex).
        let mut w = [1.0, 0.0, 0.0, 0.0];
        let mut best_d2 = f32::INFINITY;
        for i in 0..used.len() {
            for j in i..used.len() {
                let (p, q) = (at(i), at(j));
                let d = sub(q, p);
                let dd = d.0 * d.0 + d.1 * d.1;
                let t = if dd > 0.0 {
                    scalar::clamp(-(p.0 * d.0 + p.1 * d.1) / dd, 0.0, 1.0)
                } else {
                    0.0
                };
                let c = (p.0 + t * d.0, p.1 + t * d.1);
                let d2 = c.0 * c.0 + c.1 * c.1;
                if d2 < best_d2 {
                    best_d2 = d2;
                    w = [0.0; 4];
                    if let Some(x) = w.get_mut(i) {
                        *x = 1.0 - t;
                    }
                    if let Some(x) = w.get_mut(j) {
                        *x += t;
                    }
                }
            }
        }
        w
    });
    let mut point_a = Vec3::ZERO;
    let mut point_b = Vec3::ZERO;
    for (p, l) in used.iter().zip(weights) {
        point_a += p.a * l;
        point_b += p.b * l;
    }
    (point_a, point_b)
}

/// EPA on overlapping cores, seeded from GJK's simplex.
fn epa_cores(pa: &Proxy, pb: &Proxy, gjk_simplex: &Simplex, caps: EpaCaps) -> CorePenetration {
    let (axes, scale) = axis_supports(pa, pb);
    let tol = EPA_RELATIVE_TOLERANCE * scale;
    let tetra = match seed(pa, pb, gjk_simplex, &axes, tol) {
        Seed::Flat(n) => {
            // Touching through a flat D: zero core depth along its normal.
            let m = outward_towards_a(n, pa, pb);
            let (point_a, point_b) = flat_witnesses(gjk_simplex, n);
            return CorePenetration {
                depth: 0.0,
                normal: -m,
                point_a,
                point_b,
                status: EpaStatus::Converged,
                iterations: 0,
            };
        }
        Seed::Tetrahedron(t) => t,
    };
    let mut poly = Polytope::new();
    if !tetrahedron(&mut poly, tetra) {
        return bounded_answer(pa, pb, None, EpaStatus::Degenerate, 0);
    }
    let max_vertices = caps.vertices.clamp(4, MAX_EPA_VERTICES);
    // The smallest upper bound h_D(m) seen, with its direction m.
    let mut best: Option<(Vec3, f32)> = None;
    let mut status = EpaStatus::IterationLimit;
    let mut iterations = 0;
    // SAT's direction and upper bound, computed at the first stall.
    let mut sat_upper: Option<(Vec3, f32)> = None;
    while iterations < caps.iterations {
        iterations += 1;
        let Some(fi) = poly.closest_face() else {
            status = EpaStatus::Degenerate;
            break;
        };
        let face = poly.faces.get(fi).copied().unwrap_or_default();
        let w = gjk::support(pa, pb, face.normal);
        let upper = face.normal.dot(w.w);
        if best.is_none_or(|(_, u)| upper < u) {
            best = Some((face.normal, upper));
        }
        if upper - face.distance <= tol {
            return converged(&poly, &face, tol, iterations);
        }
        if poly.contains(&w) {
            // Stalled: nothing new to add, yet `w` is beyond the face by more than the
            // tolerance, so the face's plane is off by rounding (a sliver face). It is
            // the answer only if the bracket certifies it; otherwise it is set aside
            // and the next closest face is tried.
            let sat = *sat_upper.get_or_insert_with(|| sat_axis(pa, pb));
            if stall_is_certified(best, sat.1, face.distance, tol) {
                // The depth is certified. The face's normal stands when the support along
                // it is within `STALL_NORMAL_SLACK · tol` of the smallest upper bound (a
                // sliver of a true face, tilted by rounding); otherwise (a plane through
                // `D` that lost its meaning) the answer is taken along the direction of
                // that bound, which moves the cores apart, with the supports along it as
                // points (so not `Converged`: not a closest pair).
                let smallest = best.map_or(sat.1, |(_, u)| scalar::min(u, sat.1));
                if upper <= smallest + STALL_NORMAL_SLACK * tol {
                    return converged(&poly, &face, tol, iterations);
                }
                return along_upper_bound(pa, pb, best, sat, EpaStatus::Degenerate, iterations);
            }
            if let Some(f) = poly.faces.get_mut(fi) {
                f.stalled = true;
            }
            continue;
        }
        if poly.vertices.len() >= max_vertices {
            status = EpaStatus::PolytopeFull;
            break;
        }
        // Faces `w` lies on are removed only when keeping them would build a flat face
        // (a retry after an unchanged, refused polytope); other answers stay as they
        // were bit for bit. Denting by `tol` stays within EPA's tolerance.
        let grown = match poly.expand(fi, w, 0.0, tol) {
            Err(Refused::Degenerate) => poly.expand(fi, w, tol, tol),
            other => other,
        };
        match grown {
            Ok(()) => {}
            Err(Refused::Full) => {
                status = EpaStatus::PolytopeFull;
                break;
            }
            Err(Refused::Degenerate) => {
                status = EpaStatus::Degenerate;
                break;
            }
        }
    }
    bounded_answer(pa, pb, best, status, iterations)
}

/// How far (in EPA tolerances) the support along a certified stalled face's normal may
/// lie beyond the smallest upper bound for the face's normal to stand (1e-3 of `D`'s
/// size). A sliver of a true face tilted by rounding stays well within it; a plane that
/// lost its meaning (fuzz finding `sphere-on-a-sliver-hull-edge-d1bb2040`: 2.7 m along a
/// normal whose bound was 0.05 mm) is far outside.
const STALL_NORMAL_SLACK: f32 = 100.0;

/// Whether a stalled face can stand as the answer. The depth lies between the closest
/// face's distance `lower` (a lower bound while the polytope is convex and inside `D`) and
/// the smallest upper bound `h_D(m)` seen over EPA's faces (`best`) and the SAT axes
/// (`sat_upper`): the face is certified when they agree within `tol`.
///
/// A face of `D` split into thin triangles tilts them by the rounding of their vertices
/// over their height (1e-7 m over 0.5 mm is 2e-4 rad, 1e-4 m at a 1 m lever), so a thin
/// triangle's distance can be off by more than `tol`; and a triangle that lost its meaning
/// (three collinear points, a plane through the origin of a 1 m overlap) is off by the
/// whole depth. Neither is certified; EPA sets it aside instead of calling it converged.
fn stall_is_certified(best: Option<(Vec3, f32)>, sat_upper: f32, lower: f32, tol: f32) -> bool {
    let upper = best.map_or(sat_upper, |(_, u)| scalar::min(u, sat_upper));
    upper - lower <= tol
}

/// The answer from the converged face: depth `max(d, 0)`, normal `−m`, points from the
/// barycentric coordinates of the face point closest to the origin. A face of `D` is
/// usually split into several coplanar triangles, all at the same distance; the origin
/// projects into one of them, so the witnesses come from the coplanar triangle (normal
/// and distance within `tol`) whose closest point is nearest to `d m`.
fn converged(poly: &Polytope, face: &EpaFace, tol: f32, iterations: u32) -> CorePenetration {
    let target = face.normal * face.distance;
    let mut best: Option<(f32, EpaFace, [f32; 3])> = None;
    let candidates = core::iter::once(face).chain(poly.used_faces().iter().filter(|f| {
        f.normal.dot(face.normal) >= 1.0 - EPA_COPLANAR_COS
            && scalar::abs(f.distance - face.distance) <= tol
    }));
    for f in candidates {
        let [v0, v1, v2] = f.v.map(|i| poly.vertex(i).w);
        let (l, _) = gjk::s2d(v0, v1, v2);
        // The point the witnesses stand for, `Σ lᵢ wᵢ` (for a sliver, s2d's own closest
        // point can differ from it by far more than rounding).
        let closest = v0 * l[0] + v1 * l[1] + v2 * l[2];
        let miss = (closest - target).length_squared();
        if best.is_none_or(|(m, _, _)| miss < m) {
            best = Some((miss, *f, l));
        }
    }
    let (miss, f, l) = best.unwrap_or((0.0, *face, [1.0, 0.0, 0.0]));
    let [v0, v1, v2] = f.v.map(|i| poly.vertex(i));
    // When no coplanar triangle holds the point `d m` (its closest point is more than
    // `WITNESS_MISS · tol` away), `D` is too flat there for barycentric witnesses: two
    // nearly coplanar triangles sharing an edge, 5e-5 m deep, gave points 1 cm off
    // `−depth · normal` (narrow_phase fuzz finding `flat-triangle-pair-5c0fad2d`). The
    // depth and normal still bound the overlap; the answer says so.
    let status = if miss <= (WITNESS_MISS * tol) * (WITNESS_MISS * tol) {
        EpaStatus::Converged
    } else {
        EpaStatus::Degenerate
    };
    CorePenetration {
        depth: scalar::max(face.distance, 0.0),
        normal: -face.normal,
        point_a: v0.a * l[0] + v1.a * l[1] + v2.a * l[2],
        point_b: v0.b * l[0] + v1.b * l[1] + v2.b * l[2],
        status,
        iterations,
    }
}

/// The answer of an unconverged exit: the smallest upper bound `h_D(m)` between EPA's
/// best face and the shapes' face normals, with the two supports along it as points.
fn bounded_answer(
    pa: &Proxy,
    pb: &Proxy,
    best: Option<(Vec3, f32)>,
    status: EpaStatus,
    iterations: u32,
) -> CorePenetration {
    along_upper_bound(pa, pb, best, sat_axis(pa, pb), status, iterations)
}

/// The answer along the smaller of EPA's best upper bound `best` and SAT's `sat`
/// (direction `m`, `h_D(m)`): depth `max(h_D(m), 0)`, normal `−m`, the support points
/// along `m` as witnesses.
fn along_upper_bound(
    pa: &Proxy,
    pb: &Proxy,
    best: Option<(Vec3, f32)>,
    (sat_m, sat_upper): (Vec3, f32),
    status: EpaStatus,
    iterations: u32,
) -> CorePenetration {
    let (m, upper) = match best {
        Some((m, u)) if u <= sat_upper => (m, u),
        _ => (sat_m, sat_upper),
    };
    let w = gjk::support(pa, pb, m);
    CorePenetration {
        depth: scalar::max(upper, 0.0),
        normal: -m,
        point_a: w.a,
        point_b: w.b,
        status,
        iterations,
    }
}

/// Separating-axis fallback: over the face normals of both cores (box axes, hull planes,
/// triangle normal) and the line between the origins, both signs, the direction `m` with
/// the smallest `h_D(m)`. Exact for face contacts of boxes and hulls; an upper bound
/// otherwise.
fn sat_axis(pa: &Proxy, pb: &Proxy) -> (Vec3, f32) {
    let mut best = (Vec3::Y, f32::INFINITY);
    let mut try_axis = |axis: Vec3| {
        let Some((u, _)) = axis.normalize_and_length() else {
            return;
        };
        for m in [u, -u] {
            let h = m.dot(gjk::support(pa, pb, m).w);
            if h < best.1 {
                best = (m, h);
            }
        }
    };
    for p in [pa, pb] {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            try_axis(p.pose.transform_vector(axis));
        }
        match p.shape {
            Shape::Hull(h) => {
                for f in 0..h.face_count() {
                    try_axis(p.pose.transform_vector(h.plane(f).0));
                }
            }
            Shape::Triangle(t) => try_axis(p.pose.transform_vector(t.normal())),
            _ => {}
        }
    }
    try_axis(pb.pose.position - pa.pose.position);
    if !best.1.is_finite() {
        best = (Vec3::Y, 0.0);
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::gjk::distance_in_a;
    use crate::rng::SplitMix64;

    /// Moving B by `depth + 1e-3` along the normal must separate the shapes (the
    /// contract of every status); 1e-3 is far above the 1e-5 rounding at this 2 m scale.
    fn separates(a: &Shape, b: &Shape, b_in_a: &Iso, p: &Penetration) -> bool {
        let moved = Iso::new(
            b_in_a.position + p.normal * (p.depth + 1e-3),
            b_in_a.rotation,
        );
        distance_in_a(a, b, &moved, &mut SimplexCache::default()).distance > 0.0
    }

    fn boxes() -> (Shape<'static>, Shape<'static>) {
        (
            Shape::cuboid(Vec3::new(1.0, 0.6, 0.8)).unwrap(),
            Shape::cuboid(Vec3::new(0.5, 0.9, 0.4)).unwrap(),
        )
    }

    #[test]
    fn small_caps_force_bounded_exits_with_separating_answers() {
        let (a, b) = boxes();
        let mut rng = SplitMix64::new(3);
        let mut seen = [false; 2];
        for _ in 0..300 {
            let b_in_a = Iso::new(rng.unit_vector() * rng.range(0.0, 1.0), rng.rotation());
            let exact = penetration_in_a(&a, &b, &b_in_a).unwrap();
            for (k, caps) in [
                EpaCaps {
                    vertices: 5,
                    iterations: 48,
                },
                EpaCaps {
                    vertices: 64,
                    iterations: 1,
                },
            ]
            .into_iter()
            .enumerate()
            {
                let p = penetration_in_a_capped(&a, &b, &b_in_a, caps).unwrap();
                assert!(p.depth.is_finite() && p.depth >= 0.0);
                assert!((p.normal.length() - 1.0).abs() < 1e-5);
                assert!(p.point_a.is_finite() && p.point_b.is_finite());
                let expected = [EpaStatus::PolytopeFull, EpaStatus::IterationLimit];
                if p.status != EpaStatus::Converged {
                    assert_eq!(p.status, expected[k]);
                    if let Some(s) = seen.get_mut(k) {
                        *s = true;
                    }
                    // An upper bound: never shallower than the converged answer (1e-5:
                    // rounding at this scale), and it separates.
                    assert!(p.depth >= exact.depth - 1e-5, "{p:?} {exact:?}");
                    assert!(separates(&a, &b, &b_in_a, &p), "{p:?}");
                }
            }
        }
        assert_eq!(seen, [true, true], "both bounded exits were exercised");
    }

    #[test]
    fn converged_answers_separate_and_match_the_points() {
        let (a, b) = boxes();
        let mut rng = SplitMix64::new(9);
        for _ in 0..500 {
            let b_in_a = Iso::new(rng.unit_vector() * rng.range(0.0, 1.2), rng.rotation());
            let p = penetration_in_a(&a, &b, &b_in_a).unwrap();
            assert_eq!(p.status, EpaStatus::Converged, "{b_in_a:?}");
            assert!(separates(&a, &b, &b_in_a, &p));
            // point_b − point_a = −depth · normal (1e-4: f32 at a 2 m scale).
            let gap = p.point_b - p.point_a + p.normal * p.depth;
            assert!(gap.length() < 1e-4, "{gap:?} {p:?} {b_in_a:?}");
        }
    }

    #[test]
    fn flat_difference_gives_zero_core_depth() {
        // Two capsules whose core segments cross: D is a parallelogram through the
        // origin, so the depth is exactly the sum of the radii, along the cross product.
        let a = Shape::capsule(1.0, 0.2).unwrap();
        let b = Shape::capsule(1.0, 0.3).unwrap();
        let b_in_a = Iso::new(
            Vec3::ZERO,
            crate::math::Quat::from_axis_angle(Vec3::X, core::f32::consts::FRAC_PI_2),
        );
        let p = penetration_in_a(&a, &b, &b_in_a).unwrap();
        assert!((p.depth - 0.5).abs() < 1e-6, "{p:?}");
        assert!(scalar::abs(p.normal.x) > 1.0 - 1e-6, "{p:?}");
        // A sphere centred on a triangle: D is the triangle itself.
        let t = Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::Z).unwrap();
        let s = Shape::sphere(0.25).unwrap();
        let p = penetration_in_a(&t, &s, &Iso::from_position(Vec3::new(0.2, 0.0, 0.2))).unwrap();
        assert!((p.depth - 0.25).abs() < 1e-6 && scalar::abs(p.normal.y) > 1.0 - 1e-6);
    }

    /// The polytope vertex with `w` (index pair `(i, i)`).
    fn vertex_at(w: Vec3, i: u32) -> SimplexVertex {
        SimplexVertex {
            w,
            b: w,
            index_a: i,
            index_b: i,
            ..SimplexVertex::default()
        }
    }

    /// The index of the face on exactly these three vertices.
    fn face_on(poly: &Polytope, v: [u8; 3]) -> usize {
        let mut sorted = v;
        crate::sort::sort_unstable(&mut sorted);
        let found = poly.used_faces().iter().position(|f| {
            let mut s = f.v;
            crate::sort::sort_unstable(&mut s);
            s == sorted
        });
        assert!(found.is_some(), "no face on {v:?}");
        found.unwrap_or(0)
    }

    #[test]
    fn a_point_on_a_neighbour_plane_and_an_edge_line_leaves_no_collinear_face() {
        // The regression in miniature. Tetrahedron p0..p3: face G = (p0 p1 p2) lies in the
        // plane z = −1 (outward −z), face T = (p0 p1 p3) holds the edge p0 p1 on y = 0.
        // The new point w is 1e-6 m off the line of p0 p1, beyond p1: 1e-6 in front of T,
        // 1e-6 behind G, far in front of S = (p1 p2 p3).
        let p = [
            Vec3::new(-2.0, 0.0, -1.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(-1.0, 2.0, -1.0),
            Vec3::new(-1.0, 0.5, 1.0),
        ];
        let t = [0, 1, 2, 3].map(|i| vertex_at(p[i], i as u32));
        let w = vertex_at(Vec3::new(1.0, -1.0e-6, -1.0 + 1.0e-6), 4);
        let fresh = || {
            let mut p = Polytope::new();
            assert!(tetrahedron(&mut p, t));
            p
        };
        // Positively oriented already: `tetrahedron` keeps the order.
        assert_eq!(fresh().vertex(1).w, p[1]);
        let s = face_on(&fresh(), [1, 2, 3]);
        // Deciding G on the sign alone keeps it; the fan then builds (p0 p1 w), three
        // points within 1e-6 of a line (area ratio 3e-7): refused, polytope unchanged.
        let mut strict = fresh();
        assert_eq!(strict.expand(s, w, 0.0, 1.0e-5), Err(Refused::Degenerate));
        assert_eq!((strict.vertices.len(), strict.faces.len()), (4, 4));
        // Counting faces within 1e-5 as seen removes G too: p1 drops out (it lies on the
        // segment p0 w within 1e-6), and every vertex is behind every new face (convex,
        // to the 1e-5 the test allowed).
        let mut tolerant = fresh();
        assert_eq!(tolerant.expand(s, w, 1.0e-5, 1.0e-5), Ok(()));
        assert_eq!((tolerant.vertices.len(), tolerant.faces.len()), (5, 4));
        for f in tolerant.used_faces() {
            assert!(!f.v.contains(&1), "{f:?}");
            for v in tolerant.vertices.iter().take(5) {
                assert!(f.normal.dot(v.w) - f.distance <= 1.0e-5, "{f:?} {v:?}");
            }
        }
    }

    #[test]
    fn make_face_refuses_collinear_and_coincident_points() {
        let t = [
            Vec3::new(-1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, -1.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 1.0),
        ]
        .map(|w| w * 0.5);
        let mut poly = Polytope::new();
        assert!(tetrahedron(
            &mut poly,
            [0, 1, 2, 3].map(|i| vertex_at(t[i], i as u32))
        ));
        // `tetrahedron` may reorder the vertices: read them back.
        let [v0, v1, v2] = [0, 1, 2].map(|i| poly.vertex(i).w);
        // Vertex 4 1e-7 m off the midpoint of the edge 0–1 (noise level: the
        // regression's face), vertex 5 1e-9 m from vertex 2.
        let off_line = (v1 - v0).any_perpendicular().normalize_or(Vec3::X) * 1.0e-7;
        let extra = [(v0 + v1) * 0.5 + off_line, v2 + Vec3::splat(1.0e-9)];
        for (k, w) in extra.into_iter().enumerate() {
            assert!(poly.vertices.push(vertex_at(w, 4 + k as u32)).is_ok());
        }
        assert_eq!(poly.vertices.len(), 6);
        assert!(poly.make_face(0, 4, 1).is_none());
        assert!(poly.make_face(2, 5, 3).is_none());
        // A sound face: normal and distance exact to rounding (1e-6 at this 1 m scale).
        let f = poly.make_face(0, 1, 2).unwrap();
        let n = (v1 - v0).cross(v2 - v0).normalize_or(Vec3::Y);
        assert!((f.normal - n).length() < 1.0e-6 && (f.distance - n.dot(v0)).abs() < 1.0e-6);
    }
}
