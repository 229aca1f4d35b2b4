//! Scenes for the accelerator workspace: what the structures are built over
//! and which rays they answer, in one place, so that a figure quoted for
//! "the 100k soup" means the same triangles in every benchmark, test and
//! render.
//!
//! - [`generated`]: deterministic meshes ([`uv_sphere`], [`torus`],
//!   [`box_mesh`], [`terrain`], [`random_soup`], [`teapot_in_stadium`],
//!   [`flat_field`], ...) and rays ([`random_rays`]), from [`SplitMix64`]
//!   (Steele, Lea & Flood 2014), whose sequence is specified; the named
//!   benchmark scenes are [`GeneratedScene`];
//! - [`camera`]: a pinhole [`Camera`] and the one framing rule,
//!   [`Camera::frame`];
//! - [`gltf`] (feature `gltf`, on by default): glTF 2.0 files as one
//!   triangle mesh with the file's cameras, the shared test scenes
//!   (`ACCEL_SCENES`), and the benches' scene list (`gltf::bench_scenes`);
//! - [`rayfile`]: the binary ray file of the design (`RAYS`, version 1,
//!   eight `f32` per ray), for cross-checking against other tools;
//! - [`aimed`]: rays aimed at shared edges and vertices of closed meshes,
//!   which a watertight triangle test (Woop, Benthin & Wald 2013) never
//!   lets through;
//! - [`TraceDriver`]: what the profiling examples share;
//! - `strategies` (feature `proptest`): the proptest strategies every
//!   structure crate's equivalence suite draws its scenes and rays from.
//!
//! It depends on `accel-core` only, so every structure crate can use it
//! as a dev-dependency.
//!
//! ```
//! use accel_core::{Accelerator, BruteForce};
//! use accel_scenes::{Camera, GeneratedScene, Z_UP, uv_sphere};
//!
//! let mesh = uv_sphere([0.0, 0.0, 0.0].into(), 1.0, 500);
//! let camera = Camera::frame(&mesh.bounds(), Camera::DEFAULT_SIDE, Z_UP);
//! let brute = BruteForce::new(&mesh)?;
//! let centre: accel_core::Ray<f64> = camera.ray_through(32.0, 32.0, 64, 64);
//! assert!(brute.intersect(&centre)?.is_some());
//! assert_eq!(GeneratedScene::from_name("soup_100k"), Some(GeneratedScene::Soup100k));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod aimed;
pub mod camera;
pub mod generated;
#[cfg(feature = "gltf")]
pub mod gltf;
pub mod rayfile;
#[cfg(feature = "proptest")]
pub mod strategies;
mod trace_driver;

pub use camera::{Camera, Y_UP, Z_UP};
pub use generated::{
    FlatFieldSpec, GeneratedScene, SplitMix64, box_mesh, flat_field, random_rays, random_soup,
    rays_leaving_the_floor, sphere_in_tiled_box, teapot_in_stadium, terrain, torus, uv_sphere,
};
pub use trace_driver::TraceDriver;
