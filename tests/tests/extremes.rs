//! The numerical extremes: every kind of scene scaled by 10^±7 to 10^±20
//! and/or moved far from the origin (1e4 and 1e7 scene sizes in f32, 1e15
//! too in f64), with every kind of ray: every registered accelerator still
//! equals brute force bit for bit. Then the limits: every kind of scene
//! stretched to the largest finite coordinates of each precision
//! ([`Limit`]): equal to brute force, or refused by every accelerator with
//! the same `OutOfRange`.

use accel_tests::config::config;
use accel_tests::limits::{Limit, check_case_at_limit};
use accel_tests::scene::Placement;
use accel_tests::strategies::{boxes, extreme_placement, far_offsets, rays_and_windows, scene};
use accel_tests::suite::check_case;
use proptest::prelude::*;

proptest! {
    #![proptest_config(config("extremes_f32", 3000))]
    #[test]
    fn extremes_f32(
        scene in scene(extreme_placement(far_offsets::<f32>())),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..6),
    ) {
        check_case::<f32>(&scene, &rays, &regions).map_err(TestCaseError::fail)?;
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
        check_case::<f64>(&scene, &rays, &regions).map_err(TestCaseError::fail)?;
    }
}

/// The stretches of [`Limit`] the limit suites draw from: half-widths from
/// `T::MAX` and twice the limit (refused) through exactly the limit down to
/// a thousandth and a billionth of it, centered or against `+T::LIMIT`.
fn limits() -> impl Strategy<Value = Limit> {
    (
        prop::sample::select(vec![16.0, 2.0, 1.0, 0.999, 0.5, 1e-3, 1e-9]),
        any::<bool>(),
    )
        .prop_map(|(half_width, at_top)| Limit { half_width, at_top })
}

proptest! {
    #![proptest_config(config("limits_f32", 1000))]
    /// See: issue 32, item 1 (a glTF at ±3e38 panicked the grid and octree).
    #[test]
    fn limits_f32(
        scene in scene(Just(Placement::IDENTITY).boxed()),
        limit in limits(),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..6),
    ) {
        check_case_at_limit::<f32>(&scene, &limit, &rays, &regions).map_err(TestCaseError::fail)?;
    }
}

proptest! {
    #![proptest_config(config("limits_f64", 1000))]
    /// See: issue 32, item 1, in `f64` near `f64::MAX`.
    #[test]
    fn limits_f64(
        scene in scene(Just(Placement::IDENTITY).boxed()),
        limit in limits(),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..6),
    ) {
        check_case_at_limit::<f64>(&scene, &limit, &rays, &regions).map_err(TestCaseError::fail)?;
    }
}
