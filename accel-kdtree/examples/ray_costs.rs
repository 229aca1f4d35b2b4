//! Mean nodes visited and primitives tested per camera ray, kd-tree beside
//! the uniform grid, on each generated scene (for tuning and profiling):
//! `cargo run --release -p accel-kdtree --example ray_costs [scene-name|FILE.glb]`
//! (a glTF file is framed from the same side as the generated meshes)
//! (`ONLY=kdtree-default` traces one structure, `ONLY=a,b` those two, e.g. under callgrind; the
//! `KD_*` variables of `build_profile` change `kdtree-fast_build`).

use accel_core::{Accelerator, TraversalCounters, TriangleMesh};
use accel_grid::Grid;
use accel_kdtree::{KdTree, KdTreeParams};
use accel_scenes::{Camera, GeneratedScene};
use std::time::Instant;

/// Whether `ONLY` (if set: names, comma-separated) names this structure;
/// others are not even built.
fn wanted(name: &str) -> bool {
    std::env::var("ONLY").map_or(true, |o| o.split(',').any(|o| o == name))
}

#[inline(never)]
fn costs<A: Accelerator<f32>>(name: &str, a: &A, rays: &[accel_core::Ray<f32>]) {
    let mut c = TraversalCounters::default();
    let hits = rays
        .iter()
        .filter(|r| a.intersect_counted(r, &mut c).unwrap().is_some())
        .count();
    // Best of five untimed-counter runs: the machine may be shared.
    let mut s = f64::INFINITY;
    for _ in 0..5 {
        let start = Instant::now();
        std::hint::black_box(
            rays.iter()
                .filter(|r| a.intersect(r).unwrap().is_some())
                .count(),
        );
        s = s.min(start.elapsed().as_secs_f64());
    }
    let n = rays.len() as f64;
    println!(
        "  {name:>24}: {:.3} Mrays/s (best of 5), {:.1} nodes, {:.1} prims per ray, {hits} hits",
        n / s / 1e6,
        c.nodes as f64 / n,
        c.prims as f64 / n
    );
}

/// Parameters from `KT`, `KI`, `BONUS`, `DEPTH_EXTRA` (added to pbrt's
/// limit) and `LEAF`, for tuning experiments.
fn env_params(n: usize) -> KdTreeParams {
    let get = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(d)
    };
    let base = KdTreeParams::default();
    KdTreeParams {
        traversal_cost: get("KT", base.traversal_cost),
        intersect_cost: get("KI", base.intersect_cost),
        empty_bonus: get("BONUS", base.empty_bonus),
        max_depth: Some(
            (f64::from(base.depth_limit(n)) + get("DEPTH_EXTRA", 0.0)).min(64.0) as u32,
        ),
        leaf_size: get("LEAF", 0.0) as u32,
        ..base
    }
}

/// [`KdTreeParams::fast_build`] with `KD_LEAF_SIZE`, `KD_TRAVERSAL_COST`,
/// `KD_DEPTH_BASE`, `KD_CLIP_ABOVE`, `KD_TIGHTEN_ABOVE`, `KD_BINS` and
/// `KD_BINNED_ABOVE` in
/// place of its values where set (the names `build_profile` reads).
fn fast_params() -> KdTreeParams {
    fn get<V: std::str::FromStr>(k: &str) -> Option<V> {
        std::env::var(k).ok().and_then(|s| s.parse().ok())
    }
    let p = KdTreeParams::fast_build();
    KdTreeParams {
        leaf_size: get("KD_LEAF_SIZE").unwrap_or(p.leaf_size),
        traversal_cost: get("KD_TRAVERSAL_COST").unwrap_or(p.traversal_cost),
        depth_base: get("KD_DEPTH_BASE").unwrap_or(p.depth_base),
        clip_above: get("KD_CLIP_ABOVE").unwrap_or(p.clip_above),
        tighten_above: get("KD_TIGHTEN_ABOVE").unwrap_or(p.tighten_above),
        bins: get("KD_BINS").unwrap_or(p.bins),
        binned_above: get("KD_BINNED_ABOVE").unwrap_or(p.binned_above),
        ..p
    }
}

fn main() {
    let only = std::env::args().nth(1);
    if let Some(path) = only
        .as_deref()
        .filter(|o| o.ends_with(".glb") || o.ends_with(".gltf"))
    {
        let mesh = match accel_scenes::gltf::load(std::path::Path::new(path)) {
            Ok(scene) => scene.mesh,
            Err(e) => {
                eprintln!("{path}: {e}");
                std::process::exit(2);
            }
        };
        let camera = Camera::frame(&mesh.bounds(), Camera::DEFAULT_SIDE, accel_scenes::Z_UP);
        let mesh = mesh.cast::<f32>().expect("fits f32");
        println!("{path}");
        structures(&mesh, &camera.rays::<f32>(256, 256), true);
        return;
    }
    for scene in GeneratedScene::ALL {
        if only.as_deref().is_some_and(|o| o != scene.name()) {
            continue;
        }
        let mesh = scene.mesh().cast::<f32>().expect("fits f32");
        let rays = scene.camera().rays::<f32>(256, 256);
        println!("{}", scene.name());
        structures(&mesh, &rays, scene != GeneratedScene::TeapotInStadium);
    }
}

/// Traces `rays` through the grid (when `grid`) and each kD-tree setting.
fn structures(mesh: &TriangleMesh<f32>, rays: &[accel_core::Ray<f32>], grid: bool) {
    if grid && wanted("grid") {
        costs("grid", &Grid::new(mesh).unwrap(), rays);
    }
    for (name, p) in [
        ("kdtree-default", KdTreeParams::default()),
        (
            "kdtree-exact",
            KdTreeParams {
                binned_above: usize::MAX,
                ..KdTreeParams::default()
            },
        ),
        ("kdtree-pbrt", KdTreeParams::pbrt()),
        ("kdtree-fast_build", fast_params()),
        ("kdtree-best_traversal", KdTreeParams::best_traversal()),
        ("kdtree-env", env_params(mesh.triangle_count())),
    ] {
        if wanted(name) {
            costs(name, &KdTree::with_params(mesh, &p).unwrap(), rays);
        }
    }
}
