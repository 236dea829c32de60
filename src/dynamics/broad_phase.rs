//! Stages 2 and 3: movement bounds, enlarged boxes, and the search for new pairs.
//!
//! # Movement bounds and enlarged boxes (stage 2)
//!
//! An awake body that moves gets the box its shape sweeps over the step `dt`
//! ([`crate::collide::movement_bounds`]) from its current pose with its velocity (plus
//! the gravity and force of this step), grown by the speculative margin, so two shapes
//! closer than the margin always have overlapping boxes. That box is compared with the
//! body's *enlarged box* `Body::fat`: while it fits, nothing changes; when it leaves,
//! the enlarged box becomes the movement box grown by `aabb_margin` and the body is
//! flagged `moved`. Static bodies have their exact box, set when they are added or
//! teleported; sleeping bodies keep theirs.
//!
//! # New pairs (stage 3)
//!
//! A contact lives as long as the enlarged boxes of its two bodies overlap
//! (`contact::update_contacts` removes it once they do not), so only pairs with a moved
//! body can be new. When some body moved, Baraff's sort-and-sweep ("Dynamic simulation
//! of non-penetrating rigid bodies", 1992, ch. 7) on x over the enlarged boxes finds the
//! overlapping pairs with a moved body that may collide and have no contact yet. The
//! slots stay sorted by `(fat.min.x, slot)` from one step to the next, so an insertion
//! sort repairs the order in close to linear time (temporal coherence). A step in which
//! nothing moved out of its box does no search at all: a resting or sleeping world costs
//! one box test per awake body.
//!
//! Work is bounded: the sort and the sweep are at most `N²` comparisons each.

use heapless::Vec as HVec;

use super::body::{Body, BodyKind};
use super::contact::{contains_pair, Contact};
use super::events::StepReport;
use super::pool::Pool;
use super::solver::clamp_length;
use crate::collide::{movement_bounds, Motion};
use crate::config::WorldConfig;
use crate::math::{scalar, Aabb};

/// Sweep-and-prune state.
#[derive(Clone, Debug)]
pub(crate) struct BroadPhase<const N: usize> {
    /// Live slots sorted by `(fat.min.x, slot)`, as of the last search. Kept between
    /// steps as the warm start of the insertion sort; it only speeds the sort up (the
    /// pairs found do not depend on it).
    pub order: HVec<u32, N>,
}

impl<const N: usize> BroadPhase<N> {
    /// Empty.
    pub const fn new() -> Self {
        BroadPhase { order: HVec::new() }
    }

    /// Stage 3: the pairs `(lower slot, higher slot)` whose enlarged boxes overlap, with
    /// at least one body flagged `moved`, that may pair ([`may_pair`]) and have no
    /// contact in `contacts` yet, sorted by `(a, b)`. Clears the `moved` flags.
    ///
    /// When `pairs` is full, the pairs found first in sweep order are kept; the rest are
    /// counted in `report.dropped_pairs` and both bodies of each stay flagged, so the
    /// search offers them again next step.
    pub fn find_new_pairs<const P: usize>(
        &mut self,
        bodies: &mut Pool<Body<'_>, N>,
        contacts: &[Contact],
        pairs: &mut HVec<(u32, u32), P>,
        report: &mut StepReport,
    ) {
        pairs.clear();
        if !bodies.iter().any(|(_, b)| b.moved) {
            return;
        }
        self.sync_with_pool(bodies);
        self.sort_by_min_x(bodies);
        let mut dropped: u32 = 0;
        let mut retry = [false; N];
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
                if body_j.fat.min.x > body_i.fat.max.x {
                    break;
                }
                if !(body_i.moved || body_j.moved)
                    || !body_i.fat.overlaps(&body_j.fat)
                    || !may_pair(body_i, body_j)
                {
                    continue;
                }
                let pair = if slot_i < slot_j {
                    (slot_i, slot_j)
                } else {
                    (slot_j, slot_i)
                };
                if contains_pair(contacts, pair) {
                    continue;
                }
                if pairs.push(pair).is_err() {
                    dropped = dropped.saturating_add(1);
                    for s in [slot_i, slot_j] {
                        if let Some(r) = retry.get_mut(s as usize) {
                            *r = true;
                        }
                    }
                }
            }
        }
        // Keys are unique (each unordered pair is visited once), so an unstable sort is
        // deterministic.
        pairs.sort_unstable();
        for (i, b) in bodies.iter_mut() {
            b.moved = retry.get(i).copied().unwrap_or(false);
        }
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

    /// Insertion sort of `order` by `(fat.min.x, slot)`. Nearly sorted input (last
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

/// True when slot `s` sorts strictly before slot `t`: smaller `fat.min.x`, ties (and
/// `-0.0` against `+0.0`, by `total_cmp`) broken by the smaller slot.
fn sorts_before<const N: usize>(bodies: &Pool<Body<'_>, N>, s: u32, t: u32) -> bool {
    let x = |slot: u32| {
        bodies
            .at(slot as usize)
            .map_or(f32::INFINITY, |b| b.fat.min.x)
    };
    match x(s).total_cmp(&x(t)) {
        core::cmp::Ordering::Less => true,
        core::cmp::Ordering::Greater => false,
        core::cmp::Ordering::Equal => s < t,
    }
}

/// True when two bodies whose boxes overlap get a contact: at least one is dynamic
/// (static and kinematic bodies never push each other) and their filters agree,
/// `a.group & b.mask != 0 && b.group & a.mask != 0`.
pub(crate) fn may_pair(a: &Body<'_>, b: &Body<'_>) -> bool {
    let some_dynamic = a.kind == BodyKind::Dynamic || b.kind == BodyKind::Dynamic;
    let filters_agree = a.group & b.mask != 0 && b.group & a.mask != 0;
    some_dynamic && filters_agree
}

/// True when the narrow phase should look at a contact's two bodies: they may pair and
/// at least one is awake (two sleeping bodies, or a sleeping body and a static one, keep
/// their contact unchanged instead; see `contact::update_contacts`).
pub(crate) fn may_collide(a: &Body<'_>, b: &Body<'_>) -> bool {
    may_pair(a, b) && (a.awake || b.awake)
}

/// Stage 2: clamp the velocities of every awake, non-static body to the speed limits
/// (a setter may have left them above), then refresh the enlarged box of those whose
/// movement bounds over the step left it (module docs).
pub(crate) fn update_fat_boxes<const N: usize>(bodies: &mut Pool<Body<'_>, N>, cfg: &WorldConfig) {
    for (_, body) in bodies.iter_mut() {
        if body.kind == BodyKind::Static || !body.awake {
            continue;
        }
        body.linear_velocity = clamp_length(body.linear_velocity, cfg.max_linear_speed);
        body.angular_velocity = clamp_length(body.angular_velocity, cfg.max_angular_speed);
        let tight = body_bounds(body, cfg).expanded(cfg.speculative_margin);
        if !body.fat.contains(&tight) {
            body.fat = tight.expanded(cfg.aabb_margin);
            body.moved = true;
        }
    }
}

/// The box `body` covers over the next step (without the margins): its velocity plus
/// what gravity and the accumulated force add in the step.
///
/// Body velocities are those of the centre of mass `c`; [`Motion`] moves the body frame's
/// origin `o` on a straight line with `v_o = v + ω × (o − c)` and turns the shape about
/// it. The integrator instead moves `c` on the straight line and turns about `c`, so the
/// origin follows an arc: with `ℓ = o − c` and `R(t)` the step's rotation by `φ ≤ |ω| t`,
/// the true origin is off the straight line by `d(t) = R(t) ℓ − ℓ − t ω × ℓ`. Taylor's
/// bound on the rotation gives `|d| ≤ |ℓ| W²` for `W = |ω| dt ≤ 1` (the
/// `1 − cos φ ≤ W²/2` term plus `|W − sin φ| ≤ W³/4`), and `|d| ≤ |ℓ| (2 + W)` always. The
/// box grows by that bound; it is zero for shapes whose centre of mass is their origin.
pub(crate) fn body_bounds(body: &Body<'_>, cfg: &WorldConfig) -> Aabb {
    if body.kind == BodyKind::Static || !body.awake {
        return body.shape.aabb(&body.pose);
    }
    let dt = cfg.dt;
    let center = body.world_center();
    let origin_from_center = body.pose.position - center;
    let mut v = body.linear_velocity;
    if body.is_dynamic() {
        // What the step can reach: the integrator clamps to the speed limit.
        v = clamp_length(
            v + (cfg.gravity + body.force * body.inv_mass) * dt,
            cfg.max_linear_speed,
        );
    }
    let motion = Motion {
        pose: body.pose,
        linear: v + body.angular_velocity.cross(origin_from_center),
        angular: body.angular_velocity,
    };
    let swept = movement_bounds(&body.shape, &motion, dt);
    let arm = origin_from_center.length();
    if arm > 0.0 {
        let w = body.angular_velocity.length() * scalar::abs(dt);
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

    /// The search against an O(n²) loop over all pairs with the same rules, over random
    /// scenes with removals in between (so the order must resync) and random `moved`
    /// flags and existing contacts.
    #[test]
    fn search_matches_brute_force_over_steps() {
        const N: usize = 48;
        let mut rng = SplitMix64::new(7);
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        let mut bp: BroadPhase<N> = BroadPhase::new();
        let kinds = [BodyKind::Dynamic, BodyKind::Static, BodyKind::Kinematic];
        for round in 0..12 {
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
                pool.insert(b).unwrap();
            }
            for (_, b) in pool.iter_mut() {
                b.pose.position += Vec3::new(rng.range(-0.3, 0.3), 0.0, 0.0);
                b.fat = b.shape.aabb(&b.pose).expanded(rng.range(0.0, 0.2));
                b.moved = rng.next_u64().is_multiple_of(3);
            }
            // Some pairs already have contacts.
            let mut contacts: std::vec::Vec<Contact> = std::vec::Vec::new();
            for (i, _) in pool.iter() {
                for (j, _) in pool.iter() {
                    if i < j && rng.next_u64().is_multiple_of(7) {
                        contacts.push(Contact::new_pair(
                            i as u32,
                            j as u32,
                            crate::Material::DEFAULT,
                            false,
                        ));
                    }
                }
            }
            let mut expected = std::vec::Vec::new();
            for (i, a) in pool.iter() {
                for (j, b) in pool.iter() {
                    if i < j
                        && (a.moved || b.moved)
                        && a.fat.overlaps(&b.fat)
                        && may_pair(a, b)
                        && !contains_pair(&contacts, (i as u32, j as u32))
                    {
                        expected.push((i as u32, j as u32));
                    }
                }
            }
            let mut pairs: HVec<(u32, u32), 2048> = HVec::new();
            let mut report = StepReport::default();
            bp.find_new_pairs(&mut pool, &contacts, &mut pairs, &mut report);
            assert!(
                !expected.is_empty(),
                "round {round}: scene too sparse to test"
            );
            assert_eq!(pairs.as_slice(), expected.as_slice(), "round {round}");
            assert_eq!(report.dropped_pairs, 0);
            assert!(pool.iter().all(|(_, b)| !b.moved), "flags cleared");
            assert_eq!(bp.order.len(), pool.len());
            for w in bp.order.windows(2) {
                assert!(sorts_before(&pool, w[0], w[1]), "round {round}: not sorted");
            }
        }
    }

    /// A spinning body's box covers its shape at the end of any part of the step, with
    /// the rotation about the centre of mass (not the origin) taken into account.
    #[test]
    fn bounds_cover_end_pose_of_off_centre_body() {
        let shape = Shape::capsule(1.0, 0.2).unwrap();
        let mut b =
            Body::from_desc(&BodyDesc::dynamic(shape).position(Vec3::new(1.0, 2.0, 3.0))).unwrap();
        // Pretend the centre of mass is off the origin, as for an asymmetric hull.
        b.center_local = Vec3::new(0.5, 0.0, 0.0);
        b.angular_velocity = Vec3::new(0.0, 0.0, 20.0);
        b.linear_velocity = Vec3::new(3.0, 0.0, 0.0);
        let mut cfg = WorldConfig::DEFAULT;
        cfg.gravity = Vec3::ZERO;
        let bounds = body_bounds(&b, &cfg);
        let c0 = b.world_center();
        let mut end = b.pose;
        for k in 1..=16 {
            let t = cfg.dt * k as f32 / 16.0;
            let q = b.pose.rotation.integrate(b.angular_velocity, t);
            let c = c0 + b.linear_velocity * t;
            end = crate::math::Iso::new(c - q.rotate(b.center_local), q);
            let aabb = b.shape.aabb(&end);
            assert!(
                bounds.contains(&aabb),
                "k={k}: {bounds:?} does not contain {aabb:?}"
            );
        }
        assert!(end.position.distance(b.pose.position) > 0.04);
    }

    /// A full pair buffer keeps the first pairs in sweep order, counts the rest, and
    /// leaves their bodies flagged for the next search.
    #[test]
    fn full_pair_buffer_keeps_first_in_sweep_order() {
        const N: usize = 6;
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        // Six spheres on a line 0.5 apart: slots sorted by x are 0..6.
        for i in 0..N {
            pool.insert(body(
                BodyKind::Dynamic,
                Vec3::new(i as f32 * 0.5, 0.0, 0.0),
                0.3,
            ))
            .unwrap();
        }
        let mut bp: BroadPhase<N> = BroadPhase::new();
        let mut pairs: HVec<(u32, u32), 3> = HVec::new();
        let mut report = StepReport::default();
        bp.find_new_pairs(&mut pool, &[], &mut pairs, &mut report);
        // Overlapping neighbours: (0,1) (1,2) (2,3) (3,4) (4,5): sweep order finds them in
        // that order, so the first three are kept.
        assert_eq!(pairs.as_slice(), &[(0, 1), (1, 2), (2, 3)]);
        assert_eq!(report.dropped_pairs, 2);
        let moved: std::vec::Vec<bool> = pool.iter().map(|(_, b)| b.moved).collect();
        assert_eq!(moved, [false, false, false, true, true, true]);
    }
}
