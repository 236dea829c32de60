//! The query sets of the narrow-phase benchmarks (SCENES.md, "Queries for the
//! narrow-phase benchmarks"): 64 hulls of 16 random unit-sphere points, and 4096 pose pairs
//! per set with uniformly random rotations and a centre distance uniform in the set's
//! range. `core`-only and allocation-free: callers own the buffers.
//!
//! | set | A | B | centre distance (m) |
//! | --- | --- | --- | --- |
//! | `hull_hull` | one of the 64 hulls | one of the 64 hulls | [1.0, 2.2): about half overlap |
//! | `ball_box` | ball, r 0.5 | box, half-extent 0.5 | [0.6, 1.4) |
//! | `box_box` | box, half-extent 0.5 | box, half-extent 0.5 | [0.8, 1.6) |

use crate::math::{Iso, Vec3};
use crate::rng::SplitMix64;

/// Seed of the hull point clouds (ASCII "HULLSET!").
pub const HULL_SEED: u64 = 0x4855_4c4c_5345_5421;
/// Hulls in the hull set.
pub const HULLS: usize = 64;
/// Random unit-sphere points per hull.
pub const HULL_POINTS: usize = 16;
/// Pose pairs per query set.
pub const PAIRS: usize = 4096;
/// Radius of the ball in the ball-vs-box set (m).
pub const BALL_RADIUS: f32 = 0.5;
/// Half-extent of the boxes in the ball-vs-box and box-vs-box sets (m).
pub const BOX_HALF: f32 = 0.5;
/// Speculative margin of the contact queries (m): carom's default (4 × the 5 mm linear
/// slop), so near-touching pairs build their manifold as they would in a step.
pub const CONTACT_MARGIN: f32 = 0.02;

/// One of the three query sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuerySet {
    /// Hull against hull, both drawn from the [`HULLS`] hulls.
    HullHull,
    /// A ball of radius [`BALL_RADIUS`] against a box of half-extent [`BOX_HALF`].
    BallBox,
    /// A box against a box, both of half-extent [`BOX_HALF`].
    BoxBox,
}

impl QuerySet {
    /// Every set, in the order of SCENES.md.
    pub const ALL: [QuerySet; 3] = [QuerySet::HullHull, QuerySet::BallBox, QuerySet::BoxBox];

    /// The set's benchmark group name.
    pub fn name(self) -> &'static str {
        match self {
            QuerySet::HullHull => "hull_hull",
            QuerySet::BallBox => "ball_box",
            QuerySet::BoxBox => "box_box",
        }
    }

    /// Seed of the set's pose pairs.
    pub fn seed(self) -> u64 {
        match self {
            QuerySet::HullHull => 0x0001,
            QuerySet::BallBox => 0x0002,
            QuerySet::BoxBox => 0x0003,
        }
    }

    /// Range `[min, max)` of the centre distance (m). Hulls have radius up to 1, so about
    /// half the hull pairs overlap.
    pub fn distance(self) -> (f32, f32) {
        match self {
            QuerySet::HullHull => (1.0, 2.2),
            QuerySet::BallBox => (0.6, 1.4),
            QuerySet::BoxBox => (0.8, 1.6),
        }
    }

    /// Hulls the set's indices range over (1 for the sets without hulls).
    pub fn hull_count(self) -> u8 {
        match self {
            QuerySet::HullHull => HULLS as u8,
            QuerySet::BallBox | QuerySet::BoxBox => 1,
        }
    }

    /// Fill `out` with the set's pose pairs (see [`pose_pairs`]).
    pub fn fill(self, out: &mut [PoseQuery]) {
        let (d_min, d_max) = self.distance();
        pose_pairs(self.seed(), d_min, d_max, self.hull_count(), out);
    }
}

/// One query: two poses and, for the hull set, which hull each side uses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseQuery {
    /// Pose of A (world frame): at the origin, uniformly random rotation.
    pub pose_a: Iso,
    /// Pose of B (world frame): centre at a uniform distance in the set's range along a
    /// uniformly random direction, uniformly random rotation.
    pub pose_b: Iso,
    /// Hull of A, an index below [`HULLS`] (0 in the other sets).
    pub hull_a: u8,
    /// Hull of B, an index below [`HULLS`] (0 in the other sets).
    pub hull_b: u8,
}

/// Fill `out` with the hull set's point clouds, each [`HULL_POINTS`] points uniform on the
/// unit sphere. Clouds are drawn in order from one generator, so cloud `i` depends on
/// every cloud before it: the set is `out` with `out.len() == HULLS`.
pub fn hull_clouds(out: &mut [[Vec3; HULL_POINTS]]) {
    let mut rng = SplitMix64::new(HULL_SEED);
    for cloud in out.iter_mut() {
        for p in cloud.iter_mut() {
            *p = rng.unit_vector();
        }
    }
}

/// Fill `out` with pose pairs whose centre distance is uniform in `[d_min, d_max)` (m),
/// and hull indices uniform below `hull_count` (0 is read as 1). The draws per query, in
/// order: rotation A, direction, distance, rotation B, hull A, hull B.
pub fn pose_pairs(seed: u64, d_min: f32, d_max: f32, hull_count: u8, out: &mut [PoseQuery]) {
    let mut rng = SplitMix64::new(seed);
    let hulls = if hull_count == 0 {
        1
    } else {
        u64::from(hull_count)
    };
    for q in out.iter_mut() {
        let rotation_a = rng.rotation();
        let direction = rng.unit_vector();
        let d = rng.range(d_min, d_max);
        let rotation_b = rng.rotation();
        *q = PoseQuery {
            pose_a: Iso::new(Vec3::ZERO, rotation_a),
            pose_b: Iso::new(direction * d, rotation_b),
            hull_a: (rng.next_u64() % hulls) as u8,
            hull_b: (rng.next_u64() % hulls) as u8,
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shape::ConvexHull;

    #[test]
    fn pairs_lie_in_their_distance_range_with_valid_hull_indices() {
        for set in QuerySet::ALL {
            let mut out = [PoseQuery::default(); 256];
            set.fill(&mut out);
            let (lo, hi) = set.distance();
            for q in &out {
                // A sits at the origin, so |B's position| is the centre distance; the
                // unit direction carries up to a few ulps of length error, hence 1e-5 m.
                let d = q.pose_b.position.length();
                assert!(d >= lo - 1.0e-5 && d < hi + 1.0e-5, "{set:?} {d}");
                assert_eq!(q.pose_a.position, Vec3::ZERO);
                assert!(q.hull_a < set.hull_count() && q.hull_b < set.hull_count());
            }
        }
    }

    #[test]
    fn every_hull_cloud_builds_a_hull_and_the_sets_are_reproducible() {
        let mut clouds = [[Vec3::ZERO; HULL_POINTS]; HULLS];
        hull_clouds(&mut clouds);
        for c in &clouds {
            assert!(ConvexHull::new(c).is_ok());
            for p in c {
                // Unit vectors from a normalised draw: length 1 to within f32 rounding.
                assert!((p.length() - 1.0).abs() < 1.0e-5);
            }
        }
        let mut again = [[Vec3::ZERO; HULL_POINTS]; HULLS];
        hull_clouds(&mut again);
        assert_eq!(clouds, again);
        // The two sets differ: the seed matters.
        let mut a = [PoseQuery::default(); 8];
        let mut b = [PoseQuery::default(); 8];
        QuerySet::BallBox.fill(&mut a);
        QuerySet::BoxBox.fill(&mut b);
        assert_ne!(a, b);
    }
}
