//! Properties of [`time_of_impact`] and [`movement_bounds`], checked against GJK distance
//! sampled along the motions.

use super::{check, shape_size_in_range, Violation};
use crate::collide::{
    distance, movement_bounds, penetration, time_of_impact, Motion, SimplexCache, Toi,
};
use crate::math::{Iso, Vec3};
use crate::shape::Shape;

/// Times before a hit at which the shapes must be apart (no tunnelling).
pub const TOI_EARLIER_SAMPLES: u32 = 64;

/// Times in `[0, t_max]` at which separated shapes must be apart.
pub const TOI_SEPARATED_SAMPLES: u32 = 256;

/// Times in `[0, t_max]` at which a shape's box must lie in its movement bounds.
pub const TOI_BOUNDS_SAMPLES: u32 = 100;

/// Largest coordinate (m), speed (m/s), spin (rad/s) and shape size (m) for which the
/// geometric properties are checked. Outside it `f32` GJK error grows past the slack
/// below; only "no panic, time in range" is checked there.
const WORKING_RANGE: f32 = 1.0e3;

/// GJK's touching resolution, relative to the size of the numbers it works with, as the
/// gap checks assume it: cores closer than this may count as touching (distance 0). A
/// conservative bound: GJK's own threshold (`collide::gjk::GJK_OVERLAP_TOLERANCE`, which
/// `props` cannot name) is 2e-7 on vertices and edges of the Minkowski difference and
/// rounding alone on its faces; 1e-5 is the threshold it had before, kept here so that the
/// time-of-impact checks stay where they were measured.
const GJK_TOUCH_RESOLUTION: f32 = 1.0e-5;

/// How many GJK touching thresholds the tolerance must span for the gap checks (see
/// [`resolvable`]).
const RESOLVABLE_FACTOR: f32 = 10.0;

/// Relative GJK accuracy allowed when comparing a sampled gap with the tolerance: the
/// sampled GJK starts cold while the query warm-starts, so they may differ by rounding.
const GAP_SLACK: f32 = 1.0e-5;

/// How far a reported normal may be from unit length.
const UNIT_SLACK: f32 = 1.0e-3;

/// Properties of `time_of_impact(a, motion_a, b, motion_b, t_max, tolerance)`:
///
/// - it never panics; a refused input is fine (the bad-input tests check the errors);
/// - a hit time lies in `[0, t_max]`;
/// - in the working range (coordinates, speeds, spins and sizes up to 1000, sizes in range
///   by [`super::shape_size_in_range`], `t_max` up to 10 s, `tolerance` in `[1e-4, 1]` m):
///   each shape's box at [`TOI_BOUNDS_SAMPLES`] times in `[0, t_max]` lies in its
///   [`movement_bounds`] over `t_max`; a hit has a finite unit normal and finite points;
/// - there, when moreover GJK can resolve the tolerance (it is at least 10 times GJK's
///   touching threshold, 1e-5 of both bounding radii plus the largest distance between
///   the origins over the motions; always for a half-space pair): the shapes are apart at
///   the hit time (or touching within rounding: EPA depth within the GJK slack) with a gap
///   of at most `tolerance` (plus GJK slack); `Overlapping` means GJK distance 0 at time 0
///   (within the same slack);
/// - and there, at any spin, no contact is missed: [`TOI_EARLIER_SAMPLES`] times before a
///   hit or before an `Unresolved` answer's time (apart or touching within rounding), or
///   [`TOI_SEPARATED_SAMPLES`] times in `[0, t_max]` after `Separated`, show the shapes
///   apart. (Until the certified search, this held only up to one turn in all.)
pub fn toi_properties(
    a: &Shape,
    motion_a: &Motion,
    b: &Shape,
    motion_b: &Motion,
    t_max: f32,
    tolerance: f32,
) -> Result<(), Violation> {
    let Ok(toi) = time_of_impact(a, motion_a, b, motion_b, t_max, tolerance) else {
        return Ok(());
    };
    if let Toi::Hit { time, .. } | Toi::Unresolved { time } = toi {
        check(
            (0.0..=t_max).contains(&time),
            "toi: hit time outside [0, t_max]",
        )?;
    }
    if !in_working_range(a, motion_a, b, motion_b, t_max, tolerance) {
        return Ok(());
    }
    bounds_hold(a, motion_a, t_max)?;
    bounds_hold(b, motion_b, t_max)?;
    if let Toi::Hit {
        normal,
        point_a,
        point_b,
        ..
    } = toi
    {
        check(
            normal.is_finite() && point_a.is_finite() && point_b.is_finite(),
            "toi: hit normal or points not finite",
        )?;
        check(
            (1.0 - UNIT_SLACK..=1.0 + UNIT_SLACK).contains(&normal.length()),
            "toi: hit normal not unit length",
        )?;
    }
    if !resolvable(a, motion_a, b, motion_b, t_max, tolerance) {
        return Ok(());
    }
    let pair = Sampler {
        a,
        motion_a,
        b,
        motion_b,
    };
    match toi {
        Toi::Hit {
            time,
            point_a,
            point_b,
            ..
        } => {
            let gap = pair.gap_at(time)?;
            let slack = GAP_SLACK * (1.0 + pair.scale(t_max));
            // Touching within rounding is contact, not overlap: the query composes the
            // poses in f32 and the sampler in f64 (`distance`), so at an exactly touching
            // pose one may read 1e-7 m and the other 0 (fuzz finding
            // `touching-at-time-0-02d40795`).
            check(
                gap > 0.0 || pair.depth_at(time)? <= slack,
                "toi: shapes overlap at the hit time",
            )?;
            check(
                gap <= tolerance + slack,
                "toi: gap at the hit time exceeds the tolerance",
            )?;
            check(
                point_a.distance(point_b) <= tolerance + slack,
                "toi: hit points further apart than the tolerance",
            )?;
            pair.apart_before(time, slack)?;
        }
        Toi::Unresolved { time } => {
            // Nothing is claimed after `time`; up to it the shapes are apart.
            let slack = GAP_SLACK * (1.0 + pair.scale(t_max));
            check(
                pair.gap_at(time)? > 0.0 || pair.depth_at(time)? <= slack,
                "toi: unresolved, but the shapes overlap at its certain time",
            )?;
            pair.apart_before(time, slack)?;
        }
        Toi::Separated => {
            for k in 0..=TOI_SEPARATED_SAMPLES {
                let t = t_max * (k as f32 / TOI_SEPARATED_SAMPLES as f32);
                check(
                    pair.gap_at(t)? > 0.0,
                    "toi: separated but the shapes overlap at a sampled time",
                )?;
            }
        }
        Toi::Overlapping => {
            // Touching within rounding may read as a gap of rounding size the other way
            // (fuzz finding `touching-at-time-0-adc4a3f4`, the mirror of `02d40795`).
            let slack = GAP_SLACK * (1.0 + pair.scale(t_max));
            check(
                pair.gap_at(0.0)? <= slack,
                "toi: overlapping but GJK finds a gap at time 0",
            )?;
        }
    }
    Ok(())
}

/// `shape`'s box at [`TOI_BOUNDS_SAMPLES`] evenly spaced times in `[0, dt]` (both ends
/// included) lies in `movement_bounds(shape, motion, dt)`.
fn bounds_hold(shape: &Shape, motion: &Motion, dt: f32) -> Result<(), Violation> {
    let bounds = movement_bounds(shape, motion, dt);
    check(bounds.is_valid(), "movement bounds: not a valid box")?;
    for k in 0..TOI_BOUNDS_SAMPLES {
        let t = dt * (k as f32 / (TOI_BOUNDS_SAMPLES - 1) as f32);
        check(
            bounds.contains(&shape.aabb(&motion.pose_at(t))),
            "movement bounds: the shape's box at a sampled time sticks out",
        )?;
    }
    Ok(())
}

/// The pair as `time_of_impact` sees it, sampled with cold-started GJK.
struct Sampler<'q, 's> {
    a: &'q Shape<'s>,
    motion_a: &'q Motion,
    b: &'q Shape<'s>,
    motion_b: &'q Motion,
}

impl Sampler<'_, '_> {
    /// GJK distance between the shapes at time `t` (m).
    fn gap_at(&self, t: f32) -> Result<f32, Violation> {
        let pose_a: Iso = self.motion_a.pose_at(t);
        let pose_b: Iso = self.motion_b.pose_at(t);
        let mut cache = SimplexCache::default();
        distance(self.a, &pose_a, self.b, &pose_b, &mut cache)
            .map(|out| out.distance)
            .map_err(|_| Violation("toi: distance refused a pose from Motion::pose_at"))
    }

    /// The shapes are apart (or touching within `slack`) at [`TOI_EARLIER_SAMPLES`] times
    /// in `[0, time)`: nothing tunnelled before a reported time.
    fn apart_before(&self, time: f32, slack: f32) -> Result<(), Violation> {
        for k in 0..TOI_EARLIER_SAMPLES {
            let t = time * (k as f32 / TOI_EARLIER_SAMPLES as f32);
            check(
                self.gap_at(t)? > 0.0 || self.depth_at(t)? <= slack,
                "toi: shapes overlap before the hit (tunnelling)",
            )?;
        }
        Ok(())
    }

    /// EPA's penetration depth at time `t` (0 when the shapes do not overlap).
    fn depth_at(&self, t: f32) -> Result<f32, Violation> {
        let pose_a: Iso = self.motion_a.pose_at(t);
        let pose_b: Iso = self.motion_b.pose_at(t);
        penetration(self.a, &pose_a, self.b, &pose_b)
            .map(|p| p.map_or(0.0, |p| p.depth))
            .map_err(|_| Violation("toi: penetration refused a pose from Motion::pose_at"))
    }

    /// The size of the numbers GJK works with (m): coordinates and finite shape sizes.
    fn scale(&self, t_max: f32) -> f32 {
        let reach = |s: &Shape| {
            if matches!(s, Shape::HalfSpace(_)) {
                0.0
            } else {
                s.bounding_radius()
            }
        };
        let far = |m: &Motion| m.pose.position.abs().max_elem() + m.linear.abs().max_elem() * t_max;
        reach(self.a) + reach(self.b) + far(self.motion_a) + far(self.motion_b)
    }
}

/// True when GJK can tell a gap of `tolerance` from contact all along the motions: the
/// tolerance is at least [`RESOLVABLE_FACTOR`] times GJK's touching threshold,
/// [`GJK_TOUCH_RESOLUTION`] times the largest numbers it meets (both bounding radii plus
/// the largest distance between the origins, `|c_b − c_a| + |v_b − v_a| t_max`). A
/// half-space pair is a closed form with no such threshold.
///
/// Below it (boxes of 50 m and a 0.1 mm tolerance: GJK calls cores within 1.5 mm
/// touching) the distance jumps from above the tolerance to 0, so no time has a gap in
/// `(0, tolerance]`; a warm-started and a cold GJK may also disagree on "touching" near
/// the threshold. The time of impact then stops within GJK's resolution of contact, which
/// the gap checks cannot judge.
fn resolvable(
    a: &Shape,
    motion_a: &Motion,
    b: &Shape,
    motion_b: &Motion,
    t_max: f32,
    tolerance: f32,
) -> bool {
    if matches!(a, Shape::HalfSpace(_)) || matches!(b, Shape::HalfSpace(_)) {
        return true;
    }
    let apart = (motion_b.pose.position - motion_a.pose.position).length()
        + (motion_b.linear - motion_a.linear).length() * t_max;
    let size = a.bounding_radius() + b.bounding_radius() + apart;
    tolerance >= RESOLVABLE_FACTOR * GJK_TOUCH_RESOLUTION * size
}

/// True when every number is within [`WORKING_RANGE`], both shapes' sizes are in range
/// ([`shape_size_in_range`]), and the tolerance is at least
/// `1e-4` m (below that, `f32` GJK error at metre scale is a sizeable part of it).
fn in_working_range(
    a: &Shape,
    motion_a: &Motion,
    b: &Shape,
    motion_b: &Motion,
    t_max: f32,
    tolerance: f32,
) -> bool {
    let small = |v: Vec3| v.abs().max_elem() <= WORKING_RANGE;
    let sized = |s: &Shape| {
        shape_size_in_range(s)
            && (matches!(s, Shape::HalfSpace(_)) || s.bounding_radius() <= WORKING_RANGE)
    };
    let moving = |m: &Motion| small(m.pose.position) && small(m.linear) && small(m.angular);
    moving(motion_a)
        && moving(motion_b)
        && sized(a)
        && sized(b)
        && t_max <= 10.0
        && (1.0e-4..=1.0).contains(&tolerance)
}
