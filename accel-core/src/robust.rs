//! Robustness in one place: the per-ray tolerances of conservative traversal.
//!
//! Cell walks and split-plane tests round, and so does the primitive test that
//! reports a hit. To stay bit-for-bit equal to brute force, a traversal must
//! visit every cell or node that a hit *might* lie in once rounding is counted.
//! [`TraversalRay`] treats the ray as a thin box-shaped beam of half-width
//! `delta` (an L∞ "fat ray"): every structure visits all cells within `delta`
//! of the ray, and may stop only once no unvisited cell can hold a hit within
//! `t_tol` of the best one (the seed's early-termination trap, made robust).
//!
//! `delta` bounds the rounding of the primitive tests (whose errors are relative
//! to the distance between the ray origin and the geometry, as in pbrt's
//! `gamma(n)` analysis and Ize's "Robust BVH ray traversal", 2013) and of the
//! traversal's own crossing parameters, which are relative to `|t|·|d|`, itself
//! bounded by the same distance inside the structure's bounds.

use crate::real::greater;
use crate::{Aabb, PreparedRay, Ray, Real, Vec3};

/// The number of roundings that [`TraversalRay::delta`] allows for, as pbrt's
/// `gamma(n)`: generous, since a larger beam only costs a few extra cells.
pub const TRAVERSAL_ROUNDINGS: u32 = 64;

/// A validated ray prepared for conservative traversal of a structure whose
/// primitives lie inside `bounds`.
#[derive(Clone, Copy, Debug)]
pub struct TraversalRay<T> {
    /// The ray with its primitive-test constants.
    pub prepared: PreparedRay<T>,
    /// Half-width of the beam, in scene units.
    pub delta: T,
    /// The parameter tolerance of a hit: `delta / max|d_i|`.
    pub t_tol: T,
    /// First parameter to walk: the beam's entry into the bounds, no earlier
    /// than `t_min − t_tol`; always finite.
    pub t_start: T,
    /// Last parameter to walk: the beam's exit, no later than `t_max + t_tol`;
    /// always finite.
    pub t_end: T,
}

impl<T: Real> TraversalRay<T> {
    /// Prepares `ray` (already validated) against `bounds`; `None` when the
    /// interval is empty or the beam misses the bounds, so nothing can be hit.
    #[inline]
    #[must_use]
    pub fn new(ray: &Ray<T>, bounds: &Aabb<T>) -> Option<Self> {
        if ray.is_empty_interval() || bounds.is_empty() {
            return None;
        }
        let o = ray.origin;
        let d = ray.direction;
        // Plain selects (no NaN here: the ray is finite, the bounds too, and
        // their differences at worst infinite).
        let largest = |v: Vec3<T>| greater(greater(v.x, v.y), v.z);
        let reach = greater(
            largest((bounds.min - o).abs()),
            largest((bounds.max - o).abs()),
        );
        let delta = T::gamma(TRAVERSAL_ROUNDINGS) * reach;
        let t_tol = delta / largest(d.abs()) * (T::ONE + T::gamma(2));
        // The reciprocal once, for the slabs here and the walk's planes.
        let inv_dir = PreparedRay::reciprocal(d);
        let (t0, t1) = bounds.beam_interval_inv(o, d, inv_dir, delta)?;
        // Finite even for an unbounded interval whose beam entry or exit
        // overflows (a tiny direction): no hit has an infinite parameter, and
        // walks place the beam at `d·t_start`, where 0·∞ would be NaN.
        let t_start = t0.max(ray.t_min - t_tol).max(-T::MAX);
        let t_end = t1.min(ray.t_max + t_tol).min(T::MAX);
        if !(t_start <= t_end) {
            return None;
        }
        Some(Self {
            prepared: PreparedRay::with_reciprocal(*ray, inv_dir),
            delta,
            t_tol,
            t_start,
            t_end,
        })
    }

    /// The ray.
    #[inline]
    #[must_use]
    pub fn ray(&self) -> &Ray<T> {
        &self.prepared.ray
    }

    /// The parameter interval in which the beam touches the plane
    /// `x[axis] = s`, widened by rounding; `(−∞, +∞)` for a beam parallel to the
    /// plane and within `delta` of it, and an empty interval (`lo > hi`) for one
    /// parallel and farther away. A kD-tree visits the near child up to `hi`
    /// and the far child from `lo`.
    #[inline]
    #[must_use]
    pub fn plane_band(&self, axis: usize, s: T) -> (T, T) {
        let o = self.prepared.ray.origin[axis];
        let d = self.prepared.ray.direction[axis];
        if d == T::ZERO {
            return if (o - s).abs() <= self.delta {
                (T::NEG_INFINITY, T::INFINITY)
            } else {
                (T::INFINITY, T::NEG_INFINITY)
            };
        }
        // The offset from the origin first: `s − delta` alone would round
        // the beam's width away wherever delta is below the rounding unit of
        // `s` (coordinates far from zero, origins close to the plane).
        let a = ((s - o) - self.delta) / d;
        let b = ((s - o) + self.delta) / d;
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        let g = T::gamma(4);
        (lo - lo.abs() * g, hi + hi.abs() * g)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Vec3;

    #[test]
    fn beam_enters_a_box_it_only_grazes() {
        let b = Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0));
        // Passes 1e-7 above the top face: a plain slab test misses, the beam does not.
        let r = Ray::new(Vec3::new(-1.0, 1.0 + 1e-7, 0.5), Vec3::new(1.0, 0.0, 0.0)).unwrap();
        let tr = TraversalRay::new(&r, &b).expect("grazing beam touches the box");
        assert!(tr.t_start <= 1.0 && tr.t_end >= 2.0);
        // 1e-3 above: far outside the beam.
        let r = Ray::new(Vec3::new(-1.0, 1.001, 0.5), Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert!(TraversalRay::new(&r, &b).is_none());
    }

    #[test]
    fn interval_is_clipped_with_tolerance() {
        let b = Aabb::new(Vec3::new(0.0f64, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0));
        let r = Ray::with_interval(
            Vec3::new(-1.0, 0.5, 0.5),
            Vec3::new(2.0, 0.0, 0.0),
            0.6,
            0.7,
        )
        .unwrap();
        let tr = TraversalRay::new(&r, &b).unwrap();
        assert!(tr.t_start < 0.6 && tr.t_start > 0.6 - 1e-9);
        assert!(tr.t_end > 0.7 && tr.t_end < 0.7 + 1e-9);
        let empty = Ray::with_interval(
            Vec3::new(-1.0, 0.5, 0.5),
            Vec3::new(2.0, 0.0, 0.0),
            0.7,
            0.6,
        )
        .unwrap();
        assert!(TraversalRay::new(&empty, &b).is_none());
    }

    #[test]
    fn plane_band_brackets_the_crossing() {
        let b = Aabb::new(Vec3::new(0.0f64, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0));
        let r = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(2.0, 1e-3, 0.0)).unwrap();
        let tr = TraversalRay::new(&r, &b).unwrap();
        let (lo, hi) = tr.plane_band(0, 0.25);
        assert!(lo < 0.625 && hi > 0.625 && hi - lo < 1e-9);
        // Parallel to z-planes: inside the band everywhere, or nowhere.
        assert_eq!(tr.plane_band(2, 0.5), (f64::NEG_INFINITY, f64::INFINITY));
        let (lo, hi) = tr.plane_band(2, 0.75);
        assert!(lo > hi);
    }

    #[test]
    fn plane_band_keeps_the_beam_width_far_from_the_origin() {
        // In f32 at 1e4 the rounding unit (about 1e-3) dwarfs delta (about
        // 4e-6 for a ray this close to the box): the band must still span
        // the beam's whole width, `2·delta / |d|`.
        let s = 10_000.0f32;
        let b = Aabb::new(
            Vec3::new(s - 1.0, s - 1.0, s - 1.0),
            Vec3::new(s + 1.0, s + 1.0, s + 1.0),
        );
        let r = Ray::new(Vec3::new(s - 0.5, s, s), Vec3::new(1.0, 0.0, 0.0)).unwrap();
        let tr = TraversalRay::new(&r, &b).unwrap();
        assert!(
            tr.delta < 1e-4 && s - tr.delta == s,
            "premise: delta is lost in s − delta"
        );
        let (lo, hi) = tr.plane_band(0, s);
        assert!(
            lo <= 0.5 - tr.delta && hi >= 0.5 + tr.delta,
            "band [{lo}, {hi}], delta {}",
            tr.delta
        );
    }
}
