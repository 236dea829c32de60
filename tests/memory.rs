//! Memory per body and per contact: the figures the README documents, checked here.
//! A world is plain data: its size is a fixed part plus these per-slot costs.

use carom::World;

const B1: usize = 16;
const B2: usize = 32;
const C1: usize = 64;
const C2: usize = 128;

/// Bytes one more body slot costs (the body, its generation, island and solver entries,
/// and in the broad phase two tree nodes of 40 bytes and the index of its leaf),
/// measured as a difference of world sizes.
fn per_body() -> usize {
    (core::mem::size_of::<World<'static, B2, C1, 8>>()
        - core::mem::size_of::<World<'static, B1, C1, 8>>())
        / (B2 - B1)
}

/// Bytes one more contact slot costs (the contact, its double buffer, a candidate pair,
/// the solver plan's slot byte).
fn per_contact() -> usize {
    (core::mem::size_of::<World<'static, B1, C2, 8>>()
        - core::mem::size_of::<World<'static, B1, C1, 8>>())
        / (C2 - C1)
}

#[test]
fn per_slot_costs_match_the_readme() {
    let (b, c) = (per_body(), per_contact());
    eprintln!("per body {b} B, per contact {c} B");
    // README, "Capacity": 680 bytes per body and 1113 per contact on 64-bit hosts. A
    // change of layout shows here first: update the README with it.
    assert_eq!(b, 680, "per body");
    assert_eq!(c, 1113, "per contact");
    // The fixed part is small: an empty-capacity world is under 6 KiB (mostly the one
    // spare group of four solver lanes).
    assert!(core::mem::size_of::<World<'static, 0, 0, 0>>() < 6 * 1024);
}
