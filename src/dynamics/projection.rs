//! Stage 10: push out the penetration that remains after integration. Non-linear
//! projection on positions (NGS: Catto, "Solver2D", 2024, and Box2D v2.4's
//! `b2ContactSolver::SolvePositionConstraints`), weighted by inverse mass and inverse
//! inertia, bounded per point. It changes poses, never velocities.
//!
//! # The separation now
//!
//! A contact point's anchors `local_a`, `local_b` are the two surface points the narrow
//! phase found, fixed in each body's frame. Their current world positions `p_a`, `p_b`
//! (from the poses after integration, continuous collision and earlier corrections) give
//!
//! ```text
//! s = (p_b − p_a)·n
//! ```
//!
//! which equals the narrow phase's separation `s₀ = (p_b₀ − p_a₀)·n` at the poses it ran
//! at, and follows how far those features have moved along `n` since. So the simpler form
//! of `s = (p_b − p_a)·n + s₀ − (p_b₀ − p_a₀)·n` is exact here. The normal `n` stays the
//! world normal of the narrow phase: over one step the bodies turn little, and the next
//! narrow phase refreshes it.
//!
//! # The correction
//!
//! ```text
//! C = clamp(β (s + slop), −max_projection, 0)        (m; β = projection_factor)
//! K = 1/m_a + 1/m_b + (I_a⁻¹ (r_a × n))·(r_a × n) + (I_b⁻¹ (r_b × n))·(r_b × n)
//! P = −C / K · n                                     (a positional "impulse", kg·m)
//! c_a −= P / m_a,  q_a ← q_a turned by −I_a⁻¹ (r_a × P)
//! c_b += P / m_b,  q_b ← q_b turned by +I_b⁻¹ (r_b × P)
//! ```
//!
//! with `r = p − c` from the current centres of mass and the current world inverse
//! inertia. The turn by the small angle vector `θ` is `Quat::integrate(θ, 1)`
//! (`normalise(q + ½ (θ, 0) q)`), the same map as the position integrator's. Penetration
//! up to `slop` is left alone so resting contacts stay touching. Points are visited in
//! contact order then point order, `position_iterations` times (Gauss-Seidel: each point
//! sees the corrections before it). Sensor contacts and contacts where neither body is
//! dynamic and awake are skipped; static, kinematic and sleeping bodies do not move.

use super::body::Body;
use super::contact::Contact;
use super::pool::Pool;
use super::solver::{effective_mass, is_active};
use crate::config::WorldConfig;
use crate::math::{scalar, Mat3};

/// Project remaining penetration out of the contacts (module docs).
pub(crate) fn project<const N: usize>(
    contacts: &[Contact],
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
) {
    for _ in 0..cfg.position_iterations {
        for c in contacts {
            project_contact(c, bodies, cfg);
        }
    }
}

/// One pass over the points of one contact.
fn project_contact<const N: usize>(c: &Contact, bodies: &mut Pool<Body<'_>, N>, cfg: &WorldConfig) {
    if c.sensor {
        return;
    }
    let Some((a, b)) = bodies.pair_mut(c.a as usize, c.b as usize) else {
        return;
    };
    let (active_a, active_b) = (is_active(a), is_active(b));
    if !active_a && !active_b {
        return;
    }
    let n = c.normal;
    for p in c.points.iter().take(c.len as usize) {
        let p_a = a.pose.transform_point(p.local_a);
        let p_b = b.pose.transform_point(p.local_b);
        let separation = (p_b - p_a).dot(n);
        let correction = scalar::clamp(
            cfg.projection_factor * (separation + cfg.slop),
            -cfg.max_projection,
            0.0,
        );
        if correction >= 0.0 {
            continue;
        }
        let (m_a, i_a) = if active_a {
            (a.inv_mass, a.inv_inertia_world)
        } else {
            (0.0, Mat3::ZERO)
        };
        let (m_b, i_b) = if active_b {
            (b.inv_mass, b.inv_inertia_world)
        } else {
            (0.0, Mat3::ZERO)
        };
        let center_a = a.world_center();
        let center_b = b.world_center();
        let r_a = p_a - center_a;
        let r_b = p_b - center_b;
        let k_inv = effective_mass(m_a, &i_a, r_a, m_b, &i_b, r_b, n);
        if k_inv <= 0.0 {
            continue;
        }
        let push = n * (-correction * k_inv);
        if active_a {
            let q = a
                .pose
                .rotation
                .integrate(-i_a.mul_vec(r_a.cross(push)), 1.0);
            a.set_center_pose(center_a - push * m_a, q);
        }
        if active_b {
            let q = b.pose.rotation.integrate(i_b.mul_vec(r_b.cross(push)), 1.0);
            b.set_center_pose(center_b + push * m_b, q);
        }
    }
}
