//! What the profiling examples share (`accel-grid`'s `trace`, `accel-octree`'s
//! `trace_octree`, `accel`'s `bundles`): the arguments `[SCENE] [camera|random]
//! [RAYS]`, the scene in `f32` (a generated scene by name, or a glTF file
//! seen as `render` sees it, [`crate::gltf::Scene::view`]), its rays, and a
//! one-thread trace that prints throughput and work per ray. The examples
//! pass their own command line (`std::env::args().skip(1)`); the library
//! never reads it.

use crate::{Camera, GeneratedScene, random_rays};
use accel_core::{Accelerator, Ray, TraversalCounters, TriangleMesh};
use std::time::Instant;

/// A scene in `f32` and what to trace through it.
#[derive(Clone, Debug)]
pub struct TraceDriver {
    /// The generated scene's name, or the file's path.
    pub name: String,
    /// Its mesh, in `f32`.
    pub mesh: TriangleMesh<f32>,
    /// The camera of its camera rays: the generated scene's own, or the
    /// file's view.
    pub camera: Camera,
    /// `camera` or `random`.
    pub kind: String,
    /// Rays to trace (camera rays: a square view of about this many pixels).
    pub count: usize,
}

impl TraceDriver {
    /// From the arguments `[SCENE] [camera|random] [RAYS]`, program name
    /// excluded (defaults: `default_scene`, camera, 65,536). `SCENE` is a
    /// generated scene's name or, with the `gltf` feature, a `.gltf`/`.glb`
    /// file.
    ///
    /// # Errors
    /// A message naming an unknown scene and the known ones, or the file
    /// and why it did not load.
    pub fn from_args<I: IntoIterator<Item = String>>(
        args: I,
        default_scene: &str,
    ) -> Result<Self, String> {
        let args: Vec<String> = args.into_iter().collect();
        let name = args.first().map_or(default_scene, String::as_str);
        let kind = args.get(1).map_or("camera", String::as_str).to_owned();
        let count = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(65_536);
        let (mesh, camera) = scene(name)?;
        let mesh = mesh
            .cast()
            .map_err(|e| format!("{name} does not fit f32: {e}"))?;
        Ok(Self {
            name: name.to_owned(),
            mesh,
            camera,
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
            self.camera.rays(side, side)
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

/// The mesh and camera of the scene called `name`: a generated one, or a
/// glTF file (with the `gltf` feature).
fn scene(name: &str) -> Result<(TriangleMesh<f64>, Camera), String> {
    if let Some(scene) = GeneratedScene::from_name(name) {
        return Ok((scene.mesh(), scene.camera()));
    }
    #[cfg(feature = "gltf")]
    if crate::gltf::names_a_file(name) {
        let scene = crate::gltf::load(std::path::Path::new(name)).map_err(|e| e.to_string())?;
        let (camera, _) = scene.view();
        return Ok((scene.mesh, camera));
    }
    let known: Vec<&str> = GeneratedScene::ALL.iter().map(|s| s.name()).collect();
    let files = if cfg!(feature = "gltf") {
        " or a .gltf/.glb file"
    } else {
        ""
    };
    Err(format!(
        "unknown scene {name}; expected one of {}{files}",
        known.join(", ")
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unknown_scene_is_refused_naming_every_known_one() {
        let err = TraceDriver::from_args(["nowhere".to_owned()], "sphere_100k").unwrap_err();
        for scene in GeneratedScene::ALL {
            assert!(err.contains(scene.name()), "{err}");
        }
        assert!(err.starts_with("unknown scene nowhere"), "{err}");
    }

    #[cfg(feature = "gltf")]
    #[test]
    fn a_gltf_file_is_traced_through_the_view_render_takes() {
        let dir = std::env::temp_dir().join(format!("trace-driver-{}", std::process::id()));
        let path = crate::gltf::tests::square_under(&dir, "square.gltf", r#"[{"mesh":0}]"#);
        let args = [path.display().to_string(), "camera".into(), "4096".into()];
        let run = TraceDriver::from_args(args, "sphere_100k").unwrap();
        // Four vertices, no indices: one triangle (the fourth vertex is left over).
        assert_eq!(run.mesh.triangle_count(), 1);
        assert_eq!(run.camera, crate::gltf::load(&path).unwrap().view().0);
        // The view frames the triangle: a good share of the image sees it.
        let rays = run.rays();
        assert_eq!(rays.len(), 64 * 64);
        let brute = accel_core::BruteForce::new(&run.mesh).unwrap();
        let hits = rays
            .iter()
            .filter(|r| brute.intersect(r).unwrap().is_some())
            .count();
        assert!(hits > rays.len() / 20, "{hits} of {} rays hit", rays.len());
        // A file that does not load is named with its problem.
        let missing = dir.join("missing.glb").display().to_string();
        let err = TraceDriver::from_args([missing.clone()], "sphere_100k").unwrap_err();
        assert!(err.contains("missing.glb"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
