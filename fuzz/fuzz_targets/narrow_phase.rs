//! Two arbitrary shapes of any kind (hulls from arbitrary points) at two arbitrary poses:
//! GJK distance, EPA penetration, the one-shot separation and the contact manifold must
//! satisfy their properties
//! (`carom::props`), which also check that invalid poses and margins are rejected.
#![no_main]

use carom::props::{
    distance_properties, manifold_properties, penetration_properties, separation_properties,
};
use carom_fuzz::{PairInput, TOLERANCE_UNIT};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: PairInput| {
    let (Some(a), Some(b)) = (input.a.build(), input.b.build()) else {
        return;
    };
    let (a, b) = (a.shape(), b.shape());
    let (pose_a, pose_b) = (input.pose_a.iso(), input.pose_b.iso());
    let margin = input.margin.value(TOLERANCE_UNIT);
    assert_eq!(distance_properties(&a, &pose_a, &b, &pose_b), Ok(()));
    assert_eq!(penetration_properties(&a, &pose_a, &b, &pose_b), Ok(()));
    assert_eq!(separation_properties(&a, &pose_a, &b, &pose_b), Ok(()));
    assert_eq!(
        manifold_properties(&a, &pose_a, &b, &pose_b, margin),
        Ok(())
    );
});
