//! Builds a grid over a scene and traces rays through it, printing
//! the grid's statistics and the throughput: a small driver for profilers
//! (`valgrind --tool=callgrind target/release/examples/trace terrain_1m camera`).
//!
//! Usage: `trace [SCENE] [camera|random] [RAYS]`, SCENE a generated scene
//! (sphere_100k, soup_100k, terrain_1m, teapot_in_stadium, flat_field;
//! default sphere_100k) or a `.gltf`/`.glb` file, seen as `render` sees it.

use accel_core::Accelerator;
use accel_grid::Grid;
use accel_scenes::TraceDriver;

fn main() {
    let run = TraceDriver::from_args(std::env::args().skip(1), "sphere_100k").unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2);
    });
    let grid = Grid::new(&run.mesh).expect("grid builds");
    println!("{}", grid.stats());
    run.report(&grid, &run.rays());
}
