//! Snapshot decoding: arbitrary bytes, and real snapshots of a small world damaged by
//! arbitrary edits (optionally with a recomputed payload hash), restored into a world:
//! never a panic; accepted only with a valid header and a sound state that stays sound
//! when stepped; refused without changing anything
//! (`carom::props::snapshot_bytes_properties`, `snapshot_edit_properties`).
#![no_main]

use carom::props::{is_known_finding, snapshot_bytes_properties, snapshot_edit_properties};
use carom_fuzz::SnapshotInput;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: SnapshotInput| {
    let result = match &input {
        SnapshotInput::Bytes { steps, bytes } => snapshot_bytes_properties(bytes, *steps),
        SnapshotInput::Edited {
            steps,
            edits,
            reseal,
        } => {
            let edits: Vec<_> = edits.iter().map(|e| e.edit()).collect();
            snapshot_edit_properties(*steps, &edits, *reseal)
        }
    };
    if let Err(v) = result {
        // Known findings (each with an ignored test in tests/world_fuzz.rs) end the input.
        assert!(is_known_finding(&v), "{v:?}");
    }
});
