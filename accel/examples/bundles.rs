//! Traces a scene's rays one at a time and in bundles of 64 (an image's
//! rays by 8 × 8 tiles, in Z order within a tile), through any accelerator, and prints both
//! throughputs on this thread for the nearest-hit and the any-hit query (a
//! driver for profilers and for quick comparisons; `render bench` is the
//! benchmark). Bundle answers are checked against the single ones
//! ([`accel_core::check_bundle`]).
//!
//! Usage: `bundles [SCENE] [camera|random] [RAYS] [ACCEL] [RAY FILE]`
//! (scene, ray kind and count as accel-grid's `trace`: a generated scene or
//! a `.gltf`/`.glb` file, seen as `render` sees it; `ACCEL` as
//! `render --accel` takes it, default `grid`; a ray file written by
//! `render bench --write-rays` replaces the rays). The environment variable
//! `BUNDLES_ONLY=single|bundles` runs one of the two (for profilers).

use accel::AccelConfig;
use accel_core::{Accelerator, Hit, QueryError, Ray};
use accel_scenes::TraceDriver;
use accel_scenes::camera::by_tiles;
use std::time::Instant;

/// Bundle size.
const BUNDLE: usize = 64;

/// The fastest of five rounds of `pass`, in seconds (not inlined, so that
/// a profiler can count it alone).
#[inline(never)]
fn fastest(mut pass: impl FnMut()) -> f64 {
    (0..5)
        .map(|_| {
            let start = Instant::now();
            pass();
            start.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Exits with `message`.
fn fail(message: impl std::fmt::Display) -> ! {
    eprintln!("{message}");
    std::process::exit(2);
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let run = TraceDriver::from_args(args.iter().take(3).cloned(), "sphere_100k")
        .unwrap_or_else(|e| fail(e));
    let config: AccelConfig = args
        .get(3)
        .map_or("grid", String::as_str)
        .parse()
        .unwrap_or_else(|e| fail(e));
    let accel = accel::build_config(&config, &run.mesh).unwrap_or_else(|e| fail(e));
    let rays = match args.get(4) {
        Some(f) => accel_scenes::rayfile::read(std::path::Path::new(f)).unwrap_or_else(|e| fail(e)),
        None => run.rays(),
    };
    // A square set is an image: traced by tiles.
    let side = (rays.len() as f64).sqrt() as usize;
    let rays: Vec<Ray<f32>> = if side * side == rays.len() {
        by_tiles(&rays, side, 8)
    } else {
        rays
    };
    let only = std::env::var("BUNDLES_ONLY").unwrap_or_default();
    let mut nearest: Vec<Result<Option<Hit<f32>>, QueryError>> = vec![Ok(None); rays.len()];
    let mut nearest_bundled = nearest.clone();
    let mut any: Vec<Result<bool, QueryError>> = vec![Ok(false); rays.len()];
    let mut any_bundled = any.clone();
    let t_single = if only == "bundles" {
        f64::NAN
    } else {
        fastest(|| {
            for ((r, o), a) in rays.iter().zip(&mut nearest).zip(&mut any) {
                *o = accel.intersect(r);
                *a = accel.occluded(r);
            }
        })
    };
    let t_bundled = if only == "single" {
        f64::NAN
    } else {
        fastest(|| {
            for ((r, o), a) in rays
                .chunks(BUNDLE)
                .zip(nearest_bundled.chunks_mut(BUNDLE))
                .zip(any_bundled.chunks_mut(BUNDLE))
            {
                accel.intersect_bundle(r, o);
                accel.occluded_bundle(r, a);
            }
        })
    };
    if only.is_empty()
        && let Some(difference) = accel_core::check_bundle(&accel, &rays)
    {
        fail(format!(
            "bundle answers differ from single ones: {difference}"
        ));
    }
    let n = rays.len() as f64;
    println!(
        "{} on {} rays, nearest + any hit: single {:.3} Mrays/s, bundles {:.3} Mrays/s ({:.2}x), fastest of 5",
        config.label(),
        rays.len(),
        n / t_single / 1e6,
        n / t_bundled / 1e6,
        t_single / t_bundled
    );
}
