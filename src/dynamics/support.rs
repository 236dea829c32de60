//! Part of stage 7: which body holds which up, and the mass ratio capped at 20 to 1 in
//! contacts under heavy bodies (in the spirit of shock propagation: Guendelman, Bridson
//! and Fedkiw, "Nonconvex rigid bodies with stacking", 2003; and of the inverse-mass
//! scaling some engines offer per contact).
//!
//! An iterative solve passes load down a stack one contact at a time: each visit of the
//! contact under a body of mass `M` resting on a body of mass `m` moves about `m · v` of
//! impulse, so a box 1000 times as heavy as the column under it needs about a thousand
//! iterations per step to be held, and soft contacts sag by `M g / (m ω²)` under it (the
//! effective mass of the contact is close to the light body's). With a few iterations the
//! heavy box falls through the column and the column buckles.
//!
//! Where a body rests on one more than [`HEAVY_RATIO`] (20) times lighter, carom caps the
//! ratio that contact sees: the lower, lighter body's inverse mass and inertia are scaled
//! down there so that it weighs a twentieth of the heavy body, in that contact's rows
//! only. The column then carries what a box 20 times as heavy would put on it, which the
//! soft step holds (a few centimetres of sag), and the heavy box sags as on a 20-fold
//! lighter support. The ground under the column is told less than the whole weight: the
//! price of the shortcut, and why it is kept to ratios an iterative solve cannot carry.
//! A cap rather than an infinite mass (a one-way contact): a light support kicked up
//! within the step (squeezed out of a crash) gives the heavy body at most 1/21 of its
//! speed, where a one-way contact handed it all of it (a crashing pile of boxes 50 times
//! as dense as their neighbours launched one 1.8 m up).
//!
//! "Rests on" needs all of:
//!
//! - **support**: the lighter body is joined to a body that does not move in the solve
//!   (static, kinematic or sleeping) by a chain of contacts between moving bodies: its
//!   island touches the ground. A light body that nothing holds (in flight, or in a pile
//!   in free fall) is pushed as usual, and a heavy body cannot gain speed from it;
//! - **geometry**: the normal from the lighter body to the heavy one points within 60° of
//!   up (against gravity). A heavy body pushing a light one sideways pushes it as usual;
//! - **rest**: the lighter body does not move towards the heavy one faster than
//!   [`RESTING_RISE`] at the step's start, so a light body thrown up into a heavy one
//!   bounces off it rather than lifting it at its own speed.
//!
//! Support is only worked out in a step where some contact joins two moving bodies of
//! mass ratio [`HEAVY_RATIO`] or more (the solver notices while it lists the contacts):
//! union-find over the contacts between moving bodies (`union_find.rs`, as the sleep
//! stage builds its islands), with a mark on every island that touches a body that does
//! not move. In any other step the marks are not read and no contact is capped.
//!
//! The same inverse masses serve every pass over the contact this step: warm start, soft
//! and relax iterations, the restitution pass and projection.

use super::contact::Contact;
use super::solver::{moves, SolverBody, NONE};
use super::union_find;
use crate::math::Vec3;

/// The largest mass ratio a contact under a heavy body sees (module docs), and the ratio
/// from which the cap applies.
/// Below it the soft step holds a column as it is: a box 19 times as dense as the five
/// boxes under it sinks about 3 cm (1:30 would sink 4.5 cm, 1:50 8 cm, and 1:100 topples
/// the column, `tests/stability.rs`). Kept that high so that ordinary piles of bodies of
/// mixed sizes stay uncapped nearly everywhere.
pub(crate) const HEAVY_RATIO: f32 = 20.0;

/// `cos² 60°`: a capped contact's normal is within 60° of up.
const UPRIGHT_COS2: f32 = 0.25;

/// The fastest the lighter body may move towards the heavy one along the normal at the
/// step's start (m/s) for the contact to be capped: a light body thrown up into a heavy
/// one must not lift it at its own speed (three times the speed gravity adds in a
/// 1/60 s step; a resting support moves far slower).
pub(crate) const RESTING_RISE: f32 = 0.5;

/// Which side of a contact is the lighter support whose mass ratio is capped in its rows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Held {
    /// Neither: the masses as they are (every contact but those under a heavy body).
    Neither,
    /// Body A is the lighter support below B.
    SupportA,
    /// Body B is the lighter support below A.
    SupportB,
}

/// Whether one of two moving bodies (inverse masses in 1/kg) weighs at least
/// [`HEAVY_RATIO`] times the other: the solver's trigger for [`mark_supported`].
#[inline]
pub(crate) fn heavy_pair(inv_mass_a: f32, inv_mass_b: f32) -> bool {
    inv_mass_a >= HEAVY_RATIO * inv_mass_b || inv_mass_b >= HEAVY_RATIO * inv_mass_a
}

/// Whether bodies of inverse masses `lightest` (the largest, 1/kg) and `heaviest` (the
/// smallest) differ by [`HEAVY_RATIO`] or more: when the lightest and the heaviest
/// moving bodies do not, no contact can be heavy and the solver does not look for one.
/// False for no body (`0` and `∞`).
#[inline]
pub(crate) fn masses_differ(lightest: f32, heaviest: f32) -> bool {
    lightest >= HEAVY_RATIO * heaviest
}

/// Build the support marks of the solver `bodies` in `marks` (one entry each, module
/// docs) from the contacts `listed` (`(_, contact index)` entries of the contacts that
/// push); `index` maps pool slots to solver bodies. Afterwards [`Supports::held`] tells a
/// body whose island touches a body that does not move. Integer work in the listed
/// order: the same marks on every target.
pub(crate) fn mark_supported(
    marks: &mut [u32],
    bodies: &[SolverBody],
    index: &[u32],
    contacts: &[Contact],
    listed: &[(u32, u32)],
) {
    let marks = marks.get_mut(..bodies.len()).unwrap_or_default();
    union_find::reset(marks);
    let ends = |ci: u32| {
        contacts.get(ci as usize).map(|c| {
            let side = |slot: u32| index.get(slot as usize).copied().unwrap_or(NONE);
            (side(c.a), side(c.b))
        })
    };
    for &(_, ci) in listed {
        let Some((a, b)) = ends(ci) else { continue };
        match (moves(bodies, a), moves(bodies, b)) {
            (true, true) => union_find::union(marks, a, b),
            (true, false) => union_find::mark(marks, a),
            (false, true) => union_find::mark(marks, b),
            (false, false) => {}
        }
    }
    union_find::flatten(marks);
}

/// What the capped prepare reads (module docs): the support marks [`mark_supported`]
/// built this step, by solver body, and gravity (m/s²).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Supports<'m> {
    /// Union-find entries by solver body, flattened.
    pub marks: &'m [u32],
    /// The world's gravity (m/s²): "up" is against it.
    pub gravity: Vec3,
}

impl Supports<'_> {
    /// No marks, no gravity: for the prepare of a step without a heavy contact.
    pub(crate) const NONE: Supports<'static> = Supports {
        marks: &[],
        gravity: Vec3::ZERO,
    };

    /// Whether solver body `i`'s island touches a body that does not move.
    #[inline]
    pub(crate) fn held(&self, i: u32) -> bool {
        union_find::marked(self.marks, i)
    }
}

/// Which side of a contact with normal `n` (from A to B) between the moving solver
/// bodies `a` and `b`, in an island the ground holds up ([`Supports::held`]), holds the
/// other up with the ratio capped (module docs), under `gravity` (m/s²).
/// Out of line: the solver calls it only for contacts in a held island.
#[inline(never)]
pub(crate) fn held_side(a: &SolverBody, b: &SolverBody, n: Vec3, gravity: Vec3) -> Held {
    if a.inv_mass <= 0.0 || b.inv_mass <= 0.0 {
        return Held::Neither;
    }
    // n · up, with up = −g / |g|, compared against cos 60° without a square root.
    let rise = -n.dot(gravity);
    let steep = rise * rise >= UPRIGHT_COS2 * gravity.dot(gravity);
    if !steep {
        return Held::Neither;
    }
    // The support's speed towards the other body along n (from A to B).
    if rise > 0.0 && a.inv_mass >= HEAVY_RATIO * b.inv_mass && a.v.dot(n) <= RESTING_RISE {
        Held::SupportA
    } else if rise < 0.0 && b.inv_mass >= HEAVY_RATIO * a.inv_mass && -b.v.dot(n) <= RESTING_RISE {
        Held::SupportB
    } else {
        Held::Neither
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(inv_mass: f32) -> SolverBody {
        SolverBody {
            inv_mass,
            ..SolverBody::ZERO
        }
    }

    const G: Vec3 = Vec3::new(0.0, -9.81, 0.0);

    /// Union-find against a brute-force oracle: on random contact graphs (solver bodies
    /// that move, kinematic ones, slots without a solver body), a body is held exactly
    /// when a breadth-first search over moving–moving contacts reaches a moving body that
    /// touches one that does not move.
    #[test]
    fn support_marks_match_a_breadth_first_search() {
        let mut rng = crate::rng::SplitMix64::new(5);
        for round in 0..200 {
            let slots = 2 + (rng.next_u64() % 40) as usize;
            // Slot -> solver index: some slots have none (static or sleeping).
            let mut index = [NONE; 48];
            let mut bodies = [SolverBody::ZERO; 48];
            let mut count = 0usize;
            for entry in index.iter_mut().take(slots) {
                if !rng.next_u64().is_multiple_of(5) {
                    *entry = count as u32;
                    // One in six solver bodies is kinematic (inverse mass 0).
                    let kinematic = rng.next_u64().is_multiple_of(6);
                    bodies[count].inv_mass = if kinematic { 0.0 } else { 1.0 };
                    count += 1;
                }
            }
            let bodies = &bodies[..count];
            let mut contacts = [Contact::default(); 64];
            let mut listed = [(0u32, 0u32); 64];
            let pairs = (rng.next_u64() % 64) as usize;
            for (i, (c, l)) in contacts.iter_mut().zip(listed.iter_mut()).enumerate() {
                c.a = (rng.next_u64() % slots as u64) as u32;
                c.b = (rng.next_u64() % slots as u64) as u32;
                *l = (0, i as u32);
            }
            let listed = &listed[..pairs];
            let mut marks = [0u32; 48];
            mark_supported(&mut marks, bodies, &index, &contacts, listed);
            let supports = Supports {
                marks: &marks,
                gravity: G,
            };
            // The oracle.
            let moving = |i: u32| bodies.get(i as usize).is_some_and(|b| b.inv_mass > 0.0);
            let ends = |e: &(u32, u32)| {
                let c = &contacts[e.1 as usize];
                (index[c.a as usize], index[c.b as usize])
            };
            let mut held = [false; 48];
            for e in listed {
                let (a, b) = ends(e);
                if moving(a) && !moving(b) {
                    held[a as usize] = true;
                }
                if moving(b) && !moving(a) {
                    held[b as usize] = true;
                }
            }
            for _ in 0..48 {
                for e in listed {
                    let (a, b) = ends(e);
                    if moving(a) && moving(b) && (held[a as usize] || held[b as usize]) {
                        held[a as usize] = true;
                        held[b as usize] = true;
                    }
                }
            }
            for (i, b) in bodies.iter().enumerate() {
                if b.inv_mass > 0.0 {
                    assert_eq!(supports.held(i as u32), held[i], "round {round}, body {i}");
                }
            }
        }
    }

    #[test]
    fn a_heavy_body_on_a_supported_light_one_is_held_with_the_ratio_capped() {
        let light = body(1.0);
        let heavy = body(0.01);
        // Light below (A), heavy above (B): the normal from A to B points up.
        assert_eq!(held_side(&light, &heavy, Vec3::Y, G), Held::SupportA);
        // The same contact written the other way round.
        assert_eq!(held_side(&heavy, &light, -Vec3::Y, G), Held::SupportB);
    }

    #[test]
    fn the_cap_needs_the_ratio_support_slope_rest_and_gravity() {
        let light = body(1.0);
        let heavy = body(0.01);
        // Ratio just under HEAVY_RATIO: uncapped.
        let not_heavy = body(1.0 / (HEAVY_RATIO * 0.99));
        assert_eq!(held_side(&light, &not_heavy, Vec3::Y, G), Held::Neither);
        // Light above heavy: uncapped.
        assert_eq!(held_side(&heavy, &light, Vec3::Y, G), Held::Neither);
        let at_61 = Vec3::new(libm::sinf(1.065), libm::cosf(1.065), 0.0);
        let at_59 = Vec3::new(libm::sinf(1.030), libm::cosf(1.030), 0.0);
        assert_eq!(held_side(&light, &heavy, at_61, G), Held::Neither);
        assert_eq!(held_side(&light, &heavy, at_59, G), Held::SupportA);
        assert_eq!(held_side(&light, &heavy, -Vec3::Y, G), Held::Neither);
        // No gravity, no up: uncapped.
        assert_eq!(
            held_side(&light, &heavy, Vec3::Y, Vec3::ZERO),
            Held::Neither
        );
        // The light body rising into the heavy one faster than RESTING_RISE: uncapped.
        let rising = SolverBody {
            v: Vec3::new(0.0, RESTING_RISE * 1.01, 0.0),
            ..light
        };
        assert_eq!(held_side(&rising, &heavy, Vec3::Y, G), Held::Neither);
        assert_eq!(held_side(&heavy, &rising, -Vec3::Y, G), Held::Neither);
    }
}
