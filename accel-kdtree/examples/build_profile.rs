//! Builds the generated terrain once on one thread, or `THREADS` (for profilers):
//! `cargo run --release -p accel-kdtree --example build_profile -- 1000000`.

use accel_core::Accelerator;
use accel_core::scenes::terrain;
use accel_kdtree::KdTree;

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(100_000);
    let mesh = terrain(n, 0x7E).cast::<f32>().expect("fits f32");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let start = std::time::Instant::now();
    let tree = pool.install(|| KdTree::new(&mesh).expect("builds"));
    let s = start.elapsed().as_secs_f64();
    println!(
        "{} tris in {s:.3} s: {:.3} Mtris/s; {}",
        mesh.triangle_count(),
        mesh.triangle_count() as f64 / s / 1e6,
        tree.stats()
    );
}
