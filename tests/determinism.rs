//! Golden checksums: the reference scenes, run for their steps, must hash to the values in
//! `tests/golden/checksums.txt` — in debug and in release, and (through `.ci/run`) on
//! Cortex-M under QEMU and on wasm32 under Node, which print the same lines.
//!
//! To regenerate after an intended change: `CAROM_BLESS=1 cargo test --test determinism`
//! prints the new lines; say why in the commit message.

use carom::scenes::{self, ReferenceWorld, Scene};
use carom::{ConvexHull, Vec3};

fn reference_line(scene: Scene) -> String {
    let mut hulls = [ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
        scenes::REFERENCE_HULLS];
    scenes::make_hulls(&mut hulls, scenes::SEED).unwrap();
    let mut world: Box<ReferenceWorld<'_>> = Box::new(ReferenceWorld::new());
    let sum = scene.run(&mut world, &hulls).unwrap();
    format!("{} {} {:#018x}", scene.name(), scene.steps(), sum)
}

fn run_on_big_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap()
}

#[test]
fn reference_scenes_match_the_golden_checksums() {
    let lines: Vec<String> = run_on_big_stack(|| {
        Scene::REFERENCE
            .iter()
            .map(|s| reference_line(*s))
            .collect()
    });
    let golden = include_str!("golden/checksums.txt");
    let expected: Vec<&str> = golden.lines().filter(|l| !l.trim().is_empty()).collect();
    if std::env::var_os("CAROM_BLESS").is_some() {
        for l in &lines {
            println!("{l}");
        }
        return;
    }
    assert_eq!(
        lines, expected,
        "golden checksums changed: see tests/determinism.rs"
    );
}

#[test]
fn a_scene_run_twice_gives_the_same_checksum() {
    let (a, b) = run_on_big_stack(|| (reference_line(Scene::Tower), reference_line(Scene::Tower)));
    assert_eq!(a, b);
}
