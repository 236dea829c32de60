//! Events of a step and the step report.
//!
//! Events are queued in a bounded buffer in the order the step produces them: begin/end
//! and sensor events in pair order `(lower slot, higher slot)`, then hit events in the
//! same order. The queue is emptied at the start of every step. When it
//! is full, later events of the step are dropped and counted in
//! [`StepReport::dropped_events`].
//!
//! A contact *touches* when one of its points is within `WorldConfig::slop` of the other
//! body (or penetrates it); closer than the speculative margin but further than the slop
//! is a contact the solver uses that raises no event.

use super::pool::BodyHandle;
use crate::math::Vec3;

/// Something that happened during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// Two bodies started touching (a contact point within the slop). Neither is a sensor.
    ContactBegin {
        /// Body in the lower slot.
        a: BodyHandle,
        /// Body in the higher slot.
        b: BodyHandle,
    },
    /// Two bodies stopped touching, or their contact went away (bounds apart, or dropped
    /// for capacity). Removing a body with [`crate::World::remove`] sends no event.
    ContactEnd {
        /// Body in the lower slot.
        a: BodyHandle,
        /// Body in the higher slot.
        b: BodyHandle,
    },
    /// A body started overlapping a sensor (within the slop). When both are sensors,
    /// `sensor` is the one in the lower slot.
    SensorEnter {
        /// The sensor.
        sensor: BodyHandle,
        /// The other body.
        other: BodyHandle,
    },
    /// A body stopped overlapping a sensor.
    SensorLeave {
        /// The sensor.
        sensor: BodyHandle,
        /// The other body.
        other: BodyHandle,
    },
    /// Two bodies hit each other faster than `WorldConfig::hit_event_speed`: sent for a
    /// contact (never a sensor's) in the step it appears or starts touching, at its
    /// fastest closing point. A contact usually appears a step early, within the
    /// speculative margin, and the solver then stops the bodies before they touch, so the
    /// speed is the one before that solve.
    Hit {
        /// Body in the lower slot.
        a: BodyHandle,
        /// Body in the higher slot.
        b: BodyHandle,
        /// Contact point (world, m).
        point: Vec3,
        /// Contact normal from `a` to `b`.
        normal: Vec3,
        /// Closing speed along the normal before the solve (m/s, positive).
        speed: f32,
    },
}

/// Counts and overflow flags of one step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepReport {
    /// Awake dynamic bodies after the step.
    pub awake_bodies: u32,
    /// Pairs the narrow phase examined: pairs with overlapping broad-phase boxes and an
    /// awake body (pairs of sleeping bodies keep their contact unexamined).
    pub pairs: u32,
    /// Contacts with at least one point (manifolds) after the narrow phase; includes
    /// contacts kept unchanged for sleeping bodies.
    pub contacts: u32,
    /// Contact points over all contacts.
    pub points: u32,
    /// Bodies swept by continuous collision.
    pub ccd_sweeps: u32,
    /// Sweeps that found a time of impact and moved a body back.
    pub ccd_hits: u32,
    /// Time-of-impact queries the sweeps ran: one per body a fast body is swept against,
    /// or, against a mesh, height field or compound, one per part pair near the fast
    /// body's path (each part pair at most once per fast body and step).
    pub ccd_queries: u32,
    /// New candidate pairs that did not fit in the step's pair buffer (`CONTACTS` long):
    /// those with the lowest `(lower slot, higher slot)` keys are kept, whatever order the
    /// broad phase found them in; the bodies of the others look again next step.
    pub dropped_pairs: u32,
    /// New pairs that did not fit in the contact pool: those with the lowest
    /// `(lower slot, higher slot)` keys are kept; the bodies of the others look again
    /// next step.
    pub dropped_contacts: u32,
    /// Events dropped because the event queue was full (kept: the first of the step).
    pub dropped_events: u32,
}

impl StepReport {
    /// True when anything was dropped this step.
    pub fn overflowed(&self) -> bool {
        self.dropped_pairs > 0 || self.dropped_contacts > 0 || self.dropped_events > 0
    }
}

/// Push an event, or count it as dropped when the queue is full.
#[inline]
pub(crate) fn push_event<const E: usize>(
    queue: &mut heapless::Vec<Event, E>,
    report: &mut StepReport,
    event: Event,
) {
    if queue.push(event).is_err() {
        report.dropped_events = report.dropped_events.saturating_add(1);
    }
}
