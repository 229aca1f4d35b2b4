//! glTF 2.0 scenes as one triangle mesh, with the file's cameras.
//!
//! The whole node hierarchy of the default scene (or the first one) is
//! flattened: node matrices and TRS transforms are composed in `f64`, and a
//! mesh used by several nodes is instanced once per node. Every triangle
//! primitive is read (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`; `u8`,
//! `u16`, `u32` or no indices); points and lines are refused, never dropped.

use crate::{MeshError, TriangleMesh, Vec3};
use std::path::{Path, PathBuf};

/// Why a glTF file could not be loaded.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// The file could not be read or parsed.
    #[error("{path}: {message}")]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What the glTF reader reported.
        message: String,
    },
    /// A primitive is not made of triangles.
    #[error(
        "{path}: mesh {mesh} primitive {primitive} has mode {mode}, which is not a triangle mode \
         (only TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN are supported)"
    )]
    UnsupportedMode {
        /// The file.
        path: PathBuf,
        /// Mesh index (and name, when it has one).
        mesh: String,
        /// Primitive index in the mesh.
        primitive: usize,
        /// The mode's glTF name.
        mode: &'static str,
    },
    /// A triangle primitive has no POSITION attribute.
    #[error("{path}: mesh {mesh} primitive {primitive} has no POSITION attribute")]
    MissingPositions {
        /// The file.
        path: PathBuf,
        /// Mesh index (and name).
        mesh: String,
        /// Primitive index.
        primitive: usize,
    },
    /// The geometry is invalid (non-finite coordinates, bad indices).
    #[error("{path}: {source}")]
    Mesh {
        /// The file.
        path: PathBuf,
        /// What was wrong.
        source: MeshError,
    },
    /// The scene holds no triangle.
    #[error("{path}: the scene holds no triangles")]
    NoTriangles {
        /// The file.
        path: PathBuf,
    },
}

/// A camera found in the file, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneCamera {
    /// Eye position.
    pub eye: Vec3<f64>,
    /// View direction (the node's −z axis), unit length.
    pub forward: Vec3<f64>,
    /// Up direction (the node's +y axis), unit length.
    pub up: Vec3<f64>,
    /// Vertical field of view in radians (perspective cameras); `None` for
    /// orthographic ones.
    pub yfov: Option<f64>,
    /// Aspect ratio the file asks for, if any.
    pub aspect_ratio: Option<f64>,
}

/// A loaded scene: every triangle in world space, and the cameras.
#[derive(Clone, Debug)]
pub struct Scene {
    /// All triangles, transformed and instanced.
    pub mesh: TriangleMesh<f64>,
    /// Cameras in node order.
    pub cameras: Vec<SceneCamera>,
}

fn mode_name(mode: gltf::mesh::Mode) -> &'static str {
    use gltf::mesh::Mode;
    match mode {
        Mode::Points => "POINTS",
        Mode::Lines => "LINES",
        Mode::LineLoop => "LINE_LOOP",
        Mode::LineStrip => "LINE_STRIP",
        Mode::Triangles => "TRIANGLES",
        Mode::TriangleStrip => "TRIANGLE_STRIP",
        Mode::TriangleFan => "TRIANGLE_FAN",
    }
}

fn mesh_label(mesh: &gltf::Mesh<'_>) -> String {
    match mesh.name() {
        Some(name) => format!("{} ({name:?})", mesh.index()),
        None => mesh.index().to_string(),
    }
}

/// Triangles from a vertex list in the primitive's mode.
fn triangles(mode: gltf::mesh::Mode, idx: &[u32]) -> Vec<[u32; 3]> {
    use gltf::mesh::Mode;
    match mode {
        Mode::TriangleStrip => (2..idx.len())
            .map(|i| {
                // Alternate the winding so every triangle faces the same way.
                if i % 2 == 0 {
                    [idx[i - 2], idx[i - 1], idx[i]]
                } else {
                    [idx[i - 1], idx[i - 2], idx[i]]
                }
            })
            .collect(),
        Mode::TriangleFan => (2..idx.len())
            .map(|i| [idx[0], idx[i - 1], idx[i]])
            .collect(),
        _ => idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
    }
}

struct Loader<'a> {
    path: &'a Path,
    buffers: &'a [gltf::buffer::Data],
    positions: Vec<Vec3<f64>>,
    indices: Vec<[u32; 3]>,
    cameras: Vec<SceneCamera>,
}

impl Loader<'_> {
    fn node(&mut self, node: &gltf::Node<'_>, parent: glam::DMat4) -> Result<(), LoadError> {
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        if let Some(mesh) = node.mesh() {
            self.mesh(&mesh, &world)?;
        }
        if let Some(camera) = node.camera() {
            let (yfov, aspect_ratio) = match camera.projection() {
                gltf::camera::Projection::Perspective(p) => {
                    (Some(f64::from(p.yfov())), p.aspect_ratio().map(f64::from))
                }
                gltf::camera::Projection::Orthographic(_) => (None, None),
            };
            let eye = world.transform_point3(glam::DVec3::ZERO);
            let forward = world.transform_vector3(glam::DVec3::NEG_Z).normalize();
            let up = world.transform_vector3(glam::DVec3::Y).normalize();
            self.cameras.push(SceneCamera {
                eye: eye.into(),
                forward: forward.into(),
                up: up.into(),
                yfov,
                aspect_ratio,
            });
        }
        for child in node.children() {
            self.node(&child, world)?;
        }
        Ok(())
    }

    fn mesh(&mut self, mesh: &gltf::Mesh<'_>, world: &glam::DMat4) -> Result<(), LoadError> {
        use gltf::mesh::Mode;
        for (p, primitive) in mesh.primitives().enumerate() {
            let mode = primitive.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                return Err(LoadError::UnsupportedMode {
                    path: self.path.to_owned(),
                    mesh: mesh_label(mesh),
                    primitive: p,
                    mode: mode_name(mode),
                });
            }
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(positions) = reader.read_positions() else {
                return Err(LoadError::MissingPositions {
                    path: self.path.to_owned(),
                    mesh: mesh_label(mesh),
                    primitive: p,
                });
            };
            let base = self.positions.len();
            self.positions.extend(positions.map(|q| {
                let v = world.transform_point3(glam::Vec3::from(q).as_dvec3());
                Vec3::from(v)
            }));
            let count = (self.positions.len() - base) as u32;
            let local: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..count).collect(),
            };
            if let Some(&vertex) = local.iter().find(|&&i| i >= count) {
                return Err(LoadError::Mesh {
                    path: self.path.to_owned(),
                    source: MeshError::IndexOutOfRange {
                        triangle: self.indices.len(),
                        vertex,
                        vertex_count: count as usize,
                    },
                });
            }
            // Mirroring transforms flip the winding; keep faces consistent.
            let flip = world.determinant() < 0.0;
            let offset = u32::try_from(base).unwrap_or(u32::MAX);
            self.indices
                .extend(triangles(mode, &local).into_iter().map(|t| {
                    let t = t.map(|i| i.saturating_add(offset));
                    if flip { [t[0], t[2], t[1]] } else { t }
                }));
        }
        Ok(())
    }
}

/// Loads a `.gltf` or `.glb` file.
///
/// # Errors
/// [`LoadError`] naming the file and the problem: unreadable or malformed
/// files, non-triangle primitives, missing positions, non-finite coordinates,
/// out-of-range indices, or a scene without triangles.
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    let gltf_error = |e: gltf::Error| LoadError::Gltf {
        path: path.to_owned(),
        message: e.to_string(),
    };
    let gltf::Gltf { document, blob } = gltf::Gltf::open(path).map_err(gltf_error)?;
    let base = path.parent();
    let buffers = gltf::import_buffers(&document, base, blob).map_err(gltf_error)?;
    let mut loader = Loader {
        path,
        buffers: &buffers,
        positions: Vec::new(),
        indices: Vec::new(),
        cameras: Vec::new(),
    };
    if let Some(scene) = document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        for node in scene.nodes() {
            loader.node(&node, glam::DMat4::IDENTITY)?;
        }
    }
    if loader.indices.is_empty() {
        return Err(LoadError::NoTriangles {
            path: path.to_owned(),
        });
    }
    let mesh =
        TriangleMesh::new(loader.positions, loader.indices).map_err(|source| LoadError::Mesh {
            path: path.to_owned(),
            source,
        })?;
    Ok(Scene {
        mesh,
        cameras: loader.cameras,
    })
}

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strips_and_fans_become_triangles() {
        use gltf::mesh::Mode;
        assert_eq!(
            triangles(Mode::TriangleStrip, &[0, 1, 2, 3, 4]),
            vec![[0, 1, 2], [2, 1, 3], [2, 3, 4]]
        );
        assert_eq!(
            triangles(Mode::TriangleFan, &[0, 1, 2, 3]),
            vec![[0, 1, 2], [0, 2, 3]]
        );
        assert_eq!(triangles(Mode::Triangles, &[5, 6, 7, 8]), vec![[5, 6, 7]]);
    }

    #[test]
    fn khronos_box_loads_with_its_node_matrix() {
        let Some(dir) = shared_scenes_dir() else {
            eprintln!("skipped: shared scenes absent");
            return;
        };
        let scene = load(&dir.join("khronos_box_textured.glb")).unwrap();
        assert_eq!(scene.mesh.triangle_count(), 12);
        // The README's bounds: the unit cube centred at the origin.
        let b = scene.mesh.bounds();
        for a in 0..3 {
            assert!(
                (b.min[a] + 0.5).abs() < 1e-6 && (b.max[a] - 0.5).abs() < 1e-6,
                "{b:?}"
            );
        }
    }

    #[test]
    fn missing_and_malformed_files_are_named() {
        let err = load(Path::new("/nonexistent/x.glb")).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/x.glb"), "{err}");
        let dir = std::env::temp_dir().join(format!("accel-core-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.gltf");
        std::fs::write(&bad, b"{ not json").unwrap();
        let err = load(&bad).unwrap_err();
        assert!(matches!(err, LoadError::Gltf { .. }), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
