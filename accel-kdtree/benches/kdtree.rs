//! SAH kD-tree beside the uniform grid, on the same scenes and rays: build
//! throughput (triangles/s, one thread and all threads, for each preset) and
//! nearest-hit and any-hit throughput (rays/s) on the generated scenes and on
//! `../shared/scenes/*.glb` when present, with camera and random rays.
//!
//! `cargo bench -p accel-kdtree` runs everything; criterion's filter narrows
//! it, e.g. `cargo bench -p accel-kdtree -- 'terrain_1m/build'` or
//! `-- 'camera/.*/nearest/1-thread'`.

use accel_core::{Accelerator, Ray, TriangleMesh};
use accel_grid::Grid;
use accel_kdtree::{KdTree, KdTreeParams};
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

/// The leading part of `rays` that one thread traces in about `budget`:
/// a structure that is slow on a scene (the grid on the teapot in a stadium)
/// is measured on fewer rays instead of for minutes. Rays/s is unaffected.
fn calibrated<'r, A: Accelerator<f32>>(
    accel: &A,
    rays: &'r [Ray<f32>],
    budget: Duration,
) -> &'r [Ray<f32>] {
    let probe = &rays[..rays.len().min(256)];
    let start = Instant::now();
    for r in probe {
        std::hint::black_box(accel.intersect(r).unwrap());
    }
    let per_ray = start.elapsed().as_secs_f64() / probe.len() as f64;
    let n = (budget.as_secs_f64() / per_ray.max(1e-12)) as usize;
    &rays[..n.clamp(probe.len().min(64), rays.len())]
}

/// Nearest-hit and any-hit rays/s of one accelerator, named `kind/...`.
fn rays_per_second<A: Accelerator<f32>>(
    c: &mut Criterion,
    group: &str,
    kind: &str,
    accel: &A,
    rays: &[Ray<f32>],
) {
    let rays = calibrated(accel, rays, Duration::from_millis(200));
    let mut g = c.benchmark_group(group);
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function(format!("{kind}/nearest/1-thread"), |b| {
        b.iter(|| {
            rays.iter()
                .filter(|r| accel.intersect(r).unwrap().is_some())
                .count()
        });
    });
    g.bench_function(format!("{kind}/nearest/all-threads"), |b| {
        b.iter(|| {
            rays.par_iter()
                .filter(|r| accel.intersect(r).unwrap().is_some())
                .count()
        });
    });
    g.bench_function(format!("{kind}/any-hit/1-thread"), |b| {
        b.iter(|| rays.iter().filter(|r| accel.occluded(r).unwrap()).count());
    });
    g.finish();
}

fn presets() -> [(&'static str, KdTreeParams); 4] {
    [
        ("default", KdTreeParams::default()),
        ("pbrt", KdTreeParams::pbrt()),
        ("fast_build", KdTreeParams::fast_build()),
        ("best_traversal", KdTreeParams::best_traversal()),
    ]
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
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(3));
        g.throughput(Throughput::Elements(tris));
        for (name, params) in presets() {
            g.bench_function(
                BenchmarkId::new(format!("kdtree-{name}"), "1-thread"),
                |b| {
                    b.iter(|| {
                        one.install(|| {
                            KdTree::with_params(&scene.mesh, &params)
                                .unwrap()
                                .stats()
                                .references
                        })
                    });
                },
            );
            g.bench_function(
                BenchmarkId::new(format!("kdtree-{name}"), "all-threads"),
                |b| {
                    b.iter(|| {
                        KdTree::with_params(&scene.mesh, &params)
                            .unwrap()
                            .stats()
                            .references
                    });
                },
            );
        }
        g.bench_function(BenchmarkId::new("grid", "1-thread"), |b| {
            b.iter(|| one.install(|| Grid::new(&scene.mesh).unwrap().stats().references));
        });
        g.finish();

        let grid = Grid::new(&scene.mesh).expect("grid builds");
        let trees: Vec<(String, KdTree<'_, f32, TriangleMesh<f32>>)> = presets()
            .into_iter()
            .map(|(name, p)| {
                (
                    format!("kdtree-{name}"),
                    KdTree::with_params(&scene.mesh, &p).expect("tree builds"),
                )
            })
            .collect();
        for (name, t) in &trees {
            eprintln!("{} {name}: {}", scene.name, t.stats());
        }
        let camera_rays = scene.camera.rays::<f32>(CAMERA_SIDE, CAMERA_SIDE);
        let random = random_rays::<f32>(&scene.mesh.bounds().cast(), RANDOM_RAYS, 7);
        for (set, rays) in [("camera", &camera_rays), ("random", &random)] {
            let group = format!("{}/{set}", scene.name);
            rays_per_second(c, &group, "grid", &grid, rays);
            for (name, t) in &trees {
                rays_per_second(c, &group, name, t, rays);
            }
        }
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
