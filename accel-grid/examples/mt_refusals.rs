//! How often the Möller–Trumbore test refuses a hit the watertight test
//! makes: for each generated scene (the teapot in a stadium excepted: the
//! grid is too slow there) and each ray set, the share of the watertight
//! nearest hits whose triangle `intersect_triangle_mt` does not hit. Those
//! are rays near edges (Möller–Trumbore's rounded barycentrics) and rays
//! where its `t` is too ill-conditioned for its guard:
//! `cargo run --release -p accel-grid --example mt_refusals`.

use accel_core::moller_trumbore::intersect_triangle_mt;
use accel_core::{Accelerator, PreparedRay, Ray, Real, TriangleMesh};
use accel_grid::Grid;
use accel_scenes::{GeneratedScene, random_rays};

fn refusals<T: Real>(mesh: &TriangleMesh<T>, rays: &[Ray<T>], label: &str) {
    let grid = Grid::new(mesh).expect("grid builds");
    let (mut hits, mut refused) = (0usize, 0usize);
    for ray in rays {
        let Some(h) = grid.intersect(ray).expect("valid ray") else {
            continue;
        };
        hits += 1;
        let [p0, p1, p2] = mesh.triangle(h.prim as usize);
        let prepared = PreparedRay::new(*ray);
        if intersect_triangle_mt(&prepared, p0, p1, p2, T::INFINITY).is_none() {
            refused += 1;
        }
    }
    println!(
        "{label:>28} {:>3}: {refused:>4} of {hits:>5} watertight hits refused ({:.3}%)",
        T::NAME,
        100.0 * refused as f64 / hits.max(1) as f64
    );
}

fn main() {
    for scene in GeneratedScene::ALL {
        if scene == GeneratedScene::TeapotInStadium {
            continue;
        }
        let mesh = scene.mesh();
        let m32: TriangleMesh<f32> = mesh.cast().expect("fits f32");
        let camera = format!("{} camera", scene.name());
        let random = format!("{} random", scene.name());
        refusals(&m32, &scene.camera().rays(128, 128), &camera);
        refusals(&m32, &random_rays(&mesh.bounds(), 16_384, 3), &random);
        refusals(&mesh, &scene.camera().rays(128, 128), &camera);
        refusals(&mesh, &random_rays(&mesh.bounds(), 16_384, 3), &random);
    }
}
