//! Meshes and height fields from raw input: built or refused without a panic, their box
//! and ray queries equal to brute force, and bodies (convex or compound) falling on them
//! with a finite state and a snapshot that replays bit for bit
//! (`carom_fuzz::mesh_case`).
#![no_main]

use carom_fuzz::{mesh_case, MeshInput};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: MeshInput| {
    if let Err(e) = mesh_case(&input) {
        panic!("{e}");
    }
});
