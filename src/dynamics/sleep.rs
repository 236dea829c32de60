//! Stage 11: islands of touching bodies fall asleep together and wake together.
//!
//! Once per step (after the last sub-step):
//!
//! 1. **Timers.** An awake dynamic body whose speeds are both below the thresholds
//!    (`|v| < sleep_linear_speed`, `|ω| < sleep_angular_speed`) adds `dt` to its
//!    `sleep_time`; any faster and the timer restarts at 0.
//! 2. **Islands.** Union-find over the slots: every touching, non-sensor contact between
//!    two dynamic bodies joins their sets (static and kinematic bodies do not join
//!    islands, or the whole world would be one). Roots are the smaller slot of a union
//!    (deterministic); `find` halves paths. Then every slot points straight at its root.
//! 3. **Keep awake.** An island is kept awake by any member that is awake and not yet
//!    sleepy (`sleep_time < cfg.sleep_time`), and by any touching, non-sensor contact with
//!    a moving kinematic body (a moving platform keeps what it carries awake). The mark is
//!    bit 31 of the root's entry, so the scratch stays `N` words.
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
use crate::config::WorldConfig;
use crate::math::Vec3;

/// Bit of a root's entry in the scratch that marks its island as kept awake.
const KEEP_AWAKE: u32 = 1 << 31;

/// The slot bits of a scratch entry. Slots are below `2³¹` (a pool that large would not
/// fit in memory).
const SLOT: u32 = !KEEP_AWAKE;

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
        if is_marked(parent, root_of(parent, i)) {
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

/// The root of `x`'s set, halving the path on the way (each visited entry skips to its
/// grandparent). At most `N` hops: a path never revisits a slot.
fn find<const N: usize>(parent: &mut [u32; N], x: u32) -> u32 {
    let mut x = x;
    for _ in 0..N {
        let p = parent.get(x as usize).map_or(x, |e| e & SLOT);
        if p == x {
            return x;
        }
        let grand = parent.get(p as usize).map_or(p, |e| e & SLOT);
        if let Some(e) = parent.get_mut(x as usize) {
            *e = grand;
        }
        x = grand;
    }
    x
}

/// Step 2: the islands, each slot's entry pointing straight at its root afterwards.
fn build_islands<const N: usize>(
    bodies: &Pool<Body<'_>, N>,
    contacts: &[Contact],
    parent: &mut [u32; N],
) {
    let high = bodies.high();
    for (i, e) in parent.iter_mut().enumerate().take(high) {
        *e = i as u32;
    }
    for c in contacts {
        if !links(c, bodies) {
            continue;
        }
        let ra = find(parent, c.a);
        let rb = find(parent, c.b);
        // The larger root joins the smaller: the root of an island is its lowest slot.
        let (keep, join) = if ra < rb { (ra, rb) } else { (rb, ra) };
        if let Some(e) = parent.get_mut(join as usize) {
            *e = keep;
        }
    }
    for i in 0..high {
        let r = find(parent, i as u32);
        if let Some(e) = parent.get_mut(i) {
            *e = r;
        }
    }
}

/// The root of slot `i` once the islands are flat.
#[inline]
fn root_of<const N: usize>(parent: &[u32; N], i: usize) -> u32 {
    parent.get(i).map_or(i as u32, |e| e & SLOT)
}

/// True when the island of root `r` is kept awake.
#[inline]
fn is_marked<const N: usize>(parent: &[u32; N], r: u32) -> bool {
    parent.get(r as usize).is_some_and(|e| e & KEEP_AWAKE != 0)
}

/// Mark the island of slot `i` as kept awake.
#[inline]
fn mark<const N: usize>(parent: &mut [u32; N], i: usize) {
    let r = root_of(parent, i);
    if let Some(e) = parent.get_mut(r as usize) {
        *e |= KEEP_AWAKE;
    }
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
            mark(parent, i);
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
            mark(parent, c.b as usize);
        }
        if is_moving_kinematic(b) && a.is_dynamic() {
            mark(parent, c.a as usize);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn find_halves_paths_and_returns_the_root() {
        // A chain 4 → 3 → 2 → 1 → 0.
        let mut parent = [0u32, 0, 1, 2, 3];
        assert_eq!(find(&mut parent, 4), 0);
        // Halving: 4 now skips to 2, 2 to 0.
        assert_eq!(parent, [0, 0, 0, 2, 2]);
    }

    #[test]
    fn marks_live_on_roots_only() {
        let mut parent = [0u32, 0, 0, 3];
        mark(&mut parent, 2);
        assert!(is_marked(&parent, root_of(&parent, 1)));
        assert!(!is_marked(&parent, root_of(&parent, 3)));
        assert_eq!(root_of(&parent, 0), 0);
    }
}
