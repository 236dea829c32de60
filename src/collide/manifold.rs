//! Contact manifolds: dispatch per shape pair, clipping of supporting faces, reduction to
//! at most 4 points.
//!
//! Every pair runs in A's frame (`b_in_a = pose_a⁻¹ ∘ pose_b`) and answers in the world
//! frame. Pairs are put in a canonical order first (half-space, sphere, capsule, then the
//! polytopes: cuboid, hull, triangle); a pair given the other way round is computed
//! swapped and flipped by [`flipped`].
//!
//! - Closed forms ([`super::analytic`]): sphere and capsule pairs, half-space against
//!   anything.
//! - Sphere or capsule against a polytope: GJK on the cores, EPA when the cores overlap;
//!   a capsule lying on a face is clipped against the face's side planes (2 points).
//! - Polytope against polytope: the axis from GJK (separated) or EPA (overlapping), then
//!   the reference face (the supporting face most aligned with the axis, on either shape)
//!   and the incident face (the other shape's face most anti-aligned with it), clipped
//!   against each other ([`super::clip`]) and reduced to at most 4 points. The manifold
//!   normal is the reference face's normal, so a box resting flat gets an exact normal.
//!   When no face is well aligned with the axis (an edge–edge contact), one point from the
//!   GJK/EPA closest points.

use super::analytic;
use super::check_pose;
use super::clip::{self, MAX_CLIP_POINTS};
use super::gjk::{GjkStatus, SimplexCache};
use super::{distance_in_a, penetration_in_a};
use crate::error::{non_negative, Error, Input};
use crate::math::{scalar, Iso, Vec3};
use crate::shape::{Capsule, Face, FeatureId, Shape};

/// Most points in a manifold.
pub const MAX_MANIFOLD_POINTS: usize = 4;

/// Smallest `cos` between the GJK/EPA axis and the best face normal for a face contact
/// (clipping); below it (about 25.8°) the contact is treated as edge–edge or
/// vertex–edge and gives one point. Box edges meet at 90°, so an edge–edge axis halfway
/// between two faces has `cos 45° ≈ 0.71` and never passes; a face tilted by a few degrees
/// from the axis does.
pub(crate) const FACE_CONTACT_MIN_COS: f32 = 0.9;

/// A's face stays the reference unless B's is more aligned with the axis by more than this
/// (in `cos`, about 2.5° near alignment), so the choice does not flip on rounding noise and
/// a body resting on the ground keeps the ground's exact normal.
const REFERENCE_FACE_TOLERANCE: f32 = 1.0e-3;

/// A clipped face manifold is refused (one GJK/EPA point is used instead) when its
/// smallest separation differs from the GJK distance or −EPA depth by more than
/// `GUARD_ABS + GUARD_REL · |separation|` (m). Deeper means the face normal sees more
/// overlap than there is (the contact is really an edge); shallower means the deepest
/// point lies outside the reference face's prism (a corner or cap over the face's edge).
/// For a true face contact they agree up to EPA's tolerance.
const GUARD_ABS: f32 = 1.0e-3;
/// See [`GUARD_ABS`].
const GUARD_REL: f32 = 0.002;

/// The pair of features, one on each shape, that produced a contact point. It stays the
/// same for as long as the same features touch, so the solver can match points across
/// steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct ContactId {
    /// Feature on A.
    pub a: FeatureId,
    /// Feature on B.
    pub b: FeatureId,
}

impl ContactId {
    /// Both ids packed in a `u64` (A in the high half).
    #[inline]
    pub const fn key(self) -> u64 {
        ((self.a.0 as u64) << 32) | self.b.0 as u64
    }
}

/// One contact point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ManifoldPoint {
    /// The point on A's surface (world frame, m).
    pub point_a: Vec3,
    /// The point on B's surface (world frame, m).
    pub point_b: Vec3,
    /// `point_a` in A's local frame.
    pub local_a: Vec3,
    /// `point_b` in B's local frame.
    pub local_b: Vec3,
    /// Signed distance along the normal, `(point_b − point_a) · normal` (m): negative when
    /// penetrating, positive up to the speculative margin.
    pub separation: f32,
    /// Which features touch.
    pub id: ContactId,
}

/// Up to [`MAX_MANIFOLD_POINTS`] contact points sharing one normal.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Manifold {
    /// Unit normal from A towards B (world frame).
    pub normal: Vec3,
    /// Number of points used.
    pub len: u8,
    /// The points; the first `len` are used.
    pub points: [ManifoldPoint; MAX_MANIFOLD_POINTS],
}

impl Manifold {
    /// The points in use.
    pub fn points(&self) -> &[ManifoldPoint] {
        &self.points[..(self.len as usize).min(MAX_MANIFOLD_POINTS)]
    }

    /// The smallest separation over the points (m); `+∞` for an empty manifold.
    pub fn min_separation(&self) -> f32 {
        let mut s = f32::INFINITY;
        for p in self.points() {
            if p.separation < s {
                s = p.separation;
            }
        }
        s
    }
}

/// The contact manifold of `a` at `pose_a` and `b` at `pose_b` (world frame): every point
/// closer than `margin` metres (the speculative margin; penetrating points always count),
/// or `None` when the shapes are further apart than `margin`. Two half-spaces never touch.
/// Fails on an invalid pose or a negative or non-finite margin.
pub fn contact(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Result<Option<Manifold>, Error> {
    check_pose(pose_a)?;
    check_pose(pose_b)?;
    non_negative(margin, Input::Distance)?;
    Ok(contact_unchecked(a, pose_a, b, pose_b, margin))
}

/// A contact point under construction, in A's frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Candidate {
    /// Point on A's surface (A's frame, m).
    pub point_a: Vec3,
    /// Point on B's surface (A's frame, m).
    pub point_b: Vec3,
    /// `(point_b − point_a) · normal` (m).
    pub separation: f32,
    /// Which features touch.
    pub id: ContactId,
}

impl Candidate {
    /// A point pair; its separation is measured along `normal` (unit, A to B).
    #[inline]
    pub fn new(point_a: Vec3, point_b: Vec3, normal: Vec3, id: ContactId) -> Candidate {
        Candidate {
            point_a,
            point_b,
            separation: (point_b - point_a).dot(normal),
            id,
        }
    }
}

/// A manifold in A's frame, before it is moved into the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LocalManifold {
    /// Unit normal from A towards B (A's frame).
    pub normal: Vec3,
    /// Points in use.
    pub len: usize,
    /// The points; the first `len` are used.
    pub points: [Candidate; MAX_MANIFOLD_POINTS],
}

impl LocalManifold {
    /// An empty manifold with the given normal.
    pub fn new(normal: Vec3) -> LocalManifold {
        LocalManifold {
            normal,
            len: 0,
            points: [Candidate::default(); MAX_MANIFOLD_POINTS],
        }
    }

    /// Append `c` when its separation is within `margin` (and there is room).
    pub fn push_within(&mut self, c: Candidate, margin: f32) {
        if c.separation <= margin {
            if let Some(slot) = self.points.get_mut(self.len) {
                *slot = c;
                self.len += 1;
            }
        }
    }

    /// The points in use.
    pub fn points(&self) -> &[Candidate] {
        self.points.get(..self.len).unwrap_or(&[])
    }

    /// `None` when empty.
    pub fn non_empty(self) -> Option<LocalManifold> {
        (self.len > 0).then_some(self)
    }

    /// The candidates as they are when at most 4, else the 4 chosen by
    /// [`clip::reduce_to_four`]; `None` when there are none.
    pub fn from_candidates(normal: Vec3, candidates: &[Candidate]) -> Option<LocalManifold> {
        let mut m = LocalManifold::new(normal);
        if candidates.len() <= MAX_MANIFOLD_POINTS {
            for c in candidates {
                m.push_within(*c, f32::INFINITY);
            }
        } else {
            let (chosen, count) = clip::reduce_to_four(candidates, normal);
            for &i in chosen.iter().take(count) {
                if let Some(c) = candidates.get(i) {
                    m.push_within(*c, f32::INFINITY);
                }
            }
        }
        m.non_empty()
    }

    /// The smallest separation (m); `+∞` when empty.
    fn min_separation(&self) -> f32 {
        let mut s = f32::INFINITY;
        for c in self.points() {
            s = scalar::min(s, c.separation);
        }
        s
    }
}

/// [`contact`] without input checks (poses finite with unit rotations, margin finite and
/// `>= 0`). Rotations are renormalised first. Never panics; a manifold that would hold a
/// non-finite number (only for coordinates near `f32::MAX`) is dropped.
pub(crate) fn contact_unchecked(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Option<Manifold> {
    let pose_a = Iso::new(pose_a.position, pose_a.rotation.normalize());
    let pose_b = Iso::new(pose_b.position, pose_b.rotation.normalize());
    if order_rank(b) < order_rank(a) {
        contact_ordered(b, &pose_b, a, &pose_a, margin).map(|m| flipped(&m))
    } else {
        contact_ordered(a, &pose_a, b, &pose_b, margin)
    }
}

/// Canonical order of a pair: the shape with the lower rank is A. Half-space 0, sphere 1,
/// capsule 2, polytopes 3 (any order among themselves).
fn order_rank(s: &Shape) -> u8 {
    match s {
        Shape::HalfSpace(_) => 0,
        Shape::Sphere(_) => 1,
        Shape::Capsule(_) => 2,
        Shape::Cuboid(_) | Shape::Hull(_) | Shape::Triangle(_) => 3,
    }
}

/// The manifold of a pair already in canonical order, in the world frame.
fn contact_ordered(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Option<Manifold> {
    let b_in_a = pose_a.inv_mul(pose_b);
    // Fallback normal for coincident centres or crossing segments: world +Y.
    let up_in_a = pose_a
        .inverse_transform_vector(Vec3::Y)
        .normalize_or(Vec3::Y);
    let local = match (a, b) {
        (Shape::HalfSpace(plane), _) => analytic::half_space_contact(plane, b, &b_in_a, margin),
        (Shape::Sphere(sa), Shape::Sphere(sb)) => {
            analytic::sphere_sphere(sa, sb, &b_in_a, up_in_a, margin)
        }
        (Shape::Sphere(sa), Shape::Capsule(cb)) => {
            analytic::sphere_capsule(sa, cb, &b_in_a, up_in_a, margin)
        }
        (Shape::Capsule(ca), Shape::Capsule(cb)) => {
            analytic::capsule_capsule(ca, cb, &b_in_a, up_in_a, margin)
        }
        (Shape::Sphere(_) | Shape::Capsule(_), _) => round_vs_polytope(a, b, &b_in_a, margin),
        _ => polytope_vs_polytope(a, b, &b_in_a, margin),
    }?;
    to_world(&local, pose_a, &b_in_a, margin)
}

/// Move an A-frame manifold into the world: normal and points by `pose_a`, B's local
/// points by `b_in_a⁻¹`. Points with a non-finite coordinate or a separation beyond
/// `margin` are dropped; `None` when nothing is left or the normal is not a unit vector.
fn to_world(local: &LocalManifold, pose_a: &Iso, b_in_a: &Iso, margin: f32) -> Option<Manifold> {
    let (normal, _) = pose_a
        .transform_vector(local.normal)
        .normalize_and_length()?;
    let mut m = Manifold {
        normal,
        ..Manifold::default()
    };
    let mut len = 0usize;
    for c in local.points() {
        let p = ManifoldPoint {
            point_a: pose_a.transform_point(c.point_a),
            point_b: pose_a.transform_point(c.point_b),
            local_a: c.point_a,
            local_b: b_in_a.inverse_transform_point(c.point_b),
            separation: c.separation,
            id: c.id,
        };
        let finite = p.point_a.is_finite()
            && p.point_b.is_finite()
            && p.local_b.is_finite()
            && p.separation.is_finite();
        if finite && p.separation <= margin {
            if let Some(slot) = m.points.get_mut(len) {
                *slot = p;
                len += 1;
            }
        }
    }
    m.len = len as u8;
    (len > 0).then_some(m)
}

/// The manifold of (B, A) from the one of (A, B): normal negated, the two sides of every
/// point (world points, local points, feature ids) swapped; separations unchanged.
fn flipped(m: &Manifold) -> Manifold {
    let mut out = *m;
    out.normal = -m.normal;
    for p in out.points.iter_mut() {
        *p = ManifoldPoint {
            point_a: p.point_b,
            point_b: p.point_a,
            local_a: p.local_b,
            local_b: p.local_a,
            separation: p.separation,
            id: ContactId {
                a: p.id.b,
                b: p.id.a,
            },
        };
    }
    out
}

/// The contact axis of two shapes in A's frame: unit normal from A to B, the signed
/// separation along it (m) and the closest (or deepest) points on each surface.
#[derive(Clone, Copy, Debug)]
struct Axis {
    normal: Vec3,
    separation: f32,
    point_a: Vec3,
    point_b: Vec3,
}

/// GJK on the cores; when they are further apart than `margin`, `None`; when the full
/// shapes overlap (or touch), EPA. Written so that a NaN from either gives `None`.
fn find_axis(a: &Shape, b: &Shape, b_in_a: &Iso, margin: f32) -> Option<Axis> {
    let mut cache = SimplexCache::default();
    let d = distance_in_a(a, b, b_in_a, &mut cache);
    if d.status != GjkStatus::Overlapping && d.distance > 0.0 {
        let within = d.distance <= margin; // false for NaN too
        if !within {
            return None;
        }
        let (normal, _) = d.normal.normalize_and_length()?;
        return finite_axis(Axis {
            normal,
            separation: d.distance,
            point_a: d.point_a,
            point_b: d.point_b,
        });
    }
    match penetration_in_a(a, b, b_in_a) {
        Some(p) => {
            let (normal, _) = p.normal.normalize_and_length()?;
            finite_axis(Axis {
                normal,
                separation: -p.depth,
                point_a: p.point_a,
                point_b: p.point_b,
            })
        }
        None => {
            // GJK says touching, EPA says apart: touching at zero distance.
            let (normal, _) = d.normal.normalize_and_length()?;
            finite_axis(Axis {
                normal,
                separation: 0.0,
                point_a: d.point_a,
                point_b: d.point_b,
            })
        }
    }
}

fn finite_axis(axis: Axis) -> Option<Axis> {
    let ok = axis.normal.is_finite()
        && axis.separation.is_finite()
        && axis.point_a.is_finite()
        && axis.point_b.is_finite();
    ok.then_some(axis)
}

/// `shape`'s supporting face along `dir_in_a` (A's frame), moved into A's frame.
fn supporting_face_in_a(shape: &Shape, shape_in_a: &Iso, dir_in_a: Vec3) -> Face {
    shape
        .supporting_face(shape_in_a.inverse_transform_vector(dir_in_a))
        .transformed(shape_in_a)
}

/// The feature of a round shape's core (sphere: its point; capsule: an end or the
/// segment) under a surface point `p` whose outward normal is `outward` (A's frame for A).
fn round_feature(shape: &Shape, shape_in_a: &Iso, p: Vec3, outward: Vec3) -> FeatureId {
    match shape {
        Shape::Capsule(c) => {
            let core = shape_in_a.inverse_transform_point(p - outward * c.radius);
            analytic::segment_feature(c, core)
        }
        _ => FeatureId::vertex(0),
    }
}

/// True when a clipped face manifold's smallest separation agrees with the axis's (see
/// [`GUARD_ABS`]).
fn plausible(m: &LocalManifold, axis: &Axis) -> bool {
    let slack = GUARD_ABS + GUARD_REL * scalar::abs(axis.separation);
    m.len > 0 && scalar::abs(m.min_separation() - axis.separation) <= slack
}

/// Sphere or capsule `a` against polytope `b` (B at `b_in_a`).
fn round_vs_polytope(a: &Shape, b: &Shape, b_in_a: &Iso, margin: f32) -> Option<LocalManifold> {
    let axis = find_axis(a, b, b_in_a, margin)?;
    let face_b = supporting_face_in_a(b, b_in_a, -axis.normal);
    if let Shape::Capsule(c) = a {
        if let Some(m) = capsule_on_face(c, &face_b, &axis, margin) {
            return Some(m);
        }
    }
    let id = ContactId {
        a: round_feature(a, &Iso::IDENTITY, axis.point_a, axis.normal),
        b: clip::closest_feature(&face_b, axis.point_b),
    };
    single_point(&axis, id, margin)
}

/// The one-point manifold at the GJK/EPA closest points.
fn single_point(axis: &Axis, id: ContactId, margin: f32) -> Option<LocalManifold> {
    let mut m = LocalManifold::new(axis.normal);
    m.push_within(
        Candidate::new(axis.point_a, axis.point_b, axis.normal, id),
        margin,
    );
    m.non_empty()
}

/// A capsule (A, local frame) on a face of B (A's frame): the capsule's segment clipped
/// against the face's side planes gives up to 2 points, each the segment point and its
/// projection on the face, along the face normal. `None` when the face is not aligned
/// with the axis, nothing is within `margin`, or the result fails [`plausible`].
fn capsule_on_face(c: &Capsule, face: &Face, axis: &Axis, margin: f32) -> Option<LocalManifold> {
    let aligned = -face.normal.dot(axis.normal) >= FACE_CONTACT_MIN_COS;
    if face.len < 3 || !aligned {
        return None;
    }
    let (s0, s1) = c.segment();
    let clipped = clip::clip_segment(
        face,
        s0,
        s1,
        [FeatureId::vertex(0), FeatureId::vertex(1)],
        FeatureId::edge(0, 1),
    );
    let normal = -face.normal;
    let f0 = face.vertices[0];
    let mut m = LocalManifold::new(normal);
    for v in clipped.vertices() {
        // Height (m) of the core point above the face plane.
        let h = (v.point - f0).dot(face.normal);
        let point_b = v.point - face.normal * h;
        let point_a = v.point + normal * c.radius;
        let id = ContactId {
            a: v.inc_id,
            b: v.ref_id,
        };
        m.push_within(Candidate::new(point_a, point_b, normal, id), margin);
    }
    plausible(&m, axis).then_some(m)
}

/// Two polytopes (B at `b_in_a`): face clipping when a face is aligned with the axis,
/// else one point.
fn polytope_vs_polytope(a: &Shape, b: &Shape, b_in_a: &Iso, margin: f32) -> Option<LocalManifold> {
    let axis = find_axis(a, b, b_in_a, margin)?;
    let face_a = a.supporting_face(axis.normal);
    let face_b = supporting_face_in_a(b, b_in_a, -axis.normal);
    if let Some(m) = face_contact(a, b, b_in_a, &face_a, &face_b, &axis, margin) {
        return Some(m);
    }
    let id = ContactId {
        a: clip::closest_feature(&face_a, axis.point_a),
        b: clip::closest_feature(&face_b, axis.point_b),
    };
    single_point(&axis, id, margin)
}

/// The clipped face manifold of two polytopes, or `None` when no face is aligned with the
/// axis within [`FACE_CONTACT_MIN_COS`] (edge contact) or clipping keeps nothing.
fn face_contact(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    face_a: &Face,
    face_b: &Face,
    axis: &Axis,
    margin: f32,
) -> Option<LocalManifold> {
    let cos_a = face_a.normal.dot(axis.normal);
    let cos_b = -face_b.normal.dot(axis.normal);
    let reference_is_a = cos_a + REFERENCE_FACE_TOLERANCE >= cos_b;
    let (reference, incident, cos) = if reference_is_a {
        let incident = supporting_face_in_a(b, b_in_a, -face_a.normal);
        (*face_a, incident, cos_a)
    } else {
        (*face_b, a.supporting_face(-face_b.normal), cos_b)
    };
    let aligned = cos >= FACE_CONTACT_MIN_COS; // false for NaN too
    if reference.len < 3 || !aligned {
        return None;
    }
    let clipped = clip::clip_polygon(&reference, &incident);
    let nr = reference.normal;
    let r0 = reference.vertices[0];
    let normal = if reference_is_a { nr } else { -nr };
    let mut candidates = [Candidate::default(); MAX_CLIP_POINTS];
    let mut count = 0usize;
    for v in clipped.vertices() {
        // Signed height (m) of the incident point above the reference plane.
        let h = (v.point - r0).dot(nr);
        let within = h <= margin;
        if !within {
            continue;
        }
        let on_reference = v.point - nr * h;
        let c = if reference_is_a {
            let id = ContactId {
                a: v.ref_id,
                b: v.inc_id,
            };
            Candidate::new(on_reference, v.point, normal, id)
        } else {
            let id = ContactId {
                a: v.inc_id,
                b: v.ref_id,
            };
            Candidate::new(v.point, on_reference, normal, id)
        };
        if let Some(slot) = candidates.get_mut(count) {
            *slot = c;
            count += 1;
        }
    }
    let m = LocalManifold::from_candidates(normal, candidates.get(..count).unwrap_or(&[]))?;
    plausible(&m, axis).then_some(m)
}
