//! Octree of nested uniform grids, built on `accel-grid`'s cell logic.
//!
//! The seed text ("Regular Grids", *Beyond Grids*) ends with nested grids: a
//! cell that holds too many objects becomes a grid of its own, recursively,
//! so dense regions get fine cells while empty space stays coarse. A uniform
//! grid fails on a small dense object in a large sparse scene (the "teapot in
//! a stadium": every ray near the teapot tests all of it); an [`Octree`]
//! refines exactly there.
//!
//! - **Build** ([`OctreeParams`]). The root grid covers the scene's bounds. By
//!   default it is coarser than a uniform grid: about `m³·N^(3/5)` cells, the
//!   top level Ize, Shirley & Parker ("Grid creation strategies for efficient
//!   ray tracing", IEEE RT 2007) derive for a grid with one level of nested
//!   grids below (`N^(3/(3+2d))` for `d` levels), since their analysis holds
//!   for primitives on surfaces or in clusters; a scene that fills its box
//!   gets the seed's uniform grid instead. Level by level, every cell holding
//!   more than a threshold of references becomes a child grid over the part
//!   of the cell its primitives occupy, with the seed's resolution rule for
//!   them (`s = cbrt(V/n)`, `n_i = trunc(m·w_i/s) + 1`, never finer than the
//!   primitives) or a fixed `2×2×2` ([`OctreeParams::classic`]). Primitives
//!   that span the cell (a floor under a dense object, a wall) stay in it,
//!   tested once there, as hierarchical grids keep large objects at coarse
//!   levels. A child is kept only if a surface-area estimate says it saves
//!   work and it separates the primitives, within a depth limit and a memory
//!   budget. Children of one level are built in parallel and accepted in cell
//!   order, so the result does not depend on the thread count.
//! - **Parts.** A small dense part of a large sparse scene (a teapot in a
//!   stadium whose walls and floor are a few huge triangles) gets a root grid
//!   of its own over its bounds, and the large primitives another over the
//!   scene ([`accel_core::parts`], the rule the kD-tree uses): the small
//!   part is refined as if it stood alone, not cut by the root cells of the
//!   whole scene, and rays that pass it by never enter its grids.
//! - **Reuse.** Every grid is an `accel-grid` [`GridGeometry`](accel_grid::cells::GridGeometry)
//!   (point-to-cell, cell bounds), filled by its CSR build
//!   ([`CellLists`](accel_grid::csr::CellLists), [`PrimitiveCells`](accel_grid::build::PrimitiveCells))
//!   and walked by its conservative 3D-DDA ([`BeamWalk`](accel_grid::dda::BeamWalk),
//!   Amanatides & Woo 1987). All grids' cells share one CSR array, a refined
//!   cell holding a link to its child after its own primitives.
//! - **Traversal**, front to back through the levels: a linked cell's child is
//!   walked from the beam's own entry into the child's box, under the same
//!   stopping rule as the grid (stop once the next cell lies past the best hit
//!   plus the hit tolerance), with one per-query mailbox across levels. A
//!   child's beam is as thin as the rounding of what it holds allows, so a
//!   small cluster in a huge scene is walked as finely as if it stood alone.
//!   A scene in parts is walked part by part, the later ones with the best
//!   hit of the earlier. Every query is bit-for-bit the answer of
//!   [`BruteForce`](accel_core::BruteForce).
//! - **Bundles**: packets of coherent rays walk the root grid slice by
//!   slice with `accel-grid`'s packets (Wald et al. 2006), each ray walking
//!   the nested grids below alone ([`Octree::bundles_by_packets`] says
//!   where).
//!
//! ```
//! use accel_core::{Accelerator, BruteForce, Ray, TriangleMesh, Vec3};
//! use accel_octree::{Octree, OctreeParams};
//!
//! let mesh = TriangleMesh::new(
//!     vec![Vec3::new(0.0f32, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)],
//!     vec![[0, 1, 2]],
//! )?;
//! let octree = Octree::with_params(&mesh, &OctreeParams::classic())?;
//! let ray = Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::new(0.0, 0.0, 1.0))?;
//! let hit = octree.intersect(&ray)?;
//! assert_eq!(hit, BruteForce::new(&mesh)?.intersect(&ray)?);
//! assert_eq!(hit.map(|h| h.t), Some(1.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **Holding the primitives.** A [`Octree`] borrows them ([`Octree::new`],
//! `&'a P`) or shares them through an `Arc` ([`Octree::shared`], a
//! [`SharedOctree`] with no borrow), so an application can keep the octree beside its
//! mesh in one struct; the queries are the same code either way (accel-core's
//! crate docs, "Embedding"; `accel-kdtree/examples/embedded.rs`).

mod build;
mod bundle;
mod node;
mod octree;
mod params;
mod stats;
mod traverse;
mod validate;

pub use node::{LevelStats, MAX_PRIMITIVES};
pub use octree::{Octree, SharedOctree};
pub use params::{MAX_DEPTH, OctreeParams, ResolutionRule};

/// The README's example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
