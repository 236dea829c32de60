//! Stage 8: continuous collision for bodies that moved far in one step.
//!
//! After the positions are integrated, a body is *fast* when it has `ccd` on, is dynamic
//! and awake, and its sweep this step,
//!
//! ```text
//! |x₁ − x₀| + |ω| h ρ            (m; x the body origin, ρ its core's reach from it)
//! ```
//!
//! exceeds `ccd_motion_fraction · min_extent`: it may have jumped over something thinner
//! than itself (a ball that only spins jumps over nothing: its core is its centre). Fast bodies are taken in slot order. Each is swept from its pose at the
//! start of the step (`pose0`) to its pose now with [`time_of_impact_unchecked`]
//! against every other body it has a contact with, each body once (a pair with a mesh
//! or compound holds a record and a contact per part pair; its parts are swept once for
//! the pair). When a contact turned it out of its enlarged box this step, it is swept
//! instead against every body whose box its path touches, asked of the broad phase's
//! tree and taken in slot order, so a ball knocked sideways by another still meets the
//! wall it now heads for. The other body moves over the same interval from its own
//! `pose0` to its pose now (a static body stays put, a fast body is swept too: fast
//! against fast). Of the hits, the earliest is taken: the fast body goes back to its
//! pose at that time (`Motion::pose_at`), and, when the other body is fast as well, so
//! does the other. Velocities are kept: the next step's narrow phase finds the two
//! within the speculative margin and the solver's speculative contact
//! stops them before they touch.
//!
//! The sweep models the motion as the body origin moving at the constant velocity
//! `(x₁ − x₀) / h` (h = dt) while turning at the final `ω`. It starts where the step
//! started and its position ends where the sub-steps did; its rotation differs from the
//! sub-steps' by what contacts changed of `ω` within the step, and its path from theirs
//! (which move the centre of mass) by at most the off-centre distance times the turn.
//!
//! # Which hits count
//!
//! - The tolerance of the sweep is `slop` ([`MIN_TOLERANCE`] at least): the body stops
//!   with a gap of `slop/2` to `slop`, so projection has nothing to push and the gap is
//!   inside the speculative margin (`2 · slop` by default) that the next narrow phase
//!   keeps contacts within.
//! - A pair already within the tolerance (or overlapping) at the start of the step is
//!   left to the discrete contact, which already exists for it: stopping there would pin
//!   a fast body that slides along the ground.
//! - A hit counts only when the motion left after it would carry the bodies more than
//!   `slop` deeper along the hit normal: `((v_a − v_b)·n + |ω_a| ρ_a + |ω_b| ρ_b)(h − t)`,
//!   with `ρ` the reach of a shape's core (`Shape::core_reach`: its bounding radius less
//!   its radius). Shallower is what the discrete contact tolerates anyway, and it is what
//!   a fast body sliding along the ground does (gravity adds `g h²`, 2.7 mm at 60 Hz, per
//!   step): pausing it at every such graze would stall it. This filter is a departure from
//!   "the earliest hit", after Box2D v3's `b2ContinuousQueryCallback`, which also
//!   refuses hits that do not threaten to tunnel.
//!
//! - A sweep whose work budget ran out ([`Toi::Unresolved`]: a long grazing pass under a
//!   loose spin bound) counts as a hit at the last time it certified: the body stops
//!   short rather than risk tunnelling.
//!
//! A body moved back as the partner of an earlier fast body is swept again in its own
//! turn, from `pose0` to where it now is; that sweep finds the contact at the end of its
//! motion or nothing, and counts as one more sweep.

use heapless::Vec as HVec;

use super::body::{Body, BodyKind};
use super::broad_phase::{may_pair, BroadPhase};
use super::contact::Contact;
use super::events::StepReport;
use super::mid_phase;
use super::pool::Pool;
use super::solver::is_active;
use crate::collide::{time_of_impact_unchecked, Motion, Toi};
use crate::config::WorldConfig;
use crate::math::{scalar, Iso, Vec3};

/// Smallest sweep tolerance (m), for a world configured with a zero slop: the time of
/// impact needs a positive one.
pub(crate) const MIN_TOLERANCE: f32 = 1.0e-4;

/// Sweep fast bodies against the bodies they have contacts with; move them back to the
/// time of impact (module docs). `scratch` lists `(fast slot, contact index)` so each
/// fast body visits only its own contacts. A body whose path left its enlarged box (a
/// contact turned it this step), or whose entries did not fit in `scratch`, is swept
/// against every body whose box its path touches instead, found by `broad`'s tree.
pub(crate) fn sweep_fast_bodies<const N: usize, const P: usize>(
    bodies: &mut Pool<Body<'_>, N>,
    broad: &BroadPhase<N>,
    contacts: &[Contact],
    scratch: &mut HVec<(u32, u32), P>,
    cfg: &WorldConfig,
    h: f32,
    report: &mut StepReport,
) {
    if h.is_nan() || h <= 0.0 {
        return;
    }
    let mut fast = [false; N];
    let mut any = false;
    for (i, b) in bodies.iter() {
        if fast_motion(b, cfg, h).is_some() {
            if let Some(f) = fast.get_mut(i) {
                *f = true;
                any = true;
            }
        }
    }
    if !any {
        return;
    }
    scratch.clear();
    let mut overflow = [false; N];
    for (ci, c) in contacts.iter().enumerate() {
        for s in [c.a, c.b] {
            if fast.get(s as usize).copied().unwrap_or(false)
                && scratch.push((s, ci as u32)).is_err()
            {
                if let Some(o) = overflow.get_mut(s as usize) {
                    *o = true;
                }
            }
        }
    }
    // Unique entries: an unstable sort is deterministic.
    crate::sort::sort_pairs(scratch);
    let tolerance = scalar::max(cfg.slop, MIN_TOLERANCE);
    // The bodies near an escaped body's path, in slot order.
    let mut near: HVec<u32, N> = HVec::new();
    let mut at = 0usize;
    for i in 0..bodies.high() {
        let start = at;
        while scratch.get(at).is_some_and(|e| e.0 as usize == i) {
            at += 1;
        }
        if !fast.get(i).copied().unwrap_or(false) {
            continue;
        }
        let Some(body) = bodies.at(i).copied() else {
            continue;
        };
        // A partner moved back by an earlier fast body may no longer be fast.
        let Some(motion) = fast_motion(&body, cfg, h) else {
            continue;
        };
        report.ccd_sweeps = report.ccd_sweeps.saturating_add(1);
        let mine = scratch.get(start..at).unwrap_or(&[]);
        let partner = |e: &(u32, u32)| {
            contacts
                .get(e.1 as usize)
                .map(|c| if c.a == i as u32 { c.b } else { c.a })
        };
        // Its path this step: if a contact turned it out of its enlarged box, it may
        // reach bodies it has no contact with; then every body whose box the path
        // touches is a candidate.
        let path = body
            .shape
            .aabb(&body.pose0)
            .union(&body.shape.aabb(body.pose()));
        let escaped = overflow.get(i).copied().unwrap_or(false) || !body.fat.contains(&path);
        let hit = if escaped {
            broad.overlapping(bodies, &path, &mut near);
            let all = near.iter().copied();
            let queries = &mut report.ccd_queries;
            earliest_hit(
                &body, &motion, i as u32, bodies, all, cfg, h, tolerance, queries,
            )
        } else {
            // Each partner once: a pair with a mesh or compound holds a record and a
            // contact per part pair, next to each other in `contacts` (sorted by pair,
            // then part), so their entries follow each other in `mine` too.
            let mut last = None;
            let listed = mine
                .iter()
                .filter_map(partner)
                .filter(|&o| last.replace(o) != Some(o));
            let queries = &mut report.ccd_queries;
            earliest_hit(
                &body, &motion, i as u32, bodies, listed, cfg, h, tolerance, queries,
            )
        };
        if let Some((time, other)) = hit {
            report.ccd_hits = report.ccd_hits.saturating_add(1);
            if let Some(b) = bodies.at_mut(i) {
                move_to(b, &motion.pose_at(time));
            }
            if let Some(b) = bodies.at_mut(other as usize) {
                if let Some(m) = fast_motion(b, cfg, h) {
                    move_to(b, &m.pose_at(time));
                }
            }
        }
    }
}

/// The motion of a body over the step: from `pose0`, the origin at constant velocity
/// `(x₁ − x₀) / h`, turning at `ω`. Static bodies stand still.
fn motion_of(b: &Body<'_>, h: f32) -> Motion {
    if !b.awake || b.kind == BodyKind::Static {
        return Motion {
            pose: *b.pose(),
            linear: Vec3::ZERO,
            angular: Vec3::ZERO,
        };
    }
    Motion {
        pose: b.pose0,
        linear: (b.pose().position - b.pose0.position) * (1.0 / h),
        angular: b.angular_velocity,
    }
}

/// The body's motion if it is fast this step (module docs), else `None`.
fn fast_motion(b: &Body<'_>, cfg: &WorldConfig, h: f32) -> Option<Motion> {
    if !b.ccd || !is_active(b) {
        return None;
    }
    let sweep = (b.pose().position - b.pose0.position).length()
        + b.angular_velocity.length() * h * b.core_reach();
    if sweep > cfg.ccd_motion_fraction * b.shape.min_extent() {
        Some(motion_of(b, h))
    } else {
        None
    }
}

/// The earliest hit of the fast body in slot `i` that counts (module docs): its time and
/// the other body's slot. Adds the time-of-impact queries it runs to `queries`.
#[allow(clippy::too_many_arguments)]
fn earliest_hit<const N: usize>(
    fast: &Body<'_>,
    motion: &Motion,
    i: u32,
    bodies: &Pool<Body<'_>, N>,
    others: impl Iterator<Item = u32>,
    cfg: &WorldConfig,
    h: f32,
    tolerance: f32,
    queries: &mut u32,
) -> Option<(f32, u32)> {
    if fast.sensor {
        return None;
    }
    let mut best: Option<(f32, u32)> = None;
    for other in others {
        if other == i {
            continue;
        }
        let Some(o) = bodies.at(other as usize) else {
            continue;
        };
        if o.sensor || !may_pair(fast, o) {
            continue;
        }
        let other_motion = motion_of(o, h);
        let toi = if fast.shape.is_convex() && o.shape.is_convex() {
            *queries = queries.saturating_add(1);
            time_of_impact_unchecked(&fast.shape, motion, &o.shape, &other_motion, h, tolerance)
        } else {
            earliest_part_toi(fast, motion, o, &other_motion, h, tolerance, queries)
        };
        let (time, normal) = match toi {
            Toi::Hit { time, normal, .. } => (time, Some(normal)),
            // The sweep's budget ran out before it could clear the rest of the step:
            // stop at the last time it is sure of (module docs, conservative).
            Toi::Unresolved { time } => (time, None),
            Toi::Separated | Toi::Overlapping => continue,
        };
        if time <= 0.0 || best.is_some_and(|(t, _)| time >= t) {
            continue;
        }
        // How much deeper the rest of the motion would take the bodies along the normal.
        let deeper = normal.is_none_or(|n| {
            let closing = (motion.linear - other_motion.linear).dot(n)
                + motion.angular.length() * fast.shape.core_reach()
                + other_motion.angular.length() * o.shape.core_reach();
            closing * (h - time) > cfg.slop
        });
        if deeper {
            best = Some((time, other));
        }
    }
    best
}

/// The earliest time of impact between the parts of two bodies (a mesh's triangles, a
/// compound's parts) whose bounds meet the other's path over the step. A part moves with
/// its body's motion, from its pose in the body at the start, its origin at the velocity
/// it has there (`v + ω × r`): exact for parts of bodies that do not turn, a first-order
/// path for turning compounds. Adds the queries it runs to `queries`.
fn earliest_part_toi(
    fast: &Body<'_>,
    motion: &Motion,
    o: &Body<'_>,
    other_motion: &Motion,
    h: f32,
    tolerance: f32,
    queries: &mut u32,
) -> Toi {
    let path = |b: &Body<'_>| b.shape.aabb(&b.pose0).union(&b.shape.aabb(b.pose()));
    let (fast_path, other_path) = (path(fast), path(o));
    let mut best = Toi::Separated;
    let mut best_time = f32::INFINITY;
    mid_phase::parts_near(&fast.shape, &motion.pose, &other_path, |pa, at_a| {
        let ma = part_motion(motion, at_a.as_ref());
        mid_phase::parts_near(&o.shape, &other_motion.pose, &fast_path, |pb, at_b| {
            let mb = part_motion(other_motion, at_b.as_ref());
            *queries = queries.saturating_add(1);
            let toi = time_of_impact_unchecked(&pa, &ma, &pb, &mb, h, tolerance);
            let time = match toi {
                Toi::Hit { time, .. } | Toi::Unresolved { time } => time,
                // Already touching a part: the contacts handle it, as for whole bodies.
                Toi::Separated | Toi::Overlapping => return,
            };
            if time > 0.0 && time < best_time {
                best_time = time;
                best = toi;
            }
        });
    });
    best
}

/// The motion of a part at `at` in its body's frame (`None`: the body's frame).
fn part_motion(m: &Motion, at: Option<&Iso>) -> Motion {
    match at {
        None => *m,
        Some(p) => {
            let r = m.pose.rotation.rotate(p.position);
            Motion {
                pose: m.pose * *p,
                linear: m.linear + m.angular.cross(r),
                angular: m.angular,
            }
        }
    }
}

/// Put a body at `pose` (its velocities unchanged).
fn move_to(b: &mut Body<'_>, pose: &Iso) {
    b.set_center_pose(pose.transform_point(b.center_local), pose.rotation);
}
