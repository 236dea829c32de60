//! Stage 9: the last, bounded word on penetration. Non-linear projection on positions
//! (NGS: Catto, "Solver2D", 2024, and Box2D v2.4's
//! `b2ContactSolver::SolvePositionConstraints`), weighted by inverse mass and inverse
//! inertia, for the contacts the soft step left deeper than [`DEEP_SLOPS`] slops, and
//! bounded **per body**: all corrections of one body in one step add up to at most
//! `max_projection` (default 0.01 m: poses moved past friction let piles creep). It
//! changes poses, never velocities, so it gives no body speed.
//!
//! The soft step already pushes overlapping bodies apart at up to `max_push_speed`;
//! projection matters where that is not enough within a step: a body driven deep by
//! continuous collision's rewind, a heavy body on a light one, bodies spawned inside
//! each other. The per-body bound keeps a pile of bodies spawned at one pose from
//! pushing one of them through the ground: each correction of a body shares one budget.
//!
//! # The correction
//!
//! With the anchors fixed in the bodies and the poses after the solve and continuous
//! collision, `s = (p_b − p_a)·n`, and
//!
//! ```text
//! C = clamp(β (s + slop), −max_projection, 0)        (m; β = projection_factor)
//! K = 1/m_a + 1/m_b + (I_a⁻¹ (r_a × n))·(r_a × n) + (I_b⁻¹ (r_b × n))·(r_b × n)
//! P = −C / K · n                                     (a positional "impulse", kg·m)
//! c_a −= P / m_a,  q_a ← q_a turned by −I_a⁻¹ (r_a × P)
//! c_b += P / m_b,  q_b ← q_b turned by +I_b⁻¹ (r_b × P)
//! ```
//!
//! `P` is scaled down so that neither body's total displacement this step passes
//! `max_projection`. Points are visited in contact order then point order,
//! `position_iterations` times (Gauss-Seidel). Only awake dynamic bodies move.

use super::body::Body;
use super::contact::Contact;
use super::contact_solver::ContactConstraint;
use super::pool::Pool;
use super::solver::{effective_mass, Solver, NONE};
use crate::config::WorldConfig;
use crate::math::{scalar, Mat3};

/// Depth (in slops) a point must still have after the solve for projection to look at
/// its contact.
pub(crate) const DEEP_SLOPS: f32 = 4.0;

/// Project the remaining deep penetration out of the solved contacts (module docs).
pub(crate) fn project<const N: usize, const C: usize>(
    solver: &mut Solver<N, C>,
    contacts: &[Contact],
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
) {
    if cfg.position_iterations == 0 || cfg.max_projection <= 0.0 {
        return;
    }
    let deep = -DEEP_SLOPS * cfg.slop;
    for sb in solver.bodies.iter_mut() {
        sb.projected = 0.0;
    }
    // The solve's last pass measured every point and found none that deep: nothing to
    // look at (the same points the loop below would skip, without reading the store).
    if solver.store.deep == Some(false) {
        return;
    }
    for _ in 0..cfg.position_iterations {
        for g in 0..solver.store.groups as usize {
            for l in 0..4 {
                let Some(group) = solver.store.group(g) else {
                    break;
                };
                if group.contact(l) == NONE || !group.deeper_than(l, deep) {
                    continue;
                }
                let k = group.load_lane(l, contacts);
                project_constraint(solver, bodies, &k, cfg);
            }
        }
    }
}

/// One pass over the points of one constraint.
fn project_constraint<const N: usize, const C: usize>(
    solver: &mut Solver<N, C>,
    bodies: &mut Pool<Body<'_>, N>,
    k: &ContactConstraint,
    cfg: &WorldConfig,
) {
    let (slot_a, slot_b) = (k.slot_a, k.slot_b);
    let n = k.normal;
    for p in k.points.iter().take(usize::from(k.len)) {
        let Some((a, b)) = bodies.pair_mut(slot_a as usize, slot_b as usize) else {
            return;
        };
        let (move_a, move_b) = (k.inv_mass_a > 0.0, k.inv_mass_b > 0.0);
        let center_a = a.world_center();
        let center_b = b.world_center();
        // Core anchors in body axes; a body without a solver entry keeps a world lever.
        let r_a = if k.a == NONE {
            p.local_a
        } else {
            a.pose().rotation.rotate(p.local_a)
        };
        let r_b = if k.b == NONE {
            p.local_b
        } else {
            b.pose().rotation.rotate(p.local_b)
        };
        let separation = ((center_b + r_b) - (center_a + r_a)).dot(n) - k.radius_sum;
        let correction = scalar::clamp(
            cfg.projection_factor * (separation + cfg.slop),
            -cfg.max_projection,
            0.0,
        );
        if correction >= 0.0 {
            continue;
        }
        // The constraint's inverse masses: a support under a far heavier body reads
        // heavier there (`support.rs`), its inertia scaled alike; elsewhere the body's.
        let (m_a, i_a) = if move_a {
            (
                k.inv_mass_a,
                a.inv_inertia_world.scale(k.inv_mass_a / a.inv_mass),
            )
        } else {
            (0.0, Mat3::ZERO)
        };
        let (m_b, i_b) = if move_b {
            (
                k.inv_mass_b,
                b.inv_inertia_world.scale(k.inv_mass_b / b.inv_mass),
            )
        } else {
            (0.0, Mat3::ZERO)
        };
        let k_inv = effective_mass(m_a, &i_a, r_a, m_b, &i_b, r_b, n);
        if k_inv <= 0.0 {
            continue;
        }
        let mut push = -correction * k_inv; // kg·m along n
                                            // The per-body budget: scale the push so neither body passes it.
        let used_a = solver.body_of_slot(slot_a).map_or(0.0, |s| s.projected);
        let used_b = solver.body_of_slot(slot_b).map_or(0.0, |s| s.projected);
        let budget = |used: f32, m: f32, push: f32| {
            let d = push * m;
            let room = scalar::max(cfg.max_projection - used, 0.0);
            if d > room {
                push * (room / d)
            } else {
                push
            }
        };
        if move_a {
            push = budget(used_a, m_a, push);
        }
        if move_b {
            push = budget(used_b, m_b, push);
        }
        if push <= 0.0 {
            continue;
        }
        let j = n * push;
        if move_a {
            let q = a.pose().rotation.integrate(-i_a.mul_vec(r_a.cross(j)), 1.0);
            a.set_center_pose(center_a - j * m_a, q);
        }
        if move_b {
            let q = b.pose().rotation.integrate(i_b.mul_vec(r_b.cross(j)), 1.0);
            b.set_center_pose(center_b + j * m_b, q);
        }
        if let Some(s) = solver.body_of_slot_mut(slot_a) {
            s.projected += push * m_a;
        }
        if let Some(s) = solver.body_of_slot_mut(slot_b) {
            s.projected += push * m_b;
        }
    }
}
