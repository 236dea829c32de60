//! Events of a step and the step report.
//!
//! Events are queued in a bounded buffer in the order the step produces them: contact
//! events in pair order `(lower slot, higher slot)`, then hit events in the same order.
//! When the queue is full, later events of the step are dropped and counted in
//! [`StepReport::dropped_events`].

use super::pool::BodyHandle;
use crate::math::Vec3;

/// Something that happened during a step.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// Two bodies started touching (a contact point within the slop).
    ContactBegin {
        /// Body in the lower slot.
        a: BodyHandle,
        /// Body in the higher slot.
        b: BodyHandle,
    },
    /// Two bodies stopped touching (or one was removed).
    ContactEnd {
        /// Body in the lower slot.
        a: BodyHandle,
        /// Body in the higher slot.
        b: BodyHandle,
    },
    /// A body started overlapping a sensor.
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
    /// Two bodies hit each other faster than `WorldConfig::hit_event_speed`.
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
    /// Candidate pairs found by the broad phase.
    pub pairs: u32,
    /// Contacts (manifolds with at least one point) after the narrow phase.
    pub contacts: u32,
    /// Contact points over all contacts.
    pub points: u32,
    /// Bodies swept by continuous collision.
    pub ccd_sweeps: u32,
    /// Sweeps that found a time of impact and moved a body back.
    pub ccd_hits: u32,
    /// Candidate pairs dropped because the pair buffer was full (kept: the first pairs
    /// in `(lower slot, higher slot)` order).
    pub dropped_pairs: u32,
    /// Manifolds dropped because the contact pool was full (kept: the first in pair order).
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
