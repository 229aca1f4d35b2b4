//! Uniform grid: build throughput (triangles/s) and nearest-hit and any-hit
//! throughput (rays/s, one thread and all threads) on the generated scenes and
//! on `../shared/scenes/*.glb` when present, with camera and random rays.
//!
//! `cargo bench -p accel-grid` runs everything; criterion's filter narrows it,
//! e.g. `cargo bench -p accel-grid -- terrain_1m/build`.

use accel_core::{Accelerator, Ray};
use accel_grid::Grid;
use accel_scenes::gltf::{BenchScene, bench_scenes};
use accel_scenes::random_rays;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Camera image size for the coherent ray set (65,536 rays).
const CAMERA_SIDE: u32 = 256;
/// Number of random (incoherent) rays.
const RANDOM_RAYS: usize = 65_536;

fn scenes() -> Vec<BenchScene> {
    bench_scenes(|_| true)
}

/// An evenly strided subset of `rays` that one thread traces in about
/// `budget`: a structure that is slow on a scene (the grid on the teapot in a
/// stadium) is measured on fewer rays of the same distribution instead of for
/// minutes. Rays per second are unaffected.
fn calibrated<A: Accelerator<f32>>(
    accel: &A,
    rays: &[Ray<f32>],
    budget: Duration,
) -> Vec<Ray<f32>> {
    let stride = (rays.len() / 256).max(1);
    let probe: Vec<Ray<f32>> = rays.iter().step_by(stride).copied().collect();
    let start = Instant::now();
    for r in &probe {
        std::hint::black_box(accel.intersect(r).unwrap());
    }
    let per_ray = start.elapsed().as_secs_f64() / probe.len() as f64;
    let n = ((budget.as_secs_f64() / per_ray.max(1e-12)) as usize).clamp(probe.len(), rays.len());
    rays.iter().step_by(rays.len() / n).copied().collect()
}

fn rays_per_second<A: Accelerator<f32>>(
    c: &mut Criterion,
    group: &str,
    accel: &A,
    rays: &[Ray<f32>],
) {
    let rays = &calibrated(accel, rays, Duration::from_millis(200))[..];
    let mut g = c.benchmark_group(group);
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function("nearest/1-thread", |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| accel.intersect(r).unwrap().is_some())
                .count()
        });
    });
    g.bench_function("nearest/all-threads", |b| {
        b.iter(|| {
            rays.par_iter()
                .filter(|r| accel.intersect(r).unwrap().is_some())
                .count()
        });
    });
    g.bench_function("any-hit/1-thread", |b| {
        b.iter(|| rays.iter().filter(|r| accel.occluded(r).unwrap()).count());
    });
    g.bench_function("any-hit/all-threads", |b| {
        b.iter(|| {
            rays.par_iter()
                .filter(|r| accel.occluded(r).unwrap())
                .count()
        });
    });
    g.finish();
}

fn bench(c: &mut Criterion) {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    for scene in scenes() {
        let tris = scene.mesh.triangle_count() as u64;
        let mut g = c.benchmark_group(format!("{}/build", scene.name));
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(3));
        g.throughput(Throughput::Elements(tris));
        g.bench_function(BenchmarkId::from_parameter("1-thread"), |b| {
            b.iter(|| one.install(|| Grid::new(&scene.mesh).unwrap().stats().references));
        });
        g.bench_function(BenchmarkId::from_parameter("all-threads"), |b| {
            b.iter(|| Grid::new(&scene.mesh).unwrap().stats().references);
        });
        g.finish();

        let grid = Grid::new(&scene.mesh).expect("grid builds");
        let camera_rays = scene.camera.rays::<f32>(CAMERA_SIDE, CAMERA_SIDE);
        rays_per_second(c, &format!("{}/camera", scene.name), &grid, &camera_rays);
        let random = random_rays::<f32>(&scene.mesh.bounds().cast(), RANDOM_RAYS, 7);
        rays_per_second(c, &format!("{}/random", scene.name), &grid, &random);
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
