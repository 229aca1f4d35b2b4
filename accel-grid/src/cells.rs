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

    /// The cell along `axis` that holds coordinate `origin + rel`, clamped to
    /// the grid: the largest `i` with `boundary[i] − origin ≤ rel`.
    ///
    /// Comparing offsets from `origin` rather than absolute coordinates keeps
    /// small offsets exact even far from the coordinate origin (the traversal
    /// passes the ray origin here). A point on a boundary belongs to the upper
    /// cell.
    #[inline]
    #[must_use]
    pub fn axis_cell_relative(&self, axis: usize, origin: T, rel: T) -> u32 {
        let b = &self.boundaries[axis];
        let last = self.resolution[axis] - 1;
        let guess = ((origin - b[0]) + rel) * self.scale[axis];
        // Truncation is the floor of a positive guess, without the libm call
        // that `floor` becomes on baseline x86-64.
        let mut i = if guess > T::ZERO {
            (guess.to_i64_saturating().min(last as i64)) as u32
        } else {
            0
        };
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
        let mut lo = [0u32; 3];
        let mut hi = [0u32; 3];
        for a in 0..3 {
            let bounds = &self.boundaries[a];
            // Highest cell whose lower boundary is at or below b.max.
            hi[a] = self.axis_cell(a, b.max[a]);
            // Lowest cell whose upper boundary is at or above b.min: the cell
            // holding b.min, or below it when b.min sits on its lower boundary.
            let mut l = self.axis_cell(a, b.min[a]);
            while l > 0 && bounds[l as usize] >= b.min[a] {
                l -= 1;
            }
            lo[a] = l.min(hi[a]);
        }
        Some(CellBox { lo, hi })
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
