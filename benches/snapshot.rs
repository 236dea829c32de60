//! Snapshot, restore and checksum of a settled world of 100 and of 1000 boxes: what a
//! rollback or lockstep game pays per saved frame, per rollback and per desync check.
//!
//! The worlds are the `boxes` scene (SCENES.md): all of it (ground + 1000 boxes), and its
//! first layer (ground + 100 boxes: the scene built into a world with room for 101
//! bodies, which stops with `PoolFull` after its first layer). Each is stepped
//! [`SETTLE_STEPS`] times first, so the boxes have landed and the contact cache holds
//! warm-start impulses, which the snapshot carries. Snapshot sizes are printed once.
//!
//! Run: `cargo bench --bench snapshot` (or `-- --quick` for a rough figure).

use std::hint::black_box;

use carom::scenes::Scene;
use carom::{Error, Pool, World};
use criterion::{criterion_group, BenchmarkId, Criterion, Throughput};

/// Steps before measuring: 2 s at 60 Hz. The lowest layer lands after about 0.55 s, the
/// layers above within the next second.
const SETTLE_STEPS: u32 = 120;

/// Ground + the first 100 boxes of `boxes`.
type World100<'a> = World<'a, 101, 512, 64>;
/// Ground + the 1000 boxes of `boxes`.
type World1000<'a> = World<'a, 1001, 4096, 64>;

/// Build `boxes` into `world` (stopping when the body pool is full) and settle it.
fn settled_boxes<const B: usize, const C: usize, const E: usize>(
    world: &mut World<'static, B, C, E>,
) {
    world
        .set_config(Scene::Boxes.config())
        .expect("the scene's config is valid");
    match Scene::Boxes.build(world, &[]) {
        Ok(_) | Err(Error::PoolFull(Pool::Bodies)) => {}
        Err(e) => panic!("boxes does not build: {e:?}"),
    }
    let mut dropped = 0;
    for _ in 0..SETTLE_STEPS {
        let report = world.step();
        dropped += report.dropped_contacts + report.dropped_pairs;
    }
    assert_eq!(dropped, 0, "raise the contact capacity");
}

fn bench_world<const B: usize, const C: usize, const E: usize>(
    c: &mut Criterion,
    world: &mut World<'static, B, C, E>,
) {
    settled_boxes(world);
    let bodies = world.body_count();
    let mut buf = vec![0u8; World::<'static, B, C, E>::max_snapshot_len()];
    let n = world
        .snapshot(&mut buf)
        .expect("the buffer holds any snapshot");
    buf.truncate(n);
    eprintln!(
        "snapshot of {bodies} bodies and {} contacts after {SETTLE_STEPS} steps: {n} bytes \
         ({} per body); the most this world type can need: {} bytes",
        world.contact_count(),
        n / bodies,
        World::<'static, B, C, E>::max_snapshot_len()
    );
    let id = |name| BenchmarkId::new(name, format!("{}_boxes", bodies - 1));
    let mut group = c.benchmark_group("snapshot");
    group.throughput(Throughput::Bytes(n as u64));
    let mut out = vec![0u8; n];
    group.bench_function(id("snapshot"), |b| {
        b.iter(|| black_box(world.snapshot(black_box(&mut out)).ok()))
    });
    // Restore into the same world: restore replaces the whole dynamic state, so every
    // iteration does the same work (both validation passes and the write).
    group.bench_function(id("restore"), |b| {
        b.iter(|| black_box(world.restore(black_box(&buf)).ok()))
    });
    group.bench_function(id("checksum"), |b| b.iter(|| black_box(world.checksum())));
    group.finish();
    // The restored world is the snapshotted one.
    let sum = world.checksum();
    world.restore(&buf).expect("own snapshot restores");
    assert_eq!(world.checksum(), sum);
}

fn bench_snapshots(c: &mut Criterion) {
    let mut small: Box<World100<'static>> = Box::default();
    bench_world(c, &mut small);
    let mut large: Box<World1000<'static>> = Box::default();
    bench_world(c, &mut large);
}

criterion_group!(benches, bench_snapshots);

fn main() {
    // Worlds are built inline before they are boxed: give the benchmarks a big stack.
    std::thread::Builder::new()
        .stack_size(1 << 30)
        .spawn(|| {
            benches();
            criterion::Criterion::default()
                .configure_from_args()
                .final_summary();
        })
        .expect("spawn the benchmark thread")
        .join()
        .expect("the benchmarks ran");
}
