//! Exact ray-query acceleration structures behind one dependency.
//!
//! Three structures and the reference answer the same queries (nearest hit,
//! any hit, every primitive in a box) through one trait, [`Accelerator`],
//! and return **bit for bit the same nearest hit as brute force** (smallest
//! `t`, ties to the lowest primitive index, same barycentrics), in `f32` and
//! `f64`:
//!
//! - [`Grid`] (`accel-grid`): the uniform grid, walked by the 3D-DDA of
//!   Amanatides & Woo (1987), its resolution after Cleary & Wyvill's rule
//!   (about `m³·n` cells);
//! - [`Octree`] (`accel-octree`): an octree of nested grids, for dense
//!   clusters in empty space (a teapot in a stadium), refining crowded
//!   cells into grids of their own (after Jevans & Wyvill 1989);
//! - [`KdTree`] (`accel-kdtree`): the SAH kD-tree built in `O(n log n)`
//!   (Wald & Havran 2006), with pbrt's parameters as a preset;
//! - [`BruteForce`] (`accel-core`): every primitive for every ray.
//!
//! Triangles use the watertight test of Woop, Benthin & Wald (2013), and
//! traversal is conservative at every boundary (after Ize 2013), so no ray
//! leaks through a shared edge or vertex.
//!
//! This crate adds what a user needs to pick one: [`AnyAccelerator`] (one
//! type for any of them), [`AccelConfig`] with the structures' presets by
//! name (`"kdtree fast-build"`.parse()), [`build_config`], and
//! [`choose()`], which picks the structure and its parameters for a scene
//! and a ray budget from a short timed probe and says why
//! ([`choose_with_probe`] takes your own probe rays). The scenes crate is
//! here as [`scenes`]: generated meshes, a camera and its framing, glTF
//! loading (feature `gltf`, on by default), the binary ray file.
//!
//! ```
//! use accel::scenes::{Camera, Y_UP, Z_UP, uv_sphere};
//! use accel::{Accelerator, TriangleMesh, Vec3, choose};
//! use std::path::Path;
//!
//! // A glTF file if there is one (y up), else a generated sphere (z up).
//! let path = Path::new("scene.glb");
//! let (mesh, up): (TriangleMesh<f64>, _) = if path.exists() {
//!     (accel::scenes::gltf::load(path)?.mesh, Y_UP)
//! } else {
//!     (uv_sphere(Vec3::new(0.0, 0.0, 0.0), 1.0, 20_000), Z_UP)
//! };
//!
//! // Choose for a 64×64 view: the structure comes back built.
//! let (width, height) = (64, 64);
//! let (accel, reason) = choose(&mesh, u64::from(width * height))?;
//! println!("{}: {reason}", accel.kind());
//!
//! // Trace it.
//! let camera = Camera::frame(&mesh.bounds(), Camera::DEFAULT_SIDE, up);
//! let mut hits = 0;
//! for ray in camera.rays::<f64>(width, height) {
//!     hits += usize::from(accel.intersect(&ray)?.is_some());
//! }
//! assert!(hits > 0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! To depend on one structure only, depend on its crate; `accel-core`
//! alone holds the types and the trait for bringing your own primitive or
//! structure.

mod any;
pub mod choose;
mod config;

pub use any::AnyAccelerator;
pub use choose::{Choice, ChooseError, choose, choose_with_probe};
pub use config::{
    AccelConfig, AccelError, AccelKind, GRID_LAYOUT, KDTREE_PRESETS, OCTREE_PRESETS, UnknownAccel,
    build, build_config, build_config_within, kdtree_preset, octree_preset,
};

pub use accel_core::{
    Aabb, AccelStats, Accelerator, BruteForce, BuildError, Hit, Primitive, PrimitiveSet,
    QueryError, Ray, Real, SharedBruteForce, Sphere, TraversalCounters, Triangle, TriangleMesh,
    Vec3,
};
pub use accel_grid::{Grid, GridParams, SharedGrid};
pub use accel_kdtree::{KdTree, KdTreeParams, SharedKdTree};
pub use accel_octree::{Octree, OctreeParams, SharedOctree};

/// The crates behind the facade, for what it does not name.
pub use {accel_core, accel_grid, accel_kdtree, accel_octree};

/// Scenes: generated meshes and rays, the camera and its framing, glTF
/// loading, the ray file, rays aimed at shared edges (the `accel-scenes`
/// crate).
pub use accel_scenes as scenes;

/// The guide's library example, compiled and run with the crate's tests.
#[cfg(doctest)]
#[doc = include_str!("../../docs/guide.md")]
struct GuideDoctests;
