//! Two arbitrary shapes under arbitrary motions: the time of impact satisfies its
//! properties (`carom::props::toi_properties`): no hit missed, no tunnelling, bounded
//! work, invalid motions rejected.
#![no_main]

use carom::props::toi_properties;
use carom_fuzz::{ToiInput, TIME_UNIT, TOLERANCE_UNIT};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: ToiInput| {
    let (Some(a), Some(b)) = (input.a.build(), input.b.build()) else {
        return;
    };
    let (a, b) = (a.shape(), b.shape());
    let (motion_a, motion_b) = (input.motion_a.motion(), input.motion_b.motion());
    let t_max = input.t_max.value(TIME_UNIT);
    let tolerance = input.tolerance.value(TOLERANCE_UNIT);
    assert_eq!(
        toi_properties(&a, &motion_a, &b, &motion_b, t_max, tolerance),
        Ok(())
    );
});
