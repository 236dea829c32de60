//! Stages 2 and 3: movement bounds, then sweep and prune over them.

use heapless::Vec as HVec;

use super::body::Body;
use super::events::StepReport;
use super::pool::Pool;
use crate::config::WorldConfig;

/// Sweep-and-prune state.
#[derive(Clone, Debug)]
pub(crate) struct BroadPhase<const N: usize> {
    /// Slots sorted by the lower x bound of their movement bounds.
    pub order: HVec<u32, N>,
}

impl<const N: usize> BroadPhase<N> {
    /// Empty.
    pub const fn new() -> Self {
        BroadPhase { order: HVec::new() }
    }

    /// Candidate pairs `(lower slot, higher slot)`, sorted.
    pub fn find_pairs<const P: usize>(
        &mut self,
        bodies: &Pool<Body<'_>, N>,
        pairs: &mut HVec<(u32, u32), P>,
        report: &mut StepReport,
    ) {
        let _ = (bodies, report);
        pairs.clear();
    }
}

/// Stage 2: each awake body's movement bounds over the sub-step `h`.
pub(crate) fn update_bounds<const N: usize>(bodies: &mut Pool<Body<'_>, N>, cfg: &WorldConfig, h: f32) {
    let _ = (bodies, cfg, h);
}
