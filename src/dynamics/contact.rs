//! Stages 5 and 6: narrow phase over the candidate pairs, and the persistent contact
//! cache (points matched by feature id, warm-start impulses carried over, begin/end and
//! sensor events).
//!
//! # The cache
//!
//! `contacts` holds last step's contacts sorted by `(a, b)`; the broad phase hands over
//! this step's candidate pairs sorted the same way. One merge walk over both lists builds
//! the new list (in `scratch`, then swapped in), so every decision is made in key order:
//!
//! | last step | this step's pairs | result |
//! | --- | --- | --- |
//! | contact | pair, manifold | new contact, points matched to the old ones |
//! | contact | pair, no manifold | contact ends |
//! | contact | no pair, neither body awake | old contact kept unchanged (warm start survives sleep) |
//! | contact | no pair otherwise | contact ends (bounds apart, or pair dropped) |
//! | none | pair, manifold | new contact |
//!
//! A point is matched to last step's points of the same pair by its feature-id key first
//! (Catto, Box2D `b2UpdateContact`); a point whose id matches nothing takes the nearest
//! unmatched old point whose anchors both moved less than `2 · slop` in their body frames.
//! A matched point inherits the accumulated normal and friction impulses (the friction
//! impulse projected onto the new tangent plane) and the sticking flag.
//!
//! # Touching and events
//!
//! A contact is *touching* when some point has `separation <= slop`: penetrating points,
//! points resting at the slop that projection leaves, and points within one slop of the
//! surface (so a resting contact whose gap jitters by rounding does not flicker). Points
//! further out are speculative: the solver uses them, events ignore them.
//!
//! Events, in key order: `ContactBegin` / `SensorEnter` when a contact starts touching,
//! `ContactEnd` / `SensorLeave` when a touching contact stops touching or disappears. Then,
//! again in key order, one `Hit` per non-sensor contact that is *new* (no contact for the
//! pair last step) or starts touching, when its fastest point closes faster than
//! `hit_event_speed`: the closing speed `(v_a(p) − v_b(p))·n` at the midpoint `p` of the
//! two anchors, with the velocities before the solve. Counting new speculative contacts
//! matters: the solver stops a body at a speculative contact before it touches, so by the
//! time it touches its closing speed is gone.
//!
//! # Capacity
//!
//! When `contacts` is full, the contacts first in key order are kept and the rest are
//! counted in `StepReport::dropped_contacts`; a dropped contact counts as no contact
//! (a touching one sends its end event). `pairs` never exceeds the pool, so this only
//! happens when contacts kept for sleeping bodies add to this step's pairs.

use heapless::Vec as HVec;

use crate::collide::{contact_unchecked, Manifold};
use crate::config::WorldConfig;
use crate::dynamics::body::{Body, Material};
use crate::dynamics::events::{push_event, Event, StepReport};
use crate::dynamics::pool::Pool;
use crate::math::Vec3;

/// One persistent contact point with its accumulated impulses and solver scratch.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ContactPoint {
    /// `ContactId::key()` of the features that produced it.
    pub id: u64,
    /// Anchor on A in A's body frame (m).
    pub local_a: Vec3,
    /// Anchor on B in B's body frame (m).
    pub local_b: Vec3,
    /// Separation along the normal at the narrow phase (m), negative when penetrating.
    pub separation: f32,
    /// Accumulated normal impulse (N·s), ≥ 0.
    pub normal_impulse: f32,
    /// Accumulated friction impulse (N·s, world vector in the tangent plane).
    pub tangent_impulse: Vec3,
    /// Solver scratch: lever arms from the centres of mass (world, m).
    pub r_a: Vec3,
    /// Lever arm on B.
    pub r_b: Vec3,
    /// Effective mass along the normal (kg).
    pub normal_mass: f32,
    /// Effective masses along the two tangents (kg).
    pub tangent_mass: [f32; 2],
    /// Target normal velocity from restitution (m/s, ≥ 0).
    pub restitution_velocity: f32,
    /// Normal closing speed before the solve (m/s; positive when approaching), at the
    /// midpoint of the two anchors; set by the narrow phase (the solver may refresh it).
    pub approach_speed: f32,
    /// True while the contact sticks (static friction).
    pub sticking: bool,
}

/// A persistent contact between two bodies (slots `a < b`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Contact {
    /// Slot of body A (the lower slot).
    pub a: u32,
    /// Slot of body B.
    pub b: u32,
    /// Unit normal from A to B (world).
    pub normal: Vec3,
    /// Tangent basis (world), refreshed each step.
    pub tangents: [Vec3; 2],
    /// Points in use.
    pub len: u8,
    /// The points.
    pub points: [ContactPoint; 4],
    /// Combined material.
    pub material: Material,
    /// One of the bodies is a sensor: detect, never push.
    pub sensor: bool,
    /// Touching this step (some point with `separation <= slop`): drives begin/end events.
    pub touching: bool,
}

impl Contact {
    /// Sort and match key: `(a, b)` packed.
    #[inline]
    pub fn key(&self) -> u64 {
        ((self.a as u64) << 32) | self.b as u64
    }
}

/// Stages 5 and 6: a manifold for every candidate pair, matched against last step's
/// contacts to carry their impulses over; begin/end/sensor/hit events (see the module
/// docs for every rule).
///
/// `contacts` (last step's, sorted by key) is replaced by this step's, sorted by key;
/// `scratch` is left holding last step's. `pairs` must be sorted and hold distinct
/// `(lower slot, higher slot)` pairs. `report.contacts` and `report.points` describe the
/// new list; `report.dropped_contacts` accumulates over the sub-steps of a step.
#[allow(clippy::too_many_arguments)]
pub(crate) fn update_contacts<const N: usize, const C: usize, const E: usize>(
    contacts: &mut HVec<Contact, C>,
    scratch: &mut HVec<Contact, C>,
    pairs: &[(u32, u32)],
    bodies: &Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    events: &mut HVec<Event, E>,
    report: &mut StepReport,
) {
    scratch.clear();
    let mut dropped: u32 = 0;
    let mut old_at = 0;
    let mut pair_at = 0;
    // Each round moves at least one cursor on, so this many rounds end the walk.
    for _ in 0..=contacts.len() + pairs.len() {
        let old = contacts.get(old_at);
        let pair = pairs.get(pair_at).copied();
        let (old, pair) = match (old, pair) {
            (None, None) => break,
            (Some(o), Some(p)) if o.key() == pair_key(p) => (Some(o), Some(p)),
            (Some(o), Some(p)) if o.key() < pair_key(p) => (Some(o), None),
            (Some(_), Some(p)) | (None, Some(p)) => (None, Some(p)),
            (Some(o), None) => (Some(o), None),
        };
        old_at += usize::from(old.is_some());
        pair_at += usize::from(pair.is_some());
        let next = match pair {
            Some((a, b)) => narrow_phase(a, b, old, bodies, cfg),
            None => old.filter(|o| both_asleep(o, bodies)).copied(),
        };
        let kept = match next {
            Some(c) if scratch.push(c).is_ok() => Some(c),
            Some(_) => {
                dropped = dropped.saturating_add(1);
                None
            }
            None => None,
        };
        touch_events(old, kept.as_ref(), bodies, events, report);
    }
    core::mem::swap(contacts, scratch);
    hit_events(contacts, scratch, bodies, cfg, events, report);
    report.contacts = contacts.len() as u32;
    report.points = contacts
        .iter()
        .fold(0u32, |n, c| n.saturating_add(u32::from(c.len)));
    report.dropped_contacts = report.dropped_contacts.saturating_add(dropped);
}

/// The contact key of a pair, as [`Contact::key`].
#[inline]
fn pair_key((a, b): (u32, u32)) -> u64 {
    ((a as u64) << 32) | b as u64
}

/// True when neither body of `c` is awake (both live): the broad phase skipped the pair,
/// and the contact is kept as it was.
fn both_asleep<const N: usize>(c: &Contact, bodies: &Pool<Body<'_>, N>) -> bool {
    match (bodies.at(c.a as usize), bodies.at(c.b as usize)) {
        (Some(a), Some(b)) => !a.awake && !b.awake,
        _ => false,
    }
}

/// Stage 5 for one pair, then the warm start from `old` (same pair, last step).
/// `None` when the shapes are further apart than the speculative margin, or when the
/// narrow phase answers something non-finite (never let a NaN reach the solver).
fn narrow_phase<const N: usize>(
    a: u32,
    b: u32,
    old: Option<&Contact>,
    bodies: &Pool<Body<'_>, N>,
    cfg: &WorldConfig,
) -> Option<Contact> {
    let body_a = bodies.at(a as usize)?;
    let body_b = bodies.at(b as usize)?;
    let manifold = contact_unchecked(
        &body_a.shape,
        &body_a.pose,
        &body_b.shape,
        &body_b.pose,
        cfg.speculative_margin,
    )?;
    let mut c = contact_from_manifold(a, b, &manifold, body_a, body_b, cfg)?;
    if let Some(old) = old {
        warm_start(&mut c, old, cfg.slop);
    }
    Some(c)
}

/// A fresh contact (no impulses) from a manifold: world normal and tangent basis,
/// body-frame anchors, closing speeds, combined material, sensor and touching flags.
fn contact_from_manifold(
    a: u32,
    b: u32,
    m: &Manifold,
    body_a: &Body<'_>,
    body_b: &Body<'_>,
    cfg: &WorldConfig,
) -> Option<Contact> {
    let normal = m.normal;
    if m.points().is_empty() || !normal.is_finite() {
        return None;
    }
    // A right-handed orthonormal basis (t1, t2, n), the same for the same normal bits.
    let t1 = normal.any_perpendicular();
    let t2 = normal.cross(t1);
    let mut c = Contact {
        a,
        b,
        normal,
        tangents: [t1, t2],
        len: 0,
        points: [ContactPoint::default(); 4],
        material: Material::combine(&body_a.material, &body_b.material),
        sensor: body_a.sensor || body_b.sensor,
        touching: false,
    };
    for (dst, src) in c.points.iter_mut().zip(m.points()) {
        if !(src.separation.is_finite() && src.local_a.is_finite() && src.local_b.is_finite()) {
            return None;
        }
        // The shape frame is the body frame, so the manifold's local anchors are ours.
        let p = (src.point_a + src.point_b) * 0.5;
        *dst = ContactPoint {
            id: src.id.key(),
            local_a: src.local_a,
            local_b: src.local_b,
            separation: src.separation,
            approach_speed: (body_a.velocity_at(p) - body_b.velocity_at(p)).dot(normal),
            ..ContactPoint::default()
        };
        c.len += 1;
        c.touching |= src.separation <= cfg.slop;
    }
    Some(c)
}

/// Carry accumulated impulses and the sticking flag from `old` (the same pair, last step)
/// to the points of `c`: by feature id first, then by the nearest anchors within
/// `2 · slop` for points whose id matched nothing. Each old point is used at most once.
fn warm_start(c: &mut Contact, old: &Contact, slop: f32) {
    let normal = c.normal;
    let old_points = old
        .points
        .get(..usize::from(old.len))
        .unwrap_or(&old.points);
    let len = usize::from(c.len);
    let new_points = c.points.get_mut(..len).unwrap_or(&mut []);
    let mut used = [false; 4];
    let mut matched = [false; 4];
    // Pass 1: the same pair of features.
    for (p, done) in new_points.iter_mut().zip(matched.iter_mut()) {
        for (q, taken) in old_points.iter().zip(used.iter_mut()) {
            if !*taken && q.id == p.id {
                inherit(p, q, normal);
                *taken = true;
                *done = true;
                break;
            }
        }
    }
    // Pass 2: the nearest free old point, `max(|Δ local_a|, |Δ local_b|) <= 2 slop`
    // (lower old index on ties).
    let reach2 = (2.0 * slop) * (2.0 * slop);
    for (p, done) in new_points.iter_mut().zip(matched.iter()) {
        if *done {
            continue;
        }
        let mut best: Option<(usize, f32)> = None;
        for (k, (q, taken)) in old_points.iter().zip(used.iter()).enumerate() {
            let d2 = crate::math::scalar::max(
                (p.local_a - q.local_a).length_squared(),
                (p.local_b - q.local_b).length_squared(),
            );
            if !*taken && d2 <= reach2 && best.is_none_or(|(_, b)| d2 < b) {
                best = Some((k, d2));
            }
        }
        if let Some((k, _)) = best {
            if let (Some(q), Some(taken)) = (old_points.get(k), used.get_mut(k)) {
                inherit(p, q, normal);
                *taken = true;
            }
        }
    }
}

/// `p` takes over `q`'s accumulated impulses and sticking flag; the friction impulse loses
/// its component along the (possibly turned) `normal`, so it stays in the tangent plane.
#[inline]
fn inherit(p: &mut ContactPoint, q: &ContactPoint, normal: Vec3) {
    p.normal_impulse = q.normal_impulse;
    p.tangent_impulse = q.tangent_impulse - normal * q.tangent_impulse.dot(normal);
    p.sticking = q.sticking;
}

/// Begin/end (or sensor enter/leave) when the touching state of the pair changes between
/// `old` (last step) and `new` (kept this step).
fn touch_events<const N: usize, const E: usize>(
    old: Option<&Contact>,
    new: Option<&Contact>,
    bodies: &Pool<Body<'_>, N>,
    events: &mut HVec<Event, E>,
    report: &mut StepReport,
) {
    let was = old.is_some_and(|c| c.touching);
    let is = new.is_some_and(|c| c.touching);
    let Some(c) = new.or(old) else {
        return;
    };
    if was == is {
        return;
    }
    let (Some(a), Some(b)) = (
        bodies.handle_at(c.a as usize),
        bodies.handle_at(c.b as usize),
    ) else {
        return;
    };
    let event = if c.sensor {
        // The sensor first; when both are sensors, the lower slot.
        let a_is_sensor = bodies.at(c.a as usize).is_some_and(|body| body.sensor);
        let (sensor, other) = if a_is_sensor { (a, b) } else { (b, a) };
        if is {
            Event::SensorEnter { sensor, other }
        } else {
            Event::SensorLeave { sensor, other }
        }
    } else if is {
        Event::ContactBegin { a, b }
    } else {
        Event::ContactEnd { a, b }
    };
    push_event(events, report, event);
}

/// One `Hit` per non-sensor contact of `new` that has no contact in `old` or starts
/// touching, when its fastest point closes faster than `cfg.hit_event_speed`. Both lists
/// are sorted by key; events come in key order.
fn hit_events<const N: usize, const E: usize>(
    new: &[Contact],
    old: &[Contact],
    bodies: &Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    events: &mut HVec<Event, E>,
    report: &mut StepReport,
) {
    let mut old_at = 0;
    for c in new {
        // Skip old contacts with smaller keys; the cursor only moves forward.
        while old.get(old_at).is_some_and(|o| o.key() < c.key()) {
            old_at += 1;
        }
        let previous = old.get(old_at).filter(|o| o.key() == c.key());
        let began = previous.is_none_or(|o| c.touching && !o.touching);
        if !began || c.sensor {
            continue;
        }
        let Some(fastest) = fastest_point(c) else {
            continue;
        };
        if fastest.approach_speed <= cfg.hit_event_speed {
            continue;
        }
        let (Some(body_a), Some(body_b)) = (bodies.at(c.a as usize), bodies.at(c.b as usize))
        else {
            continue;
        };
        let (Some(a), Some(b)) = (
            bodies.handle_at(c.a as usize),
            bodies.handle_at(c.b as usize),
        ) else {
            continue;
        };
        let point_a = body_a.pose.transform_point(fastest.local_a);
        let point_b = body_b.pose.transform_point(fastest.local_b);
        let event = Event::Hit {
            a,
            b,
            point: (point_a + point_b) * 0.5,
            normal: c.normal,
            speed: fastest.approach_speed,
        };
        push_event(events, report, event);
    }
}

/// The point of `c` with the largest closing speed (the first on ties).
fn fastest_point(c: &Contact) -> Option<&ContactPoint> {
    let points = c.points.get(..usize::from(c.len)).unwrap_or(&c.points);
    let mut best: Option<&ContactPoint> = None;
    for p in points {
        if best.is_none_or(|b| p.approach_speed > b.approach_speed) {
            best = Some(p);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(id: u64, local_a: Vec3, local_b: Vec3, impulse: f32) -> ContactPoint {
        ContactPoint {
            id,
            local_a,
            local_b,
            normal_impulse: impulse,
            tangent_impulse: Vec3::new(impulse, impulse, 0.0),
            sticking: impulse > 2.5,
            ..ContactPoint::default()
        }
    }

    fn contact(points: &[ContactPoint]) -> Contact {
        let mut c = Contact {
            normal: Vec3::Y,
            len: points.len() as u8,
            ..Contact::default()
        };
        c.points[..points.len()].copy_from_slice(points);
        c
    }

    /// Ids first, then the nearest free old point within 2 slop; each old point once.
    #[test]
    fn warm_start_matches_ids_then_nearest_anchor() {
        let slop = 0.005;
        let x = |v: f32| Vec3::new(v, 0.0, 0.0);
        let old = contact(&[
            point(1, x(0.0), x(0.0), 1.0),
            point(2, x(1.0), x(1.0), 2.0),
            point(3, x(2.0), x(2.0), 3.0),
        ]);
        let mut new = contact(&[
            // Same id as old 2 but far away: the id wins.
            point(2, x(5.0), x(5.0), 0.0),
            // Unknown id 0.004 from old 3 (within 2 slop = 0.01): old 3.
            point(8, x(2.004), x(2.004), 0.0),
            // Unknown id next to old 2, which the id match already took: nothing.
            point(9, x(1.001), x(1.001), 0.0),
            // Unknown id 0.011 from everything: nothing (beyond 2 slop).
            point(7, x(3.011), x(3.011), 0.0),
        ]);
        warm_start(&mut new, &old, slop);
        let got: [f32; 4] = core::array::from_fn(|i| new.points[i].normal_impulse);
        assert_eq!(got, [2.0, 3.0, 0.0, 0.0]);
        assert!(new.points[1].sticking && !new.points[0].sticking);
        // The friction impulse (2, 2, 0) loses its part along the normal +Y.
        assert_eq!(new.points[0].tangent_impulse, Vec3::new(2.0, 0.0, 0.0));
    }

    /// A ball resting on a box, through the real narrow phase: a second update with the
    /// ball awake matches its point by id and keeps the impulses; with the ball asleep
    /// (pair not tested) the contact is kept bit for bit; a removed pair ends it.
    #[test]
    fn cache_carries_impulses_and_keeps_sleeping_contacts() {
        use crate::dynamics::body::BodyDesc;
        use crate::shape::Shape;
        let cfg = WorldConfig::DEFAULT;
        let mut bodies: Pool<Body<'static>, 2> = Pool::new();
        let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap();
        let ball = Shape::sphere(0.5).unwrap();
        bodies
            .insert(
                Body::from_desc(&BodyDesc::fixed(ground).position(Vec3::new(0.0, -0.5, 0.0)))
                    .unwrap(),
            )
            .unwrap();
        let ball_h = bodies
            .insert(
                Body::from_desc(&BodyDesc::dynamic(ball).position(Vec3::new(0.0, 0.499, 0.0)))
                    .unwrap(),
            )
            .unwrap();
        let mut contacts: HVec<Contact, 4> = HVec::new();
        let mut scratch: HVec<Contact, 4> = HVec::new();
        let mut events: HVec<Event, 8> = HVec::new();
        let mut report = StepReport::default();
        let pairs = [(0u32, 1u32)];
        update_contacts(
            &mut contacts,
            &mut scratch,
            &pairs,
            &bodies,
            &cfg,
            &mut events,
            &mut report,
        );
        assert_eq!(contacts.len(), 1);
        assert!(contacts[0].touching);
        assert_eq!(events.len(), 1);
        // The solver's accumulated impulses.
        contacts[0].points[0].normal_impulse = 1.25;
        contacts[0].points[0].tangent_impulse = Vec3::new(0.5, 0.0, 0.0);
        let solved = contacts[0];
        update_contacts(
            &mut contacts,
            &mut scratch,
            &pairs,
            &bodies,
            &cfg,
            &mut events,
            &mut report,
        );
        assert_eq!(contacts[0].points[0].normal_impulse, 1.25);
        assert_eq!(
            contacts[0].points[0].tangent_impulse,
            Vec3::new(0.5, 0.0, 0.0)
        );
        assert_eq!(events.len(), 1, "no new event while touching");
        // Asleep: the broad phase hands over no pair; the contact stays as it was.
        bodies.get_mut(ball_h).unwrap().awake = false;
        contacts[0] = solved;
        update_contacts(
            &mut contacts,
            &mut scratch,
            &[],
            &bodies,
            &cfg,
            &mut events,
            &mut report,
        );
        assert_eq!(contacts.as_slice(), &[solved]);
        assert_eq!((report.contacts, report.points), (1, 1));
        // Awake again, and out of reach: the contact ends with one event.
        bodies.get_mut(ball_h).unwrap().awake = true;
        update_contacts(
            &mut contacts,
            &mut scratch,
            &[],
            &bodies,
            &cfg,
            &mut events,
            &mut report,
        );
        assert!(contacts.is_empty());
        let a = bodies.handle_at(0).unwrap();
        assert_eq!(events.last(), Some(&Event::ContactEnd { a, b: ball_h }));
    }

    /// Anchors must be near on both bodies: a point that slid 1 cm on B is not matched.
    #[test]
    fn fallback_needs_both_anchors_close() {
        let old = contact(&[point(1, Vec3::ZERO, Vec3::ZERO, 4.0)]);
        let mut new = contact(&[point(5, Vec3::ZERO, Vec3::new(0.0, 0.0, 0.0101), 0.0)]);
        warm_start(&mut new, &old, 0.005);
        assert_eq!(new.points[0].normal_impulse, 0.0);
        let mut near = contact(&[point(5, Vec3::ZERO, Vec3::new(0.0, 0.0, 0.0099), 0.0)]);
        warm_start(&mut near, &old, 0.005);
        assert_eq!(near.points[0].normal_impulse, 4.0);
    }
}
