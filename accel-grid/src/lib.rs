//! A uniform grid: the seed's regular grid, made exact and fast.
//!
//! **Build.** The grid spans the union of the primitives' bounds (or a
//! user-given region). Its resolution follows the seed: with `n` objects and
//! extents `w`, `s = cbrt(wx·wy·wz/n)` and `n_i = trunc(m·w_i/s) + 1`, about
//! `m³·n` cells (density `m = 2` by default, the seed's 8 cells per object),
//! extended to flat and nearly flat scenes ([`resolution`]). Cells are stored
//! compactly ([`csr::CellLists`]: one offset per cell, one reference array),
//! built from one parallel pass (rayon) that records each primitive's cells,
//! which are then counted per cell and placed without atomics. A triangle is
//! placed only in the cells it truly overlaps (Akenine-Möller's triangle–box
//! test), not in every cell of its bounding box. A grid too large for the
//! caches also keeps a bit per cell that says whether it holds anything
//! ([`build::OCCUPIED_BITS_MIN_CELLS`]), so that its walks pass empty cells
//! without reading their offsets.
//!
//! **Traversal.** A slab test clips the ray to the grid; the walk starts in the
//! cell holding the origin or the entry point and steps with the 3D-DDA of
//! Amanatides & Woo (1987, "A fast voxel traversal algorithm for ray tracing").
//! The walk is conservative ([`dda::BeamWalk`]): it visits every cell within a
//! rounding allowance of the ray, so rays along cell faces, edges and through
//! corners lose nothing. A hit found in a cell may lie beyond it (the seed's
//! early-termination trap): the walk stops only once it has passed the best
//! hit. A per-query mailbox (no shared state) tests each primitive once.
//! A large grid with much empty space also keeps a flag per block of 4×4×4
//! cells ([`blocks`]): once the beam lies in an empty cell of an empty block,
//! a second walk over the blocks passes the empty ones a block at a time and
//! hands back to the cell walk just before the next block that holds
//! something (macrocells, as in Parker et al. 1998, "Interactive ray tracing
//! for isosurface rendering"). The answers are the same; the terrain's camera
//! rays open 6 cells each instead of 41.
//!
//! **Parts.** One grid over a small dense object in a large sparse scene
//! (a teapot in a stadium) makes cells as wide as the stadium asks, and the
//! teapot falls into one or a few of them; a floor of many triangles makes
//! every ray leaving it walk the floor's cells. So, as the octree and the
//! kD-tree do ([`accel_core::parts`]), such a scene is gridded in parts:
//! the dense primitives and the large ones, or the rest and the floor,
//! each get a uniform grid of their own, and a query walks them one after
//! the other with the best hit so far (a floor's flat box first tested with
//! the thin beam of [`accel_core::TraversalRay::with_wide_hits`], which a
//! ray leaving the floor misses). Whether a scene splits is read from the
//! same pass that unites the primitives' bounds
//! ([`accel_core::bounds_survey`]), so dense scenes pay nothing for it.
//! [`GridParams::parts`] `= false` gives the seed's single grid.
//!
//! **Bundles.** Coherent rays asked together (`intersect_bundle`,
//! `occluded_bundle`) walk the grid in packets of up to 64, slice by slice
//! of cells across their main axis (Wald et al. 2006, "Ray tracing animated
//! scenes using coherent grid traversal"), each ray still answered bit for
//! bit as alone ([`bundle`]).
//!
//! The cell logic ([`cells`], [`dda`], [`csr`], [`resolution`]) and the
//! packets' slice walk ([`bundle`]) are public: the octree of nested grids
//! is built from them.
//!
//! ```
//! use accel_core::{Accelerator, BruteForce, Ray, TriangleMesh, Vec3};
//! use accel_grid::Grid;
//!
//! let mesh = TriangleMesh::new(
//!     vec![Vec3::new(0.0f64, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)],
//!     vec![[0, 1, 2]],
//! )?;
//! let grid = Grid::new(&mesh)?;
//! let ray = Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::new(0.0, 0.0, 1.0))?;
//! let hit = grid.intersect(&ray)?;
//! assert_eq!(hit, BruteForce::new(&mesh)?.intersect(&ray)?);
//! assert_eq!(hit.map(|h| h.t), Some(1.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **Holding the primitives.** A [`Grid`] borrows them ([`Grid::new`],
//! `&'a P`) or shares them through an `Arc` ([`Grid::shared`], a
//! [`SharedGrid`] with no borrow), so an application can keep the grid beside its
//! mesh in one struct; the queries are the same code either way (accel-core's
//! crate docs, "Embedding"; `accel-kdtree/examples/embedded.rs`).

pub mod blocks;
pub mod build;
pub mod bundle;
pub mod cells;
pub mod csr;
pub mod dda;
mod grid;
pub mod resolution;
mod traverse;

pub use build::{DEFAULT_LAYOUT, GridParams};

/// `accel-core`, for the paths of [`bundle_queries_by_packets`].
#[doc(hidden)]
pub use accel_core as __core;
pub use grid::{Grid, GridPart, SharedGrid};

/// The README's library example, compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
struct ReadmeDoctests;
