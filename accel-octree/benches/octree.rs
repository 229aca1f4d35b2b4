//! Octree against the uniform grid, side by side in one run: build time,
//! memory per triangle and nearest-hit and any-hit throughput (rays/s) on the
//! generated scenes (sphere, soup, terrain, teapot in a stadium) and on
//! `../shared/scenes/*.glb` when present, with camera and random rays.
//!
//! `cargo bench -p accel-octree` runs everything; criterion's filter narrows
//! the measurements (`-- teapot_in_stadium/camera`), and two variables narrow
//! the setup, which otherwise builds every scene:
//! - `ACCEL_BENCH_SCENES=teapot,sphere`: only scenes whose name contains one
//!   of the words;
//! - `ACCEL_BENCH_PRESETS=1`: also the octree presets (`classic`, `two_level`,
//!   `grid_root`), beside the default.
//!
//! Memory and shape are printed once per scene (criterion has no unit for
//! them), e.g. `teapot_in_stadium: grid 41.9 B/tri, octree 40.3 B/tri (0.96x)`.

use accel_core::{Accelerator, Ray};
use accel_grid::Grid;
use accel_octree::{Octree, OctreeParams};
use accel_scenes::gltf::{BenchScene, bench_scenes};
use accel_scenes::random_rays;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Camera image size for the coherent ray set (65,536 rays).
const CAMERA_SIDE: u32 = 256;
/// Number of random (incoherent) rays.
const RANDOM_RAYS: usize = 65_536;

/// Whether `name` passes `ACCEL_BENCH_SCENES` (all do when it is unset).
fn wanted(name: &str) -> bool {
    std::env::var("ACCEL_BENCH_SCENES").map_or(true, |list| {
        list.split(',')
            .map(str::trim)
            .any(|w| !w.is_empty() && name.contains(w))
    })
}

fn scenes() -> Vec<BenchScene> {
    bench_scenes(wanted)
}

/// The octree variants measured: the default, and the presets on request.
fn variants() -> Vec<(&'static str, OctreeParams)> {
    let mut v = vec![("octree", OctreeParams::default())];
    if std::env::var_os("ACCEL_BENCH_PRESETS").is_some() {
        v.push(("octree-classic", OctreeParams::classic()));
        v.push(("octree-two-level", OctreeParams::two_level()));
        v.push(("octree-grid-root", OctreeParams::grid_root()));
    }
    v
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

/// Nearest-hit and any-hit throughput of `accel` on `rays`, as
/// `{group}/{label}-nearest/1-thread` and so on.
fn rays_per_second<A: Accelerator<f32>>(
    c: &mut Criterion,
    group: &str,
    label: &str,
    accel: &A,
    rays: &[Ray<f32>],
) {
    let rays = &calibrated(accel, rays, Duration::from_millis(200))[..];
    let mut g = c.benchmark_group(group);
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function(format!("{label}-nearest/1-thread"), |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| accel.intersect(r).unwrap().is_some())
                .count()
        });
    });
    g.bench_function(format!("{label}-nearest/all-threads"), |b| {
        b.iter(|| {
            rays.par_iter()
                .filter(|r| accel.intersect(r).unwrap().is_some())
                .count()
        });
    });
    g.bench_function(format!("{label}-any-hit/1-thread"), |b| {
        b.iter(|| rays.iter().filter(|r| accel.occluded(r).unwrap()).count());
    });
    g.finish();
}

fn bench(c: &mut Criterion) {
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    for scene in scenes() {
        let mesh = &scene.mesh;
        let tris = mesh.triangle_count();
        let grid = Grid::new(mesh).expect("grid builds");
        let octrees: Vec<(&str, OctreeParams, Octree<'_, f32, _>)> = variants()
            .into_iter()
            .map(|(label, p)| {
                let o = Octree::with_params(mesh, &p).expect("octree builds");
                (label, p, o)
            })
            .collect();
        let grid_bytes = grid.stats().bytes_per_primitive();
        println!("{}: {tris} triangles; {}", scene.name, grid.stats());
        for (label, _, o) in &octrees {
            let per_tri = o.stats().bytes_per_primitive();
            println!(
                "{}: grid {grid_bytes:.1} B/tri, {label} {per_tri:.1} B/tri ({:.2}x); {}",
                scene.name,
                per_tri / grid_bytes,
                o.stats()
            );
        }

        let mut g = c.benchmark_group(format!("{}/build", scene.name));
        g.sample_size(10)
            .warm_up_time(Duration::from_millis(500))
            .measurement_time(Duration::from_secs(3));
        g.throughput(Throughput::Elements(tris as u64));
        g.bench_function(BenchmarkId::new("grid", "1-thread"), |b| {
            b.iter(|| one.install(|| Grid::new(mesh).unwrap().stats().references));
        });
        for (label, p, _) in &octrees {
            g.bench_function(BenchmarkId::new(*label, "1-thread"), |b| {
                b.iter(|| one.install(|| Octree::with_params(mesh, p).unwrap().stats().references));
            });
            g.bench_function(BenchmarkId::new(*label, "all-threads"), |b| {
                b.iter(|| Octree::with_params(mesh, p).unwrap().stats().references);
            });
        }
        g.finish();

        let camera_rays = scene.camera.rays::<f32>(CAMERA_SIDE, CAMERA_SIDE);
        let random = random_rays::<f32>(&mesh.bounds().cast(), RANDOM_RAYS, 7);
        for (kind, rays) in [("camera", &camera_rays), ("random", &random)] {
            let group = format!("{}/{kind}", scene.name);
            rays_per_second(c, &group, "grid", &grid, rays);
            for (label, _, o) in &octrees {
                rays_per_second(c, &group, label, o, rays);
            }
        }
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
