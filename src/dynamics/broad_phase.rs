//! Stages 2 and 3: movement bounds, then sweep and prune over them.
//!
//! # Movement bounds (stage 2)
//!
//! An awake body that moves gets the box its shape sweeps over the sub-step `h`
//! ([`crate::collide::movement_bounds`]), from the pose at the start of the sub-step (before
//! stage 8 moves it) with the velocities stage 1 just produced. Sleeping and static bodies do
//! not move: their box is the shape's box at the current pose. Every box is then grown by
//! the speculative margin, so two shapes closer than the margin (the narrow phase keeps
//! such points) always have overlapping boxes.
//!
//! # Sweep and prune (stage 3)
//!
//! Baraff's sort-and-sweep ("Dynamic simulation of non-penetrating rigid bodies", 1992,
//! ch. 7) on one axis, x. The slots stay sorted by `(min.x, slot)` from one step to the
//! next, so an insertion sort repairs the order in close to linear time when bodies move a
//! little per step (temporal coherence). The sweep walks the order; for each box it visits
//! the following boxes until one starts beyond its `max.x`, and tests the full 3D overlap.
//!
//! Work is bounded: the sort and the sweep are at most `N²` comparisons each.

use heapless::Vec as HVec;

use super::body::{Body, BodyKind};
use super::events::StepReport;
use super::pool::Pool;
use crate::collide::{movement_bounds, Motion};
use crate::config::WorldConfig;
use crate::math::{scalar, Aabb};

/// Sweep-and-prune state.
#[derive(Clone, Debug)]
pub(crate) struct BroadPhase<const N: usize> {
    /// Live slots sorted by `(bounds.min.x, slot)` of their movement bounds, as of the
    /// last [`BroadPhase::find_pairs`]. Kept between steps: it is the warm start of the
    /// insertion sort (and part of the state a snapshot must carry to stay bit-identical).
    pub order: HVec<u32, N>,
}

impl<const N: usize> BroadPhase<N> {
    /// Empty.
    pub const fn new() -> Self {
        BroadPhase { order: HVec::new() }
    }

    /// Stage 3: candidate pairs `(lower slot, higher slot)` whose movement bounds overlap
    /// and that may collide (see [`may_collide`]), sorted by `(a, b)`.
    ///
    /// When `pairs` is full, the pairs found first in sweep order are kept and the rest are
    /// counted in `report.dropped_pairs` (accumulated over the sub-steps of a step).
    /// `report.pairs` is the number kept (of the last sub-step).
    pub fn find_pairs<const P: usize>(
        &mut self,
        bodies: &Pool<Body<'_>, N>,
        pairs: &mut HVec<(u32, u32), P>,
        report: &mut StepReport,
    ) {
        pairs.clear();
        self.sync_with_pool(bodies);
        self.sort_by_min_x(bodies);
        let mut dropped: u32 = 0;
        let order = self.order.as_slice();
        for (i, &slot_i) in order.iter().enumerate() {
            let Some(body_i) = bodies.at(slot_i as usize) else {
                continue;
            };
            // The boxes after `i` in the order start at or after `body_i`'s start: stop at
            // the first that starts beyond its end.
            for &slot_j in order.get(i + 1..).unwrap_or(&[]) {
                let Some(body_j) = bodies.at(slot_j as usize) else {
                    continue;
                };
                if body_j.bounds.min.x > body_i.bounds.max.x {
                    break;
                }
                if !body_i.bounds.overlaps(&body_j.bounds) || !may_collide(body_i, body_j) {
                    continue;
                }
                let pair = if slot_i < slot_j {
                    (slot_i, slot_j)
                } else {
                    (slot_j, slot_i)
                };
                if pairs.push(pair).is_err() {
                    dropped = dropped.saturating_add(1);
                }
            }
        }
        // Keys are unique (each unordered pair is visited once), so an unstable sort is
        // deterministic.
        pairs.sort_unstable();
        report.pairs = pairs.len() as u32;
        report.dropped_pairs = report.dropped_pairs.saturating_add(dropped);
    }

    /// Make `order` hold exactly the live slots: drop freed slots (keeping the relative
    /// order of the others), then append new slots in slot order.
    fn sync_with_pool(&mut self, bodies: &Pool<Body<'_>, N>) {
        self.order.retain(|&s| bodies.at(s as usize).is_some());
        if self.order.len() == bodies.len() {
            // Every slot in `order` is live and distinct, and there are as many as live
            // slots: nothing is missing.
            return;
        }
        let mut listed = [false; N];
        for &s in self.order.iter() {
            if let Some(flag) = listed.get_mut(s as usize) {
                *flag = true;
            }
        }
        for (slot, _) in bodies.iter() {
            if !listed.get(slot).copied().unwrap_or(true) {
                // Cannot fail: `order` holds distinct slots below `N`.
                let _ = self.order.push(slot as u32);
            }
        }
    }

    /// Insertion sort of `order` by `(bounds.min.x, slot)`. Nearly sorted input (last
    /// step's order) costs about one comparison per slot.
    fn sort_by_min_x(&mut self, bodies: &Pool<Body<'_>, N>) {
        let order = self.order.as_mut_slice();
        for i in 1..order.len() {
            let mut j = i;
            // Sift element `i` down while it sorts before its left neighbour. `j` falls
            // by one each round, so at most `i` rounds.
            while j > 0 {
                let (Some(&left), Some(&right)) = (order.get(j - 1), order.get(j)) else {
                    break;
                };
                if !sorts_before(bodies, right, left) {
                    break;
                }
                order.swap(j - 1, j);
                j -= 1;
            }
        }
    }
}

/// True when slot `s` sorts strictly before slot `t`: smaller `bounds.min.x`, ties (and
/// `-0.0` against `+0.0`, by `total_cmp`) broken by the smaller slot.
fn sorts_before<const N: usize>(bodies: &Pool<Body<'_>, N>, s: u32, t: u32) -> bool {
    let x = |slot: u32| {
        bodies
            .at(slot as usize)
            .map_or(f32::INFINITY, |b| b.bounds.min.x)
    };
    match x(s).total_cmp(&x(t)) {
        core::cmp::Ordering::Less => true,
        core::cmp::Ordering::Greater => false,
        core::cmp::Ordering::Equal => s < t,
    }
}

/// True when the narrow phase should look at two bodies whose bounds overlap:
/// - at least one is dynamic (static and kinematic bodies never push each other);
/// - at least one is awake (two sleeping bodies, or a sleeping body and a static one,
///   keep last step's contact unchanged instead; see `contact::update_contacts`);
/// - their filters agree: `a.group & b.mask != 0 && b.group & a.mask != 0`.
pub(crate) fn may_collide(a: &Body<'_>, b: &Body<'_>) -> bool {
    let some_dynamic = a.kind == BodyKind::Dynamic || b.kind == BodyKind::Dynamic;
    let some_awake = a.awake || b.awake;
    let filters_agree = a.group & b.mask != 0 && b.group & a.mask != 0;
    some_dynamic && some_awake && filters_agree
}

/// Stage 2: each body's bounds for the sub-step `h` (s), grown by the speculative margin.
pub(crate) fn update_bounds<const N: usize>(
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    h: f32,
) {
    for (_, body) in bodies.iter_mut() {
        body.bounds = body_bounds(body, h).expanded(cfg.speculative_margin);
    }
}

/// The box `body` covers over the next `h` seconds (without the margin).
///
/// Body velocities are those of the centre of mass `c`; [`Motion`] moves the body frame's
/// origin `o` on a straight line with `v_o = v + ω × (o − c)` and turns the shape about
/// it. Stage 8 instead moves `c` on the straight line and turns about `c`, so the origin
/// follows an arc: with `ℓ = o − c` and `R(t)` the step's rotation by `φ ≤ |ω| t`, the
/// true origin is off the straight line by `d(t) = R(t) ℓ − ℓ − t ω × ℓ`. Taylor's bound
/// on the rotation gives `|d| ≤ |ℓ| W²` for `W = |ω| h ≤ 1` (the `1 − cos φ ≤ W²/2` term
/// plus `|W − sin φ| ≤ W³/4`), and `|d| ≤ |ℓ| (2 + W)` always. The box grows by that
/// bound; it is zero for shapes whose centre of mass is their origin.
fn body_bounds(body: &Body<'_>, h: f32) -> Aabb {
    if body.kind == BodyKind::Static || !body.awake {
        return body.shape.aabb(&body.pose);
    }
    let center = body.world_center();
    let origin_from_center = body.pose.position - center;
    let motion = Motion {
        pose: body.pose,
        linear: body.linear_velocity + body.angular_velocity.cross(origin_from_center),
        angular: body.angular_velocity,
    };
    let swept = movement_bounds(&body.shape, &motion, h);
    let arm = origin_from_center.length();
    if arm > 0.0 {
        let w = body.angular_velocity.length() * scalar::abs(h);
        let arc = if w <= 1.0 {
            arm * w * w
        } else {
            arm * (2.0 + w)
        };
        swept.expanded(arc)
    } else {
        swept
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::body::BodyDesc;
    use crate::math::Vec3;
    use crate::rng::SplitMix64;
    use crate::shape::Shape;

    fn body(kind: BodyKind, p: Vec3, r: f32) -> Body<'static> {
        let shape = Shape::sphere(r).unwrap();
        let desc = match kind {
            BodyKind::Dynamic => BodyDesc::dynamic(shape),
            BodyKind::Static => BodyDesc::fixed(shape),
            BodyKind::Kinematic => BodyDesc::kinematic(shape),
        };
        Body::from_desc(&desc.position(p)).unwrap()
    }

    /// The sweep against an O(n²) loop over all pairs with the same overlap and filter
    /// rules, over random scenes with removals in between (so the order must resync).
    #[test]
    fn sweep_matches_brute_force_over_steps() {
        const N: usize = 48;
        let mut rng = SplitMix64::new(7);
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        let mut bp: BroadPhase<N> = BroadPhase::new();
        let cfg = WorldConfig::DEFAULT;
        let kinds = [BodyKind::Dynamic, BodyKind::Static, BodyKind::Kinematic];
        for round in 0..12 {
            // Remove a few, add a few, move everybody a bit.
            let handles: std::vec::Vec<_> = (0..N).filter_map(|i| pool.handle_at(i)).collect();
            for h in handles.iter().step_by(5) {
                pool.remove(*h);
            }
            while pool.len() < N - 3 {
                let kind = kinds[(rng.next_u64() % 3) as usize];
                let p = Vec3::new(
                    rng.range(-6.0, 6.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                );
                let mut b = body(kind, p, rng.range(0.1, 1.0));
                b.group = 1 << (rng.next_u64() % 3);
                b.mask = if rng.next_u64().is_multiple_of(4) {
                    0b101
                } else {
                    u32::MAX
                };
                b.awake = b.kind != BodyKind::Static && !rng.next_u64().is_multiple_of(5);
                b.linear_velocity = rng.unit_vector() * rng.range(0.0, 30.0);
                b.angular_velocity = rng.unit_vector() * rng.range(0.0, 5.0);
                pool.insert(b).unwrap();
            }
            for (_, b) in pool.iter_mut() {
                b.pose.position += Vec3::new(rng.range(-0.3, 0.3), 0.0, 0.0);
                b.pose.rotation = rng.rotation();
            }
            update_bounds(&mut pool, &cfg, 1.0 / 60.0);
            let mut pairs: HVec<(u32, u32), 2048> = HVec::new();
            let mut report = StepReport::default();
            bp.find_pairs(&pool, &mut pairs, &mut report);
            let mut expected = std::vec::Vec::new();
            for (i, a) in pool.iter() {
                for (j, b) in pool.iter() {
                    if i < j && a.bounds.overlaps(&b.bounds) && may_collide(a, b) {
                        expected.push((i as u32, j as u32));
                    }
                }
            }
            assert!(
                !expected.is_empty(),
                "round {round}: scene too sparse to test"
            );
            assert_eq!(pairs.as_slice(), expected.as_slice(), "round {round}");
            assert_eq!(report.pairs as usize, expected.len());
            assert_eq!(report.dropped_pairs, 0);
            // The order holds every live slot once, sorted.
            assert_eq!(bp.order.len(), pool.len());
            for w in bp.order.windows(2) {
                assert!(
                    sorts_before(&pool, w[0], w[1]),
                    "round {round}: order not sorted"
                );
            }
        }
    }

    /// A spinning body's box covers its shape at the end of the sub-step, with the
    /// rotation about the centre of mass (not the origin) taken into account.
    #[test]
    fn bounds_cover_end_pose_of_off_centre_body() {
        let hull_shape = Shape::capsule(1.0, 0.2).unwrap();
        let mut b =
            Body::from_desc(&BodyDesc::dynamic(hull_shape).position(Vec3::new(1.0, 2.0, 3.0)))
                .unwrap();
        // Pretend the centre of mass is off the origin, as for an asymmetric hull.
        b.center_local = Vec3::new(0.5, 0.0, 0.0);
        b.angular_velocity = Vec3::new(0.0, 0.0, 20.0);
        b.linear_velocity = Vec3::new(3.0, 0.0, 0.0);
        let mut pool: Pool<Body<'static>, 1> = Pool::new();
        pool.insert(b).unwrap();
        let h = 1.0 / 60.0;
        let mut cfg = WorldConfig::DEFAULT;
        cfg.speculative_margin = 0.0;
        update_bounds(&mut pool, &cfg, h);
        let bounds = pool.at(0).unwrap().bounds;
        // Stage 8 over any part `t` of the sub-step (one integration of `t`, as a
        // sub-step of that length would do): the box must hold the shape.
        let mut moving = b;
        for k in 1..=16 {
            moving = b;
            moving.integrate_position(h * k as f32 / 16.0);
            let aabb = moving.shape.aabb(&moving.pose);
            assert!(
                bounds.contains(&aabb),
                "k={k}: {bounds:?} does not contain {aabb:?}"
            );
        }
        // Not vacuous: the end box is not the start box.
        assert!(moving.pose.position.distance(b.pose.position) > 0.04);
    }

    #[test]
    fn full_pair_buffer_keeps_first_in_sweep_order() {
        const N: usize = 6;
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        // Six unit spheres on a line 0.5 apart: slots sorted by x are 0..6.
        for i in 0..N {
            pool.insert(body(
                BodyKind::Dynamic,
                Vec3::new(i as f32 * 0.5, 0.0, 0.0),
                0.3,
            ))
            .unwrap();
        }
        update_bounds(&mut pool, &WorldConfig::DEFAULT, 1.0 / 60.0);
        let mut bp: BroadPhase<N> = BroadPhase::new();
        let mut pairs: HVec<(u32, u32), 3> = HVec::new();
        let mut report = StepReport::default();
        bp.find_pairs(&pool, &mut pairs, &mut report);
        // Overlapping neighbours: (0,1) (1,2) (2,3) (3,4) (4,5): sweep order finds them in
        // that order, so the first three are kept.
        assert_eq!(pairs.as_slice(), &[(0, 1), (1, 2), (2, 3)]);
        assert_eq!(report.dropped_pairs, 2);
        assert_eq!(report.pairs, 3);
    }
}
