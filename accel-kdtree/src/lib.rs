//! A SAH kD-tree: the seed's last step, where cells are no longer equal and
//! cubical but split space where the geometry is.
//!
//! **Cost model.** Each inner node splits its box by an axis-aligned plane.
//! The surface area heuristic (Goldsmith & Salmon 1987; MacDonald & Booth
//! 1990) prices a split by the chance that a ray through the node also
//! passes through each child (their surface area ratio) times the primitives
//! there; a node becomes a leaf where no split is cheaper than testing all its
//! primitives, or at pbrt's depth limit `8 + 1.3·log2 n`. The costs are
//! [`KdTreeParams`] (pbrt-v4's `KdTreeAggregate` costs with a measured empty
//! bonus and minimum split size; presets [`KdTreeParams::fast_build`],
//! [`KdTreeParams::best_traversal`] and [`KdTreeParams::pbrt`]).
//!
//! **Build.** The O(n log n) algorithm of Wald & Havran, "On building fast
//! kd-trees for ray tracing, and on doing that in O(N log N)" (IEEE RT 2006):
//! each primitive's bounds on each axis become *events* (start, end, or planar
//! for a flat extent), sorted once at the root; one linear sweep per axis
//! finds the cheapest plane; a split partitions the sorted lists stably
//! instead of sorting again. A cut of empty space hands its lists to the
//! child that keeps every primitive, with the planes and counts its sweep
//! recorded, so the child only prices those again for its narrower box. Splits are *perfect*: a primitive straddling the
//! plane is clipped to each child's box ([`accel_core::PrimitiveSet::clipped_bounds`],
//! conservative Sutherland–Hodgman-style clipping for triangles) before its
//! new events are made, so candidate planes hug the geometry inside the node.
//! Primitives lying *in* a candidate plane are counted apart and sent to the
//! cheaper side. Nodes over [`KdTreeParams::binned_above`] primitives (only
//! the top levels of large scenes) choose among evenly spaced planes with
//! the binned SAH instead (Wald, "On fast construction of SAH-based bounding
//! volume hierarchies", IEEE RT 2007), which spares the whole-scene sort; the
//! sweep takes over below. Subtrees are built in parallel with rayon. A naive O(n²)
//! builder with the same candidates and costs is kept as the reference the
//! sweep must match node for node. The fast build
//! ([`KdTreeParams::fast_build`], `binned_above` 0) bins every node and
//! makes no events at all (Shevtsov, Soupikov & Kapustin 2007 bin all the
//! way down as well): its nodes are runs of indices and clipped boxes,
//! partitioned in place.
//!
//! **Large primitives.** A plane in a node's face is a candidate where
//! primitives lie flat in that face (a *face cut*: they go to a flat child
//! there), so a wall on a node's boundary can be cut away from the space in
//! front of it. And a small dense part of a large sparse scene (a teapot in
//! a stadium: walls and floor straddle every plane around the teapot, so the
//! SAH finds no empty cut) is built as a tree of its own beside a tree of
//! the large primitives ([`KdTree::parts`]); queries walk both.
//!
//! **Layout.** 8-byte nodes as pbrt's `KdTreeNode` ([`KdNode`]): axis or leaf
//! flag in two bits, then a leaf's 30-bit primitive count or an inner node's
//! 29-bit above-child index and a flag for an empty below child, and a word
//! for the split position (`f32`) or an index into a table (`f64`); leaves
//! index one flat `u32` reference array (a one-primitive leaf holds it
//! inline). Empty leaves are not stored: the parent marks them, and the walk
//! never visits them.
//!
//! **Traversal.** Front to back with a small stack (pbrt's `KdTreeAggregate`
//! and Havran's thesis), made exact by treating the ray as the thin beam of
//! [`accel_core::TraversalRay`]: both children are visited wherever rounding
//! could put the ray on either side of a split, and a node is skipped only
//! once the best hit lies before its entry by more than the hit tolerance.
//! Every query answers bit for bit as [`accel_core::BruteForce`].
//!
//! **Bundles.** The bundle queries walk rays of one direction octant as
//! packets of eight (Wald, Slusallek, Benthin & Wagner, "Interactive
//! rendering with coherent ray tracing", Eurographics 2001): one node fetch
//! for the packet, each ray's plane band computed in SIMD lanes (AVX where
//! the CPU has AVX2, else SSE2) with the single walk's own arithmetic, and
//! each ray entering only the nodes its single walk enters, so every answer
//! is the single query's, bit for bit. The lanes' rays are prepared side by
//! side ([`accel_core::TraversalRay::lanes_with_wide_hits`]).
//!
//! ```
//! use accel_core::{Accelerator, BruteForce, Ray, TriangleMesh, Vec3};
//! use accel_kdtree::{KdTree, KdTreeParams};
//!
//! let mesh = TriangleMesh::new(
//!     vec![Vec3::new(0.0f64, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)],
//!     vec![[0, 1, 2]],
//! )?;
//! let tree = KdTree::with_params(&mesh, &KdTreeParams::best_traversal())?;
//! let ray = Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::new(0.0, 0.0, 1.0))?;
//! let hit = tree.intersect(&ray)?;
//! assert_eq!(hit, BruteForce::new(&mesh)?.intersect(&ray)?);
//! assert_eq!(hit.map(|h| h.t), Some(1.0));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! **Holding the primitives.** A [`KdTree`] borrows them ([`KdTree::new`],
//! `&'a P`) or shares them through an `Arc` ([`KdTree::shared`], a
//! [`SharedKdTree`] with no borrow), so an application can keep the tree beside its
//! mesh in one struct; the queries are the same code either way (accel-core's
//! crate docs, "Embedding"; `accel-kdtree/examples/embedded.rs`).

mod build;
mod bundle;
mod naive;
mod node;
mod params;
mod reach;
mod traverse;
mod tree;
mod validate;

pub use build::KdPart;
pub use node::KdNode;
pub use params::KdTreeParams;
pub use tree::{KdTree, SharedKdTree};
