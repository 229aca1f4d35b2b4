//! Watertightness: rays from outside closed meshes (tessellated spheres,
//! boxes, tori), aimed at shared edges and vertices, always hit, in every
//! registered accelerator and in brute force. Leaks are counted; zero is the
//! only pass. The same rays are checked for bit-for-bit equivalence.

use accel_core::{Ray, Real, TriangleMesh};
use accel_tests::Scene;
use accel_tests::config::config;
use accel_tests::scene::{Placement, SceneSpec, Shape};
use accel_tests::strategies::{aim, closed_shape, watertight_placement};
use accel_tests::suite::check_all;
use accel_tests::watertight::{Aim, ClosedParts, assert_no_leaks};
use proptest::prelude::*;

fn run<T: Real>(shape: Shape, place: Placement, aims: &[Aim]) -> Result<(), TestCaseError> {
    let Scene::Mesh(mesh) = SceneSpec::Closed(shape, place).build::<T>() else {
        unreachable!("closed shapes are meshes");
    };
    let closed = ClosedParts::closed(&mesh).ok_or_else(|| {
        TestCaseError::fail(format!(
            "{shape:?} at {place:?} is not closed in {}",
            T::NAME
        ))
    })?;
    let rays: Vec<Ray<T>> = aims.iter().filter_map(|a| closed.ray(a)).collect();
    assert_no_leaks::<T, TriangleMesh<T>>(&mesh, &rays).map_err(TestCaseError::fail)?;
    check_all(&mesh, &rays, &[]).map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(config("watertight_f32", 750))]
    #[test]
    fn watertight_f32(
        shape in closed_shape(false),
        place in watertight_placement::<f32>(),
        aims in prop::collection::vec(aim(), 1..32),
    ) {
        run::<f32>(shape, place, &aims)?;
    }
}

proptest! {
    #![proptest_config(config("watertight_f64", 750))]
    #[test]
    fn watertight_f64(
        shape in closed_shape(false),
        place in watertight_placement::<f64>(),
        aims in prop::collection::vec(aim(), 1..32),
    ) {
        run::<f64>(shape, place, &aims)?;
    }
}

/// The aiming itself works: on a well-shaped sphere almost every target
/// gives a ray (so the property above is not vacuous), and none leaks.
#[test]
fn aimed_rays_exist_and_hit_on_a_sphere() {
    let Scene::Mesh(mesh) =
        SceneSpec::Closed(Shape::Sphere(160), Placement::IDENTITY).build::<f64>()
    else {
        unreachable!()
    };
    let closed = ClosedParts::closed(&mesh).expect("the uv sphere is closed");
    let aims: Vec<Aim> = (0..closed.edge_count())
        .map(|e| Aim {
            target: accel_tests::watertight::Target::Edge(e, 0.5),
            jitter: [0.0; 3],
            distance_exp: 0,
        })
        .collect();
    let rays: Vec<Ray<f64>> = aims.iter().filter_map(|a| closed.ray(a)).collect();
    assert!(
        rays.len() * 10 >= aims.len() * 9,
        "{} of {} aims gave rays",
        rays.len(),
        aims.len()
    );
    assert_no_leaks(&mesh, &rays).unwrap();
}
