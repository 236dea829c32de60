//! World queries: ray casts and shape overlap, filtered by group and mask.
//!
//! Queries read the world as it is now (the poses after the last step or setter) and
//! change nothing. Each body is culled by its shape's bounding box at its current pose
//! (a slab test for rays, a box overlap for shapes) before the exact test. Work is one
//! pass over the bodies in slot order, so it is bounded by the world's capacity.
//!
//! A query acts like a body in the groups `filter.group` that collides with the groups
//! `filter.mask`: it sees a body when `filter.group & body.mask != 0` and
//! `body.group & filter.mask != 0` (the pair rule of the step), and sensors only when
//! `filter.include_sensors`. [`QueryFilter::default`] has every bit set in both, so it
//! sees every body except those with a zero group or a zero mask.

use crate::collide::{check_pose, distance_in_a, SimplexCache};
use crate::dynamics::body::Body;
use crate::dynamics::mid_phase;
use crate::dynamics::pool::BodyHandle;
use crate::error::{finite_vec, non_negative, Error, Input};
use crate::math::{scalar, Aabb, Iso, Vec3};
use crate::shape::{HalfSpace, Ray, Shape};
use crate::world::World;

/// Which bodies a query sees; see the module docs for the rule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct QueryFilter {
    /// The groups the query is in: a body is seen only if `group & body.mask != 0`.
    pub group: u32,
    /// The groups the query sees: a body is seen only if `body.group & mask != 0`.
    pub mask: u32,
    /// Whether sensors are seen.
    pub include_sensors: bool,
}

impl QueryFilter {
    /// Every group, every mask, sensors included.
    pub const ALL: QueryFilter = QueryFilter {
        group: u32::MAX,
        mask: u32::MAX,
        include_sensors: true,
    };

    /// True when the query sees `body`.
    fn sees(&self, body: &Body<'_>) -> bool {
        self.group & body.mask != 0
            && body.group & self.mask != 0
            && (self.include_sensors || !body.sensor)
    }
}

impl Default for QueryFilter {
    /// [`QueryFilter::ALL`].
    fn default() -> Self {
        QueryFilter::ALL
    }
}

/// Where a ray meets a body.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RayCastHit {
    /// The body hit.
    pub body: BodyHandle,
    /// Distance along the ray (m); 0 when the ray starts inside the body.
    pub t: f32,
    /// The hit point (world, m).
    pub point: Vec3,
    /// Outward unit surface normal at the hit (world); the reversed ray direction when
    /// the ray starts inside the body.
    pub normal: Vec3,
}

impl Default for RayCastHit {
    /// A placeholder to fill output buffers with: a handle that names no body
    /// (`index = generation = u32::MAX`), `t = 0`, zero vectors.
    fn default() -> Self {
        RayCastHit {
            body: BodyHandle {
                index: u32::MAX,
                generation: u32::MAX,
            },
            t: 0.0,
            point: Vec3::ZERO,
            normal: Vec3::ZERO,
        }
    }
}

/// Largest `| |d|² − 1 |` accepted for a ray direction: the shape ray casts measure `t`
/// in units of `|d|`, so `t` is metres only for a unit direction. The same tolerance as
/// unit quaternions (about 5e-4 relative in length).
const RAY_UNIT_TOLERANCE: f32 = 1.0e-3;

impl<'a, const B: usize, const C: usize, const E: usize> World<'a, B, C, E> {
    /// The first body `ray` (world frame) meets within `max_t` metres, among the bodies
    /// `filter` sees; on equal `t`, the body in the lower slot.
    ///
    /// Fails, checking in this order, on: a negative (`Negative(Distance)`) or non-finite
    /// (`NonFinite(Distance)`) `max_t`; a non-finite origin (`NonFinite(Position)`) or
    /// direction (`NonFinite(Direction)`); a zero direction (`NotPositive(Direction)`);
    /// a direction not of unit length (`OutOfRange(Direction)`; build rays with
    /// [`Ray::new`], which normalises).
    pub fn cast_ray(
        &self,
        ray: &Ray,
        max_t: f32,
        filter: QueryFilter,
    ) -> Result<Option<RayCastHit>, Error> {
        check_ray(ray, max_t)?;
        let mut best: Option<RayCastHit> = None;
        for (slot, body) in self.bodies.iter() {
            let limit = best.map_or(max_t, |h| h.t);
            let Some(hit) = self.ray_hit(slot, body, ray, limit, filter) else {
                continue;
            };
            // Strictly nearer only: on a tie the lower slot, visited first, stays.
            if best.is_none_or(|b| hit.t < b.t) {
                best = Some(hit);
            }
        }
        Ok(best)
    }

    /// Every body `ray` meets within `max_t` metres, among the bodies `filter` sees,
    /// written to `out` sorted by `(t, slot)`; returns how many were written.
    ///
    /// When there are more hits than `out` holds, the nearest `out.len()` are kept (the
    /// first `out.len()` of the full sorted list) and the rest are not reported: a return
    /// value equal to `out.len()` may mean more hits exist. Fails like
    /// [`World::cast_ray`].
    pub fn cast_ray_all(
        &self,
        ray: &Ray,
        max_t: f32,
        filter: QueryFilter,
        out: &mut [RayCastHit],
    ) -> Result<usize, Error> {
        check_ray(ray, max_t)?;
        if out.is_empty() {
            return Ok(0);
        }
        let mut len: usize = 0;
        for (slot, body) in self.bodies.iter() {
            // Once `out` is full, only hits nearer than its last entry can enter.
            let limit = match out.get(len.wrapping_sub(1)) {
                Some(last) if len == out.len() => last.t,
                _ => max_t,
            };
            if let Some(hit) = self.ray_hit(slot, body, ray, limit, filter) {
                len = insert_sorted(out, len, hit);
            }
        }
        Ok(len)
    }

    /// The bodies whose shapes intersect (overlap or touch) `shape` placed at `pose`
    /// (world frame), among the bodies `filter` sees, written to `out` in slot order;
    /// returns how many were written.
    ///
    /// When `out` fills up, the bodies in the lowest slots are kept and the rest are not
    /// reported: a return value equal to `out.len()` may mean more exist. Fails on an
    /// invalid pose: `NonFinite(Position)`, `NonFinite(Rotation)`, `NotUnit(Rotation)`.
    pub fn overlap(
        &self,
        shape: &Shape<'_>,
        pose: &Iso,
        filter: QueryFilter,
        out: &mut [BodyHandle],
    ) -> Result<usize, Error> {
        check_pose(pose)?;
        let pose = Iso::new(pose.position, pose.rotation.normalize());
        let query_box = shape.aabb(&pose);
        let mut len = 0;
        for (slot, body) in self.bodies.iter() {
            if len >= out.len() {
                break;
            }
            if !filter.sees(body) || !query_box.overlaps(&body.shape.aabb(body.pose())) {
                continue;
            }
            if !shapes_intersect(shape, &pose, &body.shape, body.pose()) {
                continue;
            }
            let (Some(dst), Some(handle)) = (out.get_mut(len), self.bodies.handle_at(slot)) else {
                continue;
            };
            *dst = handle;
            len += 1;
        }
        Ok(len)
    }

    /// The ray's hit on the body in `slot` within `limit`, if `filter` sees the body and
    /// the ray passes through its box.
    fn ray_hit(
        &self,
        slot: usize,
        body: &Body<'_>,
        ray: &Ray,
        limit: f32,
        filter: QueryFilter,
    ) -> Option<RayCastHit> {
        if !filter.sees(body) || !ray_meets_box(ray, &body.shape.aabb(body.pose()), limit) {
            return None;
        }
        let hit = body.shape.cast_ray_unchecked(body.pose(), ray, limit)?;
        Some(RayCastHit {
            body: self.bodies.handle_at(slot)?,
            t: hit.t,
            point: hit.point,
            normal: hit.normal,
        })
    }
}

/// The input checks of the ray casts (see [`World::cast_ray`]).
fn check_ray(ray: &Ray, max_t: f32) -> Result<(), Error> {
    non_negative(max_t, Input::Distance)?;
    crate::error::position(ray.origin)?;
    finite_vec(ray.direction, Input::Direction)?;
    let d2 = ray.direction.length_squared();
    if d2 == 0.0 {
        return Err(Error::NotPositive(Input::Direction));
    }
    if scalar::abs(d2 - 1.0) > RAY_UNIT_TOLERANCE {
        return Err(Error::OutOfRange(Input::Direction));
    }
    Ok(())
}

/// Insert `hit` into `out[..len]` (sorted by `(t, slot)`) keeping it sorted; when `out` is
/// full the last entry falls off (or `hit`, if it sorts last). Returns the new length.
fn insert_sorted(out: &mut [RayCastHit], len: usize, hit: RayCastHit) -> usize {
    let len = len.min(out.len());
    // Hits arrive in slot order, so a hit sorts after every stored hit of equal `t`.
    let at = out.get(..len).map_or(0, |stored| {
        stored.iter().take_while(|h| h.t <= hit.t).count()
    });
    if at >= out.len() {
        return len;
    }
    let new_len = if len < out.len() { len + 1 } else { len };
    if let Some(tail) = out.get_mut(..new_len) {
        crate::sort::insert_shifting(tail, at, hit);
    }
    new_len
}

/// Slab test (Kay and Kajiya, 1986): does the ray meet `aabb` for some `t` in
/// `[0, max_t]`? The box is first grown by a relative `1e-5` so that rounding in the slab
/// divisions can only keep a body, never lose one (the exact cast decides).
fn ray_meets_box(ray: &Ray, aabb: &Aabb, max_t: f32) -> bool {
    // Below this `|d|` a direction component is treated as parallel to its slab: `1 / d`
    // could overflow to infinity, and `0 · ∞` is a NaN.
    const PARALLEL: f32 = 1.0e-20;
    let size = aabb.min.abs().max(aabb.max.abs()).max_elem() + ray.origin.abs().max_elem();
    let b = aabb.expanded(1.0e-5 * (1.0 + size));
    let mut t_min = 0.0;
    let mut t_max = max_t;
    let axes = [
        (ray.origin.x, ray.direction.x, b.min.x, b.max.x),
        (ray.origin.y, ray.direction.y, b.min.y, b.max.y),
        (ray.origin.z, ray.direction.z, b.min.z, b.max.z),
    ];
    for (o, d, lo, hi) in axes {
        if scalar::abs(d) < PARALLEL {
            // (Nearly) parallel to the slab: the ray moves at most `|d| max_t` across it.
            let drift = scalar::abs(d) * max_t;
            if o + drift < lo || o - drift > hi {
                return false;
            }
            continue;
        }
        let inv = 1.0 / d;
        let (t0, t1) = if inv >= 0.0 {
            ((lo - o) * inv, (hi - o) * inv)
        } else {
            ((hi - o) * inv, (lo - o) * inv)
        };
        t_min = scalar::max(t_min, t0);
        t_max = scalar::min(t_max, t1);
        if t_min > t_max {
            return false;
        }
    }
    true
}

/// True when `a` at `pose_a` and `b` at `pose_b` overlap or touch. Half-spaces are decided
/// in closed form; everything else by GJK distance (`<= 0`) in A's frame.
fn shapes_intersect(a: &Shape<'_>, pose_a: &Iso, b: &Shape<'_>, pose_b: &Iso) -> bool {
    // A mesh or compound meets the other shape when one of its nearby parts does.
    for (x, pose_x, y, pose_y) in [(a, pose_a, b, pose_b), (b, pose_b, a, pose_a)] {
        if !x.is_convex() {
            let mut hit = false;
            let region = y.aabb(pose_y);
            mid_phase::parts_near(x, pose_x, &region, |part, at| {
                let pose = at.map_or(*pose_x, |p| *pose_x * p);
                hit = hit || shapes_intersect(&part, &pose, y, pose_y);
            });
            return hit;
        }
    }
    match (a, b) {
        (Shape::HalfSpace(ha), Shape::HalfSpace(hb)) => {
            half_spaces_intersect(ha, pose_a, hb, pose_b)
        }
        (Shape::HalfSpace(h), other) => reaches_below_plane(other, pose_b, h, pose_a),
        (other, Shape::HalfSpace(h)) => reaches_below_plane(other, pose_a, h, pose_b),
        _ => {
            let b_in_a = pose_a.inv_mul(pose_b);
            let mut cache = SimplexCache::default();
            distance_in_a(a, b, &b_in_a, &mut cache).distance <= 0.0
        }
    }
}

/// A convex shape meets the half-space `{x : n·(x − o) <= 0}` (world normal `n`, plane
/// point `o`) when its lowest point along `n`, its support along `−n`, is on or below
/// the plane.
fn reaches_below_plane(shape: &Shape<'_>, pose: &Iso, h: &HalfSpace, plane_pose: &Iso) -> bool {
    let n = plane_pose.transform_vector(h.normal);
    let lowest = pose.transform_point(shape.support(pose.inverse_transform_vector(-n)));
    n.dot(lowest - plane_pose.position) <= 0.0
}

/// Two half-spaces are disjoint only when their normals are opposite and the planes
/// face away from each other; any other pair meets somewhere (possibly far away).
/// "Opposite" allows `1e-6` of rounding in `n_a · n_b = −1`.
fn half_spaces_intersect(a: &HalfSpace, pose_a: &Iso, b: &HalfSpace, pose_b: &Iso) -> bool {
    let n_a = pose_a.transform_vector(a.normal);
    let n_b = pose_b.transform_vector(b.normal);
    if n_a.dot(n_b) > -1.0 + 1.0e-6 {
        return true;
    }
    // B is {x : n_a·x >= n_a·o_b}; A is {x : n_a·x <= n_a·o_a}.
    n_a.dot(pose_b.position - pose_a.position) <= 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hit(t: f32, slot: u32) -> RayCastHit {
        RayCastHit {
            body: BodyHandle {
                index: slot,
                generation: 0,
            },
            t,
            ..RayCastHit::default()
        }
    }

    /// The bounded insertion keeps the first `out.len()` of the full `(t, slot)` order,
    /// whatever the arrival order of `t` (slots arrive increasing).
    #[test]
    fn insert_sorted_keeps_nearest() {
        let ts = [5.0, 1.0, 3.0, 1.0, 9.0, 0.0, 3.0];
        let mut all: std::vec::Vec<(f32, u32)> =
            ts.iter().enumerate().map(|(i, &t)| (t, i as u32)).collect();
        all.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
        for cap in 0..=ts.len() + 1 {
            let mut out = std::vec![RayCastHit::default(); cap];
            let mut len = 0;
            for (i, &t) in ts.iter().enumerate() {
                len = insert_sorted(&mut out, len, hit(t, i as u32));
            }
            assert_eq!(len, cap.min(ts.len()));
            let got: std::vec::Vec<(f32, u32)> =
                out[..len].iter().map(|h| (h.t, h.body.index)).collect();
            assert_eq!(got.as_slice(), &all[..len], "cap {cap}");
        }
    }

    #[test]
    fn slab_test_against_known_boxes() {
        let b = Aabb::new(Vec3::new(1.0, -1.0, -1.0), Vec3::new(2.0, 1.0, 1.0));
        let along_x = Ray::new(Vec3::ZERO, Vec3::X).unwrap();
        assert!(ray_meets_box(&along_x, &b, 1.5));
        assert!(!ray_meets_box(&along_x, &b, 0.9)); // ends before the box
        let backwards = Ray::new(Vec3::ZERO, -Vec3::X).unwrap();
        assert!(!ray_meets_box(&backwards, &b, 10.0));
        let above = Ray::new(Vec3::new(0.0, 1.5, 0.0), Vec3::X).unwrap();
        assert!(!ray_meets_box(&above, &b, 10.0)); // parallel, outside the y slab
        let diagonal = Ray::new(Vec3::new(0.0, -3.0, 0.0), Vec3::new(1.0, 2.0, 0.0)).unwrap();
        assert!(ray_meets_box(&diagonal, &b, 10.0)); // enters at (1, -1), t = √5
        assert!(!ray_meets_box(&diagonal, &b, 2.2));
    }
}
