//! The triangle-test dial keeps the equivalence invariant: every registered
//! accelerator built over a [`MollerTrumboreMesh`] answers bit for bit as
//! brute force over the same wrapper, in f32 and f64, at ordinary and
//! extreme scales and offsets. This is what the
//! Möller–Trumbore guard (a hit's point must lie near the triangle) is for:
//! a hit reported off the triangle could be found by brute force and missed
//! by a traversal.

use accel_core::{MollerTrumboreMesh, Real};
use accel_tests::config::config;
use accel_tests::scene::{Scene, SceneSpec};
use accel_tests::strategies::{
    boxes, extreme_placement, far_offsets, ordinary_placement, rays_and_windows, scene,
};
use accel_tests::suite::check_specs;
use accel_tests::{BoxSpec, Landmarks, RaySpec, WindowSpec};
use proptest::prelude::*;

fn run<T: Real>(
    scene: &SceneSpec,
    rays: &[(RaySpec, WindowSpec)],
    regions: &[BoxSpec],
) -> Result<(), TestCaseError> {
    let Scene::Mesh(mesh) = scene.build::<T>() else {
        return Ok(());
    };
    let landmarks = Landmarks::of_mesh(&mesh);
    // The registry's builders borrow their primitives for 'static; one
    // small mesh per case is leaked for that.
    let mesh: &'static _ = Box::leak(Box::new(mesh));
    let wrapped = MollerTrumboreMesh::new(mesh);
    check_specs(&wrapped, landmarks, rays, regions).map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config("moller_trumbore_f32", 600))]
    #[test]
    fn moller_trumbore_equivalence_f32(
        scene in scene(ordinary_placement()),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..3),
    ) {
        run::<f32>(&scene, &rays, &regions)?;
    }
}

proptest! {
    #![proptest_config(config("moller_trumbore_f64", 600))]
    #[test]
    fn moller_trumbore_equivalence_f64(
        scene in scene(ordinary_placement()),
        rays in rays_and_windows(24),
        regions in prop::collection::vec(boxes(), 0..3),
    ) {
        run::<f64>(&scene, &rays, &regions)?;
    }
}

proptest! {
    #![proptest_config(config("moller_trumbore_extremes_f32", 300))]
    #[test]
    fn moller_trumbore_extremes_f32(
        scene in scene(extreme_placement(far_offsets::<f32>())),
        rays in rays_and_windows(24),
    ) {
        run::<f32>(&scene, &rays, &[])?;
    }
}

proptest! {
    #![proptest_config(config("moller_trumbore_extremes_f64", 300))]
    #[test]
    fn moller_trumbore_extremes_f64(
        scene in scene(extreme_placement(far_offsets::<f64>())),
        rays in rays_and_windows(24),
    ) {
        run::<f64>(&scene, &rays, &[])?;
    }
}
