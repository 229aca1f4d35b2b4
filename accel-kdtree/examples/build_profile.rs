//! Builds the generated terrain of N triangles (or the generated scene or glTF
//! file named instead of N) once, on one thread unless told (for profilers), optionally with the
//! binned SAH above a node size and a bin count:
//! `cargo run --release -p accel-kdtree --example build_profile -- N|SCENE|FILE.glb [BINNED_ABOVE] [BINS]`;
//! `KD_PRESET=fast-build|best-traversal|pbrt` starts from a preset, `KD_MAX_DEPTH=d`
//! sets the depth limit, `KD_LEAF_SIZE=n`, `KD_TRAVERSAL_COST=c`,
//! `KD_DEPTH_BASE=b`, `KD_CLIP_ABOVE=n` and `KD_TIGHTEN_ABOVE=n` override the preset's,
//! `REPEAT=n` builds n more times and reports the fastest, `THREADS=n` builds on `n` threads.

use accel_core::Accelerator;
use accel_kdtree::{KdTree, KdTreeParams};
use accel_scenes::{GeneratedScene, terrain};

fn main() {
    let first = std::env::args().nth(1).unwrap_or_else(|| "100000".into());
    let mesh = match (first.parse::<usize>(), GeneratedScene::from_name(&first)) {
        (Ok(n), _) => terrain(n, 0x7E),
        (Err(_), Some(scene)) => scene.mesh(),
        (Err(_), None) => match accel_scenes::gltf::load(std::path::Path::new(&first)) {
            Ok(scene) => scene.mesh,
            Err(e) => {
                eprintln!("{first}: {e}");
                std::process::exit(2);
            }
        },
    }
    .cast::<f32>()
    .expect("fits f32");
    let threads = std::env::var("THREADS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    let (start, cpu_start) = (std::time::Instant::now(), cpu_seconds());
    let mut params = match std::env::var("KD_PRESET").as_deref() {
        Ok("fast-build") => KdTreeParams::fast_build(),
        Ok("best-traversal") => KdTreeParams::best_traversal(),
        Ok("pbrt") => KdTreeParams::pbrt(),
        _ => KdTreeParams::default(),
    };
    if let Some(depth) = std::env::var("KD_MAX_DEPTH")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        params.max_depth = Some(depth);
    }
    if let Some(n) = std::env::var("KD_LEAF_SIZE")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        params.leaf_size = n;
    }
    if let Some(c) = std::env::var("KD_TRAVERSAL_COST")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        params.traversal_cost = c;
    }
    if let Some(b) = std::env::var("KD_DEPTH_BASE")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        params.depth_base = b;
    }
    if let Some(n) = std::env::var("KD_CLIP_ABOVE")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        params.clip_above = n;
    }
    if let Some(n) = std::env::var("KD_TIGHTEN_ABOVE")
        .ok()
        .and_then(|s| s.parse().ok())
    {
        params.tighten_above = n;
    }
    if let Some(above) = std::env::args().nth(2).and_then(|s| s.parse().ok()) {
        params.binned_above = above;
    }
    if let Some(bins) = std::env::args().nth(3).and_then(|s| s.parse().ok()) {
        params.bins = bins;
    }
    let tree = pool.install(|| KdTree::with_params(&mesh, &params).expect("builds"));
    let s = start.elapsed().as_secs_f64();
    // `REPEAT=n`: n more builds, the fastest reported (a shared machine).
    let repeat: usize = std::env::var("REPEAT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0);
    let fastest = (0..repeat)
        .map(|_| {
            let start = std::time::Instant::now();
            drop(pool.install(|| KdTree::with_params(&mesh, &params).expect("builds")));
            start.elapsed().as_secs_f64()
        })
        .fold(s, f64::min);
    if repeat > 0 {
        println!("fastest of {}: {:.2} ms", repeat + 1, fastest * 1e3);
    }
    let cpu = cpu_seconds().zip(cpu_start).map(|(b, a)| b - a);
    println!(
        "{} tris in {s:.3} s: {:.3} Mtris/s (CPU {}); {}",
        mesh.triangle_count(),
        mesh.triangle_count() as f64 / s / 1e6,
        cpu.map_or("unknown".into(), |c| format!("{c:.2} s")),
        tree.stats()
    );
}

/// The process's CPU time (user + system) from `/proc/self/stat`, which on a
/// shared machine varies less than the wall clock; `None` off Linux.
fn cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are the
    // 14th and 15th fields, in clock ticks (100 per second on Linux).
    let rest = stat.rsplit_once(')')?.1;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
