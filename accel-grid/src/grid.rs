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
/// primitives in one struct (accel-core's crate docs, "Embedding"). A
/// scene with a small dense part in a large sparse space, or a floor of many
/// flat primitives, is gridded in parts ([`GridParams::parts`]): a uniform
/// grid per part, walked one after the other.
#[derive(Debug)]
pub struct Grid<'a, T: Real, P: PrimitiveSet<T> + ?Sized, S = &'a P> {
    pub(crate) prims: S,
    pub(crate) borrows: PhantomData<&'a P>,
    /// The first part: the whole grid of a scene in one part (nearly every
    /// scene), kept inline so its queries load nothing more.
    pub(crate) first: GridPart<T>,
    /// The other parts, if any.
    pub(crate) rest: Vec<GridPart<T>>,
    pub(crate) stats: AccelStats,
    /// True when the grid covers nothing (no primitive was placed).
    pub(crate) empty: bool,
}

/// One uniform grid of a [`Grid`]: its geometry, its cell lists, and what
/// its walks use to go faster.
#[derive(Debug)]
pub struct GridPart<T: Real> {
    pub(crate) geometry: GridGeometry<T>,
    pub(crate) cells: CellLists,
    /// Blocks of cells for skipping empty space ([`crate::blocks`]), on
    /// grids large enough for them to pay.
    pub(crate) blocks: Option<Blocks<T>>,
    /// The cells' triangles in packed blocks, when the layout asks for
    /// them and the primitives are watertight triangles.
    pub(crate) packed: Option<PackedTriangles<T>>,
}

impl<T: Real> GridPart<T> {
    /// The part's geometry (bounds, resolution, boundaries).
    #[must_use]
    pub fn geometry(&self) -> &GridGeometry<T> {
        &self.geometry
    }

    /// The part's cell lists (global primitive indices).
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
        let mut parts = built.parts.into_iter();
        let first = parts.next().expect("a build makes at least one part");
        let rest: Vec<GridPart<T>> = parts.collect();
        let grid = Self {
            prims: held,
            borrows: PhantomData,
            empty: first.cells.reference_count() == 0 && rest.is_empty(),
            first,
            rest,
            stats: built.stats,
        };
        #[cfg(debug_assertions)]
        if let Err(e) = grid.validate() {
            panic!("grid invariant broken after build: {e}");
        }
        Ok(grid)
    }

    /// The first part's geometry (bounds, resolution, boundaries): the
    /// whole grid's, unless it is in parts ([`Grid::parts`]).
    #[must_use]
    pub fn geometry(&self) -> &GridGeometry<T> {
        &self.first.geometry
    }

    /// The first part's cell lists.
    #[must_use]
    pub fn cells(&self) -> &CellLists {
        &self.first.cells
    }

    /// The first part's empty-space blocks, if it keeps them
    /// ([`GridParams::skip_empty_blocks`]).
    #[must_use]
    pub fn blocks(&self) -> Option<&Blocks<T>> {
        self.first.blocks.as_ref()
    }

    /// Every part, in the order queries walk them: one for most scenes; a
    /// small dense part, then the large primitives around it; or the rest,
    /// then a floor ([`GridParams::parts`]).
    pub fn parts(&self) -> impl Iterator<Item = &GridPart<T>> {
        core::iter::once(&self.first).chain(&self.rest)
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
        let prims = self.primitives();
        let mut seen = vec![false; prims.len()];
        for (k, part) in self.parts().enumerate() {
            part.validate(prims, &mut seen)
                .map_err(|e| format!("part {k}: {e}"))?;
        }
        Ok(())
    }
}

impl<T: Real> GridPart<T> {
    /// [`Grid::validate`] for one part; `seen` marks the primitives
    /// referenced so far, which no other part may reference.
    fn validate<P: PrimitiveSet<T> + ?Sized>(
        &self,
        prims: &P,
        seen: &mut [bool],
    ) -> Result<(), String> {
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
        let n = prims.len();
        let mut mine = Vec::new();
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
                mine.push(p);
            }
        }
        mine.sort_unstable();
        mine.dedup();
        if let Some(&p) = mine.iter().find(|&&p| seen[p as usize]) {
            return Err(format!("primitive {p} is in two parts"));
        }
        for p in mine {
            seen[p as usize] = true;
        }
        Ok(())
    }
}
