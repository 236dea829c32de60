//! Narrow-phase benchmarks: GJK distance, EPA penetration and contact manifolds, per shape
//! pair, on the standard query sets of the narrow phase (`shared/SCENES.md`, "Queries for
//! the narrow-phase benchmarks", built by `carom::scenes::queries`). One criterion
//! iteration runs a whole set of 4096 queries: the reported time divided by 4096 is the
//! time per query, the throughput queries per second.
//!
//! The figures the narrow phase is held to: `box_box/contact_manifold` (separating axis
//! test and clipping), `ball_box/contact_manifold` (the sphere–box closed form) and
//! `hull_hull/gjk_distance` (GJK). `contact_into` is the manifold query writing into one
//! manifold the loop keeps (no copy of the answer; `contact_manifold` returns each
//! manifold by value). `contact_cached_warm` runs the same manifold queries
//! with one `PairCache` per query kept from the previous iteration, as a pair that stays
//! put between steps would (the answers are the same; only the time may differ).
//!
//! Run: `cargo bench --bench narrow_phase` (or `-- --quick` for a rough figure).

use std::hint::black_box;

use carom::collide::{
    contact, contact_cached, contact_into, distance, penetration, Manifold, PairCache, SimplexCache,
};
use carom::math::Vec3;
use carom::scenes::queries::{
    self, PoseQuery, QuerySet, BALL_RADIUS, BOX_HALF, CONTACT_MARGIN, HULLS, HULL_POINTS, PAIRS,
};
use carom::shape::{ConvexHull, Shape};
use carom::Error;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

/// A pair set ready to run: the shapes by index and the queries.
struct PairSet<'h> {
    set: QuerySet,
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
    let mut clouds = vec![[Vec3::ZERO; HULL_POINTS]; HULLS];
    queries::hull_clouds(&mut clouds);
    clouds.iter().map(|c| ConvexHull::new(c)).collect()
}

fn pair_set<'h>(set: QuerySet, shapes_a: Vec<Shape<'h>>, shapes_b: Vec<Shape<'h>>) -> PairSet<'h> {
    let mut queries = vec![PoseQuery::default(); PAIRS];
    set.fill(&mut queries);
    PairSet {
        set,
        shapes_a,
        shapes_b,
        queries,
    }
}

fn bench_set(c: &mut Criterion, set: &PairSet<'_>) {
    let mut group = c.benchmark_group(set.set.name());
    group.throughput(Throughput::Elements(set.queries.len() as u64));
    group.bench_function("gjk_distance", |bench| {
        bench.iter(|| {
            for q in &set.queries {
                let (a, b) = set.shapes(q);
                let mut cache = SimplexCache::default();
                black_box(&distance(a, &q.pose_a, b, &q.pose_b, &mut cache));
            }
        })
    });
    group.bench_function("epa_penetration", |bench| {
        bench.iter(|| {
            for q in &set.queries {
                let (a, b) = set.shapes(q);
                black_box(&penetration(a, &q.pose_a, b, &q.pose_b));
            }
        })
    });
    group.bench_function("contact_manifold", |bench| {
        bench.iter(|| {
            for q in &set.queries {
                let (a, b) = set.shapes(q);
                black_box(&contact(a, &q.pose_a, b, &q.pose_b, CONTACT_MARGIN));
            }
        })
    });
    group.bench_function("contact_into", |bench| {
        let mut m = Manifold::default();
        bench.iter(|| {
            for q in &set.queries {
                let (a, b) = set.shapes(q);
                let mut cache = PairCache::default();
                let found = contact_into(
                    a,
                    &q.pose_a,
                    b,
                    &q.pose_b,
                    CONTACT_MARGIN,
                    &mut cache,
                    &mut m,
                );
                black_box((found.ok(), &m));
            }
        })
    });
    let mut caches = vec![PairCache::default(); set.queries.len()];
    group.bench_function("contact_cached_warm", |bench| {
        bench.iter(|| {
            for (q, cache) in set.queries.iter().zip(caches.iter_mut()) {
                let (a, b) = set.shapes(q);
                let m = contact_cached(a, &q.pose_a, b, &q.pose_b, CONTACT_MARGIN, cache);
                black_box(&m);
            }
        })
    });
    group.finish();
}

fn narrow_phase(c: &mut Criterion) {
    let ball = Shape::sphere(BALL_RADIUS).expect("valid radius");
    let cube = Shape::cuboid(Vec3::splat(BOX_HALF)).expect("valid half-extents");
    match build_hulls() {
        Ok(hulls) => {
            let shapes: Vec<Shape<'_>> = hulls.iter().map(Shape::hull).collect();
            bench_set(c, &pair_set(QuerySet::HullHull, shapes.clone(), shapes));
        }
        Err(e) => eprintln!("SKIP hull_hull: the hull set does not build ({e})"),
    }
    bench_set(c, &pair_set(QuerySet::BallBox, vec![ball], vec![cube]));
    bench_set(c, &pair_set(QuerySet::BoxBox, vec![cube], vec![cube]));
}

criterion_group!(benches, narrow_phase);
criterion_main!(benches);
