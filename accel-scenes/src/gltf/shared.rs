//! The shared test and benchmark meshes (`../shared/scenes`, or
//! `$ACCEL_SCENES`): where they are and which of them a bench loads.

use super::load;
use crate::{Camera, GeneratedScene, Z_UP};
use accel_core::{TriangleMesh, Vec3};
use std::path::{Path, PathBuf};

/// The folder of shared test and benchmark meshes (`../shared/scenes` beside
/// the workspace, or `$ACCEL_SCENES`), if it exists.
#[must_use]
pub fn shared_scenes_dir() -> Option<PathBuf> {
    let dir = std::env::var_os("ACCEL_SCENES").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes"),
        PathBuf::from,
    );
    dir.is_dir().then_some(dir)
}

/// The `.glb` and `.gltf` files of [`shared_scenes_dir`], sorted by name;
/// empty when the folder is absent.
#[must_use]
pub fn shared_scene_files() -> Vec<PathBuf> {
    let Some(dir) = shared_scenes_dir() else {
        return Vec::new();
    };
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("glb" | "gltf")))
        .collect();
    files.sort();
    files
}

/// A scene of the criterion benches: its name, its mesh in `f32`, and the
/// camera its coherent rays come from.
#[derive(Clone, Debug)]
pub struct BenchScene {
    /// The generated scene's name, or the file's stem.
    pub name: String,
    /// The triangles, in `f32`.
    pub mesh: TriangleMesh<f32>,
    /// The generated scene's own camera, or [`Camera::frame`] of the file's
    /// bounds from `(0.3, -1, 0.4)`, `Z_UP`.
    pub camera: Camera,
}

/// The scenes every structure crate's criterion bench runs on: each
/// [`GeneratedScene`], then each of [`shared_scene_files`], whose name
/// `wanted` accepts (a file is read only then). A file that does not load,
/// or does not fit `f32`, is passed over.
///
/// # Panics
/// If a generated scene did not fit `f32`; every one does.
#[must_use]
pub fn bench_scenes(wanted: impl Fn(&str) -> bool) -> Vec<BenchScene> {
    let mut out: Vec<BenchScene> = GeneratedScene::ALL
        .iter()
        .filter(|s| wanted(s.name()))
        .map(|&s| BenchScene {
            name: s.name().to_owned(),
            mesh: s.mesh().cast().expect("generated scenes fit f32"),
            camera: s.camera(),
        })
        .collect();
    for path in shared_scene_files() {
        let name = path
            .file_stem()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
        if !wanted(&name) {
            continue;
        }
        let Ok(scene) = load(&path) else { continue };
        let Ok(mesh) = scene.mesh.cast() else {
            continue;
        };
        let camera = Camera::frame(&scene.mesh.bounds(), Vec3::new(0.3, -1.0, 0.4), Z_UP);
        out.push(BenchScene { name, mesh, camera });
    }
    out
}

/// The shared scene files for a test that needs them: `None` (the test
/// skips, saying so) when `$ACCEL_SCENES` is not set and `../shared/scenes`
/// is absent.
///
/// # Panics
/// When `$ACCEL_SCENES` is set (CI sets it where the folder exists) but
/// names no folder holding `.glb`/`.gltf` files: a run that asked for the
/// shared scenes must not pass without testing them.
#[must_use]
pub fn shared_scene_files_for_test() -> Option<Vec<PathBuf>> {
    let files = shared_scene_files();
    match std::env::var_os("ACCEL_SCENES") {
        Some(dir) if files.is_empty() => panic!(
            "ACCEL_SCENES={} holds no .glb or .gltf files: the shared-scene tests cannot run",
            Path::new(&dir).display()
        ),
        _ if files.is_empty() => {
            eprintln!("skipped: no shared scenes (../shared/scenes absent, $ACCEL_SCENES not set)");
            None
        }
        _ => Some(files),
    }
}
