//! Builds an octree of nested grids over a scene and traces rays
//! through it, printing the throughput and the work per ray: a small driver
//! for profilers
//! (`valgrind --tool=callgrind target/release/examples/trace_octree teapot_in_stadium`).
//!
//! Usage: `trace_octree [SCENE] [camera|random] [RAYS]`, SCENE a generated
//! scene (sphere_100k, soup_100k, terrain_1m, teapot_in_stadium,
//! flat_field; default teapot_in_stadium) or a `.gltf`/`.glb` file, seen as
//! `render` sees it.

use accel_octree::Octree;
use accel_scenes::TraceDriver;
use std::time::Instant;

fn main() {
    let run =
        TraceDriver::from_args(std::env::args().skip(1), "teapot_in_stadium").unwrap_or_else(|e| {
            eprintln!("{e}");
            std::process::exit(2);
        });
    let start = Instant::now();
    let tree = Octree::new(&run.mesh).expect("octree builds");
    println!(
        "built in {:.1} ms: {} grids",
        start.elapsed().as_secs_f64() * 1e3,
        tree.grid_count()
    );
    run.report(&tree, &run.rays());
}
