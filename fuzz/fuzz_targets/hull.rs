//! An arbitrary point cloud (duplicates, coplanar and collinear sets, NaN, huge and tiny
//! coordinates): building its hull never panics, a hull that builds is valid, and building
//! it in place (`ConvexHull::rebuild`) gives the same answer
//! (`carom::props::hull_properties`).
#![no_main]

use carom::props::hull_properties;
use carom_fuzz::{points, Vec3Input};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|cloud: Vec<Vec3Input>| {
    assert_eq!(hull_properties(&points(&cloud)), Ok(()));
});
