//! glTF 2.0 scenes as one triangle mesh, with the file's cameras.
//!
//! The whole node hierarchy of the default scene (or the first one) is
//! flattened: node matrices and TRS transforms are composed in `f64`, and a
//! mesh used by several nodes is instanced once per node. Every triangle
//! primitive is read (`TRIANGLES`, `TRIANGLE_STRIP`, `TRIANGLE_FAN`; `u8`,
//! `u16`, `u32` or no indices); points and lines are refused, never dropped.
//!
//! Malformed files are refused with a [`LoadError`], never a panic: accessors
//! are checked (component type, element shape, extent within their buffer
//! view and buffer) before they are read, and a node hierarchy with a cycle
//! is refused. Skins and morph targets are ignored (the rest pose is used).

mod checks;
mod shared;
mod view;

use accel_core::glam;
use accel_core::{MeshError, TriangleMesh, Vec3};
use checks::{check_accessor, check_attribute_indices, check_buffer_uris};
pub use shared::{
    BenchScene, bench_scenes, shared_scene_files, shared_scene_files_for_test, shared_scenes_dir,
};
use std::path::{Path, PathBuf};

/// Whether a scene argument names a file rather than a scene by name: it
/// has an extension or a folder, or such a file exists. `render` and the
/// profiling drivers ([`crate::TraceDriver`]) tell the two apart by this
/// rule, so that a file's loading error names it.
#[must_use]
pub fn names_a_file(arg: &str) -> bool {
    let path = Path::new(arg);
    path.extension().is_some() || path.components().count() > 1 || path.exists()
}

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
    /// An accessor cannot be read as its role requires.
    #[error("{path}: mesh {mesh} primitive {primitive}: the {attribute} accessor {problem}")]
    BadAccessor {
        /// The file.
        path: PathBuf,
        /// Mesh index (and name).
        mesh: String,
        /// Primitive index.
        primitive: usize,
        /// `POSITION` or `indices`.
        attribute: &'static str,
        /// What is wrong with it.
        problem: String,
    },
    /// A node's transform (its matrix, or translation, rotation and scale),
    /// alone or composed with its ancestors', is not finite: a value past
    /// the `f32` range such as a translation of 1e39 reads as infinity.
    #[error(
        "{path}: node {node}'s transform {problem} (a matrix, translation, rotation or scale \
         value past the f32 range, about 3.4e38, reads as infinity)"
    )]
    BadTransform {
        /// The file.
        path: PathBuf,
        /// Node index (and name, when it has one).
        node: String,
        /// `is not finite`, or `is not finite once composed with its
        /// ancestors'`.
        problem: &'static str,
    },
    /// A node is its own ancestor.
    #[error("{path}: node {node} is its own ancestor (the node hierarchy has a cycle)")]
    NodeCycle {
        /// The file.
        path: PathBuf,
        /// The node met again.
        node: usize,
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
/// `3`, or `3 ("name")` for a named node.
fn node_label(node: &gltf::Node<'_>) -> String {
    match node.name() {
        Some(name) => format!("{} ({name:?})", node.index()),
        None => node.index().to_string(),
    }
}

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
    fn node(
        &mut self,
        node: &gltf::Node<'_>,
        parent: glam::DMat4,
        ancestors: &mut Vec<usize>,
    ) -> Result<(), LoadError> {
        if ancestors.contains(&node.index()) {
            return Err(LoadError::NodeCycle {
                path: self.path.to_owned(),
                node: node.index(),
            });
        }
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let world = parent * local;
        // Blamed on the node, not on the first vertex it would move to
        // infinity (issue 32, item 5).
        let problem = if !local.is_finite() {
            Some("is not finite")
        } else if !world.is_finite() {
            Some("is not finite once composed with its ancestors'")
        } else {
            None
        };
        if let Some(problem) = problem {
            return Err(LoadError::BadTransform {
                path: self.path.to_owned(),
                node: node_label(node),
                problem,
            });
        }
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
        ancestors.push(node.index());
        for child in node.children() {
            self.node(&child, world, ancestors)?;
        }
        ancestors.pop();
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
            use gltf::accessor::{DataType, Dimensions};
            let bad = |attribute, problem| LoadError::BadAccessor {
                path: self.path.to_owned(),
                mesh: mesh_label(mesh),
                primitive: p,
                attribute,
                problem,
            };
            let Some(position_accessor) = primitive.get(&gltf::Semantic::Positions) else {
                return Err(LoadError::MissingPositions {
                    path: self.path.to_owned(),
                    mesh: mesh_label(mesh),
                    primitive: p,
                });
            };
            check_accessor(
                &position_accessor,
                &[DataType::F32],
                Dimensions::Vec3,
                self.buffers,
            )
            .map_err(|e| bad("POSITION", e))?;
            if let Some(index_accessor) = primitive.indices() {
                check_accessor(
                    &index_accessor,
                    &[DataType::U8, DataType::U16, DataType::U32],
                    Dimensions::Scalar,
                    self.buffers,
                )
                .map_err(|e| bad("indices", e))?;
            }
            let reader = primitive.reader(|b| self.buffers.get(b.index()).map(|d| &d.0[..]));
            let base = self.positions.len();
            if position_accessor.count() > 0 {
                let positions = reader
                    .read_positions()
                    .ok_or_else(|| bad("POSITION", "cannot be read".to_owned()))?;
                self.positions.extend(positions.map(|q| {
                    let v = world.transform_point3(glam::Vec3::from(q).as_dvec3());
                    Vec3::from(v)
                }));
            }
            if self.positions.len() > u32::MAX as usize {
                return Err(LoadError::Mesh {
                    path: self.path.to_owned(),
                    source: MeshError::TooManyTriangles {
                        count: self.positions.len(),
                    },
                });
            }
            let count = (self.positions.len() - base) as u32;
            let local: Vec<u32> = match primitive.indices() {
                Some(a) if a.count() == 0 => Vec::new(),
                Some(_) => reader
                    .read_indices()
                    .ok_or_else(|| bad("indices", "cannot be read".to_owned()))?
                    .into_u32()
                    .collect(),
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
            // In range: `base + i < positions.len() <= u32::MAX` (checked above).
            let offset = base as u32;
            let new = triangles(mode, &local);
            if self.indices.len() + new.len() > u32::MAX as usize {
                return Err(LoadError::Mesh {
                    path: self.path.to_owned(),
                    source: MeshError::TooManyTriangles {
                        count: self.indices.len() + new.len(),
                    },
                });
            }
            self.indices.extend(new.into_iter().map(|t| {
                let t = t.map(|i| i + offset);
                if flip { [t[0], t[2], t[1]] } else { t }
            }));
        }
        Ok(())
    }
}

/// Every buffer's bytes, never more than its declared `byteLength`: an
/// external file is read through a limit of that length (a regular file in
/// the folder, [`check_buffer_uris`]), `data:` URIs and the binary chunk
/// (both inside the file already read) by the glTF reader. A buffer shorter
/// than its `byteLength` is refused, naming both lengths.
fn read_buffers(
    path: &Path,
    document: &gltf::Document,
    files: &[Option<PathBuf>],
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<gltf::buffer::Data>, LoadError> {
    use std::io::Read;
    let fail = |message: String| LoadError::Gltf {
        path: path.to_owned(),
        message,
    };
    let mut buffers = Vec::new();
    for (buffer, file) in document.buffers().zip(files) {
        let index = buffer.index();
        let declared = buffer.length();
        let mut data = match file {
            Some(file) => {
                let cannot = |e: std::io::Error| {
                    fail(format!(
                        "buffer {index} file {} cannot be read: {e}",
                        file.display()
                    ))
                };
                let mut data = Vec::new();
                std::fs::File::open(file)
                    .and_then(|f| f.take(declared as u64).read_to_end(&mut data))
                    .map_err(cannot)?;
                data
            }
            None => {
                gltf::buffer::Data::from_source_and_blob(buffer.source(), None, &mut blob)
                    .map_err(|e| fail(format!("buffer {index} cannot be read: {e}")))?
                    .0
            }
        };
        if data.len() < declared {
            return Err(fail(format!(
                "buffer {index} holds {} bytes, fewer than its byteLength of {declared}",
                data.len()
            )));
        }
        data.truncate(declared);
        // As the glTF reader does: a multiple of four bytes.
        while !data.len().is_multiple_of(4) {
            data.push(0);
        }
        buffers.push(gltf::buffer::Data(data));
    }
    Ok(buffers)
}

/// Loads a `.gltf` or `.glb` file.
///
/// # Errors
/// [`LoadError`] naming the file and the problem: unreadable or malformed
/// files, non-triangle primitives, missing positions, non-finite coordinates,
/// out-of-range indices, or a scene without triangles.
pub fn load(path: &Path) -> Result<Scene, LoadError> {
    let gltf_error = |what: &str, e: gltf::Error| LoadError::Gltf {
        path: path.to_owned(),
        message: match e {
            gltf::Error::Io(e) => format!("cannot read {what}: {e}"),
            e => format!("not a valid glTF file: {e}"),
        },
    };
    let file = std::fs::File::open(path).map_err(|e| gltf_error("the file", gltf::Error::Io(e)))?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_reader_without_validation(std::io::BufReader::new(file))
            .map_err(|e| gltf_error("the file", e))?;
    // gltf-json 1.4's validation indexes the POSITION accessor before it
    // checks the index (a panic for an index past the accessors, found by
    // render's mutated_inputs test): checked here first, then validated.
    check_attribute_indices(path, document.as_json())?;
    let document =
        gltf::Document::from_json(document.into_json()).map_err(|e| gltf_error("the file", e))?;
    let files = check_buffer_uris(path, &document)?;
    let buffers = read_buffers(path, &document, &files, blob)?;
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
            loader.node(&node, glam::DMat4::IDENTITY, &mut Vec::new())?;
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

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    // See: issue 32, item 2 (buffer URIs read /dev/zero until memory ran out).
    #[test]
    fn buffer_uris_outside_the_folder_or_not_regular_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("accel-uri-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for uri in [
            "/dev/zero",
            "../../../dev/zero",
            "a/%2e%2e/b.bin",
            "file:///dev/zero",
        ] {
            let file = dir.join("bad.gltf");
            let json = format!(
                r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"uri":"{uri}","byteLength":12}}]}}"#
            );
            std::fs::write(&file, json).unwrap();
            let err = super::load(&file).unwrap_err().to_string();
            assert!(err.contains("refused") && err.contains(uri), "{uri}: {err}");
        }
        // A name with an encoded space is read as the importer decodes it:
        // not refused (its buffer is too short for the mesh-less file to
        // matter).
        std::fs::write(dir.join("a b.bin"), [0u8; 12]).unwrap();
        let file = dir.join("ok.gltf");
        std::fs::write(
            &file,
            r#"{"asset":{"version":"2.0"},"buffers":[{"uri":"a%20b.bin","byteLength":12}]}"#,
        )
        .unwrap();
        if let Err(e) = load(&file) {
            assert!(!e.to_string().contains("refused"), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

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
        let Some(files) = shared_scene_files_for_test() else {
            return;
        };
        let file = files
            .iter()
            .find(|p| p.ends_with("khronos_box_textured.glb"))
            .expect("the shared scenes hold khronos_box_textured.glb");
        let scene = load(file).unwrap();
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

    /// Standard base64 (for `data:` URIs).
    fn base64(bytes: &[u8]) -> String {
        const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::new();
        for c in bytes.chunks(3) {
            let b = |i: usize| u32::from(c.get(i).copied().unwrap_or(0));
            let n = (b(0) << 16) | (b(1) << 8) | b(2);
            for i in 0..4 {
                if i <= c.len() {
                    s.push(A[(n >> (18 - 6 * i)) as usize & 63] as char);
                } else {
                    s.push('=');
                }
            }
        }
        s
    }

    /// Writes a `.gltf` with one buffer (positions, then `extra` bytes) and
    /// the given JSON arrays; returns its path.
    fn write_gltf(
        dir: &Path,
        name: &str,
        data: &[u8],
        views: &str,
        accessors: &str,
        meshes: &str,
        nodes: &str,
    ) -> PathBuf {
        std::fs::create_dir_all(dir).unwrap();
        let path = dir.join(name);
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
            "bufferViews":{views},"accessors":{accessors},"meshes":{meshes},"nodes":{nodes}}}"#,
            data.len(),
            base64(data)
        );
        std::fs::write(&path, json).unwrap();
        path
    }

    /// Four vertices of a unit square in z = 0, as f32 bytes.
    fn square() -> Vec<u8> {
        [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
        ]
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
    }

    const POS: &str = r#"{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}"#;

    #[test]
    fn u8_strips_are_instanced_through_trs_nodes() {
        let mut data = square();
        data.extend([0u8, 1, 2, 3]);
        let dir =
            std::env::temp_dir().join(format!("accel-core-gltf-strip-{}", std::process::id()));
        let path = write_gltf(
            &dir,
            "strip.gltf",
            &data,
            r#"[{"buffer":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":4}]"#,
            &format!(
                r#"[{POS},{{"bufferView":1,"componentType":5121,"count":4,"type":"SCALAR"}}]"#
            ),
            r#"[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"mode":5}]}]"#,
            r#"[{"children":[1,2]},{"mesh":0},{"mesh":0,"translation":[5,0,0],"scale":[2,2,2]}]"#,
        );
        let scene = load(&path).unwrap();
        assert_eq!(scene.mesh.triangle_count(), 4);
        let b = scene.mesh.bounds();
        assert_eq!((b.min.x, b.max.x, b.max.y), (0.0, 7.0, 2.0));
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The square as one mesh under `nodes`, its buffer inline (the crate's
    /// tests share it).
    pub(crate) fn square_under(dir: &Path, name: &str, nodes: &str) -> PathBuf {
        write_gltf(
            dir,
            name,
            &square(),
            r#"[{"buffer":0,"byteLength":48}]"#,
            &format!("[{POS}]"),
            r#"[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
            nodes,
        )
    }

    /// See: issue 32, item 5. A translation of 1e39 (infinite once read as
    /// `f32`) was blamed on the first vertex it moved; it is the node's.
    #[test]
    fn non_finite_transforms_are_blamed_on_their_node() {
        let dir =
            std::env::temp_dir().join(format!("accel-core-gltf-xform-{}", std::process::id()));
        let path = square_under(
            &dir,
            "far.gltf",
            r#"[{"children":[1]},{"name":"far","mesh":0,"translation":[1e39,0,0]}]"#,
        );
        let err = load(&path).unwrap_err();
        assert!(matches!(err, LoadError::BadTransform { .. }), "{err}");
        let text = err.to_string();
        for needle in ["far.gltf", "node 1 (\"far\")", "is not finite", "f32 range"] {
            assert!(text.contains(needle), "{needle:?} not in {text}");
        }
        assert!(!text.contains("vertex"), "{text}");
        // Finite scales whose product overflows f64: nine levels of 1e38.
        let chain: Vec<String> = (0..9)
            .map(|i| {
                let link = if i < 8 {
                    format!(r#""children":[{}]"#, i + 1)
                } else {
                    r#""mesh":0"#.to_owned()
                };
                format!(r#"{{{link},"scale":[1e38,1e38,1e38]}}"#)
            })
            .collect();
        let path = square_under(&dir, "deep.gltf", &format!("[{}]", chain.join(",")));
        let text = load(&path).unwrap_err().to_string();
        assert!(text.contains("once composed with its ancestors'"), "{text}");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// See: issue 32, item 7 (found by render's `mutated_inputs`): a POSITION
    /// attribute naming an accessor past the last made gltf-json's
    /// validation index out of bounds and panic.
    #[test]
    fn attributes_naming_missing_accessors_are_refused() {
        let dir = std::env::temp_dir().join(format!("accel-core-gltf-attr-{}", std::process::id()));
        let path = write_gltf(
            &dir,
            "attr.gltf",
            &square(),
            r#"[{"buffer":0,"byteLength":48}]"#,
            &format!("[{POS}]"),
            r#"[{"primitives":[{"attributes":{"POSITION":3}}]}]"#,
            r#"[{"mesh":0}]"#,
        );
        let text = load(&path).unwrap_err().to_string();
        for needle in ["attr.gltf", "POSITION attribute names accessor 3", "has 1"] {
            assert!(text.contains(needle), "{needle:?} not in {text}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// A `.gltf` whose one buffer is the file `uri` of `byte_length` bytes,
    /// holding the square.
    fn external(dir: &Path, name: &str, uri: &str, byte_length: usize) -> PathBuf {
        let path = dir.join(name);
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "buffers":[{{"byteLength":{byte_length},"uri":"{uri}"}}],
            "bufferViews":[{{"buffer":0,"byteLength":48}}],"accessors":[{POS}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],"nodes":[{{"mesh":0}}]}}"#
        );
        std::fs::write(&path, json).unwrap();
        path
    }

    /// See: issue 32, items 2 and 5. A missing buffer file is named; a file
    /// shorter than its `byteLength` is refused with both lengths; a longer
    /// one is read only up to it.
    #[test]
    fn buffer_files_are_named_and_read_only_to_their_declared_length() {
        let dir = std::env::temp_dir().join(format!("accel-core-gltf-len-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = external(&dir, "absent.gltf", "absent.bin", 48);
        let text = load(&path).unwrap_err().to_string();
        assert!(
            text.contains("absent.gltf")
                && text.contains("absent.bin")
                && text.contains("cannot be read"),
            "{text}"
        );
        std::fs::write(dir.join("short.bin"), &square()[..12]).unwrap();
        let path = external(&dir, "short.gltf", "short.bin", 48);
        let text = load(&path).unwrap_err().to_string();
        assert!(
            text.contains("holds 12 bytes, fewer than its byteLength of 48"),
            "{text}"
        );
        let mut long = square();
        long.resize(1 << 20, 7);
        std::fs::write(dir.join("long.bin"), &long).unwrap();
        let path = external(&dir, "long.gltf", "long.bin", 48);
        assert_eq!(load(&path).unwrap().mesh.triangle_count(), 1);
        let gltf::Gltf { document, blob } = gltf::Gltf::open(&path).unwrap();
        let files = check_buffer_uris(&path, &document).unwrap();
        let buffers = read_buffers(&path, &document, &files, blob).unwrap();
        assert_eq!(buffers[0].0.len(), 48, "read past the byteLength");
        std::fs::remove_dir_all(&dir).ok();
    }

    /// See: issue 32, item 2. A buffer file that is a symbolic link out of
    /// the file's folder is refused, even to a regular file; one that stays
    /// inside is read.
    #[cfg(unix)]
    #[test]
    fn symbolic_links_out_of_the_folder_are_refused() {
        let dir = std::env::temp_dir().join(format!("accel-core-gltf-link-{}", std::process::id()));
        let inner = dir.join("scene");
        std::fs::create_dir_all(&inner).unwrap();
        std::fs::write(dir.join("outside.bin"), square()).unwrap();
        std::fs::write(inner.join("inside.bin"), square()).unwrap();
        std::os::unix::fs::symlink("../outside.bin", inner.join("out.bin")).unwrap();
        std::os::unix::fs::symlink("inside.bin", inner.join("in.bin")).unwrap();
        let path = external(&inner, "out.gltf", "out.bin", 48);
        let text = load(&path).unwrap_err().to_string();
        assert!(
            text.contains("out.bin") && text.contains("symbolic link"),
            "{text}"
        );
        let path = external(&inner, "in.gltf", "in.bin", 48);
        assert_eq!(load(&path).unwrap().mesh.triangle_count(), 1);
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn malformed_accessors_and_hierarchies_are_refused_not_panicked_on() {
        let dir = std::env::temp_dir().join(format!("accel-core-gltf-bad-{}", std::process::id()));
        let data = square();
        let view = r#"[{"buffer":0,"byteLength":48}]"#;
        let tri = r#"[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}]"#;
        // Float indices (the gltf reader would hit `unreachable!`).
        let p = write_gltf(
            &dir,
            "float_indices.gltf",
            &data,
            view,
            &format!(
                r#"[{POS},{{"bufferView":0,"componentType":5126,"count":3,"type":"SCALAR"}}]"#
            ),
            tri,
            r#"[{"mesh":0}]"#,
        );
        let err = load(&p).unwrap_err();
        assert!(
            matches!(
                err,
                LoadError::BadAccessor {
                    attribute: "indices",
                    ..
                }
            ),
            "{err}"
        );
        // Positions past the end of their view.
        let p = write_gltf(
            &dir,
            "past_end.gltf",
            &data,
            view,
            r#"[{"bufferView":0,"componentType":5126,"count":5,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]"#,
            r#"[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
            r#"[{"mesh":0}]"#,
        );
        let err = load(&p).unwrap_err();
        assert!(err.to_string().contains("past the end"), "{err}");
        // Positions of the wrong shape.
        let p = write_gltf(
            &dir,
            "vec2.gltf",
            &data,
            view,
            r#"[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC2","min":[0,0],"max":[1,1]}]"#,
            r#"[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
            r#"[{"mesh":0}]"#,
        );
        assert!(load(&p).is_err());
        // No vertices at all: an empty scene, not an underflow.
        let p = write_gltf(
            &dir,
            "empty_accessor.gltf",
            &data,
            view,
            r#"[{"bufferView":0,"componentType":5126,"count":0,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]"#,
            r#"[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
            r#"[{"mesh":0}]"#,
        );
        assert!(matches!(
            load(&p).unwrap_err(),
            LoadError::NoTriangles { .. }
        ));
        // A node that is its own grandparent.
        let p = write_gltf(
            &dir,
            "cycle.gltf",
            &data,
            view,
            &format!("[{POS}]"),
            r#"[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
            r#"[{"children":[1]},{"children":[0],"mesh":0}]"#,
        );
        let err = load(&p).unwrap_err();
        assert!(
            err.to_string().contains("cycle") || matches!(err, LoadError::Gltf { .. }),
            "{err}"
        );
        // Lines are named.
        let p = write_gltf(
            &dir,
            "lines.gltf",
            &data,
            view,
            &format!("[{POS}]"),
            r#"[{"primitives":[{"attributes":{"POSITION":0},"mode":1}]}]"#,
            r#"[{"mesh":0}]"#,
        );
        assert!(load(&p).unwrap_err().to_string().contains("LINES"));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn missing_and_malformed_files_are_named() {
        let err = load(Path::new("/nonexistent/x.glb")).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/x.glb"), "{err}");
        assert!(err.to_string().contains("cannot read the file"), "{err}");
        let dir = std::env::temp_dir().join(format!("accel-core-gltf-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let bad = dir.join("bad.gltf");
        std::fs::write(&bad, b"{ not json").unwrap();
        let err = load(&bad).unwrap_err();
        assert!(matches!(err, LoadError::Gltf { .. }), "{err}");
        assert!(err.to_string().contains("not a valid glTF file"), "{err}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
