//! Every registered accelerator equals brute force, bit for bit, on every
//! kind of scene (ordinary placements) and every kind of ray, window and
//! region box, in f32 and f64.

use accel_tests::config::config;
use accel_tests::strategies::{boxes, ordinary_placement, rays_and_windows, scene};
use accel_tests::suite::check_case;
use proptest::prelude::*;

proptest! {
    #![proptest_config(config("equivalence_f32", 3000))]
    #[test]
    fn equivalence_f32(
        scene in scene(ordinary_placement()),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..6),
    ) {
        check_case::<f32>(&scene, &rays, &regions).map_err(TestCaseError::fail)?;
    }
}

proptest! {
    #![proptest_config(config("equivalence_f64", 3000))]
    #[test]
    fn equivalence_f64(
        scene in scene(ordinary_placement()),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..6),
    ) {
        check_case::<f64>(&scene, &rays, &regions).map_err(TestCaseError::fail)?;
    }
}
