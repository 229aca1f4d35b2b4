//! Bundle queries (`intersect_bundle`, `occluded_bundle`) answer every ray
//! of a bundle as brute force answers it alone, bit for bit, for every
//! registered accelerator in f32 and f64: coherent tiles of camera-like
//! rays (some fanning across a zero direction component, so of mixed
//! signs, some with ±0 components), each ray with its own window. The
//! equivalence suite checks random bundles (its rays, as one bundle and in
//! bundles of 5) the same way.

use accel_tests::config::config;
use accel_tests::strategies::{coherent_tile, ordinary_placement, scene};
use accel_tests::suite::check_case;
use proptest::prelude::*;

proptest! {
    #![proptest_config(config("bundles_f32", 400))]
    #[test]
    fn coherent_bundles_f32(scene in scene(ordinary_placement()), tile in coherent_tile()) {
        check_case::<f32>(&scene, &tile, &[]).map_err(TestCaseError::fail)?;
    }
}

proptest! {
    #![proptest_config(config("bundles_f64", 400))]
    #[test]
    fn coherent_bundles_f64(scene in scene(ordinary_placement()), tile in coherent_tile()) {
        check_case::<f64>(&scene, &tile, &[]).map_err(TestCaseError::fail)?;
    }
}
