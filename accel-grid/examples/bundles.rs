//! Traces a scene's camera rays one at a time and in 8 × 8 tiles through
//! the grid's bundle query, alternating rounds, and prints both
//! throughputs on this thread (a driver for profilers and for quick
//! comparisons; `render bench` is the benchmark).
//!
//! Usage: `bundles [SCENE] [camera|random] [RAYS] [RAY FILE]` (as `trace`;
//! a ray file written by `render bench --write-rays` replaces the rays).

use accel_core::{Accelerator, Hit, QueryError, Ray};
use accel_grid::Grid;
use accel_scenes::TraceDriver;
use std::time::Instant;

/// The rays of a `side × side` image, reordered into 8 × 8 tiles.
fn tiled(rays: &[Ray<f32>], side: usize) -> Vec<Ray<f32>> {
    let mut out = Vec::with_capacity(rays.len());
    for ty in (0..side).step_by(8) {
        for tx in (0..side).step_by(8) {
            for y in ty..(ty + 8).min(side) {
                for x in tx..(tx + 8).min(side) {
                    out.push(rays[y * side + x]);
                }
            }
        }
    }
    out
}

fn main() {
    let run = TraceDriver::from_args(std::env::args().skip(1), "sphere_100k").unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2);
    });
    let grid = Grid::new(&run.mesh).expect("grid builds");
    // A ray file as fourth argument replaces the generated rays.
    let rays = match std::env::args().nth(4) {
        Some(f) => accel_scenes::rayfile::read(std::path::Path::new(&f)).expect("ray file"),
        None => run.rays(),
    };
    let side = (rays.len() as f64).sqrt() as usize;
    let rays = if side * side == rays.len() {
        tiled(&rays, side)
    } else {
        rays
    };
    let mut out: Vec<Result<Option<Hit<f32>>, QueryError>> = vec![Ok(None); rays.len()];
    let (mut single, mut bundled) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..5 {
        let start = Instant::now();
        for (r, o) in rays.iter().zip(out.iter_mut()) {
            *o = grid.intersect(r);
        }
        single = single.min(start.elapsed().as_secs_f64());
        let start = Instant::now();
        for (r, o) in rays.chunks(64).zip(out.chunks_mut(64)) {
            grid.intersect_bundle(r, o);
        }
        bundled = bundled.min(start.elapsed().as_secs_f64());
    }
    let n = rays.len() as f64;
    println!(
        "{} rays: single {:.3} Mrays/s, bundles {:.3} Mrays/s ({:.2}x), fastest of 5",
        rays.len(),
        n / single / 1e6,
        n / bundled / 1e6,
        single / bundled
    );
}
