//! Core types of the accelerator workspace.
//!
//! A ray query asks for the nearest primitive along a ray ([`Accelerator::intersect`]),
//! for any primitive at all ([`Accelerator::occluded`], shadow rays) or for every
//! primitive overlapping a box ([`Accelerator::query_region`]). This crate holds
//! what every accelerator shares:
//!
//! - [`Real`]: one generic implementation for `f32` and `f64`; [`Vec3`], [`Aabb`]
//!   (pbrt's vocabulary), [`Ray`] with its `[t_min, t_max]` and typed [`QueryError`]s;
//! - [`PrimitiveSet`] and [`Primitive`]: what an accelerator needs from the things
//!   it indexes (bounds, the ray test, an exact box-overlap test). Provided:
//!   [`TriangleMesh`] (shared vertices, the watertight test of Woop, Benthin &
//!   Wald, JCGT 2013, and the triangle–box test of Akenine-Möller 2001),
//!   [`Triangle`] and [`Sphere`];
//! - [`Accelerator`]: the query interface, and [`BruteForce`], the reference every
//!   other accelerator must match bit for bit (smallest `t`, ties to the lowest
//!   index, same `u`, `v`);
//! - [`TraversalRay`]: the per-ray tolerances that make traversal conservative
//!   (after pbrt's `gamma(n)` error bounds and Ize, "Robust BVH ray traversal", 2013);
//! - [`parts`]: the rule that builds a small dense part of a large sparse
//!   scene (a teapot in a stadium) apart from the large primitives around it,
//!   shared by the kD-tree and the octree.
//!
//! The speed-against-accuracy dials live here too: [`moller_trumbore`] (a
//! faster, non-watertight triangle test, as a [`PrimitiveSet`] wrapper) and
//! [`spawn`] (where secondary rays start: a fixed epsilon or pbrt-v4's
//! error-bound offset).
//!
//! **Embedding.** Every accelerator holds its primitives without copying
//! them: borrowed (`new`, `with_params`: `Grid<'a, T, P>`, tied to the
//! borrow), or shared through an [`Arc`](std::sync::Arc) (`shared`,
//! `shared_with_params`: `Grid<'static, T, P, Arc<P>>`, alias `SharedGrid<T,
//! P>`). A shared one keeps its primitives alive itself, so an application
//! can keep a mesh and its accelerator in one struct and return both from
//! the function that loaded them:
//!
//! ```
//! use accel_core::{Accelerator, BruteForce, Ray, SharedBruteForce, TriangleMesh, Vec3};
//! use std::sync::Arc;
//!
//! struct Scene {
//!     mesh: Arc<TriangleMesh<f32>>,
//!     accel: SharedBruteForce<f32, TriangleMesh<f32>>,
//! }
//!
//! fn load() -> Result<Scene, Box<dyn std::error::Error>> {
//!     let mesh = Arc::new(TriangleMesh::new(
//!         vec![[0.0f32, 0.0, 1.0].into(), [1.0, 0.0, 1.0].into(), [0.0, 1.0, 1.0].into()],
//!         vec![[0, 1, 2]],
//!     )?);
//!     let accel = BruteForce::shared(Arc::clone(&mesh))?;
//!     Ok(Scene { mesh, accel })
//! }
//!
//! let scene = load()?;
//! let ray = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.0, 0.0, 1.0))?;
//! assert_eq!(scene.accel.intersect(&ray)?.map(|h| h.prim), Some(0));
//! assert!(std::ptr::eq(scene.accel.primitives(), &*scene.mesh));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The extra type parameter (`S`, the holder: `&'a P` by default) is
//! resolved at compile time: a shared accelerator's queries run the same
//! code as a borrowing one's. (An enum of the two holders would have made
//! every accelerator over a `Sync` but not `Send` primitive set lose its
//! `Sync`, since `Arc<P>` is `Sync` only for `P: Send + Sync`.)
//!
//! **glam.** [`Vec3`] converts to and from the glam this crate depends on,
//! re-exported as [`glam`]; vectors of any other glam version convert
//! through arrays (`Vec3::from(v.to_array())`, `<[f32; 3]>::from(w)`).
//!
//! Scenes (generated meshes and rays, the camera, glTF loading, the ray
//! file) live in the `accel-scenes` crate; the `accel` crate puts every
//! structure and the chooser behind one dependency.
//!
//! ```
//! use accel_core::{Accelerator, BruteForce, Ray, TriangleMesh, Vec3};
//!
//! let mesh = TriangleMesh::new(
//!     vec![Vec3::new(0.0f32, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)],
//!     vec![[0, 1, 2]],
//! )?;
//! let brute = BruteForce::new(&mesh)?;
//! let ray = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.0, 0.0, 1.0))?;
//! let hit = brute.intersect(&ray)?.expect("the ray meets the triangle");
//! assert_eq!((hit.t, hit.prim), (1.0, 0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod aabb;
mod accelerator;
mod bounds;
mod brute;
mod error;
mod hit;
mod mailbox;
mod mesh;
pub mod moller_trumbore;
pub mod packed;
pub mod parts;
mod primitive;
mod ray;
mod real;
mod robust;
pub mod spawn;
mod sphere;
pub mod triangle;
mod triangle_box;
mod vec3;

/// The glam version [`Vec3`]'s `From` conversions are written for (0.34):
/// use it to name those types without depending on glam yourself. With a
/// different glam version, convert through arrays (`[T; 3]`), which every
/// version supports, since `From` holds for one version's types only.
pub use glam;

pub use aabb::Aabb;
pub use accelerator::{
    AccelStats, Accelerator, CostCounter, TraversalCounters, check_bundle, region_matches,
    region_search_box, validate_region,
};
pub use bounds::{SceneSurvey, bounds_survey, bounds_union, check_range, primitive_bounds};
pub use brute::{BruteForce, SharedBruteForce};
pub use error::BuildError;
pub use hit::{Hit, PrimHit, nearer};
pub use mailbox::Mailbox;
pub use mesh::{MeshError, TriangleMesh};
pub use moller_trumbore::{MollerTrumboreMesh, TriangleTest};
pub use primitive::{Primitive, PrimitiveSet};
pub use ray::{PreparedRay, QueryError, Ray};
pub use real::Real;
pub use robust::{TRAVERSAL_ROUNDINGS, TraversalRay, WideBeam, WideRay};
pub use sphere::Sphere;
pub use triangle::Triangle;
pub use vec3::Vec3;
