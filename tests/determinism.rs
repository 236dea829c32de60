//! Golden checksums: the reference scenes, run for their steps, and the narrow-phase
//! workload (`carom::scenes::narrow`) must hash to the values in
//! `tests/golden/checksums.txt` — in debug and in release, and (through `.ci/run`) on
//! Cortex-M under QEMU and on wasm32 under Node, which print the same lines.
//!
//! `tests/golden/mixed_500.snap` is a snapshot of the `mixed` scene at step 500 taken on
//! the host; every target restores it, finishes the run and must reach the golden `mixed`
//! checksum (a snapshot crosses targets intact).
//!
//! The feature `micromath` gives other bits (its square root and trig differ from libm's
//! in the last places), so a `micromath` build has its own two files beside them,
//! `tests/golden/checksums_micromath.txt` and `tests/golden/mixed_500_micromath.snap`,
//! checked the same way; each backend refuses the other's snapshot.
//!
//! To regenerate after an intended change: `CAROM_BLESS=1 cargo test --test determinism`
//! rewrites both files of the build's backend (add `--features micromath` for the
//! micromath pair); say why in the commit message.

use carom::scenes::{self, ReferenceWorld, Scene};
use carom::{ConvexHull, Error, SnapshotError, Vec3};

/// The golden lines of this build's math backend.
#[cfg(not(feature = "micromath"))]
const GOLDEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/checksums.txt");
/// The golden lines of this build's math backend.
#[cfg(feature = "micromath")]
const GOLDEN: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/golden/checksums_micromath.txt"
);
/// The host snapshot of `mixed` at step 500 taken by this build's math backend.
#[cfg(not(feature = "micromath"))]
const SNAPSHOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/mixed_500.snap");
/// The host snapshot of `mixed` at step 500 taken by this build's math backend.
#[cfg(feature = "micromath")]
const SNAPSHOT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/golden/mixed_500_micromath.snap"
);
/// The same snapshot taken by the other math backend.
#[cfg(not(feature = "micromath"))]
const OTHER_BACKEND_SNAPSHOT: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/golden/mixed_500_micromath.snap"
);
/// The same snapshot taken by the other math backend.
#[cfg(feature = "micromath")]
const OTHER_BACKEND_SNAPSHOT: &str =
    concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/mixed_500.snap");

fn reference_hulls() -> Vec<ConvexHull> {
    let tetra = ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
    let mut hulls = vec![tetra; scenes::REFERENCE_HULLS];
    scenes::make_hulls(&mut hulls, scenes::SEED).unwrap();
    hulls
}

fn line(scene: Scene, sum: u64) -> String {
    scene.line(sum).to_string()
}

fn reference_line(scene: Scene) -> String {
    let hulls = reference_hulls();
    let mut terrain: Box<scenes::TerrainData> = Box::default();
    let shapes = terrain.shapes().unwrap();
    let mut world: Box<ReferenceWorld<'_>> = Box::new(ReferenceWorld::new());
    let sum = scene
        .run_on(&mut world, &hulls, shapes.ground(scene))
        .unwrap();
    line(scene, sum)
}

/// The mixed scene's snapshot at [`scenes::SNAPSHOT_STEP`].
fn mixed_snapshot() -> Vec<u8> {
    let hulls = reference_hulls();
    let mut world: Box<ReferenceWorld<'_>> = Box::new(ReferenceWorld::new());
    world.set_config(Scene::Mixed.config()).unwrap();
    Scene::Mixed.build(&mut world, &hulls).unwrap();
    while world.step_count() < scenes::SNAPSHOT_STEP {
        world.step();
    }
    let mut buf = vec![0u8; world.snapshot_len()];
    let n = world.snapshot(&mut buf).unwrap();
    buf.truncate(n);
    buf
}

fn run_on_big_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap()
}

fn bless() -> bool {
    std::env::var_os("CAROM_BLESS").is_some()
}

#[test]
fn the_reference_scenes_and_the_narrow_workload_match_the_golden_checksums() {
    let lines: Vec<String> = run_on_big_stack(|| {
        let mut lines: Vec<String> = Scene::REFERENCE
            .iter()
            .map(|s| reference_line(*s))
            .collect();
        lines.push(scenes::narrow::run().to_string());
        lines
    });
    if bless() {
        std::fs::write(GOLDEN, lines.join("\n") + "\n").unwrap();
        return;
    }
    let golden = std::fs::read_to_string(GOLDEN).unwrap();
    let expected: Vec<&str> = golden.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(
        lines, expected,
        "golden checksums changed: see tests/determinism.rs"
    );
}

#[test]
fn the_host_snapshot_is_byte_identical_and_continues_to_the_golden_checksum() {
    let snap = run_on_big_stack(mixed_snapshot);
    if bless() {
        std::fs::write(SNAPSHOT, &snap).unwrap();
        return;
    }
    let stored = std::fs::read(SNAPSHOT).unwrap();
    assert!(
        snap == stored,
        "the snapshot format or the simulation changed: re-bless"
    );
    let finished = run_on_big_stack(move || {
        let hulls = reference_hulls();
        let mut world: Box<ReferenceWorld<'_>> = Box::new(ReferenceWorld::new());
        let sum =
            scenes::continue_from_snapshot(Scene::Mixed, &mut world, &hulls, &stored).unwrap();
        line(Scene::Mixed, sum)
    });
    let golden = std::fs::read_to_string(GOLDEN).unwrap();
    assert!(
        golden.lines().any(|l| l == finished),
        "{finished} not in the golden file"
    );
}

#[test]
fn golden_lines_have_the_documented_format() {
    // `<name> <steps> 0x<16 lower-case hex digits>`: the format every target prints and
    // `.ci/run` diffs, so a formatting change on one side would fail CI, not pass silently.
    let l = Scene::Tower.line(0x00ab_cdef_0123_4567).to_string();
    assert_eq!(l, "tower 1000 0x00abcdef01234567");
    let n = scenes::narrow::NarrowResult {
        count: 256,
        hash: 1,
    }
    .to_string();
    assert_eq!(n, "narrow 256 0x0000000000000001");
    let golden = std::fs::read_to_string(GOLDEN).unwrap();
    let names: Vec<&str> = golden.lines().filter_map(|l| l.split(' ').next()).collect();
    assert_eq!(
        names,
        [
            "mixed",
            "bullets",
            "tower",
            "terrain",
            "terrain_mesh",
            "narrow"
        ]
    );
    for l in golden.lines() {
        let hex = l.rsplit(' ').next().unwrap();
        assert!(hex.len() == 18 && hex.starts_with("0x"), "{l}");
        assert!(hex[2..]
            .bytes()
            .all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)));
    }
}

#[test]
fn a_scene_run_twice_gives_the_same_checksum() {
    let (a, b) = run_on_big_stack(|| (reference_line(Scene::Tower), reference_line(Scene::Tower)));
    assert_eq!(a, b);
}

#[test]
fn the_other_math_backends_snapshot_is_refused_and_changes_nothing() {
    let other = std::fs::read(OTHER_BACKEND_SNAPSHOT).unwrap();
    let (refused, unchanged) = run_on_big_stack(move || {
        let hulls = reference_hulls();
        let mut world: Box<ReferenceWorld<'_>> = Box::new(ReferenceWorld::new());
        world.set_config(Scene::Mixed.config()).unwrap();
        Scene::Mixed.build(&mut world, &hulls).unwrap();
        for _ in 0..10 {
            world.step();
        }
        let before = world.checksum();
        let refused = world.restore_with_hulls(&other, &hulls);
        (
            refused,
            world.checksum() == before && world.step_count() == 10,
        )
    });
    assert_eq!(refused, Err(Error::Snapshot(SnapshotError::MathBackend)));
    assert!(unchanged);
}
