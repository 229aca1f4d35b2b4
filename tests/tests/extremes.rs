//! The numerical extremes: every kind of scene scaled by 10^±7 to 10^±20
//! and/or moved far from the origin (1e4 and 1e7 scene sizes in f32, 1e15
//! too in f64), with every kind of ray: every registered accelerator still
//! equals brute force bit for bit.

use accel_core::Real;
use accel_tests::config::config;
use accel_tests::scene::SceneSpec;
use accel_tests::strategies::{boxes, extreme_placement, far_offsets, rays_and_windows, scene};
use accel_tests::suite::check_case;
use accel_tests::{BoxSpec, RaySpec, WindowSpec};
use proptest::prelude::*;

fn run<T: Real>(
    scene: &SceneSpec,
    rays: &[(RaySpec, WindowSpec)],
    regions: &[BoxSpec],
) -> Result<(), TestCaseError> {
    check_case::<T>(scene, rays, regions).map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config("extremes_f32", 3000))]
    #[test]
    fn extremes_f32(
        scene in scene(extreme_placement(far_offsets::<f32>())),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..6),
    ) {
        run::<f32>(&scene, &rays, &regions)?;
    }
}

proptest! {
    #![proptest_config(config("extremes_f64", 3000))]
    #[test]
    fn extremes_f64(
        scene in scene(extreme_placement(far_offsets::<f64>())),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..6),
    ) {
        run::<f64>(&scene, &rays, &regions)?;
    }
}
