//! Scenes: what SCENE names, how it is loaded, and how it is looked at.
//!
//! A scene is one triangle mesh in `f64` (cast to the query precision later),
//! its materials (albedo per triangle range), and a [`View`]: camera, up
//! direction, one point light and the ambient-occlusion distance.
//!
//! Sources: the embedded default scene ([`default_scene`]), the workspace's
//! generated benchmark scenes ([`GeneratedScene`]), or a glTF file loaded by
//! [`accel_scenes::gltf::load`], seen through its first camera or framed
//! automatically (glTF is y-up).

use accel_core::{Aabb, MeshError, TriangleMesh, Vec3};
use accel_scenes::gltf::{self, LoadError};
use accel_scenes::{Camera, GeneratedScene, Y_UP, Z_UP, box_mesh, random_soup, torus, uv_sphere};
use std::path::{Path, PathBuf};

/// The name of the embedded default scene.
pub const DEFAULT_SCENE: &str = "default";

/// What a SCENE argument names.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SceneSource {
    /// The embedded procedural scene.
    Default,
    /// One of the workspace's generated benchmark scenes.
    Generated(GeneratedScene),
    /// A `.gltf` or `.glb` file.
    File(PathBuf),
}

/// Why a scene could not be had.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// Not a built-in name, and no such file.
    #[error(
        "{name:?} is neither a file nor a built-in scene (built-in: {})",
        builtin_names().join(", ")
    )]
    Unknown {
        /// The argument given.
        name: String,
    },
    /// The glTF file could not be loaded.
    #[error(transparent)]
    Load(#[from] LoadError),
    /// Procedural geometry was refused (a bug, reported rather than panicking).
    #[error("building the {name} scene: {source}")]
    Mesh {
        /// Which scene.
        name: &'static str,
        /// Why.
        source: MeshError,
    },
}

/// The built-in scene names: `default` and the generated scenes.
#[must_use]
pub fn builtin_names() -> Vec<&'static str> {
    std::iter::once(DEFAULT_SCENE)
        .chain(GeneratedScene::ALL.iter().map(|g| g.name()))
        .collect()
}

impl SceneSource {
    /// Reads a SCENE argument: a built-in name, or else a file path.
    ///
    /// # Errors
    /// [`SceneError::Unknown`] for a word that is neither a built-in name nor
    /// an existing file (a path with a separator or an extension is always
    /// taken as a file, so that its loading error names it).
    pub fn parse(arg: &str) -> Result<Self, SceneError> {
        if arg == DEFAULT_SCENE {
            return Ok(Self::Default);
        }
        if let Some(g) = GeneratedScene::from_name(arg) {
            return Ok(Self::Generated(g));
        }
        if gltf::names_a_file(arg) {
            Ok(Self::File(PathBuf::from(arg)))
        } else {
            Err(SceneError::Unknown {
                name: arg.to_owned(),
            })
        }
    }

    /// The name for reports: the built-in name or the file path.
    #[must_use]
    pub fn name(&self) -> String {
        match self {
            Self::Default => DEFAULT_SCENE.to_owned(),
            Self::Generated(g) => g.name().to_owned(),
            Self::File(p) => p.display().to_string(),
        }
    }

    /// Loads or generates the scene.
    ///
    /// # Errors
    /// [`SceneError`] naming the file and the problem.
    pub fn load(&self) -> Result<Scene, SceneError> {
        match self {
            Self::Default => default_scene(),
            Self::Generated(g) => Ok(generated_scene(*g)),
            Self::File(p) => file_scene(p),
        }
    }
}

/// A surface colour (linear RGB reflectance).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Albedo {
    /// One colour.
    Solid([f64; 3]),
    /// A checkerboard in the plane orthogonal to the view's up axis.
    Checker {
        /// First colour.
        a: [f64; 3],
        /// Second colour.
        b: [f64; 3],
        /// Side of one square, in scene units.
        size: f64,
    },
}

/// The albedo of a range of triangles: triangles below `end` (and at or
/// above the previous material's `end`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// One past the last triangle index.
    pub end: u32,
    /// The colour.
    pub albedo: Albedo,
}

/// How a scene is looked at and lit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The pinhole camera.
    pub camera: Camera,
    /// The scene's up direction (sky and checkerboard orientation), unit length.
    pub up: Vec3<f64>,
    /// Position of the point light.
    pub light: Vec3<f64>,
    /// Length of ambient-occlusion rays.
    pub ao_distance: f64,
}

/// A scene ready to render.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name for reports.
    pub name: String,
    /// Every triangle, in world space.
    pub mesh: TriangleMesh<f64>,
    /// Albedo by triangle range, ascending `end`; the last covers every triangle.
    pub materials: Vec<Material>,
    /// Camera, light and occlusion distance.
    pub view: View,
    /// Remarks for the report (which camera was used, and why).
    pub notes: Vec<String>,
}

impl Scene {
    /// The albedo of triangle `prim` at point `p`.
    #[must_use]
    pub fn albedo(&self, prim: u32, p: Vec3<f64>) -> [f64; 3] {
        let i = self.materials.partition_point(|m| m.end <= prim);
        match self.materials.get(i).map_or(GREY, |m| m.albedo) {
            Albedo::Solid(c) => c,
            Albedo::Checker { a, b, size } => {
                let (u, v) = plane_coords(p, self.view.up);
                let parity = ((u / size).floor() + (v / size).floor()).rem_euclid(2.0);
                if parity < 0.5 { a } else { b }
            }
        }
    }
}

/// Two coordinates of `p` in the plane orthogonal to `up`.
fn plane_coords(p: Vec3<f64>, up: Vec3<f64>) -> (f64, f64) {
    let helper = if up.x.abs() < 0.9 {
        Vec3::new(1.0, 0.0, 0.0)
    } else {
        Vec3::new(0.0, 1.0, 0.0)
    };
    let s = up.cross(helper).normalized();
    let t = up.cross(s);
    (p.dot(s), p.dot(t))
}

const GREY: Albedo = Albedo::Solid([0.75, 0.75, 0.75]);

/// Collects meshes and their colours into one mesh with material ranges.
struct Builder {
    name: &'static str,
    mesh: TriangleMesh<f64>,
    materials: Vec<Material>,
}

impl Builder {
    fn new(name: &'static str) -> Self {
        Self {
            name,
            mesh: TriangleMesh::default(),
            materials: Vec::new(),
        }
    }

    fn add(
        &mut self,
        mesh: &TriangleMesh<f64>,
        albedo: Albedo,
        place: impl Fn(Vec3<f64>) -> Vec3<f64>,
    ) -> Result<(), SceneError> {
        let err = |source| SceneError::Mesh {
            name: self.name,
            source,
        };
        let moved = TriangleMesh::new(
            mesh.positions().iter().map(|&p| place(p)).collect(),
            mesh.indices().to_vec(),
        )
        .map_err(err)?;
        self.mesh.append(&moved).map_err(err)?;
        self.materials.push(Material {
            end: u32::try_from(self.mesh.triangle_count()).unwrap_or(u32::MAX),
            albedo,
        });
        Ok(())
    }
}

/// Rotation about the x axis by `angle` radians.
fn rotate_x(p: Vec3<f64>, angle: f64) -> Vec3<f64> {
    let (s, c) = angle.sin_cos();
    Vec3::new(p.x, p.y * c - p.z * s, p.y * s + p.z * c)
}

/// Rotation about the z axis by `angle` radians.
fn rotate_z(p: Vec3<f64>, angle: f64) -> Vec3<f64> {
    let (s, c) = angle.sin_cos();
    Vec3::new(p.x * c - p.y * s, p.x * s + p.y * c, p.z)
}

/// The embedded default scene (z up, about 19k triangles): dense objects on
/// a large two-triangle floor, ringed by sparse pillars, so the accelerators
/// differ. A standing torus of 8,640 triangles, a sphere of about 4,000, a
/// cloud of 6,000 tiny random triangles, 8 coarse spheres at distance 6 and
/// 24 box pillars at distance 9.5. Sized to render in a few seconds.
///
/// # Errors
/// [`SceneError::Mesh`] only if the generators were broken.
pub fn default_scene() -> Result<Scene, SceneError> {
    use core::f64::consts::{FRAC_PI_2, TAU};
    let mut b = Builder::new(DEFAULT_SCENE);
    let h = 12.0;
    let floor = TriangleMesh::from_triangles(&[
        [
            Vec3::new(-h, -h, 0.0),
            Vec3::new(h, -h, 0.0),
            Vec3::new(h, h, 0.0),
        ],
        [
            Vec3::new(-h, -h, 0.0),
            Vec3::new(h, h, 0.0),
            Vec3::new(-h, h, 0.0),
        ],
    ])
    .map_err(|source| SceneError::Mesh {
        name: DEFAULT_SCENE,
        source,
    })?;
    b.add(
        &floor,
        Albedo::Checker {
            a: [0.8, 0.8, 0.78],
            b: [0.35, 0.36, 0.4],
            size: 1.0,
        },
        |p| p,
    )?;
    // Dense: a standing torus, a sphere and a cloud of tiny triangles.
    b.add(
        &torus(Vec3::ZERO, 1.1, 0.38, 120, 36),
        Albedo::Solid([0.9, 0.5, 0.25]),
        |p| rotate_z(rotate_x(p, FRAC_PI_2 * 0.8), 0.5) + Vec3::new(0.1, 0.5, 1.65),
    )?;
    b.add(
        &uv_sphere(Vec3::ZERO, 0.75, 4_000),
        Albedo::Solid([0.25, 0.45, 0.9]),
        |p| p + Vec3::new(2.4, -0.7, 0.75),
    )?;
    b.add(
        &random_soup(6_000, 0xDEFA_u64),
        Albedo::Solid([0.4, 0.8, 0.3]),
        |p| (p - Vec3::splat(0.5)) * 1.6 + Vec3::new(-2.4, -0.3, 1.2),
    )?;
    // Sparse: coarse spheres and tall pillars far apart.
    for i in 0..8 {
        let a = TAU * f64::from(i) / 8.0 + 0.2;
        b.add(
            &uv_sphere(Vec3::ZERO, 0.5, 80),
            Albedo::Solid([0.85, 0.8, 0.7]),
            |p| p + Vec3::new(6.0 * a.cos(), 6.0 * a.sin() + 1.0, 0.5),
        )?;
    }
    for i in 0..24 {
        let a = TAU * f64::from(i) / 24.0;
        let height = 1.0 + 4.0 * f64::from((i * 7) % 5) / 4.0;
        let c = Vec3::new(9.5 * a.cos(), 9.5 * a.sin(), 0.0);
        let pillar = box_mesh(
            &Aabb::new(
                c - Vec3::new(0.4, 0.4, 0.0),
                c + Vec3::new(0.4, 0.4, height),
            ),
            1,
        );
        b.add(&pillar, Albedo::Solid([0.8, 0.78, 0.75]), |p| p)?;
    }
    let camera = Camera::look_at(
        Vec3::new(0.8, -7.6, 3.3),
        Vec3::new(0.0, 0.0, 0.9),
        Z_UP,
        45.0,
    );
    Ok(Scene {
        name: DEFAULT_SCENE.to_owned(),
        mesh: b.mesh,
        materials: b.materials,
        view: View {
            camera,
            up: Z_UP,
            light: Vec3::new(-6.0, -8.0, 12.0),
            ao_distance: 1.0,
        },
        notes: Vec::new(),
    })
}

/// A generated benchmark scene with its own camera (z up).
#[must_use]
pub fn generated_scene(g: GeneratedScene) -> Scene {
    let mesh = g.mesh();
    let camera = g.camera();
    let focus = if g == GeneratedScene::TeapotInStadium {
        Vec3::ZERO
    } else {
        mesh.bounds().center()
    };
    let view = view_from(camera, Z_UP, focus);
    Scene {
        name: g.name().to_owned(),
        materials: vec![Material {
            end: u32::MAX,
            albedo: GREY,
        }],
        mesh,
        view,
        notes: Vec::new(),
    }
}

/// Light and occlusion distance for a camera looking at `focus`: the light
/// above and to the left of the camera, occlusion rays 15% of the distance.
fn view_from(camera: Camera, up: Vec3<f64>, focus: Vec3<f64>) -> View {
    let d = (focus - camera.eye).length().max(1e-12);
    View {
        camera,
        up,
        light: camera.eye + camera.up * (0.8 * d) - camera.right * (0.6 * d),
        ao_distance: 0.15 * d,
    }
}

/// Loads a glTF file, seen through its first camera if usable, else framed
/// automatically ([`gltf::Scene::view`]).
///
/// # Errors
/// [`SceneError::Load`] naming the file and the problem.
pub fn file_scene(path: &Path) -> Result<Scene, SceneError> {
    let loaded = gltf::load(path)?;
    let bounds = loaded.mesh.bounds();
    let (camera, note) = loaded.view();
    Ok(Scene {
        name: path.display().to_string(),
        mesh: loaded.mesh,
        materials: vec![Material {
            end: u32::MAX,
            albedo: GREY,
        }],
        view: view_from(camera, Y_UP, bounds.center()),
        notes: vec![note],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_scenes::gltf::shared_scene_files_for_test;

    #[test]
    fn names_and_paths_are_told_apart() {
        assert_eq!(SceneSource::parse("default").unwrap(), SceneSource::Default);
        assert_eq!(
            SceneSource::parse("terrain_1m").unwrap(),
            SceneSource::Generated(GeneratedScene::Terrain1M)
        );
        assert_eq!(
            SceneSource::parse("missing.glb").unwrap(),
            SceneSource::File("missing.glb".into())
        );
        let err = SceneSource::parse("sphere_1k").unwrap_err();
        assert!(err.to_string().contains("teapot_in_stadium"), "{err}");
    }

    #[test]
    fn default_scene_is_dense_in_the_middle_and_sparse_around() {
        let s = default_scene().unwrap();
        let n = s.mesh.triangle_count();
        assert!((15_000..25_000).contains(&n), "{n} triangles");
        assert_eq!(s.materials.last().unwrap().end as usize, n);
        let b = s.mesh.bounds();
        // The floor spans 24 units; the dense objects sit within 4 of the centre.
        assert_eq!((b.min.x, b.max.x), (-12.0, 12.0));
        let central = (0..n)
            .filter(|&i| {
                s.mesh
                    .triangle(i)
                    .iter()
                    .all(|p| p.x.abs() < 4.0 && p.y.abs() < 4.0)
            })
            .count();
        assert!(central > n * 9 / 10, "{central} of {n} central");
        // Materials: floor checker, then the solid objects.
        assert!(matches!(s.materials[0].albedo, Albedo::Checker { .. }));
        let a = s.albedo(0, Vec3::new(0.5, 0.5, 0.0));
        let b2 = s.albedo(0, Vec3::new(1.5, 0.5, 0.0));
        assert_ne!(a, b2, "checker squares alternate");
        assert_eq!(s.albedo(3, Vec3::ZERO), [0.9, 0.5, 0.25]);
    }

    /// One row of the table of `shared/scenes/README.md`.
    struct Shared {
        file: &'static str,
        triangles: usize,
        min: [f64; 3],
        max: [f64; 3],
        /// Half a unit of the README's last printed digit (or rounding).
        tol: f64,
    }

    const fn row(
        file: &'static str,
        triangles: usize,
        min: [f64; 3],
        max: [f64; 3],
        tol: f64,
    ) -> Shared {
        Shared {
            file,
            triangles,
            min,
            max,
            tol,
        }
    }

    /// The README's table: triangles and bounds.
    const SHARED: [Shared; 7] = [
        row(
            "teapot.glb",
            992,
            [-16.07, -7.875, -10.0],
            [16.07, 7.875, 10.0],
            0.01,
        ),
        row(
            "bunny_lowres.glb",
            3_674,
            [-4.958, -0.003, -3.73],
            [4.949, 9.655, 3.811],
            0.002,
        ),
        row(
            "duck_4k.glb",
            4_212,
            [-0.962, 0.099, -0.539],
            [0.693, 1.64, 0.613],
            0.002,
        ),
        row(
            "armadillo_52k.glb",
            52_000,
            [-63.5, -54.2, -57.7],
            [63.52, 97.11, 57.72],
            0.06,
        ),
        row(
            "stanford_bunny_69k.glb",
            69_666,
            [-1.0, -0.991, -0.775],
            [1.0, 0.991, 0.775],
            0.002,
        ),
        row(
            "elephant_89k.glb",
            88_928,
            [-0.359, -0.499, -0.300],
            [0.358, 0.498, 0.300],
            0.002,
        ),
        row(
            "khronos_box_textured.glb",
            12,
            [-0.5, -0.5, -0.5],
            [0.5, 0.5, 0.5],
            1e-6,
        ),
    ];

    #[test]
    fn shared_scenes_load_with_their_counts_and_bounds() {
        let Some(files) = shared_scene_files_for_test() else {
            return;
        };
        for Shared {
            file: name,
            triangles,
            min,
            max,
            tol,
        } in SHARED
        {
            let Some(path) = files.iter().find(|p| p.ends_with(name)) else {
                panic!("{name} missing from the shared scenes");
            };
            let scene = SceneSource::parse(path.to_str().unwrap())
                .unwrap()
                .load()
                .unwrap();
            assert_eq!(scene.mesh.triangle_count(), triangles, "{name}");
            let b = scene.mesh.bounds();
            for a in 0..3 {
                assert!(
                    (b.min[a] - min[a]).abs() <= tol && (b.max[a] - max[a]).abs() <= tol,
                    "{name}: bounds {b:?}, README {min:?} .. {max:?}"
                );
            }
            assert!(scene.view.camera.eye.is_finite(), "{name}");
        }
    }
}
