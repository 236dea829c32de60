//! Contact manifolds: dispatch per shape pair, clipping of supporting faces, reduction to
//! at most 4 points.
//!
//! Every pair runs in A's frame (`b_in_a = pose_a⁻¹ ∘ pose_b`) and answers in the world
//! frame. Pairs are put in a canonical order first (half-space, sphere, capsule, then the
//! polytopes: cuboid, hull, triangle); a pair given the other way round is computed
//! swapped and flipped by [`flip`].
//!
//! - Closed forms ([`super::analytic`]): sphere and capsule pairs, half-space against
//!   anything, sphere against box and against a triangle.
//! - Box and hull pairs (box–box, box–hull, hull–hull) and a box or hull against a
//!   triangle: the separating axis test with the pair's cached axis first
//!   ([`super::sat`]; a triangle as a flat polytope), the incident face clipped against
//!   the reference face; capsule against box by the same test on the segment.
//! - Sphere against a hull, capsule against a hull or triangle: GJK on the cores, EPA when
//!   the cores overlap; a capsule lying on a face is clipped against the face's side
//!   planes (2 points).
//! - Every other polytope pair (two triangles), and the SAT pairs whose closest features the
//!   test cannot name exactly ([`super::sat::SatOutcome::Fallback`]): the general path,
//!   also available on its own as [`contact_gjk_epa`]. The axis from GJK (separated) or
//!   EPA (overlapping, seeded from GJK's simplex, so GJK runs once), then
//!   the reference face (the supporting face most aligned with the axis, on either shape)
//!   and the incident face (the other shape's face most anti-aligned with it), clipped
//!   against each other ([`super::clip`]) and reduced to at most 4 points. The manifold
//!   normal is the reference face's normal, so a box resting flat gets an exact normal.
//!   When no face is well aligned with the axis (an edge–edge contact), one point from the
//!   GJK/EPA closest points.

use super::analytic;
use super::check_pose;
use super::clip::{self, MAX_CLIP_POINTS};
use super::epa;
use super::gjk::{self, GjkStatus, SimplexCache, MAX_GJK_ITERATIONS};
use super::sat::{self, PairCache, SatOutcome, TrianglePolytope, SAT_TOLERANCE};
use super::Proxy;
use crate::error::{non_negative, Error, Input};
use crate::math::{scalar, Iso, Vec3};
use crate::shape::{Capsule, Face, FeatureId, Polygon, Shape, Sphere};
use core::cmp::Ordering;

/// Most points in a manifold.
pub const MAX_MANIFOLD_POINTS: usize = 4;

/// Tolerance of the general path's face choice, relative to the pair's scale
/// `|t| + r_A + r_B` (`t` B's position in A's frame, `r` the bounding radii), the same
/// relative tolerance as the separating axis test's ([`SAT_TOLERANCE`]): about 3e-5 m for
/// 1 m shapes.
///
/// A supporting face becomes the reference face (its normal the manifold's, its clipped
/// points the manifold's) only when its own separation, measured along its normal with
/// the other shape's support point, is within this of the GJK distance or −EPA depth: the
/// face then realises the minimal translation up to that tolerance, which is a few times
/// EPA's own (1e-5 of the Minkowski difference's size). And the clipped manifold's
/// deepest point must lie within it of the face's separation (else the deepest point is
/// outside the reference face's prism: a corner or edge over the face's rim). Otherwise
/// the contact is an edge or vertex contact and gets one point, at GJK's or EPA's
/// witnesses along their normal. So the deepest point always agrees with the minimal
/// depth to about twice this tolerance. (This replaces a normal snapped to any face
/// within 26° of the axis, kept when it agreed within 1 mm + 0.2 %: on overlapping hull
/// pairs that reported depths up to 2.2 mm deeper than the minimal one.)
pub(crate) const GENERAL_FACE_TOLERANCE: f32 = SAT_TOLERANCE;

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
    /// True when the deepest separation stands on an upper bound of the penetration depth,
    /// not on the exact minimal one: EPA stopped at a bound (a Minkowski difference too
    /// thin to expand, such as a core just touching a nearly flat hull, or its caps; see
    /// [`EpaStatus`](super::EpaStatus)). The bound is never shallower than the exact depth.
    pub depth_bound: bool,
}

impl Manifold {
    /// The points in use.
    pub fn points(&self) -> &[ManifoldPoint] {
        self.points.get(..self.len as usize).unwrap_or(&self.points)
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
///
/// The same as [`contact_cached`] with a fresh cache.
///
/// # Examples
///
/// ```
/// use carom::collide::contact;
/// use carom::{Iso, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?;
/// let ball = Shape::sphere(0.5)?;
/// let ground_pose = Iso::from_position(Vec3::new(0.0, -0.5, 0.0)); // top face at y = 0
/// let ball_pose = Iso::from_position(Vec3::new(0.0, 0.49, 0.0)); // 1 cm deep
/// let m = contact(&ground, &ground_pose, &ball, &ball_pose, 0.02)?.expect("touching");
/// assert_eq!(m.points().len(), 1);
/// assert!((m.normal - Vec3::Y).length() < 1e-6); // from the ground (A) to the ball (B)
/// assert!((m.min_separation() + 0.01).abs() < 1e-5); // negative: penetrating
///
/// // 5 cm apart: outside the 2 cm margin.
/// let above = Iso::from_position(Vec3::new(0.0, 0.55, 0.0));
/// assert!(contact(&ground, &ground_pose, &ball, &above, 0.02)?.is_none());
/// # Ok(())
/// # }
/// ```
pub fn contact(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Result<Option<Manifold>, Error> {
    contact_cached(a, pose_a, b, pose_b, margin, &mut PairCache::default())
}

/// [`contact`] for a pair queried again and again (once per step): box and hull pairs try
/// the axis in `cache` first and store the axis the test ended on (see [`PairCache`]). The
/// result never depends on the cache: a fresh, stale or garbage cache gives the same
/// manifold, bit for bit; only the time differs. Fails like [`contact`].
pub fn contact_cached(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    cache: &mut PairCache,
) -> Result<Option<Manifold>, Error> {
    check_inputs(a, pose_a, b, pose_b, margin)?;
    // Built in the result, not in a local moved into it at the end (the compiler made two
    // copies of that). It still builds the result in a local of its own and copies it out
    // once, about 256 bytes: [`contact_into`] writes in place.
    let mut result = Ok(Some(Manifold::default()));
    let found = match &mut result {
        Ok(Some(m)) => dispatch(a, pose_a, b, pose_b, margin, Route::Fast(cache), m),
        _ => false,
    };
    if !found {
        result = Ok(None);
    }
    result
}

/// [`contact_cached`] into the caller's manifold: true when the shapes are within
/// `margin`, with the manifold in `out` (the same one, bit for bit); false when they are
/// further apart, with `out.len` 0 (its other fields unspecified). A returned manifold is
/// copied out once (about 256 bytes, 14 % of a sphere–box query on x86_64); a caller that
/// keeps one to fill, such as a loop over many pairs or firmware, saves that copy. Fails
/// like [`contact`], with `out` unchanged.
///
/// # Examples
///
/// ```
/// use carom::collide::{contact_into, Manifold, PairCache};
/// use carom::{Iso, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?;
/// let ball = Shape::sphere(0.5)?;
/// let ground_pose = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
/// let mut m = Manifold::default();
/// let mut cache = PairCache::default();
/// for height in [0.49, 0.55] {
///     let ball_pose = Iso::from_position(Vec3::new(0.0, height, 0.0));
///     let touching = contact_into(&ground, &ground_pose, &ball, &ball_pose, 0.02, &mut cache, &mut m)?;
///     assert_eq!(touching, height < 0.5);
///     assert_eq!(m.points().len(), usize::from(touching));
/// }
/// # Ok(())
/// # }
/// ```
pub fn contact_into(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    cache: &mut PairCache,
    out: &mut Manifold,
) -> Result<bool, Error> {
    check_inputs(a, pose_a, b, pose_b, margin)?;
    let found = dispatch(a, pose_a, b, pose_b, margin, Route::Fast(cache), out);
    if !found {
        out.len = 0;
    }
    Ok(found)
}

/// The checks at the door of [`contact`] and its kin: valid poses, convex shapes, a
/// finite margin `>= 0`. Inputs that pass every check (nearly all) are told apart in one
/// branch ([`super::pose_passes`]; the margin's compares are false for NaN and `+∞`); the
/// others go through the checks one by one for the first failure's error. (The checks
/// one by one were a fifth of a sphere–box query's instructions.)
#[inline]
fn check_inputs(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Result<(), Error> {
    let margin_ok = (0.0..=f32::MAX).contains(&margin);
    let shapes_ok = a.is_convex() & b.is_convex();
    if super::pose_passes(pose_a) & super::pose_passes(pose_b) & shapes_ok & margin_ok {
        return Ok(());
    }
    first_input_error(a, pose_a, b, pose_b, margin)
}

/// [`check_inputs`] one check at a time: the first failure's error (`Ok` only if every
/// check passes, which the caller has ruled out).
#[cold]
fn first_input_error(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Result<(), Error> {
    check_pose(pose_a)?;
    check_pose(pose_b)?;
    a.check_convex()?;
    b.check_convex()?;
    non_negative(margin, Input::Distance)?;
    Ok(())
}

/// The general path of [`contact`] for every pair, without the separating axis test and
/// the sphere–box, sphere–triangle and capsule–box closed forms: GJK, EPA when the shapes overlap, then
/// face clipping or one point (module docs). Slower; kept as the reference the fast paths
/// are tested against. Fails like [`contact`].
pub fn contact_gjk_epa(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Result<Option<Manifold>, Error> {
    check_inputs(a, pose_a, b, pose_b, margin)?;
    let mut m = Manifold::default();
    let found = dispatch(a, pose_a, b, pose_b, margin, Route::General, &mut m);
    Ok(found.then_some(m))
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
    /// The depth is EPA's bound, not exact ([`Manifold::depth_bound`]).
    pub depth_bound: bool,
}

impl LocalManifold {
    /// An empty manifold with the given normal.
    pub fn new(normal: Vec3) -> LocalManifold {
        LocalManifold {
            normal,
            len: 0,
            points: [Candidate::default(); MAX_MANIFOLD_POINTS],
            depth_bound: false,
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
        m.fill_from_candidates(normal, candidates).then_some(m)
    }

    /// [`LocalManifold::from_candidates`] in place: `self` is reset to `normal` and filled;
    /// false when there are no candidates.
    pub fn fill_from_candidates(&mut self, normal: Vec3, candidates: &[Candidate]) -> bool {
        self.normal = normal;
        self.len = 0;
        if candidates.len() <= MAX_MANIFOLD_POINTS {
            for c in candidates {
                self.push_within(*c, f32::INFINITY);
            }
        } else {
            let (chosen, count) = clip::reduce_to_four(candidates, normal);
            for &i in chosen.iter().take(count) {
                if let Some(c) = candidates.get(i) {
                    self.push_within(*c, f32::INFINITY);
                }
            }
        }
        self.len > 0
    }

    /// Reset to an empty manifold with the given normal.
    pub fn reset(&mut self, normal: Vec3) {
        self.normal = normal;
        self.len = 0;
    }

    /// The smallest separation (m); `+∞` when empty.
    pub fn min_separation(&self) -> f32 {
        let mut s = f32::INFINITY;
        for c in self.points() {
            s = scalar::min(s, c.separation);
        }
        s
    }
}

/// [`contact_cached`] without input checks (poses finite with unit rotations, margin
/// finite and `>= 0`). Never panics; a manifold that would hold a non-finite number (only
/// for coordinates near `f32::MAX`) is dropped.
pub(crate) fn contact_cached_unchecked(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    cache: &mut PairCache,
) -> Option<Manifold> {
    let mut m = Manifold::default();
    dispatch(a, pose_a, b, pose_b, margin, Route::Fast(cache), &mut m).then_some(m)
}

/// Which narrow phase runs: the fast paths (with the pair's cache) or the general one.
enum Route<'c> {
    Fast(&'c mut PairCache),
    General,
}

/// Put the pair in canonical order, run it, flip back; the manifold is written to `out`
/// (true when there is one). Written through one `&mut` rather than returned level by
/// level: a manifold is about 300 bytes.
///
/// The canonical order is by rank ([`order_rank`]), and two polytopes are put in the
/// order [`polytope_order`] gives (the larger first, whose face the tie rule prefers and
/// whose frame then gives its normal exactly; then geometry and poses) for the fast paths
/// as well as the general one: the separating axis test's tie rule cannot tell two copies of one shape
/// apart when faces of the same index tie, and with faces preferred to slightly
/// shallower edge pairs (`sat::EDGE_DEPTH_PREFERENCE`) such ties are common between
/// equal boxes. In one order, `contact(B, A)` is `contact(A, B)` flipped, to the bit.
fn dispatch(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    route: Route,
    out: &mut Manifold,
) -> bool {
    out.depth_bound = false;
    let (rank_a, rank_b) = (order_rank(a), order_rank(b));
    let swap = rank_b < rank_a
        || (rank_a == 3 && rank_b == 3 && polytope_order(b, pose_b, a, pose_a) == Ordering::Less);
    if swap {
        let found = contact_ordered(b, pose_b, a, pose_a, margin, route, out);
        if found {
            flip(out);
        }
        found
    } else {
        contact_ordered(a, pose_a, b, pose_b, margin, route, out)
    }
}

/// The order of two polytopes with their poses for the fast paths: the larger extent
/// (largest core coordinate, as the separating axis test measures it) first, then
/// [`pair_order`]. Independent of which was called A.
fn polytope_order(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> Ordering {
    let extent = |s: &Shape| match s {
        Shape::Cuboid(c) => c.half_extents.max_elem(),
        Shape::Hull(h) => h.tolerance() / crate::shape::ConvexHull::TOLERANCE,
        Shape::Triangle(t) => {
            let [u, v, w] = t.vertices;
            u.abs().max(v.abs()).max(w.abs()).max_elem()
        }
        _ => 0.0,
    };
    extent(b)
        .total_cmp(&extent(a))
        .then_with(|| pair_order(a, pose_a, b, pose_b))
}

/// Canonical order of a pair: the shape with the lower rank is A. Half-space 0, sphere 1,
/// capsule 2, polytopes 3 (any order among themselves).
fn order_rank(s: &Shape) -> u8 {
    match s {
        Shape::HalfSpace(_) => 0,
        Shape::Sphere(_) => 1,
        Shape::Capsule(_) => 2,
        Shape::Cuboid(_) | Shape::Hull(_) | Shape::Triangle(_) => 3,
        // Never in the narrow phase (its doors refuse them); ranked last to stay total.
        Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => 4,
    }
}

/// Two spheres at their world poses, in closed form in the world frame, in either order:
/// the normal from `a` to `b` and the one point, or `None` when they are apart by more
/// than `margin` (the numbers are not checked for finiteness). Rotations are
/// renormalised first, as every pair's are. Coincident centres take world +Y from the
/// pair's canonical A to its B (as the general path does), so both orders agree: the
/// answer of `(b, a)` is that of `(a, b)` flipped, to the bit. [`contact`] gives the same
/// point (the dynamics' sphere pairs call this directly).
#[inline]
pub(crate) fn sphere_pair(
    a: &Sphere,
    pose_a: &Iso,
    b: &Sphere,
    pose_b: &Iso,
    margin: f32,
) -> Option<(Vec3, ManifoldPoint)> {
    let pose_a = Iso::new(pose_a.position, pose_a.rotation.normalize());
    let pose_b = Iso::new(pose_b.position, pose_b.rotation.normalize());
    let fallback = || {
        let (sa, sb) = (Shape::Sphere(*a), Shape::Sphere(*b));
        if pair_order(&sb, &pose_b, &sa, &pose_a) == Ordering::Less {
            -Vec3::Y
        } else {
            Vec3::Y
        }
    };
    analytic::sphere_sphere_point(a, &pose_a, b, &pose_b, fallback, margin)
}

/// The manifold of a pair already in canonical order, in the world frame. Rotations are
/// renormalised first: A's, and the relative rotation `b_in_a` (or B's own, when B's pose
/// is used as it is).
fn contact_ordered(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    mut route: Route,
    out: &mut Manifold,
) -> bool {
    let unit_a = pose_a.rotation.normalize();
    if let (Shape::Sphere(s), Shape::Cuboid(c), Route::Fast(cache)) = (a, b, &mut route) {
        // Closed form in the box's frame, world frame in and out (no A-frame round trip).
        **cache = PairCache::default();
        let pose_a = Iso::new(pose_a.position, unit_a);
        let pose_b = Iso::new(pose_b.position, pose_b.rotation.normalize());
        return analytic::sphere_cuboid(s, &pose_a, c, &pose_b, margin, out);
    }
    if let (Shape::Sphere(sa), Shape::Sphere(sb), Route::Fast(cache)) = (a, b, &mut route) {
        **cache = PairCache::default();
        return match sphere_pair(sa, pose_a, sb, pose_b, margin) {
            Some((normal, point)) => analytic::write_one_point(normal, point, out),
            None => false,
        };
    }
    if let (Shape::Sphere(s), Shape::Triangle(t), Route::Fast(cache)) = (a, b, &mut route) {
        // Closed form in the triangle's frame, like the box's.
        **cache = PairCache::default();
        let pose_a = Iso::new(pose_a.position, unit_a);
        let pose_b = Iso::new(pose_b.position, pose_b.rotation.normalize());
        return analytic::sphere_triangle(s, &pose_a, t, &pose_b, margin, out);
    }
    let (unit_pose_a, b_in_a) = relative(pose_a, unit_a, pose_b);
    let mut local = LocalManifold::new(Vec3::Y);
    let outcome = match route {
        Route::Fast(cache) => fast_path(a, b, &b_in_a, margin, cache, &mut local),
        Route::General => SatOutcome::Fallback,
    };
    match outcome {
        SatOutcome::Separated => false,
        SatOutcome::Contact => to_world(&local, &unit_pose_a, &b_in_a, margin, out),
        SatOutcome::Fallback => general_in_canonical_order(a, pose_a, b, pose_b, margin, out),
    }
}

/// A's pose with its rotation `unit_a` (the given one, normalised) and B in A's frame: the
/// relative rotation `qa* qb` from the given rotations, renormalised (so its scale does
/// not wait for A's renormalisation), the position by A's unit rotation.
fn relative(pose_a: &Iso, unit_a: crate::math::Quat, pose_b: &Iso) -> (Iso, Iso) {
    let b_in_a = Iso::new(
        unit_a.inverse_rotate(pose_b.position - pose_a.position),
        (pose_a.rotation.conjugate() * pose_b.rotation).normalize(),
    );
    (Iso::new(pose_a.position, unit_a), b_in_a)
}

/// The general path ([`general`]) of a pair in canonical rank order, world frame in and
/// out. Two shapes of the same rank (two polytopes, two capsules, two spheres) are
/// computed in a canonical order of their own, the one [`pair_order`] puts first as A,
/// and flipped back when that is B: GJK, EPA, the closed forms and the face choice then
/// see the same pair the same way whichever order the caller gave, so `contact(B, A)` is
/// `contact(A, B)` with the normal negated and the sides swapped, to the bit. (Each order
/// run in its own frame disagreed by rounding, by whole faces where two faces or EPA axes
/// tie within the tolerances, and for two nearly coaxial capsules by the ill-conditioned
/// normal of their segments' closest points: fuzz finding `bd34b9f7`.)
fn general_in_canonical_order(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    out: &mut Manifold,
) -> bool {
    let same_rank = order_rank(a) == order_rank(b);
    if same_rank && pair_order(b, pose_b, a, pose_a) == Ordering::Less {
        let found = general_in_world(b, pose_b, a, pose_a, margin, out);
        if found {
            flip(out);
        }
        found
    } else {
        general_in_world(a, pose_a, b, pose_b, margin, out)
    }
}

/// [`general`] for `a` at `pose_a` and `b` at `pose_b` (world frame, rotations as given),
/// into `out`.
fn general_in_world(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    out: &mut Manifold,
) -> bool {
    let (pose_a, b_in_a) = relative(pose_a, pose_a.rotation.normalize(), pose_b);
    // Fallback normal for coincident centres or crossing segments: world +Y, from the
    // pair's canonical A (see `general_in_canonical_order`) to its B.
    let up_in_a = || {
        pose_a
            .inverse_transform_vector(Vec3::Y)
            .normalize_or(Vec3::Y)
    };
    match general(a, b, &b_in_a, up_in_a, margin) {
        Some(local) => to_world(&local, &pose_a, &b_in_a, margin, out),
        None => false,
    }
}

/// A total order of two shapes of the same rank with their poses that does not depend on
/// which is called A: by kind (cuboid, hull, triangle; sphere; capsule), then by their
/// geometry (half-extents, hull vertices, triangle vertices, radius, half-height and
/// radius, by `total_cmp`), then by their world poses (position, then rotation). Equal
/// only for the same geometry at the same pose, where both orders of the pair are the same
/// query.
fn pair_order(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> Ordering {
    let kind = |s: &Shape| match s {
        Shape::Cuboid(_) => 0u8,
        Shape::Hull(_) => 1,
        Shape::Triangle(_) => 2,
        Shape::Sphere(_) => 3,
        Shape::Capsule(_) => 4,
        Shape::HalfSpace(_) => 5,
        Shape::Mesh(_) => 6,
        Shape::HeightField(_) => 8,
        Shape::Compound(_) => 7,
    };
    // Lazily: each comparison only when the ones before it tie.
    let vec = |u: Vec3, v: Vec3| {
        u.x.total_cmp(&v.x)
            .then_with(|| u.y.total_cmp(&v.y))
            .then_with(|| u.z.total_cmp(&v.z))
    };
    let points = |p: &[Vec3], q: &[Vec3]| {
        let mut o = p.len().cmp(&q.len());
        for (u, v) in p.iter().zip(q) {
            if o != Ordering::Equal {
                break;
            }
            o = vec(*u, *v);
        }
        o
    };
    let geometry = match (a, b) {
        (Shape::Sphere(x), Shape::Sphere(y)) => x.radius.total_cmp(&y.radius),
        (Shape::Capsule(x), Shape::Capsule(y)) => x
            .half_height
            .total_cmp(&y.half_height)
            .then(x.radius.total_cmp(&y.radius)),
        (Shape::Cuboid(x), Shape::Cuboid(y)) => vec(x.half_extents, y.half_extents),
        (Shape::Hull(x), Shape::Hull(y)) => points(x.vertices(), y.vertices()),
        (Shape::Triangle(x), Shape::Triangle(y)) => points(&x.vertices, &y.vertices),
        _ => kind(a).cmp(&kind(b)),
    };
    let (qa, qb) = (pose_a.rotation, pose_b.rotation);
    geometry
        .then_with(|| vec(pose_a.position, pose_b.position))
        .then_with(|| vec(qa.xyz(), qb.xyz()))
        .then_with(|| qa.w.total_cmp(&qb.w))
}

/// The general path of a pair in canonical order (module docs), in A's frame: closed
/// forms for half-spaces and round pairs, GJK/EPA for the rest. `up_in_a` gives the
/// fallback normal (world +Y) where a closed form needs one.
fn general(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    up_in_a: impl Fn() -> Vec3,
    margin: f32,
) -> Option<LocalManifold> {
    match (a, b) {
        (Shape::HalfSpace(plane), _) => analytic::half_space_contact(plane, b, b_in_a, margin),
        (Shape::Sphere(sa), Shape::Sphere(sb)) => {
            analytic::sphere_sphere(sa, sb, b_in_a, up_in_a(), margin)
        }
        (Shape::Sphere(sa), Shape::Capsule(cb)) => {
            analytic::sphere_capsule(sa, cb, b_in_a, up_in_a(), margin)
        }
        (Shape::Capsule(ca), Shape::Capsule(cb)) => {
            analytic::capsule_capsule(ca, cb, b_in_a, up_in_a(), margin)
        }
        (Shape::Sphere(_) | Shape::Capsule(_), _) => round_vs_polytope(a, b, b_in_a, margin),
        _ => polytope_vs_polytope(a, b, b_in_a, margin),
    }
}

/// The fast paths of a pair in canonical order (sphere–box and sphere–triangle are taken
/// before, in [`contact_ordered`]): capsule–box, the box and hull pairs and a box or hull
/// against a triangle by the separating axis test, the manifold written to `out`; [`SatOutcome::Fallback`] for every other pair and
/// when a test cannot answer exactly. The cache is used by the box and hull pairs only,
/// and reset for every other pair. Out of line, with the shape pairs' tests it calls:
/// their buffers take stack only under the pair that needs them (on a Cortex-M4F a box
/// pair's manifold took 14.2 KiB of stack while the hull tables were inlined here, 7.3
/// KiB since).
#[inline(never)]
fn fast_path(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    margin: f32,
    cache: &mut PairCache,
    out: &mut LocalManifold,
) -> SatOutcome {
    let closed = |h: &crate::shape::ConvexHull| h.is_closed();
    match (a, b) {
        (Shape::Cuboid(ca), Shape::Cuboid(cb)) => sat::cuboids(ca, cb, b_in_a, margin, cache, out),
        (Shape::Cuboid(ca), Shape::Hull(hb)) if closed(hb) => {
            sat::polytopes(ca, *hb, b_in_a, margin, cache, out)
        }
        (Shape::Hull(ha), Shape::Cuboid(cb)) if closed(ha) => {
            sat::polytopes(*ha, cb, b_in_a, margin, cache, out)
        }
        (Shape::Hull(ha), Shape::Hull(hb)) if closed(ha) && closed(hb) => {
            sat::polytopes(*ha, *hb, b_in_a, margin, cache, out)
        }
        // A triangle (a mesh or height-field part) against a box or a hull.
        (Shape::Cuboid(ca), Shape::Triangle(tb)) => {
            sat::polytopes(ca, &TrianglePolytope::new(tb), b_in_a, margin, cache, out)
        }
        (Shape::Triangle(ta), Shape::Cuboid(cb)) => {
            sat::polytopes(&TrianglePolytope::new(ta), cb, b_in_a, margin, cache, out)
        }
        (Shape::Hull(ha), Shape::Triangle(tb)) if closed(ha) => {
            sat::polytopes(*ha, &TrianglePolytope::new(tb), b_in_a, margin, cache, out)
        }
        (Shape::Triangle(ta), Shape::Hull(hb)) if closed(hb) => {
            sat::polytopes(&TrianglePolytope::new(ta), *hb, b_in_a, margin, cache, out)
        }
        _ => {
            *cache = PairCache::default();
            match (a, b) {
                (Shape::Capsule(c), Shape::Cuboid(cb)) => {
                    sat::capsule_cuboid(c, cb, b_in_a, margin, out)
                }
                (Shape::Capsule(c), Shape::Triangle(t)) => {
                    sat::capsule_triangle(c, t, b_in_a, margin, out)
                }
                _ => SatOutcome::Fallback,
            }
        }
    }
}

/// Move an A-frame manifold into the world, into `m`: normal and points by `pose_a`, B's
/// local points by `b_in_a⁻¹`. Points with a non-finite coordinate or a separation beyond
/// `margin` are dropped; false when nothing is left or the normal is not a unit vector.
fn to_world(
    local: &LocalManifold,
    pose_a: &Iso,
    b_in_a: &Iso,
    margin: f32,
    m: &mut Manifold,
) -> bool {
    let Some((normal, _)) = pose_a.transform_vector(local.normal).normalize_and_length() else {
        return false;
    };
    m.normal = normal;
    m.depth_bound = local.depth_bound;
    // Rotation matrices: a manifold moves up to 12 points and vectors.
    let ra = sat::rotation_matrix(pose_a.rotation);
    let rb = sat::rotation_matrix(b_in_a.rotation);
    let mut len = 0usize;
    for c in local.points() {
        let p = ManifoldPoint {
            point_a: ra.mul_vec(c.point_a) + pose_a.position,
            point_b: ra.mul_vec(c.point_b) + pose_a.position,
            local_a: c.point_a,
            local_b: rb.transpose_mul_vec(c.point_b - b_in_a.position),
            separation: c.separation,
            id: c.id,
        };
        // `&`, not `&&`: the points are nearly always finite, so every check runs anyway,
        // and one branch replaces four.
        let finite = p.point_a.is_finite()
            & p.point_b.is_finite()
            & p.local_b.is_finite()
            & p.separation.is_finite();
        if finite & (p.separation <= margin) {
            if let Some(slot) = m.points.get_mut(len) {
                *slot = p;
                len += 1;
            }
        }
    }
    m.len = len as u8;
    len > 0
}

/// The manifold of (B, A) from the one of (A, B), in place: normal negated, the two sides
/// of every point (world points, local points, feature ids) swapped; separations
/// unchanged.
pub(crate) fn flip(out: &mut Manifold) {
    out.normal = -out.normal;
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
}

/// The contact axis of two shapes in A's frame: unit normal from A to B, the signed
/// separation along it (m) and the closest (or deepest) points on each surface.
#[derive(Clone, Copy, Debug)]
struct Axis {
    normal: Vec3,
    separation: f32,
    point_a: Vec3,
    point_b: Vec3,
    /// The separation is EPA's bound on the depth, not exact.
    bounded: bool,
}

/// GJK on the cores; when they are further apart than `margin`, `None`; when the full
/// shapes overlap (or touch), EPA. Written so that a NaN from either gives `None`.
///
/// GJK runs once: its answer gives the distance (as [`super::distance`] would) and its
/// final simplex seeds EPA (as [`super::penetration`] would, which runs the same GJK
/// again), so both answers are the public queries' to the bit.
fn find_axis(a: &Shape, b: &Shape, b_in_a: &Iso, margin: f32) -> Option<Axis> {
    let pa = Proxy::at_origin(a);
    let pb = Proxy::new(b, *b_in_a);
    let mut cache = SimplexCache::default();
    let core = gjk::gjk_cores(&pa, &pb, &mut cache, MAX_GJK_ITERATIONS);
    let d = gjk::finite_or_fallback(
        gjk::inflate(&core, a.radius(), b.radius()),
        Vec3::ZERO,
        b_in_a.position,
    );
    if d.status != GjkStatus::Overlapping && d.distance > 0.0 {
        let within = d.distance <= margin; // false for NaN too
        if !within {
            return None;
        }
        if core.ambiguous {
            // Apart by less than the rounding of GJK's direction (a vertex or an edge of
            // `D` at the origin, see `gjk::GJK_DIRECTION_TOLERANCE`): EPA on the touching
            // cores gives the normal, a face normal of `D`; the separation stays GJK's.
            let n = epa::touching_normal(&pa, &pb, &core, epa::EpaCaps::DEFAULT);
            let usable = n
                .normalize_and_length()
                .filter(|(n, _)| n.dot(d.normal) > 0.0);
            if let Some((normal, _)) = usable {
                return finite_axis(Axis {
                    normal,
                    separation: (d.point_b - d.point_a).dot(normal),
                    point_a: d.point_a,
                    point_b: d.point_b,
                    bounded: false,
                });
            }
        }
        let (normal, _) = d.normal.normalize_and_length()?;
        return finite_axis(Axis {
            normal,
            separation: d.distance,
            point_a: d.point_a,
            point_b: d.point_b,
            bounded: false,
        });
    }
    match epa::penetration_from_gjk(&pa, &pb, &core, epa::EpaCaps::DEFAULT) {
        Some(p) => {
            let (normal, _) = p.normal.normalize_and_length()?;
            finite_axis(Axis {
                normal,
                separation: -p.depth,
                point_a: p.point_a,
                point_b: p.point_b,
                bounded: p.status != epa::EpaStatus::Converged,
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
                bounded: false,
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

/// The face choice's tolerance for a pair (see [`GENERAL_FACE_TOLERANCE`]).
fn face_tolerance(a: &Shape, b: &Shape, b_in_a: &Iso) -> f32 {
    GENERAL_FACE_TOLERANCE * (b_in_a.position.length() + a.bounding_radius() + b.bounding_radius())
}

/// The separation of two shapes along a face's normal: `n · p − n · f₀` with `n` the
/// face's outward unit normal, `f₀` one of its vertices and `p` the other shape's support
/// point along `−n` (radius included), all in A's frame. `None` for a face that is not a
/// polygon (an edge or a vertex). For A's face this is the separation along `n`, for B's
/// along `−n`: either way from A towards B.
fn face_separation(face: &Face, other_support: impl Fn(Vec3) -> Vec3) -> Option<f32> {
    if face.len < 3 {
        return None;
    }
    let n = face.normal;
    Some(n.dot(other_support(-n)) - n.dot(face.vertices[0]))
}

/// B's support point (radius included) along `dir` (A's frame), in A's frame.
fn support_in_a(shape: &Shape, shape_in_a: &Iso, dir: Vec3) -> Vec3 {
    shape_in_a.transform_point(shape.support(shape_in_a.inverse_transform_vector(dir)))
}

/// Sphere or capsule `a` against polytope `b` (B at `b_in_a`).
fn round_vs_polytope(a: &Shape, b: &Shape, b_in_a: &Iso, margin: f32) -> Option<LocalManifold> {
    on_axis(a, b, b_in_a, margin, round_vs_polytope_on)
}

/// The manifold `build` makes on the pair's axis ([`find_axis`]), flagged
/// [`LocalManifold::depth_bound`] when that axis stands on EPA's bound.
fn on_axis(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    margin: f32,
    build: fn(&Shape, &Shape, &Iso, f32, &Axis) -> Option<LocalManifold>,
) -> Option<LocalManifold> {
    let axis = find_axis(a, b, b_in_a, margin)?;
    build(a, b, b_in_a, margin, &axis).map(|m| LocalManifold {
        depth_bound: axis.bounded,
        ..m
    })
}

/// [`round_vs_polytope`] on the axis found.
fn round_vs_polytope_on(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    margin: f32,
    axis: &Axis,
) -> Option<LocalManifold> {
    let face_b = supporting_face_in_a(b, b_in_a, -axis.normal);
    if let Shape::Capsule(c) = a {
        let tol = face_tolerance(a, b, b_in_a);
        let s_face = face_separation(&face_b, |d| a.support(d));
        if let Some(m) = capsule_on_face(c, &face_b, s_face, axis, tol, margin) {
            return Some(m);
        }
    }
    let id = ContactId {
        a: round_feature(a, &Iso::IDENTITY, axis.point_a, axis.normal),
        b: clip::closest_feature(&face_b, axis.point_b),
    };
    single_point(axis, id, margin)
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
/// projection on the face, along the face normal. `None` when the face's separation
/// `s_face` ([`face_separation`]) is not within `tol` of the axis's (the face does not
/// realise the minimal translation), nothing is within `margin`, or the deepest point is
/// more than `tol` shallower than `s_face` (see [`GENERAL_FACE_TOLERANCE`]).
fn capsule_on_face(
    c: &Capsule,
    face: &Face,
    s_face: Option<f32>,
    axis: &Axis,
    tol: f32,
    margin: f32,
) -> Option<LocalManifold> {
    let s_face = s_face?;
    let realises = s_face >= axis.separation - tol; // false for NaN too
    if face.len < 3 || !realises {
        return None;
    }
    let (s0, s1) = c.segment();
    let (mut front, mut back) = (clip::ClipPolygon::new(), clip::ClipPolygon::new());
    let mut buffers = clip::ClipBuffers::new(&mut front, &mut back);
    let clipped = buffers.segment(
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
    (m.len > 0 && m.min_separation() <= s_face + tol).then_some(m)
}

/// Two polytopes (B at `b_in_a`): face clipping when a face is aligned with the axis,
/// else one point.
fn polytope_vs_polytope(a: &Shape, b: &Shape, b_in_a: &Iso, margin: f32) -> Option<LocalManifold> {
    on_axis(a, b, b_in_a, margin, polytope_vs_polytope_on)
}

/// [`polytope_vs_polytope`] on the axis found.
fn polytope_vs_polytope_on(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    margin: f32,
    axis: &Axis,
) -> Option<LocalManifold> {
    let face_a = a.supporting_face(axis.normal);
    let face_b = supporting_face_in_a(b, b_in_a, -axis.normal);
    if let Some(m) = face_contact(a, b, b_in_a, &face_a, &face_b, axis, margin) {
        return Some(m);
    }
    let id = ContactId {
        a: clip::closest_feature(&face_a, axis.point_a),
        b: clip::closest_feature(&face_b, axis.point_b),
    };
    single_point(axis, id, margin)
}

/// The clipped face manifold of two polytopes, or `None` when neither supporting face
/// realises the axis's separation within the tolerance (an edge or vertex contact), or
/// the clipped manifold's deepest point is not on the face's separation (see
/// [`GENERAL_FACE_TOLERANCE`]). Both faces qualifying, A's is the reference unless B's
/// separates more by more than the tolerance; the pair's order is canonical (see
/// [`general_in_canonical_order`]), so this tie rule does not depend on the order the
/// caller gave.
fn face_contact(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    face_a: &Face,
    face_b: &Face,
    axis: &Axis,
    margin: f32,
) -> Option<LocalManifold> {
    let tol = face_tolerance(a, b, b_in_a);
    let floor = axis.separation - tol;
    let s_a = face_separation(face_a, |d| support_in_a(b, b_in_a, d)).filter(|s| *s >= floor);
    let s_b = face_separation(face_b, |d| a.support(d)).filter(|s| *s >= floor);
    let (reference_is_a, s_ref) = match (s_a, s_b) {
        (Some(sa), Some(sb)) if sb > sa + tol => (false, sb),
        (Some(sa), _) => (true, sa),
        (None, Some(sb)) => (false, sb),
        (None, None) => return None,
    };
    let (reference, incident) = if reference_is_a {
        (*face_a, supporting_face_in_a(b, b_in_a, -face_a.normal))
    } else {
        (*face_b, a.supporting_face(-face_b.normal))
    };
    let mut m = LocalManifold::new(axis.normal);
    let found = clipped_face_manifold(&reference, &incident, reference_is_a, margin, &mut m);
    (found && m.min_separation() <= s_ref + tol).then_some(m)
}

/// The face manifold of a reference face and an incident face (both in A's frame; the
/// reference on A when `reference_is_a`): the incident face clipped against the reference
/// face's side planes, every point within `margin` of the reference plane paired with its
/// projection on it, reduced to at most 4 ([`LocalManifold::from_candidates`]). The
/// normal is the reference face's (turned from A towards B); ids pair the reference and
/// incident features of each point. Written to `out`; false when the reference face is
/// not a polygon or nothing is within the margin.
pub(crate) fn clipped_face_manifold(
    reference: &impl Polygon,
    incident: &impl Polygon,
    reference_is_a: bool,
    margin: f32,
    out: &mut LocalManifold,
) -> bool {
    let (&[r0, _, _, ..], nr) = (reference.points(), reference.normal()) else {
        return false;
    };
    let (mut front, mut back) = (clip::ClipPolygon::new(), clip::ClipPolygon::new());
    let mut buffers = clip::ClipBuffers::new(&mut front, &mut back);
    let clipped = buffers.polygon(reference, incident);
    let normal = if reference_is_a { nr } else { -nr };
    let mut candidates: heapless::Vec<Candidate, MAX_CLIP_POINTS> = heapless::Vec::new();
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
        // Cannot be full: one candidate per clipped vertex.
        let _ = candidates.push(c);
    }
    out.fill_from_candidates(normal, &candidates)
}
