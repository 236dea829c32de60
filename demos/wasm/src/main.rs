//! Prints the golden lines of `tests/golden/checksums.txt` — the reference scenes
//! (`Scene::REFERENCE`, each run in a fresh `ReferenceWorld`) and the narrow-phase
//! workload — then restores the host's snapshot of `mixed` at step 500
//! (`tests/golden/mixed_500.snap`, built into the binary), finishes the run and prints
//! `restored mixed 1000 0x<checksum>`. Built for `wasm32-wasip1` it runs under Node's WASI
//! (`run.mjs`); built for the host it prints the same lines. Exits 1 on an error. With the
//! feature `micromath` it prints `tests/golden/checksums_micromath.txt` instead and
//! restores `tests/golden/mixed_500_micromath.snap`.

use carom::scenes::{self, ReferenceWorld, Scene, REFERENCE_HULLS, SEED};
use carom::ConvexHull;

/// The host's snapshot of the `mixed` scene at step [`scenes::SNAPSHOT_STEP`].
#[cfg(not(feature = "micromath"))]
static MIXED_500: &[u8] = include_bytes!("../../../tests/golden/mixed_500.snap");
/// The host's snapshot of the `mixed` scene at step [`scenes::SNAPSHOT_STEP`], taken by a
/// `micromath` build (the feature `micromath`: the lines of `checksums_micromath.txt`).
#[cfg(feature = "micromath")]
static MIXED_500: &[u8] = include_bytes!("../../../tests/golden/mixed_500_micromath.snap");

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e:?}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), carom::Error> {
    let mut hulls = vec![ConvexHull::UNIT_TETRAHEDRON; REFERENCE_HULLS];
    scenes::make_hulls(&mut hulls, SEED)?;
    // The ground of `terrain` (height field) and `terrain_mesh` (the same triangles as a
    // mesh), about 50 KB.
    let mut terrain: Box<scenes::TerrainData> = Box::default();
    let terrain = terrain.shapes()?;
    // About 1.1 MB: on the heap, not on wasm's 1 MiB stack.
    let mut world: Box<ReferenceWorld<'_>> = Box::default();
    for scene in Scene::REFERENCE {
        *world = ReferenceWorld::new();
        let checksum = scene.run_on(&mut world, &hulls, terrain.ground(scene))?;
        println!("{}", scene.line(checksum));
    }
    println!("{}", scenes::narrow::run());
    *world = ReferenceWorld::new();
    let checksum = scenes::continue_from_snapshot(Scene::Mixed, &mut world, &hulls, MIXED_500)?;
    println!("restored {}", Scene::Mixed.line(checksum));
    Ok(())
}
