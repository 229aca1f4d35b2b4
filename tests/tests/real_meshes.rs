//! The same assertions on real meshes: the glTF files of `../shared/scenes`
//! (or `$ACCEL_SCENES`), skipped with a note when the folder is absent and `$ACCEL_SCENES` unset, an error when it is set and empty. Per
//! file and precision: a few thousand rays of every kind (camera, random,
//! aimed at vertices, edges, cell faces, edges and corners, starting on the
//! surface, narrow windows), region boxes, and, for closed meshes, rays aimed
//! at shared edges and vertices, which must not leak.

use accel_core::{BruteForce, Ray, Real, TriangleMesh};
use accel_scenes::gltf::{load, shared_scene_files_for_test};
use accel_scenes::{Camera, random_rays};
use accel_tests::Landmarks;
use accel_tests::assertions::{Expected, check_accelerator};
use accel_tests::registry::accelerators;
use accel_tests::strategies::{aim_in, boxes_in, ray_in, window};
use accel_tests::suite::resolve;
use accel_tests::watertight::{ClosedParts, assert_no_leaks};
use proptest::strategy::{Strategy, ValueTree};
use proptest::test_runner::TestRunner;

/// Rays aimed by the property suites' strategies, per file and precision.
const AIMED_RAYS: usize = 1200;
/// Camera rays: a square image of this side.
const CAMERA_SIDE: u32 = 24;
/// Random rays from around the mesh.
const RANDOM_RAYS: usize = 300;
/// Region boxes.
const BOXES: usize = 40;
/// Watertightness targets on closed meshes.
const AIMS: usize = 600;

/// A deterministic sample of a strategy.
fn sample<S: Strategy>(s: S, runner: &mut TestRunner) -> S::Value {
    s.new_tree(runner)
        .expect("strategies never reject")
        .current()
}

fn check_mesh<T: Real>(name: &str, mesh: &TriangleMesh<T>) -> Result<String, String> {
    let mut runner = TestRunner::deterministic();
    let n = mesh.positions().len().max(mesh.triangle_count());
    let specs = sample(
        proptest::collection::vec((ray_in(n), window()), AIMED_RAYS),
        &mut runner,
    );
    let box_specs = sample(proptest::collection::vec(boxes_in(n), BOXES), &mut runner);
    let resolved = resolve(mesh, Landmarks::of_mesh(mesh), &specs, &box_specs)?;
    let (mut rays, regions) = (resolved.rays, resolved.regions);
    let b = mesh.bounds().cast::<f64>();
    let camera = Camera::frame(&b, Camera::DEFAULT_SIDE, accel_scenes::Z_UP);
    rays.extend(camera.rays::<T>(CAMERA_SIDE, CAMERA_SIDE));
    rays.extend(random_rays::<T>(&b, RANDOM_RAYS, 0x5eed));

    let brute = BruteForce::new(mesh).map_err(|e| e.to_string())?;
    let expected = Expected::compute(&brute, &rays, &regions)?;
    // Brute force is the reference; on meshes this large it is not also
    // checked against itself.
    for entry in accelerators::<T, TriangleMesh<T>>()
        .iter()
        .filter(|e| e.name != "brute")
    {
        let acc = (entry.build)(mesh).map_err(|e| format!("{name}: {}: {e}", entry.name))?;
        check_accelerator(entry.name, &*acc, mesh, &rays, &regions, &expected)
            .map_err(|e| format!("{name}: {e}"))?;
    }
    let hits = expected.hits.iter().filter(|h| h.is_some()).count();
    let mut note = format!(
        "{name} ({}): {} rays ({hits} hit), {} boxes",
        T::NAME,
        rays.len(),
        regions.len()
    );
    match ClosedParts::closed(mesh) {
        Some(closed) => {
            let aims = sample(proptest::collection::vec(aim_in(n), AIMS), &mut runner);
            let aimed: Vec<Ray<T>> = aims.iter().filter_map(|a| closed.ray(a)).collect();
            assert_no_leaks(mesh, &aimed).map_err(|e| format!("{name}: {e}"))?;
            note += &format!(
                ", closed: {} rays at shared edges and vertices, no leak",
                aimed.len()
            );
        }
        None => note += ", not closed (no watertightness check)",
    }
    Ok(note)
}

fn check_all_files<T: Real>() {
    let Some(files) = shared_scene_files_for_test() else {
        return;
    };
    for path in files {
        let name = path
            .file_name()
            .map_or_else(String::new, |f| f.to_string_lossy().into_owned());
        let scene = load(&path).unwrap_or_else(|e| panic!("{e}"));
        let mesh = scene
            .mesh
            .cast::<T>()
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        match check_mesh(&name, &mesh) {
            Ok(note) => eprintln!("{note}"),
            Err(e) => panic!("{e}"),
        }
    }
}

#[test]
fn real_meshes_f32() {
    check_all_files::<f32>();
}

#[test]
fn real_meshes_f64() {
    check_all_files::<f64>();
}
