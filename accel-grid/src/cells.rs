//! Grid geometry: cell boundaries, point-to-cell, cell bounds, cell ranges.
//!
//! A [`GridGeometry`] divides a box into `nx × ny × nz` cells. Its boundaries
//! are computed once (`lo + k·w`, the last one exactly `hi`) and stored, and
//! every question about cells (which cell holds a point, which cells a box
//! overlaps, the bounds of a cell) is answered against those stored values.
//! Insertion and traversal therefore agree exactly on where cells begin and
//! end, whatever the rounding of `lo + k·w`.

use accel_core::{Aabb, Real, Vec3};

/// An inclusive box of cell coordinates `lo[a] ..= hi[a]` per axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CellBox {
    /// Lowest cell coordinate per axis.
    pub lo: [u32; 3],
    /// Highest cell coordinate per axis (inclusive).
    pub hi: [u32; 3],
}

impl CellBox {
    /// The box holding one cell.
    #[inline]
    #[must_use]
    pub const fn single(c: [u32; 3]) -> Self {
        Self { lo: c, hi: c }
    }

    /// Number of cells in the box.
    #[inline]
    #[must_use]
    pub fn len(&self) -> usize {
        (0..3)
            .map(|a| (self.hi[a] - self.lo[a]) as usize + 1)
            .product()
    }

    /// Always false: a cell box holds at least one cell.
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The cell coordinates in the box, x fastest.
    pub fn iter(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        (self.lo[2]..=self.hi[2]).flat_map(move |z| {
            (self.lo[1]..=self.hi[1])
                .flat_map(move |y| (self.lo[0]..=self.hi[0]).map(move |x| [x, y, z]))
        })
    }
}

/// The geometry of a uniform grid over a box.
#[derive(Clone, Debug, PartialEq)]
pub struct GridGeometry<T> {
    bounds: Aabb<T>,
    resolution: [u32; 3],
    /// `resolution[a] + 1` boundaries per axis, non-decreasing.
    boundaries: [Vec<T>; 3],
    /// `n / width` per axis (0 for a flat axis): the first guess of point-to-cell.
    scale: Vec3<T>,
}

impl<T: Real> GridGeometry<T> {
    /// The geometry of `resolution` cells over `bounds`.
    ///
    /// # Panics
    /// If `bounds` is empty or not finite, or a resolution is 0: the builders
    /// check both before they get here.
    #[must_use]
    pub fn new(bounds: Aabb<T>, resolution: [u32; 3]) -> Self {
        assert!(
            bounds.is_finite() && !bounds.is_empty(),
            "grid bounds must be finite and non-empty"
        );
        assert!(
            resolution.iter().all(|&n| n >= 1),
            "every axis needs a cell"
        );
        let boundaries = core::array::from_fn(|a| {
            let (lo, hi) = (bounds.min[a], bounds.max[a]);
            let n = resolution[a] as usize;
            let w = (hi - lo) / T::from_usize(n);
            let mut b: Vec<T> = (0..n).map(|k| lo + T::from_usize(k) * w).collect();
            b.push(hi);
            // Monotone by construction (rounding is monotone); a huge n with a
            // rounded-up w could still overshoot hi at the end, so clamp.
            for x in &mut b {
                *x = x.min(hi);
            }
            b
        });
        let mut scale = Vec3::ZERO;
        for a in 0..3 {
            let width = bounds.max[a] - bounds.min[a];
            scale[a] = if width > T::ZERO {
                T::from_usize(resolution[a] as usize) / width
            } else {
                T::ZERO
            };
        }
        Self {
            bounds,
            resolution,
            boundaries,
            scale,
        }
    }

    /// The grid of blocks of `2^shift` cells per axis over the same box (the
    /// last block of an axis may hold fewer): its boundaries are every
    /// `2^shift`-th of these and the last, the very same values, so a point
    /// lies in a block exactly when it lies in one of the block's cells.
    #[must_use]
    pub fn coarsened(&self, shift: u32) -> Self {
        let resolution = self.resolution.map(|n| n.div_ceil(1 << shift));
        let boundaries = core::array::from_fn(|a| {
            let fine = &self.boundaries[a];
            let mut b: Vec<T> = fine.iter().step_by(1 << shift).copied().collect();
            if b.len() == resolution[a] as usize {
                b.push(fine[fine.len() - 1]);
            }
            b
        });
        let mut scale = self.scale;
        for a in 0..3 {
            scale[a] = scale[a] * T::from_usize(resolution[a] as usize)
                / T::from_usize(self.resolution[a] as usize);
        }
        Self {
            bounds: self.bounds,
            resolution,
            boundaries,
            scale,
        }
    }

    /// The box the grid divides.
    #[inline]
    #[must_use]
    pub fn bounds(&self) -> &Aabb<T> {
        &self.bounds
    }

    /// Cells per axis.
    #[inline]
    #[must_use]
    pub fn resolution(&self) -> [u32; 3] {
        self.resolution
    }

    /// Total number of cells.
    #[inline]
    #[must_use]
    pub fn cell_count(&self) -> usize {
        self.resolution.iter().map(|&n| n as usize).product()
    }

    /// The `resolution[axis] + 1` boundaries along `axis`.
    #[inline]
    #[must_use]
    pub fn boundaries(&self, axis: usize) -> &[T] {
        &self.boundaries[axis]
    }

    /// The linear index of cell `c` (x fastest).
    #[inline]
    #[must_use]
    pub fn linear_index(&self, c: [u32; 3]) -> usize {
        let [nx, ny, _] = self.resolution;
        c[0] as usize + nx as usize * (c[1] as usize + ny as usize * c[2] as usize)
    }

    /// The cell coordinates of a linear index.
    #[inline]
    #[must_use]
    pub fn cell_coords(&self, index: usize) -> [u32; 3] {
        let [nx, ny, _] = self.resolution.map(|n| n as usize);
        [
            (index % nx) as u32,
            ((index / nx) % ny) as u32,
            (index / (nx * ny)) as u32,
        ]
    }

    /// The closed box of cell `c`, from the stored boundaries.
    #[inline]
    #[must_use]
    pub fn cell_bounds(&self, c: [u32; 3]) -> Aabb<T> {
        let b = &self.boundaries;
        Aabb {
            min: Vec3::new(
                b[0][c[0] as usize],
                b[1][c[1] as usize],
                b[2][c[2] as usize],
            ),
            max: Vec3::new(
                b[0][c[0] as usize + 1],
                b[1][c[1] as usize + 1],
                b[2][c[2] as usize + 1],
            ),
        }
    }

    /// Calls `f` with the linear index of every cell of `range`, x fastest
    /// (as [`CellBox::iter`] and [`GridGeometry::linear_index`], in plain
    /// loops; a range of one cell, a walk's usual step, without them).
    #[inline]
    pub fn for_each_cell_index(&self, range: &CellBox, mut f: impl FnMut(usize)) {
        if range.lo == range.hi {
            f(self.linear_index(range.lo));
            return;
        }
        let [nx, ny, _] = self.resolution.map(|n| n as usize);
        let [lo, hi] = [range.lo, range.hi].map(|c| c.map(|i| i as usize));
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                let row = nx * (y + ny * z);
                for x in lo[0]..=hi[0] {
                    f(row + x);
                }
            }
        }
    }

    /// Calls `f` with the linear index and the closed box
    /// ([`GridGeometry::cell_bounds`]) of every cell of `range`, x fastest.
    #[inline]
    pub fn for_each_cell_box(&self, range: &CellBox, mut f: impl FnMut(usize, Aabb<T>)) {
        let [nx, ny, _] = self.resolution.map(|n| n as usize);
        let lo = range.lo.map(|i| i as usize);
        let span = |a: usize| &self.boundaries[a][lo[a]..=range.hi[a] as usize + 1];
        let (xs, ys, zs) = (span(0), span(1), span(2));
        for (z, zb) in (lo[2]..).zip(zs.windows(2)) {
            for (y, yb) in (lo[1]..).zip(ys.windows(2)) {
                let row = nx * (y + ny * z);
                for (x, xb) in (lo[0]..).zip(xs.windows(2)) {
                    let b = Aabb {
                        min: Vec3::new(xb[0], yb[0], zb[0]),
                        max: Vec3::new(xb[1], yb[1], zb[1]),
                    };
                    f(row + x, b);
                }
            }
        }
    }

    /// The cell along `axis` that holds coordinate `origin + rel`, clamped to
    /// the grid: the largest `i` with `boundary[i] − origin ≤ rel`.
    ///
    /// Comparing offsets from `origin` rather than absolute coordinates keeps
    /// small offsets exact even far from the coordinate origin (the traversal
    /// passes the ray origin here). A point on a boundary belongs to the upper
    /// cell.
    ///
    /// Always inlined: a walk's restart locates the beam on each axis
    /// (the octree's every child grid, the grid after each pass over empty
    /// blocks), and a call per axis, which the inliner kept, cost the
    /// octree's teapot in a stadium camera rays 4% of their speed.
    #[inline(always)]
    #[must_use]
    pub fn axis_cell_relative(&self, axis: usize, origin: T, rel: T) -> u32 {
        let b = &self.boundaries[axis];
        let last = self.resolution[axis] - 1;
        let mut i = self.guess_cell(axis, origin, rel);
        // The guess is off by at most a cell or two near boundaries; fix it
        // against the stored values.
        while i > 0 && rel < b[i as usize] - origin {
            i -= 1;
        }
        while i < last && rel >= b[i as usize + 1] - origin {
            i += 1;
        }
        i
    }

    /// The first guess of [`GridGeometry::axis_cell_relative`]: the cell
    /// that `origin + rel` would lie in if the boundaries were exactly
    /// evenly spaced, clamped to the grid. Off by a cell or two near
    /// boundaries; callers check it against the stored boundaries.
    #[inline(always)]
    #[must_use]
    pub fn guess_cell(&self, axis: usize, origin: T, rel: T) -> u32 {
        let last = self.resolution[axis] - 1;
        let guess = ((origin - self.boundaries[axis][0]) + rel) * self.scale[axis];
        // Truncation is the floor of a positive guess, without the libm call
        // that `floor` becomes on baseline x86-64.
        if guess > T::ZERO {
            (guess.to_i64_saturating().min(i64::from(last))) as u32
        } else {
            0
        }
    }

    /// The cell along `axis` holding coordinate `x` (clamped).
    #[inline]
    #[must_use]
    pub fn axis_cell(&self, axis: usize, x: T) -> u32 {
        self.axis_cell_relative(axis, T::ZERO, x)
    }

    /// The cell holding point `p` (clamped to the grid).
    #[inline]
    #[must_use]
    pub fn point_to_cell(&self, p: Vec3<T>) -> [u32; 3] {
        [
            self.axis_cell(0, p.x),
            self.axis_cell(1, p.y),
            self.axis_cell(2, p.z),
        ]
    }

    /// Every cell whose closed box overlaps the closed box `b`; `None` when
    /// `b` is empty or lies outside the grid.
    #[must_use]
    pub fn cells_overlapping(&self, b: &Aabb<T>) -> Option<CellBox> {
        if b.is_empty() || !b.overlaps(&self.bounds) {
            return None;
        }
        let (x, y, z) = (
            self.axis_span(0, self.scale.x, b.min.x, b.max.x),
            self.axis_span(1, self.scale.y, b.min.y, b.max.y),
            self.axis_span(2, self.scale.z, b.min.z, b.max.z),
        );
        Some(CellBox {
            lo: [x.0, y.0, z.0],
            hi: [x.1, y.1, z.1],
        })
    }

    /// The cells along `axis` whose closed extent meets `[min, max]`: from
    /// the highest cell whose lower boundary lies below `min` (or the first)
    /// to the highest whose lower boundary is at most `max`. One guess from
    /// `scale` per end, fixed against the stored boundaries; the caller has
    /// checked that `[min, max]` meets the grid (`max ≥ b[0]`).
    ///
    /// Each fix-up loop tests only what can stop it: the guess is nearly
    /// always right, so each loop's one test is predictable, where a second
    /// condition on the span's width (is `lo` below `hi`?) was not. `lo` is
    /// clamped to `hi` afterwards, the same cell as clamping it first.
    #[inline(always)]
    fn axis_span(&self, axis: usize, scale: T, min: T, max: T) -> (u32, u32) {
        let b = self.boundaries[axis].as_slice();
        let last = self.resolution[axis] - 1;
        let first = b[0];
        let guess = |x: T| {
            let g = (x - first) * scale;
            // A select, not a branch: truncation of `+0` is the first cell.
            let g = if g > T::ZERO { g } else { T::ZERO };
            g.to_i64_saturating().min(i64::from(last)) as u32
        };
        let mut hi = guess(max);
        // Stops at 0 at the latest, since `max ≥ b[0]`.
        while max < b[hi as usize] {
            hi -= 1;
        }
        while hi < last && max >= b[hi as usize + 1] {
            hi += 1;
        }
        let mut lo = guess(min);
        while lo > 0 && b[lo as usize] >= min {
            lo -= 1;
        }
        while lo < last && b[lo as usize + 1] < min {
            lo += 1;
        }
        (lo.min(hi), hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn geom() -> GridGeometry<f64> {
        GridGeometry::new(
            Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(3.0, 3.0, 2.5)),
            [4, 3, 1],
        )
    }

    #[test]
    fn boundaries_and_cell_bounds() {
        let g = geom();
        assert_eq!(g.boundaries(0), &[-1.0, 0.0, 1.0, 2.0, 3.0]);
        assert_eq!(g.boundaries(2), &[2.0, 2.5]);
        assert_eq!(g.cell_count(), 12);
        let c = g.cell_bounds([1, 2, 0]);
        assert_eq!(
            c,
            Aabb::new(Vec3::new(0.0, 2.0, 2.0), Vec3::new(1.0, 3.0, 2.5))
        );
        for i in 0..g.cell_count() {
            assert_eq!(g.linear_index(g.cell_coords(i)), i);
        }
    }

    #[test]
    fn points_on_boundaries_go_up_and_outside_points_clamp() {
        let g = geom();
        assert_eq!(g.point_to_cell(Vec3::new(0.0, 1.0, 2.0)), [1, 1, 0]);
        assert_eq!(g.point_to_cell(Vec3::new(-0.0001, 0.9999, 2.5)), [0, 0, 0]);
        assert_eq!(g.point_to_cell(Vec3::new(3.0, 3.0, 9.0)), [3, 2, 0]);
        assert_eq!(g.point_to_cell(Vec3::new(-1e30, 1e30, -5.0)), [0, 2, 0]);
    }

    #[test]
    fn relative_lookup_is_exact_far_from_the_origin() {
        // Cells of width 1/8 at y ≈ 1e4 in f32, where absolute coordinates are
        // spaced about 1e-3 apart; offsets from a nearby origin keep 1e-7.
        let lo = 1.0e4f32;
        let g = GridGeometry::new(
            Aabb::new(Vec3::new(0.0, lo, 0.0), Vec3::new(1.0, lo + 1.0, 1.0)),
            [1, 8, 1],
        );
        let origin = lo + 0.5;
        // 1.2e-7 below the boundary lo + 1/8: cell 0.
        assert_eq!(g.axis_cell_relative(1, origin, -0.375_000_1), 0);
        assert_eq!(g.axis_cell_relative(1, origin, -0.375), 1);
        // The absolute coordinate rounds onto the boundary and lands in cell 1.
        assert_eq!(g.axis_cell(1, origin + -0.375_000_1), 1);
        assert_eq!(g.axis_cell_relative(1, origin, 0.0), 4);
    }

    #[test]
    fn overlapping_cells_are_closed() {
        let g = geom();
        // Touches the boundary x = 1 from below: cells 1 and 2 share it.
        let b = Aabb::new(Vec3::new(0.5, 0.5, 2.1), Vec3::new(1.0, 0.5, 2.2));
        assert_eq!(
            g.cells_overlapping(&b),
            Some(CellBox {
                lo: [1, 0, 0],
                hi: [2, 0, 0]
            })
        );
        // Starts on the boundary y = 2: cells 1 and 2 along y.
        let b = Aabb::new(Vec3::new(0.5, 2.0, 2.1), Vec3::new(0.6, 2.5, 2.2));
        assert_eq!(g.cells_overlapping(&b).unwrap().lo[1], 1);
        let outside = Aabb::new(Vec3::new(5.0, 0.0, 2.0), Vec3::new(6.0, 1.0, 2.0));
        assert_eq!(g.cells_overlapping(&outside), None);
        let all = g.cells_overlapping(g.bounds()).unwrap();
        assert_eq!(all.len(), g.cell_count());
        assert_eq!(all.iter().count(), g.cell_count());
    }

    /// The cells along one axis whose closed extent meets `[min, max]`, by
    /// scanning every cell: the definition `cells_overlapping` must meet.
    fn scanned_span(bounds: &[f32], min: f32, max: f32) -> Option<(u32, u32)> {
        let meets: Vec<u32> = (0..bounds.len() - 1)
            .filter(|&i| bounds[i] <= max && bounds[i + 1] >= min)
            .map(|i| i as u32)
            .collect();
        Some((*meets.first()?, *meets.last()?))
    }

    proptest::proptest! {
        /// Boxes anywhere in, across and outside grids of every shape, with
        /// ends on, just beside and between boundaries, far from the origin
        /// too: the range is exactly the cells a scan finds.
        #[test]
        fn overlapping_cells_are_the_scanned_ones(
            lo in proptest::array::uniform3(-1.0e6f32..1.0e6),
            size in proptest::array::uniform3(1.0e-3f32..1.0e3),
            res in proptest::array::uniform3(1u32..40),
            ends in proptest::array::uniform3((-0.2f32..1.2, 0.0f32..0.6)),
            snap in proptest::array::uniform3(0u8..4),
        ) {
            let min = Vec3::new(lo[0], lo[1], lo[2]);
            let grid = Aabb::new(min, min + Vec3::new(size[0], size[1], size[2]));
            let g = GridGeometry::new(grid, res);
            let mut bmin = Vec3::ZERO;
            let mut bmax = Vec3::ZERO;
            for a in 0..3 {
                let (at, len) = ends[a];
                let bs = g.boundaries(a);
                let width = grid.max[a] - grid.min[a];
                let mut x0 = grid.min[a] + at * width;
                // Some ends sit on a boundary or one ulp beside it.
                let k = ((at.clamp(0.0, 1.0) * res[a] as f32) as usize).min(bs.len() - 1);
                match snap[a] {
                    1 => x0 = bs[k],
                    2 => x0 = bs[k].next_up(),
                    3 => x0 = bs[k].next_down(),
                    _ => {}
                }
                bmin[a] = x0;
                bmax[a] = x0 + len * width;
            }
            let b = Aabb::new(bmin, bmax);
            let scanned: Option<Vec<(u32, u32)>> = (0..3)
                .map(|a| scanned_span(g.boundaries(a), b.min[a], b.max[a]))
                .collect();
            let got = g.cells_overlapping(&b);
            match scanned {
                None => proptest::prop_assert!(got.is_none()),
                Some(spans) => {
                    let want = CellBox {
                        lo: [spans[0].0, spans[1].0, spans[2].0],
                        hi: [spans[0].1, spans[1].1, spans[2].1],
                    };
                    proptest::prop_assert_eq!(got, Some(want));
                }
            }
        }
    }

    #[test]
    fn flat_axis_has_one_cell() {
        let g = GridGeometry::new(
            Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0)),
            [2, 2, 1],
        );
        assert_eq!(g.point_to_cell(Vec3::new(0.7, 0.2, 0.0)), [1, 0, 0]);
        assert_eq!(g.point_to_cell(Vec3::new(0.7, 0.2, -3.0)), [1, 0, 0]);
        assert_eq!(g.cell_bounds([1, 1, 0]).min.z, 0.0);
    }
}
