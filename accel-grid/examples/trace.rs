//! Builds a grid over a generated scene and traces rays through it, printing
//! the grid's statistics and the throughput: a small driver for profilers
//! (`valgrind --tool=callgrind target/release/examples/trace terrain_1m camera`).
//!
//! Usage: `trace [SCENE] [camera|random] [RAYS]`, SCENE one of sphere_100k,
//! soup_100k, terrain_1m, teapot_in_stadium (default sphere_100k).

use accel_core::scenes::{GeneratedScene, random_rays};
use accel_core::{Accelerator, Ray, TraversalCounters, TriangleMesh};
use accel_grid::Grid;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("sphere_100k", String::as_str);
    let kind = args.get(2).map_or("camera", String::as_str);
    let count: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(65_536);
    let Some(scene) = GeneratedScene::from_name(name) else {
        eprintln!(
            "unknown scene {name}; expected one of sphere_100k, soup_100k, terrain_1m, teapot_in_stadium"
        );
        std::process::exit(2);
    };
    let mesh: TriangleMesh<f32> = scene.mesh().cast().expect("fits f32");
    let grid = Grid::new(&mesh).expect("grid builds");
    println!("{}", grid.stats());
    let rays: Vec<Ray<f32>> = if kind == "random" {
        random_rays(&mesh.bounds().cast(), count, 7)
    } else {
        let side = (count as f64).sqrt() as u32;
        scene.camera().rays(side, side)
    };
    let start = Instant::now();
    let hits = rays
        .iter()
        .filter(|r| grid.intersect(r).unwrap().is_some())
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
        grid.intersect_counted(r, &mut work).unwrap();
    }
    let n = rays.len().max(1) as f64;
    println!(
        "per ray: {:.1} cells visited, {:.1} triangle tests",
        work.nodes as f64 / n,
        work.prims as f64 / n
    );
}
