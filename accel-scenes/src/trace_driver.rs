//! What the profiling examples share (`accel-grid`'s `trace`, `accel-octree`'s
//! `trace_octree`): the arguments `[SCENE] [camera|random] [RAYS]`, the
//! scene in `f32`, its rays, and a one-thread trace that prints throughput
//! and work per ray. The examples pass their own command line
//! (`std::env::args().skip(1)`); the library never reads it.

use crate::{GeneratedScene, random_rays};
use accel_core::{Accelerator, Ray, TraversalCounters, TriangleMesh};
use std::time::Instant;

/// A generated scene in `f32` and what to trace through it.
pub struct TraceDriver {
    /// The scene.
    pub scene: GeneratedScene,
    /// Its mesh, in `f32`.
    pub mesh: TriangleMesh<f32>,
    /// `camera` or `random`.
    pub kind: String,
    /// Rays to trace (camera rays: a square view of about this many pixels).
    pub count: usize,
}

impl TraceDriver {
    /// From the arguments `[SCENE] [camera|random] [RAYS]`, program name
    /// excluded (defaults: `default_scene`, camera, 65,536).
    ///
    /// # Errors
    /// A message naming an unknown scene and the known ones.
    pub fn from_args<I: IntoIterator<Item = String>>(
        args: I,
        default_scene: &str,
    ) -> Result<Self, String> {
        let args: Vec<String> = args.into_iter().collect();
        let name = args.first().map_or(default_scene, String::as_str);
        let kind = args.get(1).map_or("camera", String::as_str).to_owned();
        let count = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(65_536);
        let scene = GeneratedScene::from_name(name).ok_or_else(|| {
            format!(
                "unknown scene {name}; expected one of sphere_100k, soup_100k, terrain_1m, teapot_in_stadium"
            )
        })?;
        let mesh = scene
            .mesh()
            .cast()
            .map_err(|e| format!("{name} does not fit f32: {e}"))?;
        Ok(Self {
            scene,
            mesh,
            kind,
            count,
        })
    }

    /// The rays: `count` random rays through the mesh's bounds for
    /// `random`, else the scene's camera rays.
    #[must_use]
    pub fn rays(&self) -> Vec<Ray<f32>> {
        if self.kind == "random" {
            random_rays(&self.mesh.bounds().cast(), self.count, 7)
        } else {
            let side = (self.count as f64).sqrt() as u32;
            self.scene.camera().rays(side, side)
        }
    }

    /// Traces `rays` through `accel` on this thread, then prints hits, time,
    /// Mrays/s, and the cells or nodes visited and triangles tested per ray
    /// (a second, counted pass).
    ///
    /// # Panics
    /// If the accelerator refuses a ray (generated rays are valid).
    pub fn report<A: Accelerator<f32> + ?Sized>(&self, accel: &A, rays: &[Ray<f32>]) {
        let start = Instant::now();
        let hits = rays
            .iter()
            .filter(|r| accel.intersect(r).unwrap().is_some())
            .count();
        let secs = start.elapsed().as_secs_f64();
        println!(
            "{} {} rays: {hits} hits, {:.3} s, {:.3} Mrays/s (one thread)",
            rays.len(),
            self.kind,
            secs,
            rays.len() as f64 / secs / 1e6
        );
        let mut work = TraversalCounters::default();
        for r in rays {
            accel.intersect_counted(r, &mut work).unwrap();
        }
        let n = rays.len().max(1) as f64;
        println!(
            "per ray: {:.1} cells visited, {:.1} triangle tests",
            work.nodes as f64 / n,
            work.prims as f64 / n
        );
    }
}
