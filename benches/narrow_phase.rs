//! Narrow-phase benchmarks: GJK distance, EPA penetration and contact manifolds, per shape
//! pair, on the standard query sets of the narrow phase (`shared/SCENES.md`, "Queries for
//! the narrow-phase benchmarks"). One criterion iteration runs a whole set of 4096
//! queries; the reported throughput is queries per second.
//!
//! Run: `cargo bench --bench narrow_phase` (or `-- --quick` for a rough figure).

use std::hint::black_box;

use carom::collide::{contact, distance, penetration, SimplexCache};
use carom::math::{Iso, Vec3};
use carom::rng::SplitMix64;
use carom::shape::{ConvexHull, Shape};
use carom::Error;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

// ---------------------------------------------------------------------------------------
// Query sets. `core`-only and allocation-free (callers own the buffers), so they can move
// as they are into the crate's scenes module and be shared with tests and demos.
// ---------------------------------------------------------------------------------------

/// Seed of the hull point clouds.
pub const QUERY_HULL_SEED: u64 = 0x4855_4c4c_5345_5421; // "HULLSET!"
/// Seed of the hull-vs-hull pose pairs.
pub const QUERY_HULL_PAIR_SEED: u64 = 0x0001;
/// Seed of the ball-vs-box pose pairs.
pub const QUERY_BALL_BOX_SEED: u64 = 0x0002;
/// Seed of the box-vs-box pose pairs.
pub const QUERY_BOX_BOX_SEED: u64 = 0x0003;
/// Hulls in the hull set.
pub const QUERY_HULLS: usize = 64;
/// Random unit-sphere points per hull.
pub const QUERY_HULL_POINTS: usize = 16;
/// Pose pairs per query set.
pub const QUERY_PAIRS: usize = 4096;
/// Radius of the ball in the ball-vs-box set (m).
pub const QUERY_BALL_RADIUS: f32 = 0.5;
/// Half-extent of the boxes in the ball-vs-box and box-vs-box sets (m).
pub const QUERY_BOX_HALF: f32 = 0.5;
/// Centre distance range of the hull pairs (m): hulls have radius up to 1, so about half
/// the pairs overlap.
pub const QUERY_HULL_DISTANCE: (f32, f32) = (1.0, 2.2);
/// Centre distance range of the ball-vs-box pairs (m).
pub const QUERY_BALL_BOX_DISTANCE: (f32, f32) = (0.6, 1.4);
/// Centre distance range of the box-vs-box pairs (m).
pub const QUERY_BOX_BOX_DISTANCE: (f32, f32) = (0.8, 1.6);

/// Speculative margin of the contact queries (m): carom's default (4 × the 5 mm linear
/// slop), so near-touching pairs build their manifold as they would in a step.
pub const QUERY_CONTACT_MARGIN: f32 = 0.02;

/// One query: two poses and, for the hull set, which hull each side uses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PoseQuery {
    /// Pose of A (world frame): at the origin, uniformly random rotation.
    pub pose_a: Iso,
    /// Pose of B (world frame): centre at a uniform distance in the set's range along a
    /// uniformly random direction, uniformly random rotation.
    pub pose_b: Iso,
    /// Hull of A, an index below [`QUERY_HULLS`] (0 in the other sets).
    pub hull_a: u8,
    /// Hull of B, an index below [`QUERY_HULLS`] (0 in the other sets).
    pub hull_b: u8,
}

/// The `index`-th point cloud of the hull set: [`QUERY_HULL_POINTS`] points uniform on the
/// unit sphere. Clouds are drawn in order from one generator, so cloud `i` depends on all
/// clouds before it; build them in a loop from `0`.
pub fn query_hull_clouds(out: &mut [[Vec3; QUERY_HULL_POINTS]]) {
    let mut rng = SplitMix64::new(QUERY_HULL_SEED);
    for cloud in out.iter_mut() {
        for p in cloud.iter_mut() {
            *p = rng.unit_vector();
        }
    }
}

/// Fill `out` with pose pairs whose centre distance is uniform in `[d_min, d_max)` (m),
/// and hull indices uniform below `hull_count` (use 1 for sets without hulls). The draws
/// per query, in order: rotation A, direction, distance, rotation B, hull A, hull B.
pub fn query_pose_pairs(seed: u64, d_min: f32, d_max: f32, hull_count: u8, out: &mut [PoseQuery]) {
    let mut rng = SplitMix64::new(seed);
    let hulls = u64::from(hull_count.max(1));
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

// ---------------------------------------------------------------------------------------
// Benchmarks.
// ---------------------------------------------------------------------------------------

/// A pair set ready to run: the shapes by index and the queries.
struct PairSet<'h> {
    name: &'static str,
    shapes_a: Vec<Shape<'h>>,
    shapes_b: Vec<Shape<'h>>,
    queries: Vec<PoseQuery>,
}

impl PairSet<'_> {
    fn shapes(&self, q: &PoseQuery) -> (&Shape<'_>, &Shape<'_>) {
        let a = &self.shapes_a[usize::from(q.hull_a) % self.shapes_a.len()];
        let b = &self.shapes_b[usize::from(q.hull_b) % self.shapes_b.len()];
        (a, b)
    }
}

fn build_hulls() -> Result<Vec<ConvexHull>, Error> {
    let mut clouds = vec![[Vec3::ZERO; QUERY_HULL_POINTS]; QUERY_HULLS];
    query_hull_clouds(&mut clouds);
    clouds.iter().map(|c| ConvexHull::new(c)).collect()
}

fn pair_set<'h>(
    name: &'static str,
    seed: u64,
    range: (f32, f32),
    shapes_a: Vec<Shape<'h>>,
    shapes_b: Vec<Shape<'h>>,
) -> PairSet<'h> {
    let mut queries = vec![PoseQuery::default(); QUERY_PAIRS];
    let hull_count = shapes_a.len().max(shapes_b.len()) as u8;
    query_pose_pairs(seed, range.0, range.1, hull_count, &mut queries);
    PairSet {
        name,
        shapes_a,
        shapes_b,
        queries,
    }
}

fn bench_set(c: &mut Criterion, set: &PairSet<'_>) {
    let mut group = c.benchmark_group(set.name);
    group.throughput(Throughput::Elements(set.queries.len() as u64));
    group.bench_function("gjk_distance", |bench| {
        bench.iter(|| {
            for q in &set.queries {
                let (a, b) = set.shapes(q);
                let mut cache = SimplexCache::default();
                black_box(distance(a, &q.pose_a, b, &q.pose_b, &mut cache).ok());
            }
        })
    });
    group.bench_function("epa_penetration", |bench| {
        bench.iter(|| {
            for q in &set.queries {
                let (a, b) = set.shapes(q);
                black_box(penetration(a, &q.pose_a, b, &q.pose_b).ok());
            }
        })
    });
    group.bench_function("contact_manifold", |bench| {
        bench.iter(|| {
            for q in &set.queries {
                let (a, b) = set.shapes(q);
                black_box(contact(a, &q.pose_a, b, &q.pose_b, QUERY_CONTACT_MARGIN).ok());
            }
        })
    });
    group.finish();
}

fn narrow_phase(c: &mut Criterion) {
    let ball = Shape::sphere(QUERY_BALL_RADIUS).expect("valid radius");
    let cube = Shape::cuboid(Vec3::splat(QUERY_BOX_HALF)).expect("valid half-extents");
    match build_hulls() {
        Ok(hulls) => {
            let shapes: Vec<Shape<'_>> = hulls.iter().map(Shape::hull).collect();
            let set = pair_set(
                "hull_hull",
                QUERY_HULL_PAIR_SEED,
                QUERY_HULL_DISTANCE,
                shapes.clone(),
                shapes,
            );
            bench_set(c, &set);
        }
        Err(e) => eprintln!("SKIP hull_hull: the hull set does not build ({e})"),
    }
    let set = pair_set(
        "ball_box",
        QUERY_BALL_BOX_SEED,
        QUERY_BALL_BOX_DISTANCE,
        vec![ball],
        vec![cube],
    );
    bench_set(c, &set);
    let set = pair_set(
        "box_box",
        QUERY_BOX_BOX_SEED,
        QUERY_BOX_BOX_DISTANCE,
        vec![cube],
        vec![cube],
    );
    bench_set(c, &set);
}

criterion_group!(benches, narrow_phase);
criterion_main!(benches);
