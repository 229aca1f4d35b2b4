//! Strategies for the watertightness suite.

use crate::scene::Placement;
use accel_core::Real;
use accel_scenes::aimed::Aim;
pub use accel_scenes::strategies::aim_in;
use proptest::prelude::*;

/// Placements under which a unit mesh stays well-conditioned in `T` (its
/// triangles keep their shape after rounding): any scale, and offsets up to
/// 1e4 scene sizes in f32, 1e10 in f64.
pub fn watertight_placement<T: Real>() -> BoxedStrategy<Placement> {
    let offsets = if size_of::<T>() == 4 {
        vec![0.0, 0.0, 100.0, 1e4]
    } else {
        vec![0.0, 0.0, 1e4, 1e7, 1e10]
    };
    (
        prop_oneof![3 => Just(0i32), 1 => prop::sample::select(vec![-20, -7, 7, 20])],
        prop::sample::select(offsets),
    )
        .prop_map(|(scale_exp, offset)| Placement { scale_exp, offset })
        .boxed()
}

/// A ray aimed at a vertex or at a point of an edge (its ends included).
pub fn aim() -> BoxedStrategy<Aim> {
    aim_in(super::INDEX_RANGE)
}
