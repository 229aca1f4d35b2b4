//! The uniform grid: its parts, and its invariant checker.

use crate::blocks::Blocks;
use crate::build::{GridParams, build};
use crate::cells::GridGeometry;
use crate::csr::CellLists;
use accel_core::packed::PackedTriangles;
use accel_core::{AccelStats, BuildError, PrimitiveSet, Real};
use core::borrow::Borrow;
use core::marker::PhantomData;
use std::sync::Arc;

/// A uniform grid over a primitive set (see the crate docs).
///
/// It stores only `u32` indices into the primitives, which it holds as `S`:
/// borrowed (`&'a P`, the default: [`Grid::new`], [`Grid::with_params`]) or
/// shared ([`Arc<P>`]: [`Grid::shared`], [`Grid::shared_with_params`], a
/// [`SharedGrid`]), which lets an application keep the grid beside its
/// primitives in one struct (accel-core's crate docs, "Embedding").
#[derive(Debug)]
pub struct Grid<'a, T: Real, P: PrimitiveSet<T> + ?Sized, S = &'a P> {
    pub(crate) prims: S,
    pub(crate) borrows: PhantomData<&'a P>,
    pub(crate) geometry: GridGeometry<T>,
    pub(crate) cells: CellLists,
    /// Blocks of cells for skipping empty space ([`crate::blocks`]), on
    /// grids large enough for them to pay.
    pub(crate) blocks: Option<Blocks<T>>,
    /// The cells' triangles in packed blocks, when the layout asks for
    /// them and the primitives are watertight triangles.
    pub(crate) packed: Option<PackedTriangles<T>>,
    pub(crate) stats: AccelStats,
    /// True when the grid covers nothing (no primitive was placed).
    pub(crate) empty: bool,
}

impl<'a, T: Real, P: PrimitiveSet<T> + ?Sized> Grid<'a, T, P> {
    /// Builds a grid with default parameters (density 2).
    ///
    /// # Errors
    /// [`BuildError`] for non-finite primitives or an exceeded budget.
    pub fn new(prims: &'a P) -> Result<Self, BuildError> {
        Self::with_params(prims, &GridParams::default())
    }

    /// Builds a grid with the given parameters.
    ///
    /// # Errors
    /// [`BuildError`] for non-finite primitives, an invalid density or region,
    /// or an exceeded cell or reference budget.
    pub fn with_params(prims: &'a P, params: &GridParams<T>) -> Result<Self, BuildError> {
        Self::over(prims, params)
    }
}

/// A [`Grid`] that shares its primitives through an [`Arc`].
pub type SharedGrid<T, P> = Grid<'static, T, P, Arc<P>>;

impl<T: Real, P: PrimitiveSet<T> + ?Sized> Grid<'static, T, P, Arc<P>> {
    /// [`Grid::new`] over primitives it shares: the grid keeps them alive
    /// itself, so it can be kept beside them in one struct or returned from
    /// the function that loaded them.
    ///
    /// # Errors
    /// As [`Grid::new`].
    pub fn shared(prims: Arc<P>) -> Result<Self, BuildError> {
        Self::over(prims, &GridParams::default())
    }

    /// [`Grid::with_params`] over primitives it shares (see [`Grid::shared`]).
    ///
    /// # Errors
    /// As [`Grid::with_params`].
    pub fn shared_with_params(prims: Arc<P>, params: &GridParams<T>) -> Result<Self, BuildError> {
        Self::over(prims, params)
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> Grid<'_, T, P, S> {
    /// Builds a grid over the primitives `held` holds, and keeps them.
    fn over(held: S, params: &GridParams<T>) -> Result<Self, BuildError> {
        let built = build(held.borrow(), params)?;
        let grid = Self {
            prims: held,
            borrows: PhantomData,
            empty: built.cells.reference_count() == 0,
            geometry: built.geometry,
            cells: built.cells,
            blocks: built.blocks,
            packed: built.packed,
            stats: built.stats,
        };
        #[cfg(debug_assertions)]
        if let Err(e) = grid.validate() {
            panic!("grid invariant broken after build: {e}");
        }
        Ok(grid)
    }

    /// The grid's geometry (bounds, resolution, boundaries).
    #[must_use]
    pub fn geometry(&self) -> &GridGeometry<T> {
        &self.geometry
    }

    /// The cell lists.
    #[must_use]
    pub fn cells(&self) -> &CellLists {
        &self.cells
    }

    /// The blocks its walks skip empty space with, if it keeps them
    /// ([`GridParams::skip_empty_blocks`]).
    #[must_use]
    pub fn blocks(&self) -> Option<&Blocks<T>> {
        self.blocks.as_ref()
    }

    /// The indexed primitives.
    #[inline]
    #[must_use]
    pub fn primitives(&self) -> &P {
        self.prims.borrow()
    }

    /// Checks the structure's invariants: offsets monotone and covering the
    /// reference array, each cell's references ascending, unique, in range,
    /// and each referenced primitive's bounds touching the cell.
    ///
    /// # Errors
    /// A message naming the first broken invariant.
    pub fn validate(&self) -> Result<(), String> {
        let offsets = self.cells.offsets();
        if offsets.len() != self.geometry.cell_count() + 1 {
            return Err(format!(
                "{} offsets for {} cells",
                offsets.len(),
                self.geometry.cell_count()
            ));
        }
        if offsets[0] != 0 || *offsets.last().unwrap_or(&0) as usize != self.cells.reference_count()
        {
            return Err("offsets do not span the reference array".into());
        }
        if let Some(i) = offsets.windows(2).position(|w| w[0] > w[1]) {
            return Err(format!("offsets decrease at cell {i}"));
        }
        if let Some(blocks) = &self.blocks {
            blocks.check(&self.geometry, &self.cells)?;
        }
        let prims = self.primitives();
        let n = prims.len();
        for c in 0..self.geometry.cell_count() {
            let refs = self.cells.cell(c);
            if let Some(w) = refs.windows(2).find(|w| w[0] >= w[1]) {
                return Err(format!(
                    "cell {c}: references not strictly ascending at {w:?}"
                ));
            }
            let cell_box = self.geometry.cell_bounds(self.geometry.cell_coords(c));
            for &p in refs {
                if p as usize >= n {
                    return Err(format!(
                        "cell {c}: reference {p} out of range ({n} primitives)"
                    ));
                }
                if !prims.bounds(p as usize).overlaps(&cell_box) {
                    return Err(format!("cell {c}: primitive {p} lies outside the cell"));
                }
            }
        }
        Ok(())
    }
}
