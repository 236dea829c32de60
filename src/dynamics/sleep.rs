//! Stage 11: islands of touching bodies fall asleep together and wake together.
//!
//! Once per step (after the last sub-step):
//!
//! 1. **Timers.** An awake dynamic body whose speeds are both below the thresholds
//!    (`|v| < sleep_linear_speed`, `|ω| < sleep_angular_speed`) adds `dt` to its
//!    `sleep_time`; any faster and the timer restarts at 0.
//! 2. **Islands.** Union-find over the slots: every touching, non-sensor contact between
//!    two dynamic bodies joins their sets (static and kinematic bodies do not join
//!    islands, or the whole world would be one), in `union_find.rs`: roots are the
//!    smaller slot of a union (deterministic). Then every slot points straight at its
//!    root.
//! 3. **Keep awake.** An island is kept awake by any member that is awake and not yet
//!    sleepy (`sleep_time < cfg.sleep_time`), and by any touching, non-sensor contact with
//!    a moving kinematic body (a moving platform keeps what it carries awake). The mark is
//!    bit 31 of the root's entry (`union_find.rs`), so the scratch stays `N` words.
//! 4. **Decide.** Members of a kept island are all awake (sleepers woken with a fresh
//!    timer: this is how a hit on a sleeping stack wakes the stack). Members of any other
//!    island, where every awake member has been slow long enough, fall asleep with their
//!    velocities zeroed.
//!
//! With `sleep_enabled` off, every non-static body is awake.

use super::body::{Body, BodyKind};
use super::contact::Contact;
use super::pool::Pool;
use super::solver::is_moving_kinematic;
use super::union_find;
use crate::config::WorldConfig;
use crate::math::Vec3;

/// Update sleep timers and island sleep state; returns the number of awake dynamic bodies.
pub(crate) fn update_sleep<const N: usize>(
    bodies: &mut Pool<Body<'_>, N>,
    contacts: &[Contact],
    parent: &mut [u32; N],
    cfg: &WorldConfig,
) -> u32 {
    if !cfg.sleep_enabled {
        wake_all(bodies);
        return awake_count(bodies);
    }
    update_timers(bodies, cfg);
    build_islands(bodies, contacts, parent);
    mark_kept_islands(bodies, contacts, parent, cfg);
    for (i, b) in bodies.iter_mut() {
        if !b.is_dynamic() {
            continue;
        }
        if union_find::marked(parent, i as u32) {
            if !b.awake {
                b.awake = true;
                b.sleep_time = 0.0;
            }
        } else {
            b.awake = false;
            b.linear_velocity = Vec3::ZERO;
            b.angular_velocity = Vec3::ZERO;
        }
    }
    awake_count(bodies)
}

/// Every non-static body awake, timers at 0.
fn wake_all<const N: usize>(bodies: &mut Pool<Body<'_>, N>) {
    for (_, b) in bodies.iter_mut() {
        if b.kind != BodyKind::Static {
            b.awake = true;
            b.sleep_time = 0.0;
        }
    }
}

/// Awake dynamic bodies.
fn awake_count<const N: usize>(bodies: &Pool<Body<'_>, N>) -> u32 {
    let mut n = 0u32;
    for (_, b) in bodies.iter() {
        if b.is_dynamic() && b.awake {
            n = n.saturating_add(1);
        }
    }
    n
}

/// Step 1: `sleep_time += dt` for slow awake dynamic bodies, 0 for the others.
fn update_timers<const N: usize>(bodies: &mut Pool<Body<'_>, N>, cfg: &WorldConfig) {
    let lin2 = cfg.sleep_linear_speed * cfg.sleep_linear_speed;
    let ang2 = cfg.sleep_angular_speed * cfg.sleep_angular_speed;
    for (_, b) in bodies.iter_mut() {
        if !(b.is_dynamic() && b.awake) {
            continue;
        }
        let slow =
            b.linear_velocity.length_squared() < lin2 && b.angular_velocity.length_squared() < ang2;
        b.sleep_time = if slow { b.sleep_time + cfg.dt } else { 0.0 };
    }
}

/// True when a contact joins two bodies into one island.
fn links<const N: usize>(c: &Contact, bodies: &Pool<Body<'_>, N>) -> bool {
    if !c.touching || c.sensor || c.len == 0 {
        return false;
    }
    match (bodies.at(c.a as usize), bodies.at(c.b as usize)) {
        (Some(a), Some(b)) => a.is_dynamic() && b.is_dynamic(),
        _ => false,
    }
}

/// Step 2: the islands, each slot's entry pointing straight at its root afterwards.
fn build_islands<const N: usize>(
    bodies: &Pool<Body<'_>, N>,
    contacts: &[Contact],
    parent: &mut [u32; N],
) {
    let entries = parent.get_mut(..bodies.high()).unwrap_or_default();
    union_find::reset(entries);
    for c in contacts {
        if links(c, bodies) {
            union_find::union(entries, c.a, c.b);
        }
    }
    union_find::flatten(entries);
}

/// Step 3: mark islands with an awake, not yet sleepy member or a moving kinematic
/// neighbour.
fn mark_kept_islands<const N: usize>(
    bodies: &Pool<Body<'_>, N>,
    contacts: &[Contact],
    parent: &mut [u32; N],
    cfg: &WorldConfig,
) {
    for (i, b) in bodies.iter() {
        if b.is_dynamic() && b.awake && b.sleep_time < cfg.sleep_time {
            union_find::mark(parent, i as u32);
        }
    }
    for c in contacts {
        if !c.touching || c.sensor || c.len == 0 {
            continue;
        }
        let (Some(a), Some(b)) = (bodies.at(c.a as usize), bodies.at(c.b as usize)) else {
            continue;
        };
        if is_moving_kinematic(a) && b.is_dynamic() {
            union_find::mark(parent, c.b);
        }
        if is_moving_kinematic(b) && a.is_dynamic() {
            union_find::mark(parent, c.a);
        }
    }
}
