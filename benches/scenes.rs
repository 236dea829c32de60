//! A step of each standard scene (SCENES.md), sleeping off as timing runs require.
//!
//! `cargo bench --bench scenes` reports, per scene, the time of one step averaged over the
//! scene's whole run (a fresh copy of the scene each sample).

use std::time::{Duration, Instant};

use carom::scenes::{self, Scene};
use carom::{ConvexHull, World, WorldConfig};
use criterion::{criterion_group, Criterion};

/// Large enough for pyramid100 and spheres.
type BigWorld<'a> = World<'a, 5120, 24576, 64>;

fn hulls() -> &'static [ConvexHull] {
    let mut v = vec![ConvexHull::UNIT_TETRAHEDRON; 64];
    scenes::make_hulls(&mut v, scenes::SEED).unwrap();
    Box::leak(v.into_boxed_slice())
}

/// The `mesh_pile` terrain, leaked like the hulls so worlds can borrow it.
fn terrain() -> &'static carom::shape::HeightField<'static> {
    let mut heights = vec![0.0f32; scenes::MESH_PILE_SAMPLES];
    scenes::mesh_pile_heights(&mut heights);
    let heights: &'static [f32] = Box::leak(heights.into_boxed_slice());
    Box::leak(Box::new(scenes::mesh_pile_field(heights).unwrap()))
}

/// The reference terrain's two grounds (`terrain`, `terrain_mesh`), leaked likewise.
fn reference_terrain() -> &'static scenes::TerrainShapes<'static> {
    let data: &'static mut scenes::TerrainData = Box::leak(Box::default());
    Box::leak(Box::new(data.shapes().unwrap()))
}

fn bench_scenes(c: &mut Criterion) {
    let hulls = hulls();
    let terrain = terrain();
    let reference = reference_terrain();
    let mut group = c.benchmark_group("scene_step");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    for scene in Scene::ALL {
        let mut template: Box<BigWorld<'_>> = Box::new(World::new());
        let cfg = WorldConfig {
            sleep_enabled: false,
            ..scene.config()
        };
        template.set_config(cfg).unwrap();
        let ground = reference
            .ground(scene)
            .unwrap_or(carom::Shape::HeightField(terrain));
        scene.build_on(&mut template, hulls, Some(ground)).unwrap();
        let steps = scene.steps();
        group.bench_function(scene.name(), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let mut w = template.clone();
                    let t0 = Instant::now();
                    for _ in 0..steps {
                        w.step();
                    }
                    total += t0.elapsed() / steps;
                }
                total
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_scenes);

fn main() {
    // Worlds live inline: give the benchmarks a big stack.
    std::thread::Builder::new()
        .stack_size(1 << 30)
        .spawn(|| {
            benches();
            Criterion::default().configure_from_args().final_summary();
        })
        .unwrap()
        .join()
        .unwrap();
}
