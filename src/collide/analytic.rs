//! Closed forms: sphere, capsule and half-space pairs. They also serve as test oracles.

use crate::math::{scalar, Vec3};

/// Closest points between segments `p1–q1` and `p2–q2`: returns `(s, t)` with the points
/// `p1 + s (q1 − p1)` and `p2 + t (q2 − p2)`, `s, t ∈ [0, 1]`. Degenerate segments
/// (points) are handled. (Ericson, Real-Time Collision Detection, 5.1.9.)
pub fn segment_closest_points(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> (f32, f32) {
    const EPS: f32 = 1.0e-12;
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    if a <= EPS && e <= EPS {
        return (0.0, 0.0);
    }
    if a <= EPS {
        return (0.0, scalar::clamp(f / e, 0.0, 1.0));
    }
    let c = d1.dot(r);
    if e <= EPS {
        return (scalar::clamp(-c / a, 0.0, 1.0), 0.0);
    }
    let b = d1.dot(d2);
    let denom = a * e - b * b;
    let mut s = if denom > EPS * a * e {
        scalar::clamp((b * f - c * e) / denom, 0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = scalar::clamp(-c / a, 0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = scalar::clamp((b - c) / a, 0.0, 1.0);
    }
    (s, t)
}
