//! Region-query box descriptions.

use crate::Surface;
use crate::rays::{RayContext, surface_box};
use accel_core::{Aabb, Real, Vec3};

/// A region-query box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BoxSpec {
    /// Corners at unit coordinates of the frame (any order).
    Random([f64; 3], [f64; 3]),
    /// Like `Random`, but of zero thickness along `axis`.
    Flat([f64; 3], [f64; 3], usize),
    /// Half-size `10^size_exp` scene sizes around a vertex (a point box
    /// below about −20).
    AroundVertex(usize, i32),
    /// Exactly a primitive's bounds.
    PrimitiveBounds(usize),
    /// Exactly a cell of a probe grid.
    Cell(usize, usize),
    /// Inverted (`min > max` on one axis): an empty box.
    Inverted([f64; 3], [f64; 3], usize),
    /// The whole frame.
    Frame,
}

impl BoxSpec {
    /// The box, in the scene's precision.
    #[must_use]
    pub fn resolve<T: Real>(&self, ctx: &RayContext<T>) -> Aabb<T> {
        let lm = &ctx.landmarks;
        match *self {
            Self::Random(a, b) => Aabb::new(lm.in_frame(a), lm.in_frame(b)),
            Self::Flat(a, b, axis) => {
                let mut b = b;
                b[axis % 3] = a[axis % 3];
                Aabb::new(lm.in_frame(a), lm.in_frame(b))
            }
            Self::AroundVertex(v, size_exp) => {
                let c = lm.vertex(v).cast::<f64>();
                let h = Vec3::splat(lm.size() * 10f64.powi(size_exp));
                Aabb::new((c - h).cast(), (c + h).cast())
            }
            Self::PrimitiveBounds(i) => match lm.surface(i) {
                Some(Surface::Triangle(v)) => Aabb::from_points(v),
                Some(s) => surface_box(&s).cast(),
                None => lm.frame().cast(),
            },
            Self::Cell(grid, cell) => match ctx.grid(grid) {
                Some(g) => g.cell_bounds(g.cell_coords(cell % g.cell_count())),
                None => lm.frame().cast(),
            },
            Self::Inverted(a, b, axis) => {
                let mut r = Aabb::new(lm.in_frame(a), lm.in_frame(b));
                let axis = axis % 3;
                if r.min[axis] == r.max[axis] {
                    r.max[axis] = r.min[axis].next_down();
                } else {
                    core::mem::swap(&mut r.min[axis], &mut r.max[axis]);
                }
                r
            }
            Self::Frame => lm.frame().cast(),
        }
    }
}
