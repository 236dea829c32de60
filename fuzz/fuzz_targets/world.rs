//! An arbitrary call sequence on a small world (bodies of every kind and shape with raw
//! values, removals and stale handles, setters, configurations, steps, queries, snapshot
//! round trips and damaged restores): `carom::props::world_ops_properties` must hold:
//! no panic, finite state, errors change nothing, handles follow the pool model.
#![no_main]

use carom::props::{is_known_finding, world_ops_properties};
use carom_fuzz::{world_ops, OpInput};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|ops: Vec<OpInput>| {
    let ops = world_ops(&ops);
    if let Err(v) = world_ops_properties(&ops) {
        // Known findings (each with an ignored test in tests/world_fuzz.rs) end the input.
        assert!(is_known_finding(&v), "{v:?}");
    }
});
