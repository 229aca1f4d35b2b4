//! The layout: grids in one array, all their cells in one CSR array.
//!
//! Every grid of the octree (the root first, then level by level in the order
//! their parent cells were split) is a [`Node`]: an `accel-grid`
//! [`GridGeometry`] and the index of its first cell in one [`CellLists`](accel_grid::csr::CellLists)
//! shared by all grids. A cell's entry in that array is the ascending list of
//! the primitives it holds, optionally followed by one link to a child grid:
//! the child's index with [`CHILD`] set (so it sorts last). A leaf holds no
//! link; a refined cell holds a link and the primitives that span it (which
//! would cross every child cell, so they are tested once here instead).
//! Primitive indices therefore stay below `2^31`. An empty cell costs one
//! offset, a link one more entry, a grid its geometry (`n + 1` boundaries per
//! axis).

use accel_core::Aabb;
use accel_grid::cells::GridGeometry;
use accel_grid::csr::CellLists;

/// The bit that marks a cell entry as a link to a child grid.
pub(crate) const CHILD: u32 = 1 << 31;

/// The most primitives an octree indexes (`2^31`): a cell entry with the
/// top bit set is a link to a child grid, so primitive indices leave it clear.
pub const MAX_PRIMITIVES: usize = CHILD as usize;

/// One grid of the octree.
#[derive(Clone, Debug)]
pub(crate) struct Node<T> {
    /// Its box, boundaries and resolution.
    pub(crate) geometry: GridGeometry<T>,
    /// Its box and the bounds of every primitive referenced in it or below
    /// it: the rounding of every hit its walk must catch is relative to the
    /// distance from the ray origin to this box (see [`crate::traverse`]).
    pub(crate) reach: Aabb<T>,
    /// The index of its first cell in the shared cell lists.
    pub(crate) base: u32,
    /// Its level: 0 for the root.
    pub(crate) level: u32,
}

impl<T> Node<T> {
    /// The index in the shared cell lists of the cell with linear index `cell`.
    #[inline]
    pub(crate) fn cell_index(&self, cell: usize) -> usize {
        self.base as usize + cell
    }

    /// Whether the cell with linear index `cell` holds nothing in the shared
    /// cell lists `cells`: no primitive and no child grid.
    #[inline(always)]
    pub(crate) fn holds_nothing(&self, cells: &CellLists, cell: usize) -> bool {
        // Two offsets, without slicing the references.
        let (offsets, i) = (cells.offsets(), self.cell_index(cell));
        offsets[i] == offsets[i + 1]
    }
}

/// What a cell entry holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Entry<'a> {
    /// Primitive indices, ascending.
    pub(crate) prims: &'a [u32],
    /// The index of the child grid refining the cell, if any.
    pub(crate) child: Option<usize>,
}

/// Reads a cell entry.
#[inline]
pub(crate) fn entry(refs: &[u32]) -> Entry<'_> {
    match refs.split_last() {
        Some((&last, prims)) if last & CHILD != 0 => Entry {
            prims,
            child: Some((last & !CHILD) as usize),
        },
        _ => Entry {
            prims: refs,
            child: None,
        },
    }
}

/// Shape figures of one level of the octree (level 0 is the root).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LevelStats {
    /// Grids at this level.
    pub grids: usize,
    /// Their cells.
    pub cells: usize,
    /// Cells not refined by a child grid.
    pub leaves: usize,
    /// Of those, the ones holding no primitive.
    pub empty_leaves: usize,
    /// Primitive references in all cells (a refined cell keeps the
    /// primitives that span it).
    pub references: usize,
    /// The most references in one cell.
    pub max_leaf_references: usize,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entries_tell_links_from_primitives() {
        let leaf = |prims| Entry { prims, child: None };
        assert_eq!(
            entry(&[CHILD | 5]),
            Entry {
                prims: &[],
                child: Some(5)
            }
        );
        assert_eq!(
            entry(&[2, 9, CHILD]),
            Entry {
                prims: &[2, 9],
                child: Some(0)
            }
        );
        assert_eq!(entry(&[CHILD - 1]), leaf(&[CHILD - 1]));
        assert_eq!(entry(&[]), leaf(&[]));
        assert_eq!(entry(&[3, 4]), leaf(&[3, 4]));
    }
}
