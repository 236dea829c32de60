//! Stage 4: the mid phase. A pair of convex bodies is one contact. A pair with a triangle
//! mesh or a compound is a *record* (no points; it carries the pair's touching state and
//! events) and one *part contact* per pair of parts that may touch: per triangle of a
//! mesh, per part of a compound. Each part contact runs the convex narrow phase on its
//! two parts, keeps its own manifold, cache and warm start, and is solved like any
//! other contact.
//!
//! # Which parts
//!
//! A part of body X may touch body Y when its bounds, in X's frame, overlap Y's enlarged
//! box (`Body::fat`, which covers Y's motion this step and the speculative margin)
//! moved into X's frame ([`Aabb::transformed`]): a compound tests each part's bounds, a
//! mesh walks its hierarchy ([`TriangleMesh::query_aabb`]). When both bodies have parts
//! (a compound on a mesh, two compounds), each part of X that may touch Y is grown by as
//! much as X's enlarged box exceeds X's bounds, and Y's parts are those its box reaches.
//!
//! # Keys and order
//!
//! Part `i` of A and part `j` of B have the key `sub = 1 + i · parts(B) + j` (a convex
//! shape has one part); the record has [`RECORD`], so in `contacts` (sorted by pair, then
//! `sub`) a pair's part contacts come in key order and its record last. Every step, for
//! every pair with an awake body, this stage lists the part pairs that may touch (sorted,
//! at most [`MAX_PAIR_PARTS`]: the first found in the hierarchy's order are kept, the
//! rest counted in `StepReport::dropped_contacts`), removes the part contacts no longer
//! listed (compacting in place, in key order) and adds the new ones with no points
//! (expanding in place from the back); new part contacts that do not fit in `contacts`
//! are dropped, the highest keys first, and counted the same way. Sleeping pairs keep
//! their part contacts as they are.
//!
//! # Lists kept
//!
//! A pair's list is a function of the convex body's enlarged box and of the other body's
//! pose (its parts' bounds in its frame). When that body is static (terrain, level
//! geometry) its pose changes only by a teleport, and an enlarged box is replaced only
//! with the body flagged `moved`; so while neither body has been flagged since the
//! pair was last listed, the list is the one its part contacts hold, and stage 4 reads
//! it from them instead of querying the hierarchy again ([`list_kept`]). The broad
//! phase turns each `moved` flag it clears into `Body::relist`; stage 4 clears every
//! `relist` once it has placed every list whole, and keeps them all (every list formed
//! again next step) after a step that dropped part contacts. New and restored bodies
//! start flagged, and a new pair always has a flagged body (the broad phase finds pairs
//! only around moved bodies). The lists, and so the contacts, are the same bits either
//! way (`kept_part_lists_give_the_bits_of_lists_formed_every_step`). The terrain scenes
//! keep 85 % of their lists over 300 steps; `mesh_pile`'s stage 4 takes a quarter fewer
//! instructions (its 300 bodies replace about 37 enlarged boxes a step).

use heapless::Vec as HVec;

use crate::collide::Manifold;
use crate::dynamics::body::{Body, BodyKind};
use crate::dynamics::broad_phase::may_collide;
use crate::dynamics::contact::{Contact, ContactPoint, RECORD};
use crate::dynamics::events::StepReport;
use crate::dynamics::pool::Pool;
use crate::math::{scalar, Aabb, Iso, Vec3};
use crate::shape::Shape;
use crate::shape::{HeightField, Triangle, TriangleMesh};

/// Most part pairs one body pair may have contacts for at a time (a box on a mesh whose
/// triangles are much smaller than it reaches this; the rest are dropped and counted).
pub const MAX_PAIR_PARTS: usize = 128;

// A record counts the part contacts it adds in a `u8` (`Contact::new_parts`).
const _: () = assert!(MAX_PAIR_PARTS <= u8::MAX as usize);

/// The two convex parts of a part contact, each with its pose in its body's frame (`None`
/// when the part's frame is the body's: a convex body, a mesh triangle).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PartPair<'a> {
    pub a: Shape<'a>,
    pub pose_a: Option<Iso>,
    pub b: Shape<'a>,
    pub pose_b: Option<Iso>,
}

/// How many parts the mid phase numbers in a shape: a mesh's triangles, a compound's
/// parts, or 1 for a convex shape.
#[inline]
pub(crate) fn part_count(s: &Shape<'_>) -> u32 {
    match s {
        Shape::Mesh(m) => m.triangle_count(),
        Shape::HeightField(f) => f.triangle_count(),
        Shape::Compound(c) => c.part_count(),
        _ => 1,
    }
}

/// Part `i` of a shape and its pose in the shape's frame; `None` past the last.
fn part<'a>(s: &Shape<'a>, i: u32) -> Option<(Shape<'a>, Option<Iso>)> {
    match s {
        Shape::Mesh(m) => m.triangle(i).map(|t| (Shape::Triangle(t), None)),
        Shape::HeightField(f) => f.triangle(i).map(|t| (Shape::Triangle(t), None)),
        Shape::Compound(c) => c.part(i).map(|(p, _)| (p.shape, Some(p.pose))),
        _ => (i == 0).then_some((*s, None)),
    }
}

/// The part pair a part contact's `sub` names (module docs); `None` for a key that names
/// no part (a record, a convex pair's contact, a key past the shapes' parts).
pub(crate) fn part_pair<'a>(a: &Shape<'a>, b: &Shape<'a>, sub: u32) -> Option<PartPair<'a>> {
    if sub == RECORD {
        return None;
    }
    let k = sub.checked_sub(1)?;
    let nb = part_count(b).max(1);
    let (pa, pose_a) = part(a, k.checked_div(nb)?)?;
    let (pb, pose_b) = part(b, k.checked_rem(nb)?)?;
    Some(PartPair {
        a: pa,
        pose_a,
        b: pb,
        pose_b,
    })
}

/// A lower bound (m) of the distance between two parts (convex shapes at their world
/// poses) when they are certainly farther apart than `margin`, so their narrow phase
/// would find no point; `None` when they may come within `margin`. Judged by the ball
/// about each convex part's origin (radius [`Shape::bounding_radius`]) and, for a triangle, by
/// the exact closest point on it. A part group runs its narrow phase on every part whose
/// box meets the other body's enlarged box; on terrain most of those are a neighbouring
/// cell's triangles that a body only overhangs (`mesh_pile`: 46 % of the calls, none of
/// them with a point).
pub(crate) fn beyond_reach(
    a: &Shape<'_>,
    pose_a: &Iso,
    b: &Shape<'_>,
    pose_b: &Iso,
    margin: f32,
) -> Option<f32> {
    // (distance between the balls' or the ball's and the triangle's nearest points, the
    // size of the numbers it was computed from)
    let (gap, scale) = match (a, b) {
        (Shape::Triangle(t), other) => ball_to_triangle(t, pose_a, other, pose_b),
        (other, Shape::Triangle(t)) => ball_to_triangle(t, pose_b, other, pose_a),
        _ => {
            let radii = a.bounding_radius() + b.bounding_radius();
            let d = pose_b.position - pose_a.position;
            (d.length() - radii, d.abs().max_elem() + radii)
        }
    };
    // The gap is exact to rounding of those numbers; a relative guard keeps the test and
    // the bound on the safe side of it.
    let guard = REACH_GUARD * (1.0 + scale);
    (gap > margin + guard).then_some(gap - guard)
}

/// Relative rounding guard of [`beyond_reach`].
const REACH_GUARD: f32 = 1.0e-5;

/// Distance (m) from triangle `t` at `pose_t` to the ball about `other`'s origin, and the
/// size of the numbers it comes from. Only a ball beside the triangle (nearest to an edge
/// or a corner) is measured; one over its face reads as touching: the separating axis
/// test answers that case at once from its cached face axis, and a distance to the plane
/// would cost more than it saves (`mesh_pile`: +0.5 % instructions).
fn ball_to_triangle(t: &Triangle, pose_t: &Iso, other: &Shape<'_>, pose_o: &Iso) -> (f32, f32) {
    let centre = pose_t.inverse_transform_point(pose_o.position);
    let r = other.bounding_radius();
    let (closest, _) = crate::collide::analytic::closest_on_triangle(t, centre);
    let d = closest - centre;
    (
        d.length() - r,
        centre.abs().max_elem() + d.abs().max_elem() + r,
    )
}

/// Part `i`'s bounds in its shape's frame (a convex shape: its own).
fn part_bounds(s: &Shape<'_>, i: u32) -> Aabb {
    match s {
        Shape::Mesh(_) | Shape::HeightField(_) => {
            part(s, i).map_or(Aabb::default(), |(t, _)| t.local_aabb())
        }
        Shape::Compound(c) => c.part(i).map_or(Aabb::default(), |(_, b)| b),
        _ => s.local_aabb(),
    }
}

/// Call `f` with every part of `s` whose bounds (in `s`'s frame) overlap `region` (in
/// `s`'s frame): a mesh in its hierarchy's order, a compound in part order, a convex
/// shape's only part always.
fn query_parts(s: &Shape<'_>, region: &Aabb, f: impl FnMut(u32)) {
    let mut f = f;
    match s {
        Shape::Mesh(m) => m.query_aabb(region, f),
        Shape::HeightField(h) => h.query_aabb(region, f),
        Shape::Compound(c) => c.query_aabb(region, f),
        _ => f(0),
    }
}

/// How far a body's enlarged box reaches past its bounds (m): the largest margin on any
/// side, never negative.
fn fat_growth(body: &Body<'_>) -> f32 {
    let tight = body.shape.aabb(body.pose());
    let lo = tight.min - body.fat.min;
    let hi = body.fat.max - tight.max;
    lo.max(hi).max_elem().max(0.0)
}

/// The part pairs of bodies `a` and `b` that may touch (module docs), sorted; false when
/// some did not fit in `out` (those found first are kept).
pub(crate) fn candidates(a: &Body<'_>, b: &Body<'_>, out: &mut HVec<u32, MAX_PAIR_PARTS>) -> bool {
    out.clear();
    let nb = part_count(&b.shape).max(1);
    let mut fits = true;
    let mut push = |i: u32, j: u32| {
        let key = 1 + i * nb + j;
        if out.push(key).is_err() {
            fits = false;
        }
    };
    let b_in_a_frame = b.fat.transformed(&a.pose().inverse());
    if b.shape.is_convex() {
        query_parts(&a.shape, &b_in_a_frame, |i| push(i, 0));
    } else if a.shape.is_convex() {
        let a_in_b_frame = a.fat.transformed(&b.pose().inverse());
        query_parts(&b.shape, &a_in_b_frame, |j| push(0, j));
    } else {
        // Both have parts: each of A's that reaches B, grown like A's box, against B's.
        let grow = fat_growth(a);
        let a_to_b = b.pose().inverse() * *a.pose();
        let a_in_b_frame = a.fat.transformed(&b.pose().inverse());
        query_parts(&a.shape, &b_in_a_frame, |i| {
            let region = part_bounds(&a.shape, i).transformed(&a_to_b).expanded(grow);
            if region.overlaps(&a_in_b_frame) {
                query_parts(&b.shape, &region, |j| push(i, j));
            }
        });
    }
    // A height field lists its cells' triangles in index order, and a convex partner
    // keeps the keys in that order: sort only what came out of order (a mesh's tree, a
    // compound's parts, two part lists).
    // (Pairs by zipped iterators: `is_sorted` links a slice-index panic on thumbv7em.)
    let in_order = out.iter().zip(out.iter().skip(1)).all(|(x, y)| x <= y);
    if !in_order {
        crate::sort::sort_unstable(out);
    }
    fits
}

/// Stage 4 over every pair with a mesh or compound (module docs): part contacts no
/// longer listed are removed, new ones added with no points, in key order. Pairs of
/// convex shapes pass through untouched.
///
/// Each contact that stays is copied at most once, straight to its new slot
/// ([`plan_relocation`], then [`relocate`]); a step with more new part contacts or
/// more runs of contacts moving up than the plan holds, or with more new part contacts
/// than the buffer has room for, takes [`update_parts_in_two_passes`] instead (the
/// same result). Then the bodies' `relist` flags ([`lists_placed`]).
pub(crate) fn update_parts<const N: usize, const C: usize>(
    contacts: &mut HVec<Contact, C>,
    bodies: &mut Pool<Body<'_>, N>,
    report: &mut StepReport,
) {
    if contacts.iter().any(Contact::is_record) {
        let dropped = report.dropped_contacts;
        update_part_contacts(contacts, bodies, report);
        lists_placed(bodies, report.dropped_contacts == dropped);
    }
}

/// [`update_parts`] for a buffer with a pair record. Kept out of line: its plan and list
/// (about 3 KiB) take stack only in worlds with meshes or compounds, not in every step
/// of a world of convex shapes (the minimal firmware's peak grew by that much while
/// they were inlined).
#[inline(never)]
fn update_part_contacts<const N: usize, const C: usize>(
    contacts: &mut HVec<Contact, C>,
    bodies: &Pool<Body<'_>, N>,
    report: &mut StepReport,
) {
    let mut list: HVec<u32, MAX_PAIR_PARTS> = HVec::new();
    match plan_relocation(contacts.as_mut_slice(), C, bodies, &mut list) {
        Some(plan) => {
            relocate(contacts, &plan);
            report.dropped_contacts = report.dropped_contacts.saturating_add(plan.dropped);
        }
        None => {
            // The plan's marks are undone; its lists are formed again (and its drops
            // counted once, there).
            for c in contacts.iter_mut() {
                c.new_parts = 0;
            }
            update_parts_in_two_passes(contacts, bodies, report);
        }
    }
}

/// [`Contact::new_parts`] of a part contact that goes, while an update is planned
/// ([`plan_relocation`]); any other contact holds there how many new part contacts
/// come just before it (at most [`MAX_PAIR_PARTS`]).
const GOES: u8 = u8::MAX;

const _: () = assert!(MAX_PAIR_PARTS < GOES as usize);

/// Most new part contacts a [`Relocation`] holds (a step of `mesh_pile` adds a few
/// dozen).
const RELOCATE_NEW: usize = 128;

/// Most runs of contacts moving up a [`Relocation`] holds.
const RELOCATE_RUNS: usize = 64;

/// The moves of one update of the part contacts ([`plan_relocation`]). With `dest(i)`
/// the slot contact `i` ends in, the map is increasing, so contacts moving down can be
/// copied in slot order and those moving up in reverse slot order, each straight to its
/// slot, without overwriting one that has not moved yet.
struct Relocation {
    /// Contacts after the update.
    total: usize,
    /// Each new part contact: its slot, the slot its pair's record ends in, its part key.
    new: HVec<[u32; 3], RELOCATE_NEW>,
    /// Runs of contacts moving up: first slot, end slot (exclusive), how many slots up.
    up: HVec<[u32; 3], RELOCATE_RUNS>,
    /// Pairs whose list did not fit.
    dropped: u32,
}

/// Plan an update (pass 1, forward; nothing moves): mark each part contact that goes
/// ([`GOES`]) and write into every other how many new part contacts come just before
/// it: the pair's listed parts that no contact holds, below it and above the pair's
/// last contact that stays (for a record, all those left). `None` when the plan does
/// not fit ([`RELOCATE_NEW`], [`RELOCATE_RUNS`]) or the update would hold more than
/// `capacity` contacts.
fn plan_relocation<const N: usize>(
    slots: &mut [Contact],
    capacity: usize,
    bodies: &Pool<Body<'_>, N>,
    list: &mut HVec<u32, MAX_PAIR_PARTS>,
) -> Option<Relocation> {
    let mut plan = Relocation {
        total: 0,
        new: HVec::new(),
        up: HVec::new(),
        dropped: 0,
    };
    // The pair whose list is in `list`, and the next list entry to match.
    let mut current: Option<(u64, usize)> = None;
    // Where the current pair's new part contacts start in `plan.new`.
    let mut pair_new = 0usize;
    // The slot after the last contact that stays, and the new part contacts placed
    // since (they come before the next contact that stays: the pair's record at last).
    let mut pos = 0usize;
    let mut before = 0usize;
    for i in 0..slots.len() {
        let Some((key, sub, a, b)) = slots.get(i).map(|c| (c.key(), c.sub, c.a, c.b)) else {
            break;
        };
        if sub != 0 && current.is_none_or(|(k, _)| k != key) {
            let pair = slots.get(i..).unwrap_or(&[]);
            current = listed(a, b, bodies, list, &mut plan.dropped, Some(pair)).map(|_| (key, 0));
            pair_new = plan.new.len();
        }
        let Some(c) = slots.get_mut(i) else {
            break;
        };
        if sub != 0 {
            if let Some((_, next)) = current.as_mut() {
                while let Some(&listed_sub) = list.get(*next) {
                    if listed_sub >= sub {
                        break;
                    }
                    plan.new.push([(pos + before) as u32, 0, listed_sub]).ok()?;
                    before += 1;
                    *next += 1;
                }
                if sub == RECORD {
                    let record = (pos + before) as u32;
                    for e in plan.new.iter_mut().skip(pair_new) {
                        e[1] = record;
                    }
                    current = None;
                } else if list.get(*next) == Some(&sub) {
                    *next += 1;
                } else {
                    c.new_parts = GOES;
                    continue;
                }
            }
        }
        // At most the list's length: below `GOES`.
        c.new_parts = before as u8;
        let dest = pos + before;
        pos = dest + 1;
        before = 0;
        if dest > i {
            let shift = (dest - i) as u32;
            match plan.up.last_mut() {
                Some(run) if run[1] == i as u32 && run[2] == shift => run[1] += 1,
                _ => plan.up.push([i as u32, i as u32 + 1, shift]).ok()?,
            }
        }
    }
    plan.total = pos;
    (pos <= capacity).then_some(plan)
}

/// Carry out `plan` (made by [`plan_relocation`] on `contacts` as they are): pass 2,
/// forward, copies each contact that moves down to its slot and clears every mark;
/// pass 3 copies the runs that move up, last first, each from its end; then each new
/// part contact is written to its slot with its record's bodies and material, and the
/// buffer takes its new length.
fn relocate<const C: usize>(contacts: &mut HVec<Contact, C>, plan: &Relocation) {
    let len = contacts.len();
    let slots = contacts.as_mut_slice();
    let mut pos = 0usize;
    for i in 0..len {
        let Some(c) = slots.get_mut(i) else {
            break;
        };
        let before = c.new_parts;
        if before == GOES {
            continue;
        }
        c.new_parts = 0;
        let dest = pos + usize::from(before);
        pos = dest + 1;
        if dest < i {
            move_down(slots, i, dest);
        }
    }
    for _ in len..plan.total {
        // Cannot fail: the plan checked the capacity.
        let _ = contacts.push(Contact::default());
    }
    let slots = contacts.as_mut_slice();
    for &[start, end, shift] in plan.up.iter().rev() {
        for i in (start..end).rev() {
            move_up(slots, i as usize, (i + shift) as usize);
        }
    }
    for &[slot, record, sub] in plan.new.iter() {
        let Some(r) = slots.get(record as usize) else {
            continue;
        };
        let (a, b, material, sensor) = (r.a, r.b, r.material, r.sensor);
        if let Some(dst) = slots.get_mut(slot as usize) {
            *dst = Contact::new_pair(a, b, material, sensor);
            dst.sub = sub;
        }
    }
    contacts.truncate(plan.total);
}

/// [`update_parts`] in two passes, each contact copied up to twice: pass 1 compacts away
/// the part contacts no longer listed, pass 2 ([`add_missing`]) opens room for the new
/// ones from the end. It handles a full buffer (the lowest keys are kept).
fn update_parts_in_two_passes<const N: usize, const C: usize>(
    contacts: &mut HVec<Contact, C>,
    bodies: &Pool<Body<'_>, N>,
    report: &mut StepReport,
) {
    let mut list: HVec<u32, MAX_PAIR_PARTS> = HVec::new();
    let mut dropped = 0u32;
    // Pass 1, forward: compact away the part contacts no longer listed; each record
    // notes how many of its list are missing.
    let len = contacts.len();
    let slots = contacts.as_mut_slice();
    let mut write = 0usize;
    // The pair whose list is in `list`, how many of it exist so far.
    let mut current: Option<(u64, usize)> = None;
    let mut missing_total = 0usize;
    for read in 0..len {
        // Only the key is read here: a contact is copied only when it moves down.
        let Some((key, sub, a, b)) = slots.get(read).map(|c| (c.key(), c.sub, c.a, c.b)) else {
            break;
        };
        let mut keep = true;
        if sub != 0 {
            if current.is_none_or(|(k, _)| k != key) {
                let pair = slots.get(read..).unwrap_or(&[]);
                current =
                    listed(a, b, bodies, &mut list, &mut dropped, Some(pair)).map(|_| (key, 0));
            }
            if sub == RECORD {
                let missing = match current {
                    // At most MAX_PAIR_PARTS (the list's capacity): fits in a u8.
                    Some((_, found)) => list.len().saturating_sub(found) as u8,
                    None => 0,
                };
                if let Some(c) = slots.get_mut(read) {
                    c.new_parts = missing;
                }
                missing_total += usize::from(missing);
                current = None;
            } else if let Some((_, found)) = current.as_mut() {
                if list.binary_search(&sub).is_ok() {
                    *found += 1;
                } else {
                    keep = false;
                }
            }
        }
        if keep {
            if read != write {
                move_down(slots, read, write);
            }
            write += 1;
        }
    }
    contacts.truncate(write);
    if missing_total > 0 {
        let room = C - contacts.len();
        if missing_total > room {
            // Keep the lowest keys: cut from the last record backwards.
            let mut excess = missing_total - room;
            for c in contacts.iter_mut().rev() {
                if excess == 0 {
                    break;
                }
                if c.is_record() {
                    let cut = usize::from(c.new_parts).min(excess);
                    c.new_parts -= cut as u8;
                    excess -= cut;
                    dropped = dropped.saturating_add(cut as u32);
                }
            }
            missing_total = room;
        }
        add_missing(contacts, bodies, missing_total, &mut list);
    }
    report.dropped_contacts = report.dropped_contacts.saturating_add(dropped);
}

/// The list of the pair of slots `a` and `b` (a part contact's or record's) into
/// `list`, or `None` when the pair is left as it is this step: a body gone, the boxes
/// apart (stage 6 removes it), or nothing awake. With `pair` (the contacts from the
/// pair's first on), a pair whose list is the one its part contacts hold ([`list_kept`])
/// takes theirs, read from them instead of formed again.
fn listed<const N: usize>(
    a: u32,
    b: u32,
    bodies: &Pool<Body<'_>, N>,
    list: &mut HVec<u32, MAX_PAIR_PARTS>,
    dropped: &mut u32,
    pair: Option<&[Contact]>,
) -> Option<()> {
    let (a, b) = (bodies.at(a as usize)?, bodies.at(b as usize)?);
    if !a.fat.overlaps(&b.fat) || !may_collide(a, b) {
        return None;
    }
    if let (Some(pair), true) = (pair, list_kept(a, b)) {
        #[cfg(test)]
        tests::KEPT.with(|k| k.set(k.get() + 1));
        list.clear();
        for c in pair.iter().take_while(|c| !c.is_record()) {
            // Cannot fail: a pair holds at most `MAX_PAIR_PARTS` part contacts.
            let _ = list.push(c.sub);
        }
        return Some(());
    }
    if !candidates(a, b, list) {
        *dropped = dropped.saturating_add(1);
    }
    Some(())
}

/// True when the part list of bodies `a` and `b` is the one their part contacts hold
/// (module docs, "Lists kept"): neither box changed since the last listing
/// ([`Body::relist`]) and the body with parts is static, so that what the list is formed
/// from (the convex body's enlarged box, the other's pose) is as it was.
fn list_kept(a: &Body<'_>, b: &Body<'_>) -> bool {
    if a.relist || b.relist {
        return false;
    }
    match (a.shape.is_convex(), b.shape.is_convex()) {
        (false, true) => a.kind == BodyKind::Static,
        (true, false) => b.kind == BodyKind::Static,
        _ => false,
    }
}

/// After stage 4 ([`update_parts`]): with every list placed whole (`whole`: nothing
/// dropped), each body's part lists are as its box gives them, and its `relist` flag
/// is cleared; otherwise every flag stays, and every list is formed again next step.
fn lists_placed<const N: usize>(bodies: &mut Pool<Body<'_>, N>, whole: bool) {
    if whole {
        for (_, b) in bodies.iter_mut() {
            b.relist = false;
        }
    } else {
        for (_, b) in bodies.iter_mut() {
            b.relist = true;
        }
    }
}

/// Copy `slots[from]` to `slots[to]` (`to < from`) straight, without a copy on the way
/// (a contact is a few hundred bytes); nothing when either is out of range.
#[inline(always)]
fn move_down(slots: &mut [Contact], from: usize, to: usize) {
    if let Some((low, high)) = slots.split_at_mut_checked(from) {
        if let (Some(dst), Some(src)) = (low.get_mut(to), high.first()) {
            dst.copy_from(src);
        }
    }
}

/// Copy `slots[from]` to `slots[to]` (`to > from`), as [`move_down`].
#[inline(always)]
fn move_up(slots: &mut [Contact], from: usize, to: usize) {
    if let Some((low, high)) = slots.split_at_mut_checked(to) {
        if let (Some(src), Some(dst)) = (low.get(from), high.first_mut()) {
            dst.copy_from(src);
        }
    }
}

/// Pass 2, backward: open room for `total` new part contacts and write each record's
/// first `new_parts` missing ones (the lowest keys), merged with its existing part
/// contacts in key order. Every contact moves up by the number of new ones below it, so
/// each is read before its slot is written.
fn add_missing<const N: usize, const C: usize>(
    contacts: &mut HVec<Contact, C>,
    bodies: &Pool<Body<'_>, N>,
    total: usize,
    list: &mut HVec<u32, MAX_PAIR_PARTS>,
) {
    let old_len = contacts.len();
    for _ in 0..total {
        // Cannot fail: `total` is at most the room left.
        let _ = contacts.push(Contact::default());
    }
    let slots = contacts.as_mut_slice();
    let mut write = slots.len();
    let mut read = old_len;
    let mut missing: HVec<u32, MAX_PAIR_PARTS> = HVec::new();
    let mut unused = 0u32;
    while read > 0 && write > read {
        read -= 1;
        write -= 1;
        move_up(slots, read, write);
        let Some(c) = slots.get_mut(write) else {
            break;
        };
        let wanted = usize::from(c.new_parts);
        c.new_parts = 0;
        if !c.is_record() || wanted == 0 {
            continue;
        }
        let (a, b, material, sensor, key) = (c.a, c.b, c.material, c.sensor, c.key());
        // The same list as pass 1 (nothing changed since).
        if listed(a, b, bodies, list, &mut unused, None).is_none() {
            continue;
        }
        // The pair's part contacts are `slots[first..read]`.
        let mut first = read;
        while first > 0 && slots.get(first - 1).is_some_and(|e| e.key() == key) {
            first -= 1;
        }
        missing.clear();
        let mut e = first;
        for &sub in list.iter() {
            while e < read && slots.get(e).is_some_and(|x| x.sub < sub) {
                e += 1;
            }
            let exists = e < read && slots.get(e).is_some_and(|x| x.sub == sub);
            if !exists && missing.len() < wanted {
                // Cannot fail: `missing` holds at most the list's length.
                let _ = missing.push(sub);
            }
        }
        let (mut ei, mut mi) = (read, missing.len());
        while ei > first || mi > 0 {
            let next_missing = if mi > 0 { missing.get(mi - 1) } else { None };
            let next_existing = if ei > first { slots.get(ei - 1) } else { None };
            let existing_next = match (next_missing, next_existing) {
                (Some(&m), Some(x)) if m < x.sub => true,
                (Some(&m), _) => {
                    mi -= 1;
                    write -= 1;
                    if let Some(dst) = slots.get_mut(write) {
                        *dst = Contact::new_pair(a, b, material, sensor);
                        dst.sub = m;
                    }
                    false
                }
                (None, Some(_)) => true,
                (None, None) => break,
            };
            if existing_next {
                ei -= 1;
                write -= 1;
                move_up(slots, ei, write);
            }
        }
        read = first;
    }
}

/// Call `f` with every part of `shape` (at `pose`) whose bounds meet the world box
/// `region`: the part's convex shape and its pose in `shape`'s frame (`None`: the same
/// frame). A convex shape is its own only part. The order is the parts' query order.
pub(crate) fn parts_near<'a>(
    shape: &Shape<'a>,
    pose: &Iso,
    region: &Aabb,
    mut f: impl FnMut(Shape<'a>, Option<Iso>),
) {
    if shape.is_convex() {
        f(*shape, None);
        return;
    }
    let local = region.transformed(&pose.inverse());
    query_parts(shape, &local, |i| {
        if let Some((p, at)) = part(shape, i) {
            f(p, at);
        }
    });
}

/// Largest `1 − n·f` for which a triangle contact's normal `n` is taken as the face
/// normal `f` (about 2.6°): the contact presses on the face.
const FACE_NORMAL_COS_SLACK: f32 = 1.0e-4;

/// Smallest bend (the sine of the angle the neighbour turns down by) that makes a mesh
/// edge *active*, a real ridge whose own normals contacts may use (about 2°): a flatter
/// or concave edge, inside a smooth surface, must not push bodies sideways.
const ACTIVE_EDGE_SIN: f32 = 0.035;

/// Internal edges (Box2D's smooth chain shapes, in 3D): a contact with triangle `tri` of
/// `mesh` (at `mesh_pose`) whose normal is within [`FACE_NORMAL_COS_SLACK`] of the face
/// normal takes the face normal exactly, its separations measured again along it (so a
/// body resting on a flat mesh is pushed straight up, never sideways by rounding in an
/// edge or GJK normal). A normal that leans further, towards an edge that is not active
/// (shared with a neighbour that continues the surface flat or bends up), is a ghost of
/// that seam: the contact is dropped (`m.len = 0`), since the neighbour's own contact
/// holds the body there. Edges without a neighbour, and ridges bending down by more than
/// [`ACTIVE_EDGE_SIN`], keep the normals the narrow phase found. `mesh_is_a` says which
/// side of the manifold the mesh is (the normal points from A to B). Neighbours are
/// found when needed, by the hierarchy, among the triangles that share the edge's two
/// end points.
pub(crate) fn correct_internal_edges(
    m: &mut Manifold,
    mesh: &Soup<'_, '_>,
    tri: u32,
    mesh_pose: &Iso,
    mesh_is_a: bool,
) {
    let Some(t) = mesh.triangle(tri) else {
        return;
    };
    // The manifold's normal as seen from the triangle, in the mesh's frame.
    let sign = if mesh_is_a { 1.0 } else { -1.0 };
    let n = mesh_pose.inverse_transform_vector(m.normal) * sign;
    let mut f = t.normal();
    if n.dot(f) < 0.0 {
        f = -f; // two-sided: the side the other body is on
    }
    let cos = n.dot(f);
    if cos >= 1.0 - FACE_NORMAL_COS_SLACK {
        // The face normal: the same witness points, their gap measured along it.
        let face = mesh_pose.transform_vector(f) * sign;
        m.normal = face;
        for p in m.points.iter_mut().take(usize::from(m.len)) {
            p.separation = (p.point_b - p.point_a).dot(face);
        }
        return;
    }
    // The edge the normal leans towards: the largest share of its tangential part along
    // the edge's outward direction in the triangle's plane.
    let lean = n - f * cos;
    let [p0, p1, p2] = t.vertices;
    let centroid = (p0 + p1 + p2) * (1.0 / 3.0);
    let mut best: Option<(usize, f32)> = None;
    for (k, (u, v)) in [(p0, p1), (p1, p2), (p2, p0)].into_iter().enumerate() {
        let mut out = (v - u).cross(f).normalize_or(Vec3::ZERO);
        if out.dot(u - centroid) < 0.0 {
            out = -out;
        }
        let d = out.dot(lean);
        if best.is_none_or(|(_, b)| d > b) {
            best = Some((k, d));
        }
    }
    if let Some((edge, _)) = best {
        if !edge_is_active(mesh, tri, edge, f) {
            m.len = 0;
        }
    }
}

/// True when edge `edge` (0: v0–v1, 1: v1–v2, 2: v2–v0) of triangle `tri` has no
/// neighbour, or its neighbour turns down from the face (normal `f`, the side in use) by
/// more than [`ACTIVE_EDGE_SIN`] (see [`correct_internal_edges`]). A neighbour is another
/// triangle with both of the edge's end points, the same bits.
fn edge_is_active(soup: &Soup<'_, '_>, tri: u32, edge: usize, f: Vec3) -> bool {
    let Some(t) = soup.triangle(tri) else {
        return true;
    };
    let [p0, p1, p2] = t.vertices;
    let (u, v) = match edge {
        0 => (p0, p1),
        1 => (p1, p2),
        _ => (p2, p0),
    };
    // The neighbour's third vertex: below the face's plane by more than the threshold
    // (relative to its distance) means a ridge.
    soup.neighbour_apex(tri, edge, u, v)
        .is_none_or(|w| turns_down(f, w - u))
}

/// True when `r` (from the shared edge to the neighbour's third vertex) lies below the
/// face's plane (normal `f`) by more than [`ACTIVE_EDGE_SIN`] of its length: a ridge.
#[inline]
fn turns_down(f: Vec3, r: Vec3) -> bool {
    f.dot(r) < -ACTIVE_EDGE_SIN * r.length()
}

/// The triangles of a mesh or a height field, for the internal-edge rule.
#[derive(Clone, Copy)]
pub(crate) enum Soup<'s, 'a> {
    /// A triangle mesh.
    Mesh(&'s TriangleMesh<'a>),
    /// A height field's cells.
    Field(&'s HeightField<'a>),
}

impl Soup<'_, '_> {
    /// The soup of a shape made of triangles.
    fn of<'s, 'a>(shape: &'s Shape<'a>) -> Option<Soup<'s, 'a>> {
        match shape {
            Shape::Mesh(m) => Some(Soup::Mesh(m)),
            Shape::HeightField(f) => Some(Soup::Field(f)),
            _ => None,
        }
    }

    fn triangle(&self, i: u32) -> Option<Triangle> {
        match self {
            Soup::Mesh(m) => m.triangle(i),
            Soup::Field(f) => f.triangle(i),
        }
    }

    /// The third vertex of the other triangle holding both end points `u` and `v` (the
    /// same bits) of edge `edge` of triangle `tri`, or `None` when no other triangle
    /// does. A height field's grid names that triangle; a mesh searches its hierarchy
    /// for the first one, in query order, with a third vertex.
    fn neighbour_apex(&self, tri: u32, edge: usize, u: Vec3, v: Vec3) -> Option<Vec3> {
        let apex = |o: Triangle| o.vertices.into_iter().find(|&x| x != u && x != v);
        let mesh = match self {
            Soup::Field(field) => {
                return field
                    .edge_neighbour(tri, edge)
                    .and_then(|o| field.triangle(o))
                    .and_then(apex)
            }
            Soup::Mesh(mesh) => mesh,
        };
        let mut found = None;
        mesh.query_aabb(&Aabb::new(u.min(v), u.max(v)), |other| {
            if other == tri || found.is_some() {
                return;
            }
            found = mesh
                .triangle(other)
                .filter(|o| o.vertices.contains(&u) && o.vertices.contains(&v))
                .and_then(apex);
        });
        found
    }
}

/// [`correct_internal_edges`] for a part contact's manifold when one of the bodies is a
/// mesh or height field (`sub` the part contact's key).
pub(crate) fn correct_mesh_contact(
    m: &mut Manifold,
    a: &Shape<'_>,
    pose_a: &Iso,
    b: &Shape<'_>,
    pose_b: &Iso,
    sub: u32,
) {
    let Some(k) = sub.checked_sub(1) else {
        return;
    };
    let nb = part_count(b).max(1);
    let (Some(i), Some(j)) = (k.checked_div(nb), k.checked_rem(nb)) else {
        return;
    };
    if let Some(soup) = Soup::of(a) {
        correct_internal_edges(m, &soup, i, pose_a, true);
    } else if let Some(soup) = Soup::of(b) {
        correct_internal_edges(m, &soup, j, pose_b, false);
    }
}

/// Smallest `cos` between two part contacts' normals for them to count as one patch in
/// [`merge_patches`] (about 1.8°): the triangles of a flat or gently curved mesh.
pub(crate) const PATCH_NORMAL_COS: f32 = 0.9995;

/// Per body pair, after a rebuild: part contacts whose normals agree within
/// [`PATCH_NORMAL_COS`] form one patch (a box on a flat mesh touches many triangles,
/// each with up to four points), whose points are reduced to the four a single plane
/// would give and moved into the patch's first contact (in key order), its *owner*; the
/// others keep no points. One patch is one contact to the solver, with one friction
/// patch, as on a single plane: a ring of redundant points makes a stiff, jittery
/// support that bounces and twists a landing body, and separate friction patches drag
/// unevenly. The four: among the points within `slop` of the deepest, the one furthest
/// from the points' centroid; then the furthest from it, the one spanning the largest
/// triangle with those, and the one adding the most area to that triangle (positions in
/// A's frame, ties to the earlier contact and point); points closer than `slop` to a
/// kept one count as the same point. Patches are grouped in key order, each around the
/// normal of its first contact. Sets each contact's `touching` from what it keeps.
pub(crate) fn merge_patches(group: &mut [Contact], slop: f32) {
    let mut grouped = [false; MAX_PAIR_PARTS];
    for start in 0..group.len().min(MAX_PAIR_PARTS) {
        let Some(first) = group.get(start) else {
            break;
        };
        if first.len == 0 || grouped.get(start).copied().unwrap_or(true) {
            continue;
        }
        let n = first.normal;
        // The patch's points: (contact, point) indices.
        let mut points: HVec<(u8, u8), { MAX_PAIR_PARTS * 4 }> = HVec::new();
        for (k, c) in group
            .iter()
            .enumerate()
            .skip(start)
            .take(MAX_PAIR_PARTS - start)
        {
            let free = !grouped.get(k).copied().unwrap_or(true);
            if free && c.len > 0 && c.normal.dot(n) >= PATCH_NORMAL_COS {
                if let Some(g) = grouped.get_mut(k) {
                    *g = true;
                }
                for i in 0..c.len {
                    // Cannot fail: at most 4 points for each of MAX_PAIR_PARTS contacts.
                    let _ = points.push((k as u8, i));
                }
            }
        }
        let point = |&(k, i): &(u8, u8)| {
            group
                .get(usize::from(k))
                .and_then(|c| c.points.get(usize::from(i)))
                .copied()
                .unwrap_or_default()
        };
        // What the choice reads of each point: its depth and its place on A, read where
        // the point lies (a copy of them all would be 8 KiB of stack: a Cortex-M step's
        // deepest frame).
        let read = |i: usize| {
            let p = points.get(i).map(point).unwrap_or_default();
            (p.separation, p.local_a)
        };
        let mut keep: HVec<ContactPoint, 4> = HVec::new();
        for &i in &choose_four(points.len(), read, slop) {
            if let Some(key) = points.get(i) {
                // Cannot fail: at most four.
                let _ = keep.push(point(key));
            }
        }
        for &(k, _) in &points {
            if let Some(c) = group.get_mut(usize::from(k)) {
                c.len = 0;
            }
        }
        if let Some(owner) = group.get_mut(start) {
            for (dst, p) in owner.points.iter_mut().zip(keep.iter()) {
                *dst = *p;
            }
            owner.len = keep.len() as u8;
        }
    }
    for c in group.iter_mut() {
        c.touching = c.points().iter().any(|p| p.separation <= slop);
    }
}

/// The (at most) four points of a patch [`merge_patches`] keeps, as their indices among
/// its `count` points; `read(i)` gives point `i`'s separation and its place in A's frame.
fn choose_four(count: usize, read: impl Fn(usize) -> (f32, Vec3), slop: f32) -> HVec<usize, 4> {
    let mut keep: HVec<usize, 4> = HVec::new();
    let mut at: HVec<Vec3, 4> = HVec::new();
    let area = |u: Vec3, v: Vec3, w: Vec3| scalar::sqrt((v - u).cross(w - u).length_squared());
    // The first point: the one furthest from the points' centroid among those within a
    // slop of the deepest (on a flat patch, a corner of the footprint).
    let mut deepest = f32::INFINITY;
    let mut sum = Vec3::ZERO;
    for (separation, x) in (0..count).map(&read) {
        deepest = scalar::min(deepest, separation);
        sum += x;
    }
    let centroid = sum * (1.0 / count.max(1) as f32);
    for _ in 0..4 {
        let score = |separation: f32, x: Vec3| -> f32 {
            match at.as_slice() {
                [] if separation <= deepest + slop => (x - centroid).length_squared(),
                [] => f32::NEG_INFINITY,
                [x1] => (x - *x1).length_squared(),
                [x1, x2] => (*x2 - *x1).cross(x - *x1).length_squared(),
                [x1, x2, x3, ..] => area(*x1, *x2, x) + area(*x2, *x3, x) + area(*x3, *x1, x),
            }
        };
        let mut best: Option<(usize, Vec3, f32)> = None;
        for (i, (separation, x)) in (0..count).map(&read).enumerate() {
            // A point on top of a kept one adds nothing (nor does a kept one).
            if at.iter().any(|k| (x - *k).length_squared() <= slop * slop) {
                continue;
            }
            let v = score(separation, x);
            if best.is_none_or(|(_, _, b)| v > b) {
                best = Some((i, x, v));
            }
        }
        let Some((i, x, _)) = best else {
            break;
        };
        // Cannot fail: four rounds.
        let _ = keep.push(i);
        let _ = at.push(x);
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::{contact, distance, SimplexCache};
    use crate::rng::SplitMix64;
    use crate::shape::ConvexHull;

    std::thread_local! {
        /// Pairs whose list this thread's mid phase kept (`listed`).
        pub(super) static KEPT: core::cell::Cell<u64> = const { core::cell::Cell::new(0) };
    }

    /// Run `f` with the reference hulls and the terrain scenes' shapes, on a thread with
    /// the stack their worlds need.
    fn on_terrain(
        f: impl FnOnce(&[ConvexHull], &crate::scenes::TerrainShapes<'_>) + Send + 'static,
    ) {
        use crate::scenes::{self, TerrainData};
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn(|| {
                let mut hulls = std::vec![ConvexHull::UNIT_TETRAHEDRON; scenes::REFERENCE_HULLS];
                scenes::make_hulls(&mut hulls, scenes::SEED).unwrap();
                let mut terrain: std::boxed::Box<TerrainData> = std::boxed::Box::default();
                let shapes = terrain.shapes().unwrap();
                f(&hulls, &shapes);
            })
            .unwrap()
            .join()
            .unwrap();
    }

    /// Kept lists ("Lists kept") against lists formed every step: on both terrain scenes
    /// (a height field and a mesh under 40 mixed bodies, both static) and on boxes and
    /// balls falling on the mesh as a kinematic body (whose lists are never kept), a
    /// world whose bodies are all flagged `relist` before every step (every list formed)
    /// ends every step with the checksum of the world that keeps them (on the terrains,
    /// the same contacts too, bit for bit); and the terrain worlds keep most lists.
    #[test]
    fn kept_part_lists_give_the_bits_of_lists_formed_every_step() {
        use crate::scenes::{ReferenceWorld, Scene};
        on_terrain(|hulls, shapes| {
            for scene in [Scene::Terrain, Scene::TerrainMesh] {
                let mut keeps: std::boxed::Box<ReferenceWorld<'_>> = std::boxed::Box::default();
                keeps.set_config(scene.config()).unwrap();
                scene
                    .build_on(&mut keeps, hulls, shapes.ground(scene))
                    .unwrap();
                let mut forms = keeps.clone();
                let (mut kept, mut listed) = (0u64, 0u64);
                for step in 0..300 {
                    for (_, b) in forms.bodies.iter_mut() {
                        b.relist = true;
                    }
                    let before = KEPT.with(|k| k.get());
                    forms.step();
                    assert_eq!(KEPT.with(|k| k.get()), before, "{scene:?} step {step}");
                    keeps.step();
                    kept += KEPT.with(|k| k.get()) - before;
                    listed += keeps.contacts.iter().filter(|c| c.is_record()).count() as u64;
                    let same = keeps.contacts.len() == forms.contacts.len()
                        && keeps
                            .contacts
                            .iter()
                            .zip(forms.contacts.iter())
                            .all(|(x, y)| x.same_as(y));
                    assert!(same, "{scene:?}: contacts differ after step {step}");
                    assert_eq!(keeps.checksum(), forms.checksum(), "{scene:?} step {step}");
                }
                // Most records are of resting or slowly moving bodies whose boxes stay.
                assert!(
                    kept * 2 > listed,
                    "{scene:?}: {kept} of {listed} lists kept"
                );
                std::println!("{scene:?}: {kept} of {listed} lists kept");
            }
            // The mesh as a kinematic body gliding under boxes and balls: its pose
            // moves every step, so no list of it is ever kept.
            let mesh = shapes.ground(Scene::TerrainMesh).unwrap();
            let mut keeps: std::boxed::Box<crate::World<'_, 64, 4096, 64>> =
                std::boxed::Box::default();
            keeps
                .add(
                    crate::BodyDesc::kinematic(mesh)
                        .position(Vec3::new(-8.0, -1.0, -8.0))
                        .velocity(Vec3::new(0.3, 0.0, 0.1)),
                )
                .unwrap();
            let cube = Shape::cuboid(Vec3::splat(0.3)).unwrap();
            let ball = Shape::sphere(0.25).unwrap();
            for i in 0..16 {
                let p = Vec3::new((i % 4) as f32 - 1.5, 2.5, (i / 4) as f32 - 1.5);
                let shape = if i % 2 == 0 { cube } else { ball };
                keeps
                    .add(crate::BodyDesc::dynamic(shape).position(p))
                    .unwrap();
            }
            let mut forms = keeps.clone();
            let before = KEPT.with(|k| k.get());
            for step in 0..200 {
                for (_, b) in forms.bodies.iter_mut() {
                    b.relist = true;
                }
                forms.step();
                keeps.step();
                assert_eq!(keeps.checksum(), forms.checksum(), "kinematic step {step}");
            }
            assert!(keeps.contacts.iter().any(|c| c.is_part() && c.len > 0));
            assert_eq!(
                KEPT.with(|k| k.get()),
                before,
                "a kinematic mesh's list kept"
            );
        });
    }

    /// The single-move update against the two-pass one, on both terrain scenes (a height
    /// field and a mesh under 40 mixed bodies) and the same scene packed into a contact
    /// buffer too small for it: in every step, after its enlarged boxes are refreshed,
    /// both run on copies of the world's contacts and give the same contacts, bit for
    /// bit, and the same drop count. The plan must carry most updates that change
    /// anything, and the small buffer must send some to the two passes.
    #[test]
    fn the_single_move_update_is_the_two_pass_update() {
        use crate::scenes::{ReferenceWorld, Scene};
        on_terrain(|hulls, shapes| {
            fn compare<const B: usize, const C: usize, const E: usize>(
                world: &mut crate::World<'_, B, C, E>,
                steps: u32,
            ) -> (u32, u32, u32) {
                let (mut changed, mut planned, mut fallback) = (0, 0, 0);
                for _ in 0..steps {
                    // Stage 4's input: the enlarged boxes of this step (stage 2; the
                    // step's own pass then finds nothing left to refresh).
                    let cfg = *world.config();
                    crate::dynamics::broad_phase::update_fat_boxes(&mut world.bodies, &cfg);
                    // Stage 3's part: a body whose box moved lists its pairs again.
                    for (_, b) in world.bodies.iter_mut() {
                        b.relist |= b.moved;
                    }
                    let mut single = world.contacts.clone();
                    let mut twice = world.contacts.clone();
                    let (mut r1, mut r2) = (StepReport::default(), StepReport::default());
                    let mut probe = world.contacts.clone();
                    let mut list = HVec::new();
                    let plan = plan_relocation(probe.as_mut_slice(), C, &world.bodies, &mut list);
                    update_part_contacts(&mut single, &world.bodies, &mut r1);
                    update_parts_in_two_passes(&mut twice, &world.bodies, &mut r2);
                    let same = |x: &[Contact], y: &[Contact]| {
                        x.len() == y.len() && x.iter().zip(y).all(|(a, b)| a.same_as(b))
                    };
                    assert!(same(&single, &twice), "step {}", world.step_count());
                    assert_eq!(r1.dropped_contacts, r2.dropped_contacts);
                    if !same(&twice, &world.contacts) {
                        changed += 1;
                        if plan.is_some() {
                            planned += 1;
                        } else {
                            fallback += 1;
                        }
                    }
                    world.step();
                }
                (changed, planned, fallback)
            }
            for scene in [Scene::Terrain, Scene::TerrainMesh] {
                let mut world: std::boxed::Box<ReferenceWorld<'_>> = std::boxed::Box::default();
                world.set_config(scene.config()).unwrap();
                scene
                    .build_on(&mut world, hulls, shapes.ground(scene))
                    .unwrap();
                let (changed, planned, fallback) = compare(&mut world, 300);
                assert!(
                    changed > 50,
                    "{scene:?}: {changed} updates changed anything"
                );
                assert!(
                    planned * 10 >= changed * 9,
                    "{scene:?}: {planned} of {changed}"
                );
                std::println!("{scene:?}: {changed} changed, {planned} planned, {fallback} not");
            }
            // A buffer the pile fills: some updates do not fit the plan.
            let mut small: std::boxed::Box<crate::World<'_, 128, 200, 64>> =
                std::boxed::Box::default();
            small.set_config(Scene::Terrain.config()).unwrap();
            Scene::Terrain
                .build_on(&mut small, hulls, shapes.ground(Scene::Terrain))
                .unwrap();
            let (changed, _, fallback) = compare(&mut small, 300);
            std::println!("small: {changed} changed, {fallback} not planned");
            assert!(fallback > 0, "the full buffer never fell back");
        });
    }

    /// `beyond_reach` against the exact queries: whenever it skips a part pair, the
    /// manifold with that margin has no point, GJK's distance exceeds the margin and the
    /// bound it gives; and it does skip many (a test that never skips would pass).
    #[test]
    fn beyond_reach_skips_only_pairs_without_contact() {
        let mut rng = SplitMix64::new(9);
        let mut cloud = [Vec3::ZERO; 12];
        for p in cloud.iter_mut() {
            *p = rng.unit_vector() * rng.range(0.2, 0.9);
        }
        let hull = ConvexHull::new(&cloud).unwrap();
        let shapes = [
            Shape::sphere(0.4).unwrap(),
            Shape::cuboid(Vec3::new(0.5, 0.2, 0.3)).unwrap(),
            Shape::capsule(0.4, 0.2).unwrap(),
            Shape::hull(&hull),
        ];
        let (mut skipped, mut touching) = (0, 0);
        for i in 0..4000 {
            let tri = Shape::triangle(
                rng.unit_vector() * rng.range(0.5, 2.0),
                rng.unit_vector() * rng.range(0.5, 2.0),
                rng.unit_vector() * rng.range(0.5, 2.0),
            );
            let Ok(tri) = tri else { continue };
            let shape = shapes[i % shapes.len()];
            let pose_t = Iso::new(rng.unit_vector() * rng.range(0.0, 1.0), rng.rotation());
            let pose_s = Iso::new(rng.unit_vector() * rng.range(0.0, 3.0), rng.rotation());
            let margin = rng.range(0.0, 0.1);
            let (first, second) = if i % 2 == 0 {
                ((tri, pose_t), (shape, pose_s))
            } else {
                ((shape, pose_s), (tri, pose_t))
            };
            let kept = beyond_reach(&first.0, &first.1, &second.0, &second.1, margin);
            let m = contact(&first.0, &first.1, &second.0, &second.1, margin).unwrap();
            let points = m.map_or(0, |m| m.len);
            let gap = distance(&tri, &pose_t, &shape, &pose_s, &mut SimplexCache::default())
                .unwrap()
                .distance;
            if let Some(kept) = kept {
                skipped += 1;
                assert_eq!(points, 0, "pair {i} skipped with points");
                assert!(
                    gap > margin,
                    "pair {i} skipped at distance {gap} <= {margin}"
                );
                assert!(
                    kept <= gap,
                    "pair {i}: bound {kept} above the distance {gap}"
                );
            }
            touching += usize::from(points > 0);
        }
        assert!(
            skipped > 1000 && touching > 300,
            "{skipped} skipped, {touching} touching"
        );
    }
}
