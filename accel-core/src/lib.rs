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
//! With the `scenes` feature, [`scenes`] generates the workspace's benchmark
//! scenes and rays; with `gltf`, [`gltf_scene`] loads glTF 2.0 files.
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

#[cfg(feature = "gltf")]
pub mod gltf_scene;
#[cfg(feature = "scenes")]
pub mod scenes;

pub use aabb::Aabb;
pub use accelerator::{
    AccelStats, Accelerator, CostCounter, TraversalCounters, region_matches, region_search_box,
    validate_region,
};
pub use bounds::{SceneSurvey, bounds_survey, bounds_union, check_range, primitive_bounds};
pub use brute::BruteForce;
pub use error::BuildError;
pub use hit::{Hit, PrimHit, nearer};
pub use mailbox::Mailbox;
pub use mesh::{MeshError, TriangleMesh};
pub use moller_trumbore::{MollerTrumboreMesh, TriangleTest};
pub use primitive::{Primitive, PrimitiveSet};
pub use ray::{PreparedRay, QueryError, Ray};
pub use real::Real;
pub use robust::{TRAVERSAL_ROUNDINGS, TraversalRay};
pub use sphere::Sphere;
pub use triangle::Triangle;
pub use vec3::Vec3;
