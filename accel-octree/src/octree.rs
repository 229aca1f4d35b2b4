//! The octree: its parts, construction and accessors.

use crate::build::build;
use crate::node::entry;
use crate::node::{LevelStats, Node};
use crate::params::OctreeParams;
use crate::stats::{accel_stats, level_stats};
use accel_core::packed::PackedTriangles;
use accel_core::{Aabb, AccelStats, BuildError, PrimitiveSet, Real};
use accel_grid::cells::GridGeometry;
use accel_grid::csr::CellLists;
use core::borrow::Borrow;
use core::marker::PhantomData;
use std::sync::Arc;
use std::time::Instant;

/// An octree of nested uniform grids over a primitive set (see the crate docs).
///
/// It stores only `u32` indices into the primitives, which it holds as `S`:
/// borrowed (`&'a P`, the default: [`Octree::new`], [`Octree::with_params`])
/// or shared ([`Arc<P>`]: [`Octree::shared`], [`Octree::shared_with_params`],
/// a [`SharedOctree`]), which lets an application keep the octree beside its
/// primitives in one struct (accel-core's crate docs, "Embedding").
#[derive(Debug)]
pub struct Octree<'a, T: Real, P: PrimitiveSet<T> + ?Sized, S = &'a P> {
    pub(crate) prims: S,
    pub(crate) borrows: PhantomData<&'a P>,
    /// The grids: the root of each part first, then every other grid after
    /// its parent.
    pub(crate) nodes: Vec<Node<T>>,
    /// How many parts ([`accel_core::parts`]): the first `parts` grids are
    /// their roots.
    pub(crate) parts: usize,
    /// The bounds of everything indexed: the union of the roots' boxes.
    pub(crate) bounds: Aabb<T>,
    /// Every grid's cells: primitive lists and child links.
    pub(crate) cells: CellLists,
    /// The cells' triangles in packed blocks, when the layout asks for
    /// them and the primitives are watertight triangles.
    pub(crate) packed: Option<PackedTriangles<T>>,
    pub(crate) levels: Vec<LevelStats>,
    pub(crate) params: OctreeParams,
    pub(crate) stats: AccelStats,
    /// True when the octree holds no reference (nothing to hit).
    pub(crate) empty: bool,
}

impl<'a, T: Real, P: PrimitiveSet<T> + ?Sized> Octree<'a, T, P> {
    /// Builds an octree with the default parameters ([`OctreeParams::default`]).
    ///
    /// # Errors
    /// [`BuildError`] for non-finite primitives, more than
    /// [`crate::MAX_PRIMITIVES`] of them, or a root grid over the memory budget.
    pub fn new(prims: &'a P) -> Result<Self, BuildError> {
        Self::with_params(prims, &OctreeParams::default())
    }

    /// Builds an octree with the given parameters.
    ///
    /// # Errors
    /// [`BuildError::InvalidParameter`] for a parameter out of range, and the
    /// errors of [`Octree::new`].
    ///
    /// # Panics
    /// In debug builds, if [`Octree::validate`] finds a broken invariant (a bug).
    pub fn with_params(prims: &'a P, params: &OctreeParams) -> Result<Self, BuildError> {
        Self::over(prims, params)
    }
}

/// An [`Octree`] that shares its primitives through an [`Arc`].
pub type SharedOctree<T, P> = Octree<'static, T, P, Arc<P>>;

impl<T: Real, P: PrimitiveSet<T> + ?Sized> Octree<'static, T, P, Arc<P>> {
    /// [`Octree::new`] over primitives it shares: the octree keeps them
    /// alive itself, so it can be kept beside them in one struct or returned
    /// from the function that loaded them.
    ///
    /// # Errors
    /// As [`Octree::new`].
    pub fn shared(prims: Arc<P>) -> Result<Self, BuildError> {
        Self::over(prims, &OctreeParams::default())
    }

    /// [`Octree::with_params`] over primitives it shares (see
    /// [`Octree::shared`]).
    ///
    /// # Errors
    /// As [`Octree::with_params`].
    ///
    /// # Panics
    /// As [`Octree::with_params`].
    pub fn shared_with_params(prims: Arc<P>, params: &OctreeParams) -> Result<Self, BuildError> {
        Self::over(prims, params)
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> Octree<'_, T, P, S> {
    /// Builds an octree over the primitives `held` holds, and keeps them.
    fn over(held: S, params: &OctreeParams) -> Result<Self, BuildError> {
        let start = Instant::now();
        let prims = held.borrow();
        let built = build(prims, params)?;
        let levels = level_stats(&built.nodes, &built.cells);
        let packed = PackedTriangles::new(
            params.layout,
            prims,
            built.cells.refs(),
            (0..built.cells.cell_count()).map(|c| {
                let (start, refs) = built.cells.cell_at(c);
                (start, entry(refs).prims.len())
            }),
        );
        let bytes = built.nodes.capacity() * size_of::<Node<T>>()
            + built
                .nodes
                .iter()
                .map(|n| {
                    (0..3)
                        .map(|a| size_of_val(n.geometry.boundaries(a)))
                        .sum::<usize>()
                })
                .sum::<usize>()
            + built.cells.bytes()
            + packed.as_ref().map_or(0, PackedTriangles::memory_bytes)
            + levels.capacity() * size_of::<LevelStats>();
        let stats = accel_stats(
            prims.len(),
            start.elapsed(),
            bytes,
            &levels,
            built.parts,
            built.nodes[0].geometry.resolution(),
            built.capped,
        );
        let bounds = built.nodes[..built.parts]
            .iter()
            .fold(Aabb::empty(), |b, n| b.union(n.geometry.bounds()));
        let octree = Self {
            prims: held,
            borrows: PhantomData,
            parts: built.parts,
            bounds,
            empty: built.cells.reference_count() == 0,
            nodes: built.nodes,
            cells: built.cells,
            packed,
            levels,
            params: params.clone(),
            stats,
        };
        #[cfg(debug_assertions)]
        if let Err(e) = octree.validate() {
            panic!("octree invariant broken after build: {e}");
        }
        Ok(octree)
    }

    /// The geometry of the root grid (of the first part, when the scene is
    /// built in parts: see [`Octree::part_roots`]).
    #[must_use]
    pub fn root_geometry(&self) -> &GridGeometry<T> {
        &self.nodes[0].geometry
    }

    /// The geometry of each part's root grid. A small dense part of a large
    /// sparse scene (a teapot in a stadium) is built apart from the large
    /// primitives around it ([`accel_core::parts`]): the small part's root
    /// comes first, then the large part's over the whole scene. Nearly every
    /// scene is one part.
    pub fn part_roots(&self) -> impl ExactSizeIterator<Item = &GridGeometry<T>> + '_ {
        self.nodes[..self.parts].iter().map(|n| &n.geometry)
    }

    /// The number of grids (the root and every child).
    #[must_use]
    pub fn grid_count(&self) -> usize {
        self.nodes.len()
    }

    /// Shape figures per level, root first: grids, cells, leaves, references.
    #[must_use]
    pub fn levels(&self) -> &[LevelStats] {
        &self.levels
    }

    /// The parameters it was built with.
    #[must_use]
    pub fn params(&self) -> &OctreeParams {
        &self.params
    }

    /// The indexed primitives.
    #[inline]
    #[must_use]
    pub fn primitives(&self) -> &P {
        self.prims.borrow()
    }
}
