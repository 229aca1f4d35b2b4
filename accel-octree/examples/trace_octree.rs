//! Builds an octree of nested grids over a generated scene and traces rays
//! through it, printing the throughput and the work per ray: a small driver
//! for profilers
//! (`valgrind --tool=callgrind target/release/examples/trace_octree teapot_in_stadium`).
//!
//! Usage: `trace_octree [SCENE] [camera|random] [RAYS]`, SCENE one of
//! sphere_100k, soup_100k, terrain_1m, teapot_in_stadium (default
//! teapot_in_stadium).

use accel_core::scenes::{GeneratedScene, random_rays};
use accel_core::{Accelerator, Ray, TraversalCounters, TriangleMesh};
use accel_octree::Octree;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("teapot_in_stadium", String::as_str);
    let kind = args.get(2).map_or("camera", String::as_str);
    let count: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(65_536);
    let Some(scene) = GeneratedScene::from_name(name) else {
        eprintln!(
            "unknown scene {name}; expected one of sphere_100k, soup_100k, terrain_1m, teapot_in_stadium"
        );
        std::process::exit(2);
    };
    let mesh: TriangleMesh<f32> = scene.mesh().cast().expect("fits f32");
    let start = Instant::now();
    let tree = Octree::new(&mesh).expect("octree builds");
    println!(
        "built in {:.1} ms: {} grids",
        start.elapsed().as_secs_f64() * 1e3,
        tree.grid_count()
    );
    let rays: Vec<Ray<f32>> = if kind == "random" {
        random_rays(&mesh.bounds().cast(), count, 7)
    } else {
        let side = (count as f64).sqrt() as u32;
        scene.camera().rays(side, side)
    };
    let start = Instant::now();
    let hits = rays
        .iter()
        .filter(|r| tree.intersect(r).unwrap().is_some())
        .count();
    let secs = start.elapsed().as_secs_f64();
    println!(
        "{} {kind} rays: {hits} hits, {:.3} s, {:.3} Mrays/s (one thread)",
        rays.len(),
        secs,
        rays.len() as f64 / secs / 1e6
    );
    let mut work = TraversalCounters::default();
    for r in &rays {
        tree.intersect_counted(r, &mut work).unwrap();
    }
    let n = rays.len().max(1) as f64;
    println!(
        "per ray: {:.1} cells visited, {:.1} triangle tests",
        work.nodes as f64 / n,
        work.prims as f64 / n
    );
}
