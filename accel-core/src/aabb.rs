//! Axis-aligned bounding boxes, with pbrt's vocabulary.

use crate::real::{greater, lesser};
use crate::{Real, Vec3};

/// An axis-aligned box `[min, max]`, closed on both sides.
///
/// [`Aabb::empty`] is the inverted infinite box (`min = +∞`, `max = −∞`), the
/// identity of [`Aabb::union`], as pbrt's default `Bounds3`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb<T> {
    /// Lower corner.
    pub min: Vec3<T>,
    /// Upper corner.
    pub max: Vec3<T>,
}

impl<T: Real> Default for Aabb<T> {
    fn default() -> Self {
        Self::empty()
    }
}

impl<T: Real> Aabb<T> {
    /// The empty box: contains nothing, and `empty().union(b) == b`.
    #[inline]
    #[must_use]
    pub const fn empty() -> Self {
        Self {
            min: Vec3::splat(T::INFINITY),
            max: Vec3::splat(T::NEG_INFINITY),
        }
    }

    /// The box spanned by two corners, in any order.
    #[inline]
    #[must_use]
    pub fn new(a: Vec3<T>, b: Vec3<T>) -> Self {
        Self {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// The degenerate box holding one point.
    #[inline]
    #[must_use]
    pub const fn from_point(p: Vec3<T>) -> Self {
        Self { min: p, max: p }
    }

    /// The smallest box holding all `points` (empty for none).
    #[must_use]
    pub fn from_points(points: impl IntoIterator<Item = Vec3<T>>) -> Self {
        points
            .into_iter()
            .fold(Self::empty(), |b, p| b.union_point(p))
    }

    /// True when the box holds no point (`min > max` on some axis).
    #[inline]
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Both corners finite.
    #[inline]
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    /// The two parts of this box on either side of the plane
    /// `x[axis] = at`: below (`max[axis] = at`) and above (`min[axis] = at`),
    /// both closed, so both hold the plane. A kD-tree node's children.
    #[inline]
    #[must_use]
    pub fn split_at(&self, axis: usize, at: T) -> (Self, Self) {
        let (mut below, mut above) = (*self, *self);
        below.max[axis] = at;
        above.min[axis] = at;
        (below, above)
    }

    /// The box holding both boxes.
    #[inline]
    #[must_use]
    pub fn union(&self, o: &Self) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// Grows this box to hold `o` (in-place [`Aabb::union`]).
    #[inline]
    pub fn merge(&mut self, o: &Self) {
        *self = self.union(o);
    }

    /// The box holding this box and `p`.
    #[inline]
    #[must_use]
    pub fn union_point(&self, p: Vec3<T>) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Grows this box to hold `p` (in-place [`Aabb::union_point`]).
    #[inline]
    pub fn merge_point(&mut self, p: Vec3<T>) {
        *self = self.union_point(p);
    }

    /// The common part of both boxes (empty if they are disjoint).
    #[inline]
    #[must_use]
    pub fn intersection(&self, o: &Self) -> Self {
        Self {
            min: self.min.max(o.min),
            max: self.max.min(o.max),
        }
    }

    /// True when the closed boxes share at least one point.
    #[inline]
    #[must_use]
    pub fn overlaps(&self, o: &Self) -> bool {
        self.min.x <= o.max.x
            && o.min.x <= self.max.x
            && self.min.y <= o.max.y
            && o.min.y <= self.max.y
            && self.min.z <= o.max.z
            && o.min.z <= self.max.z
    }

    /// True when `p` lies in the closed box.
    #[inline]
    #[must_use]
    pub fn contains_point(&self, p: Vec3<T>) -> bool {
        p.x >= self.min.x
            && p.x <= self.max.x
            && p.y >= self.min.y
            && p.y <= self.max.y
            && p.z >= self.min.z
            && p.z <= self.max.z
    }

    /// True when `o` lies entirely inside this box.
    #[inline]
    #[must_use]
    pub fn contains(&self, o: &Self) -> bool {
        self.contains_point(o.min) && self.contains_point(o.max)
    }

    /// `max − min`.
    #[inline]
    #[must_use]
    pub fn diagonal(&self) -> Vec3<T> {
        self.max - self.min
    }

    /// The midpoint.
    #[inline]
    #[must_use]
    pub fn center(&self) -> Vec3<T> {
        (self.min + self.max) * T::HALF
    }

    /// Half the surface area: `dx·dy + dy·dz + dz·dx` (what SAH ratios need).
    #[inline]
    #[must_use]
    pub fn half_area(&self) -> T {
        let d = self.diagonal();
        d.x * d.y + d.y * d.z + d.z * d.x
    }

    /// The surface area `2·(dx·dy + dy·dz + dz·dx)`.
    #[inline]
    #[must_use]
    pub fn surface_area(&self) -> T {
        let h = self.half_area();
        h + h
    }

    /// The volume `dx·dy·dz`.
    #[inline]
    #[must_use]
    pub fn volume(&self) -> T {
        let d = self.diagonal();
        d.x * d.y * d.z
    }

    /// The axis of the longest extent; ties go to the lower axis.
    #[inline]
    #[must_use]
    pub fn max_dimension(&self) -> usize {
        self.diagonal().max_dimension()
    }

    /// The position of `p` relative to the box: `(0,0,0)` at `min`, `(1,1,1)` at
    /// `max` (pbrt's `Offset`). Axes of zero extent give 0.
    #[inline]
    #[must_use]
    pub fn offset(&self, p: Vec3<T>) -> Vec3<T> {
        let mut o = p - self.min;
        for axis in 0..3 {
            let extent = self.max[axis] - self.min[axis];
            o[axis] = if extent > T::ZERO {
                o[axis] / extent
            } else {
                T::ZERO
            };
        }
        o
    }

    /// Corner `i` (bit 0 selects x max, bit 1 y max, bit 2 z max).
    #[inline]
    #[must_use]
    pub fn corner(&self, i: usize) -> Vec3<T> {
        Vec3::new(
            if i & 1 == 0 { self.min.x } else { self.max.x },
            if i & 2 == 0 { self.min.y } else { self.max.y },
            if i & 4 == 0 { self.min.z } else { self.max.z },
        )
    }

    /// Converts to another precision through `f64` (rounding to nearest).
    #[inline]
    #[must_use]
    pub fn cast<U: Real>(&self) -> Aabb<U> {
        Aabb {
            min: self.min.cast(),
            max: self.max.cast(),
        }
    }

    /// The box grown by `margin` on every side.
    #[inline]
    #[must_use]
    pub fn expanded(&self, margin: T) -> Self {
        Self {
            min: self.min - Vec3::splat(margin),
            max: self.max + Vec3::splat(margin),
        }
    }

    /// The largest absolute coordinate of either corner: the scale that
    /// rounding errors of computations on this box are relative to.
    #[inline]
    #[must_use]
    pub fn max_abs_coordinate(&self) -> T {
        self.min.abs().max(self.max.abs()).max_component()
    }

    /// The parameter interval `[t0, t1]` in which the line `origin + t·dir`
    /// lies in the closed box, widened outward by `2·gamma(3)` of each end
    /// (pbrt's slab test) so that rounding never loses a touching ray.
    ///
    /// Zero direction components are handled exactly (the ray is inside the
    /// slab for all `t` or for none); `None` means no intersection.
    #[inline]
    #[must_use]
    pub fn line_interval(&self, origin: Vec3<T>, dir: Vec3<T>) -> Option<(T, T)> {
        self.beam_interval(origin, dir, T::ZERO)
    }

    /// [`Aabb::line_interval`] for the box grown by `margin` on every side.
    ///
    /// The margin is applied to the corner offsets from the origin
    /// (`(min − origin) − margin`), not to the corners, so that a margin far
    /// below the rounding unit of large coordinates is not lost. The interval
    /// holds every parameter at which the line lies in the box grown by the
    /// margin less the offsets' own rounding (`u·|corner − origin|` per
    /// axis, `u` the unit roundoff; nothing when the margin is 0). The origin
    /// and direction must be finite, as a validated ray's are (with a NaN the
    /// answer is unspecified).
    #[inline]
    #[must_use]
    pub fn beam_interval(&self, origin: Vec3<T>, dir: Vec3<T>, margin: T) -> Option<(T, T)> {
        self.beam_interval_inv(origin, dir, crate::PreparedRay::reciprocal(dir), margin)
    }

    /// [`Aabb::beam_interval`] given the direction's reciprocal as well,
    /// `inv_dir = (1/dir.x, 1/dir.y, 1/dir.z)` each rounded once (a ray's
    /// [`crate::PreparedRay::inv_dir`], from [`crate::PreparedRay::reciprocal`]):
    /// each slab end is the offset times the reciprocal, a multiplication
    /// where a division takes several times as long, and the three slabs
    /// are taken at once, without a branch (a ray that misses a box is
    /// refused in about half the time). That is two roundings of the
    /// quotient instead of one, both within the `2·gamma(3)` widening. When
    /// a reciprocal is not finite (a zero or subnormal component), every
    /// end is a quotient, as in [`Aabb::line_interval`]: an infinite
    /// reciprocal times a zero offset would be NaN.
    #[inline(always)]
    #[must_use]
    pub fn beam_interval_inv(
        &self,
        origin: Vec3<T>,
        dir: Vec3<T>,
        inv_dir: Vec3<T>,
        margin: T,
    ) -> Option<(T, T)> {
        if !inv_dir.is_finite() {
            return self.divided_slabs(origin, dir, margin);
        }
        let (t0, t1) = self.finite_slabs(origin, inv_dir, margin);
        (t0 <= t1).then_some((t0, t1))
    }

    /// [`Aabb::beam_interval_inv`]'s interval for a finite `inv_dir`,
    /// widened, and empty (`t0 > t1`, or NaN) where the beam misses:
    /// straight-line code, no early exit, so that the three slabs are taken
    /// at once (each end ordered by selects: a branch on them waited for the
    /// products) and several rays' intervals can be computed side by side
    /// ([`crate::TraversalRay::lanes_with_wide_hits`]).
    #[inline(always)]
    #[must_use]
    pub(crate) fn finite_slabs(&self, origin: Vec3<T>, inv_dir: Vec3<T>, margin: T) -> (T, T) {
        let lo = (self.min - origin) - Vec3::splat(margin);
        let hi = (self.max - origin) + Vec3::splat(margin);
        let (a, b) = (lo * inv_dir, hi * inv_dir);
        // Each slab's entry is the lesser of its two ends, its exit the greater.
        let t0 = greater(
            greater(lesser(a.x, b.x), lesser(a.y, b.y)),
            lesser(a.z, b.z),
        );
        let t1 = lesser(
            lesser(greater(a.x, b.x), greater(a.y, b.y)),
            greater(a.z, b.z),
        );
        widen(t0, t1)
    }

    /// [`Aabb::beam_interval`] by divisions, one slab after the other.
    fn divided_slabs(&self, origin: Vec3<T>, dir: Vec3<T>, margin: T) -> Option<(T, T)> {
        // One slab per axis, written out so that the axes are constants
        // (a loop over a runtime axis index selects every component by a
        // branch).
        let slab = |axis: usize| -> Option<(T, T)> {
            let d = dir[axis];
            let lo = (self.min[axis] - origin[axis]) - margin;
            let hi = (self.max[axis] - origin[axis]) + margin;
            if d == T::ZERO {
                return if lo > T::ZERO || hi < T::ZERO {
                    None
                } else {
                    Some((T::NEG_INFINITY, T::INFINITY))
                };
            }
            // Division keeps 0/d = 0 exact for origins on a face and stays
            // finite for tiny components.
            let near = lo / d;
            let far = hi / d;
            Some(if near > far { (far, near) } else { (near, far) })
        };
        let (n0, f0) = slab(0)?;
        let (n1, f1) = slab(1)?;
        let (n2, f2) = slab(2)?;
        // Plain selects: a slab end is a finite or infinite quotient of a
        // finite (or infinite) offset by a nonzero component, never NaN.
        let t0 = greater(greater(n0, n1), n2);
        let t1 = lesser(lesser(f0, f1), f2);
        let (t0, t1) = widen(t0, t1);
        (t0 <= t1).then_some((t0, t1))
    }
}

/// The slab test's interval `[t0, t1]` widened by `2·gamma(3)` of each end
/// (empty where `t0 > t1`).
#[inline(always)]
fn widen<T: Real>(t0: T, t1: T) -> (T, T) {
    let slack = T::gamma(3) + T::gamma(3);
    (t0 - t0.abs() * slack, t1 + t1.abs() * slack)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-symmetric box, so that swapped axes or halved terms show.
    fn box123() -> Aabb<f64> {
        Aabb::new(Vec3::new(1.0, -2.0, 0.5), Vec3::new(2.0, 0.0, 3.5))
    }

    #[test]
    fn split_at_cuts_only_the_named_axis() {
        let (below, above) = box123().split_at(1, -0.5);
        assert_eq!(
            below,
            Aabb::new(Vec3::new(1.0, -2.0, 0.5), Vec3::new(2.0, -0.5, 3.5))
        );
        assert_eq!(
            above,
            Aabb::new(Vec3::new(1.0, -0.5, 0.5), Vec3::new(2.0, 0.0, 3.5))
        );
    }

    #[test]
    fn measures_of_a_1_by_2_by_3_box() {
        let b = box123();
        assert_eq!(b.diagonal(), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(b.surface_area(), 22.0);
        assert_eq!(b.half_area(), 11.0);
        assert_eq!(b.volume(), 6.0);
        assert_eq!(b.max_dimension(), 2);
        assert_eq!(b.center(), Vec3::new(1.5, -1.0, 2.0));
        assert_eq!(b.max_abs_coordinate(), 3.5);
    }

    #[test]
    fn offset_maps_corners_to_unit_cube() {
        let b = box123();
        assert_eq!(b.offset(b.min), Vec3::ZERO);
        assert_eq!(b.offset(b.max), Vec3::splat(1.0));
        assert_eq!(
            b.offset(Vec3::new(1.25, -1.0, 2.0)),
            Vec3::new(0.25, 0.5, 0.5)
        );
    }

    #[test]
    fn empty_is_the_identity_of_union() {
        let b = box123();
        let e = Aabb::<f64>::empty();
        assert!(e.is_empty());
        assert_eq!(e.union(&b), b);
        assert!(!e.overlaps(&b));
        let mut m = e;
        m.merge_point(Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(m, Aabb::from_point(Vec3::new(1.0, 2.0, 3.0)));
    }

    #[test]
    fn overlap_and_containment_are_closed() {
        let b = box123();
        let touching = Aabb::new(Vec3::new(2.0, 0.0, 3.5), Vec3::new(5.0, 5.0, 5.0));
        assert!(b.overlaps(&touching));
        let apart = Aabb::new(Vec3::new(2.0 + 1e-12, 0.0, 3.5), Vec3::new(5.0, 5.0, 5.0));
        assert!(!b.overlaps(&apart));
        assert!(b.contains_point(b.corner(5)));
        assert_eq!(b.corner(5), Vec3::new(2.0, -2.0, 3.5));
        assert!(b.intersection(&apart).is_empty());
    }

    #[test]
    fn line_interval_through_a_non_symmetric_box() {
        let b = box123();
        let (t0, t1) = b
            .line_interval(Vec3::new(0.0, -1.0, 2.0), Vec3::new(1.0, 0.0, 0.0))
            .unwrap();
        assert!(t0 <= 1.0 && t0 > 1.0 - 1e-12);
        assert!((2.0..2.0 + 1e-12).contains(&t1));
        // Reversed direction: the same segment at negative parameters.
        let (t0, t1) = b
            .line_interval(Vec3::new(0.0, -1.0, 2.0), Vec3::new(-1.0, 0.0, 0.0))
            .unwrap();
        assert!(t0 <= -2.0 && (-1.0..-1.0 + 1e-12).contains(&t1));
    }

    /// A value of either sign spread over many binades.
    fn spread(max_exp: i32) -> impl proptest::strategy::Strategy<Value = f32> {
        use proptest::prelude::*;
        (any::<bool>(), 1.0..2.0f32, -max_exp..=max_exp)
            .prop_map(|(neg, m, e)| if neg { -m } else { m } * 2f32.powi(e))
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(20_000))]
        /// The slab interval holds the exact interval of the box grown by
        /// the margin less the rounding of the corner offsets, as its doc
        /// says, computed in `f64` (the `f32` differences are exact or
        /// nearly so there, its roundings far below the `f32` widening), and
        /// is `None` only where that is empty. Margins from 0 (the line) to
        /// well beyond the coordinates' rounding.
        #[test]
        fn beam_interval_holds_the_exact_interval_of_the_grown_box(
            a in [spread(12), spread(12), spread(12)],
            b in [spread(12), spread(12), spread(12)],
            o in [spread(14), spread(14), spread(14)],
            d in [spread(20), spread(20), spread(20)],
            margin_exp in proptest::option::of(-30..4i32),
        ) {
            let bx = Aabb::new(Vec3::from(a), Vec3::from(a)).union_point(Vec3::from(b));
            let margin = margin_exp.map_or(0.0, |e| 2f32.powi(e));
            let (o, d) = (Vec3::from(o), Vec3::from(d));
            let got = bx.beam_interval(o, d, margin);
            let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
            for axis in 0..3 {
                // The margin less the first difference's rounding, which is
                // absolute (`u·|corner − origin|`) once a margin follows.
                let (lo, hi) = (
                    f64::from(bx.min[axis]) - f64::from(o[axis]),
                    f64::from(bx.max[axis]) - f64::from(o[axis]),
                );
                let rounding = f64::from(f32::EPSILON) * lo.abs().max(hi.abs());
                let m = (f64::from(margin) - rounding).max(0.0);
                let (lo, hi) = (lo - m, hi + m);
                let dd = f64::from(d[axis]);
                let (n, f) = if dd > 0.0 { (lo / dd, hi / dd) } else { (hi / dd, lo / dd) };
                t0 = t0.max(n);
                t1 = t1.min(f);
            }
            // The reference's own error: a few f64 roundings of each end.
            let (s0, s1) = (t0.abs() * 8.0 * f64::EPSILON, t1.abs() * 8.0 * f64::EPSILON);
            if t0 + s0 <= t1 - s1 {
                let (g0, g1) = got.expect("the grown box meets the line");
                proptest::prop_assert!(f64::from(g0) <= t0 + s0, "{g0} > {t0}");
                proptest::prop_assert!(f64::from(g1) >= t1 - s1, "{g1} < {t1}");
            }
        }
    }

    #[test]
    fn a_subnormal_component_divides_instead_of_multiplying_by_infinity() {
        let b = Aabb::new(Vec3::new(0.0f32, 0.0, 0.0), Vec3::new(1.0, 1.0, 1.0));
        let tiny = f32::from_bits(1);
        assert!(
            (1.0 / tiny).is_infinite(),
            "premise: the reciprocal overflows"
        );
        // The origin on a face across x (a zero offset there), heading
        // into the box by +-tiny along x: the ray lies in the x slab from
        // t = 0 (exactly, by division) to far beyond the box, so the
        // interval is that of y and z, [0.5, 1.5], not NaN.
        for (x, dx) in [(0.0, tiny), (1.0, -tiny)] {
            let (t0, t1) = b
                .line_interval(Vec3::new(x, -0.5, -0.5), Vec3::new(dx, 1.0, 1.0))
                .expect("the ray crosses the box");
            assert!(
                t0 <= 0.5 && t0 > 0.49 && (1.5..1.51).contains(&t1),
                "{t0} {t1}"
            );
        }
        // Heading out of it: only t <= 0 is inside the x slab.
        assert!(
            b.line_interval(Vec3::new(0.0, -0.5, -0.5), Vec3::new(-tiny, 1.0, 1.0))
                .is_none()
        );
    }

    #[test]
    fn line_interval_with_zero_components_on_a_face() {
        let b = box123();
        // Along the face y = 0 with dy = +0 and with dy = -0: inside (closed box).
        for dy in [0.0, -0.0] {
            let r = b.line_interval(Vec3::new(1.5, 0.0, -1.0), Vec3::new(0.0, dy, 1.0));
            let (t0, t1) = r.expect("a ray along a face touches the closed box");
            assert!(t0 <= 1.5 && t1 >= 4.5);
        }
        // Just outside the face: misses, even with a -0 component.
        let r = b.line_interval(Vec3::new(1.5, 1e-300, -1.0), Vec3::new(-0.0, -0.0, 1.0));
        assert!(r.is_none());
    }
}
