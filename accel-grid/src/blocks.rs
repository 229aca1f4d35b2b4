//! Empty-space skipping: blocks of cells, and walks that pass over the empty
//! ones a block at a time.
//!
//! A large grid's walk spends most of its steps in empty cells (the 1M
//! terrain's camera rays: 40 cells per ray, 95% of the grid empty). Blocks of
//! `2^shift` cells per axis, each with a flag that says whether any of its
//! cells holds a reference, let a walk that has settled in an empty cell of
//! an empty block hand over to a second [`BeamWalk`] over the blocks, which
//! steps block by block until it opens one that holds something, and then
//! resume the cell walk just before that block: the macrocells of Parker et
//! al. (1998, "Interactive ray tracing for isosurface rendering"), with the
//! beam of [`TraversalRay`] on both levels.
//!
//! Why no cell is lost: the cell walk hands over only while its beam lies
//! in one cell `c` alone, at a parameter `t` past that moment and before its
//! next crossing ([`BeamWalk::settled`], with margins for rounding). Every
//! cell the beam touches after `t` lies in a block the beam touches after
//! `t`, and the block walk visits those in order; the cells of the empty
//! ones hold nothing. When it opens a block that holds something (or one
//! its beam enters while still in the last, where the walk would turn wide
//! over two blocks: [`BeamWalk::pass_thin`] keeps to thin steps, in
//! registers), at a computed crossing `t_e`, the cell walk starts again at
//! `t_e − gamma(SETTLED_MARGIN)·|t_e|`, at or before the moment, exactly,
//! that the beam first touched that block or any block opened after it, and
//! from there visits every cell the beam touches. A cell visited twice only
//! costs time: the mailbox skips most of its primitives, and a primitive
//! tested again gives the same answer.

use crate::cells::{CellBox, GridGeometry};
use crate::csr::CellLists;
use crate::dda::{BeamWalk, SETTLED_MARGIN, Step};
use accel_core::{Real, TraversalRay};
use rayon::prelude::*;

/// The blocks of a grid and which of them hold something.
#[derive(Clone, Debug)]
pub struct Blocks<T> {
    /// The grid of blocks over the grid's box.
    geometry: GridGeometry<T>,
    /// `log2` of the cells per block along each axis.
    shift: u32,
    /// Per block (x fastest), whether any of its cells holds a reference.
    occupied: Vec<bool>,
}

impl<T: Real> Blocks<T> {
    /// The blocks of `2^shift` cells per axis over `geometry`, whose cells
    /// are `cells`; made in one parallel pass over runs of cells
    /// ([`CellLists::any_in_run`]: two offsets, or a few occupancy bits).
    #[must_use]
    pub fn new(geometry: &GridGeometry<T>, cells: &CellLists, shift: u32) -> Self {
        let coarse = geometry.coarsened(shift);
        let [nx, ny, nz] = geometry.resolution().map(|n| n as usize);
        let [bx, by, _] = coarse.resolution().map(|n| n as usize);
        let side = 1usize << shift;
        let mut occupied = vec![false; coarse.cell_count()];
        // One task per layer of blocks: the cells of layer `kz` are the
        // z-slices `kz·side ..` of the fine grid. Each block is asked of
        // each of its rows of cells.
        occupied
            .par_chunks_mut(bx * by)
            .enumerate()
            .for_each(|(kz, layer)| {
                for z in kz * side..((kz + 1) * side).min(nz) {
                    for y in 0..ny {
                        let row = nx * (y + ny * z);
                        let blocks = &mut layer[bx * (y >> shift)..][..bx];
                        for (k, block) in blocks.iter_mut().enumerate() {
                            let x = k << shift;
                            *block |= cells.any_in_run(row + x, side.min(nx - x));
                        }
                    }
                }
            });
        Self {
            geometry: coarse,
            shift,
            occupied,
        }
    }

    /// The share of blocks that hold nothing.
    #[must_use]
    pub fn empty_share(&self) -> f64 {
        let empty = self.occupied.iter().filter(|&&o| !o).count();
        empty as f64 / self.occupied.len().max(1) as f64
    }

    /// The bytes the blocks take.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.occupied.capacity()
            + (0..3)
                .map(|a| size_of_val(self.geometry.boundaries(a)))
                .sum::<usize>()
    }

    /// Checks that the blocks are those of `geometry` and that each is flagged
    /// exactly when one of its cells in `cells` holds a reference.
    ///
    /// # Errors
    /// A message naming the first block that is wrong.
    pub fn check(&self, geometry: &GridGeometry<T>, cells: &CellLists) -> Result<(), String> {
        if self.geometry != geometry.coarsened(self.shift) {
            return Err("blocks are not the grid's, coarsened".into());
        }
        let mut want = vec![false; self.occupied.len()];
        for c in 0..geometry.cell_count() {
            if !cells.cell(c).is_empty() {
                let cell = geometry.cell_coords(c);
                want[self.geometry.linear_index(cell.map(|i| i >> self.shift))] = true;
            }
        }
        match want.iter().zip(&self.occupied).position(|(w, o)| w != o) {
            Some(b) => Err(format!(
                "block {:?} flagged {} but {}",
                self.geometry.cell_coords(b),
                self.occupied[b],
                if want[b] {
                    "holds references"
                } else {
                    "is empty"
                }
            )),
            None => Ok(()),
        }
    }

    /// The grid of blocks.
    #[must_use]
    pub fn geometry(&self) -> &GridGeometry<T> {
        &self.geometry
    }

    /// Whether the block holding cell `c` holds nothing.
    #[inline]
    #[must_use]
    pub fn is_empty_around(&self, c: [u32; 3]) -> bool {
        !self.occupied[self.geometry.linear_index(c.map(|i| i >> self.shift))]
    }

    /// `log2` of the cells per block along each axis.
    #[inline]
    pub(crate) fn shift(&self) -> u32 {
        self.shift
    }

    /// Whether any block of layer `layer` across axis `k` (`axes[0]`)
    /// under the rectangle `hull` (lowest and highest coordinates on
    /// `axes[1]` and `axes[2]`) holds something.
    #[inline]
    pub(crate) fn any_occupied_under(&self, axes: [usize; 3], layer: u32, hull: &[T; 4]) -> bool {
        let [k, u, v] = axes;
        let g = &self.geometry;
        let mut range = CellBox::single([0; 3]);
        (range.lo[k], range.hi[k]) = (layer, layer);
        (range.lo[u], range.hi[u]) = (g.axis_cell(u, hull[0]), g.axis_cell(u, hull[1]));
        (range.lo[v], range.hi[v]) = (g.axis_cell(v, hull[2]), g.axis_cell(v, hull[3]));
        self.any_occupied(&range)
    }

    /// Whether any block of `range` (block coordinates) holds something.
    #[inline]
    fn any_occupied(&self, range: &CellBox) -> bool {
        let mut any = false;
        self.geometry
            .for_each_cell_index(range, |b| any |= self.occupied[b]);
        any
    }

    /// After `walk` (over `geometry`, the cells these blocks group) opened
    /// an empty cell: if its beam has settled in that cell and the cell's
    /// block is empty, passes over the empty blocks ahead (up to `limit`)
    /// and restarts the cell walk before the next block that holds
    /// something, returning what it opens first ([`Step::End`] when nothing
    /// is left up to `limit`). `None` when the walk should simply step on.
    /// Always inlined, so that the step it returns stays in registers.
    #[inline(always)]
    pub fn pass_empty(
        &self,
        walk: &mut BeamWalk<'_, T>,
        geometry: &GridGeometry<T>,
        tr: &TraversalRay<T>,
        limit: T,
    ) -> Option<Step> {
        let (cell, from) = walk.settled()?;
        if !self.is_empty_around(cell) {
            return None;
        }
        // Restarted here, not in `pass_from`: a `Step` returned from a call
        // went through memory in 4-byte stores that the caller read back in
        // 16-byte loads straddling them (no store forwarding).
        Some(match self.pass_from(walk, tr, from, limit) {
            Some(restart) => Step::Cells(walk.restart(geometry, restart)),
            None => Step::End,
        })
    }

    /// [`Blocks::pass_empty`] from parameter `from`, at which the beam lies
    /// in the walk's lead cell alone, in an empty block: the parameter at
    /// which to restart the cell walk, `None` when nothing is left up to
    /// `limit`.
    #[inline(never)]
    fn pass_from(
        &self,
        walk: &BeamWalk<'_, T>,
        tr: &TraversalRay<T>,
        from: T,
        limit: T,
    ) -> Option<T> {
        let blocks = walk.settled_block(&self.geometry, self.shift, from);
        let t = blocks.pass_thin(limit, &self.occupied)?;
        Some((t - T::gamma(SETTLED_MARGIN) * t.abs()).max(tr.t_start))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::{Aabb, Vec3};

    /// Lists with one reference in each cell of `full` (linear indices).
    fn lists(cell_count: usize, full: &[usize]) -> CellLists {
        CellLists::from_cells((0..cell_count).map(|c| {
            if full.contains(&c) {
                vec![0u32]
            } else {
                vec![]
            }
        }))
        .unwrap()
    }

    #[test]
    fn blocks_share_the_boundaries_of_the_cells() {
        let g = GridGeometry::new(
            Aabb::new(Vec3::new(-1.0f64, 0.0, 0.1), Vec3::new(2.0, 1.0, 0.7)),
            [9, 8, 1],
        );
        let b = g.coarsened(2);
        assert_eq!(b.resolution(), [3, 2, 1]);
        for a in 0..3 {
            let fine = g.boundaries(a);
            let expected: Vec<f64> = (0..=b.resolution()[a] as usize)
                .map(|k| fine[(4 * k).min(fine.len() - 1)])
                .collect();
            assert_eq!(b.boundaries(a), &expected[..], "axis {a}");
        }
        // Point location agrees: a point lies in block k exactly when it lies
        // in one of block k's cells.
        for i in 0..=300 {
            let x = -1.0 + 3.0 * f64::from(i) / 300.0;
            assert_eq!(b.axis_cell(0, x), g.axis_cell(0, x) / 4, "x = {x}");
        }
    }

    #[test]
    fn a_block_is_flagged_exactly_when_a_cell_of_it_holds_something() {
        let g = GridGeometry::new(
            Aabb::new(Vec3::new(0.0f64, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0)),
            [9, 5, 6],
        );
        let full = [
            g.linear_index([0, 0, 0]),
            g.linear_index([8, 4, 5]),
            g.linear_index([4, 3, 2]),
        ];
        let cells = lists(g.cell_count(), &full);
        let blocks = Blocks::new(&g, &cells, 2);
        assert_eq!(blocks.geometry().resolution(), [3, 2, 2]);
        let flagged: Vec<[u32; 3]> = (0..blocks.geometry().cell_count())
            .filter(|&b| blocks.occupied[b])
            .map(|b| blocks.geometry().cell_coords(b))
            .collect();
        assert_eq!(flagged, vec![[0, 0, 0], [1, 0, 0], [2, 1, 1]]);
        assert!(blocks.check(&g, &cells).is_ok());
        assert!(blocks.is_empty_around([8, 0, 0]));
        assert!(!blocks.is_empty_around([5, 2, 3]));
        // A flag that lies is caught.
        let mut wrong = blocks.clone();
        wrong.occupied[1] = false;
        assert!(
            wrong
                .check(&g, &cells)
                .unwrap_err()
                .contains("holds references")
        );
    }
}
