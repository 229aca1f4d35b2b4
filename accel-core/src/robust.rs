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
        let delta = T::gamma(TRAVERSAL_ROUNDINGS) * reach(bounds, o);
        // The reciprocal once, for the slabs here and the walk's planes.
        let inv_dir = PreparedRay::reciprocal(d);
        let (t0, t1) = bounds.beam_interval_inv(o, d, inv_dir, delta)?;
        Self::clipped(ray, inv_dir, delta, t0, t1)
    }

    /// [`TraversalRay::new`] for primitives whose hits are accurate to the
    /// rounding of [`Real::Wide`] ([`crate::PrimitiveSet::wide_hits`]): the
    /// beam is `gamma(64)` **of the wide type** of the farthest corner, about
    /// 5·10⁸ times thinner than `new`'s in `f32`, so that a ray leaving a
    /// surface need not walk the surface's nodes. The bounds are entered in
    /// the wide type, where that width is not lost in the rounding of `T`.
    ///
    /// Only a walk whose own crossings allow for their rounding relative to
    /// the parameters (a kD-tree's plane bands) may use this beam: a cell
    /// walk's crossings round in `T` and need `new`'s. In `f64`, where the
    /// wide type is `T`, the two beams are the same.
    #[inline]
    #[must_use]
    pub fn with_wide_hits(ray: &Ray<T>, bounds: &Aabb<T>) -> Option<Self> {
        Self::from_wide(ray, WideRay::new(ray)?.beam(bounds)?)
    }

    /// [`TraversalRay::with_wide_hits`] for several rays through the same
    /// bounds, lane by lane the same arithmetic, so the same bits. The wide
    /// beams' slab tests, where a ray that misses the bounds spends its
    /// preparation (three wide divisions, the reach, the slabs), are
    /// written for `N` lanes side by side, which the compiler turns into
    /// vector instructions; only the rays that meet the bounds are then
    /// prepared further, one by one. A ray with a zero direction component
    /// (an infinite wide reciprocal) takes `with_wide_hits` itself. Lane
    /// `l` of `out` receives `rays[l]`'s traversal ray. Always inlined, so
    /// that a caller compiled for wider vectors (AVX2) gets them here too.
    #[inline(always)]
    pub fn lanes_with_wide_hits<const N: usize>(
        rays: [&Ray<T>; N],
        bounds: &Aabb<T>,
        out: &mut [Option<Self>; N],
    ) {
        if bounds.is_empty() {
            *out = [None; N];
            return;
        }
        let b: Aabb<T::Wide> = bounds.cast();
        let zero = <T::Wide as Real>::ZERO;
        let inf = <T::Wide as Real>::INFINITY;
        let (mut o, mut d) = ([[zero; N]; 3], [[zero; N]; 3]);
        for (l, ray) in rays.iter().enumerate() {
            for a in 0..3 {
                o[a][l] = ray.origin[a].to_wide();
                d[a][l] = ray.direction[a].to_wide();
            }
        }
        let mut beam = [[zero; N]; 3];
        let (mut finite, mut met) = ([false; N], [false; N]);
        for l in 0..N {
            let o = Vec3::new(o[0][l], o[1][l], o[2][l]);
            let inv = PreparedRay::reciprocal(Vec3::new(d[0][l], d[1][l], d[2][l]));
            let delta = <T::Wide as Real>::gamma(TRAVERSAL_ROUNDINGS) * reach(&b, o);
            let (t0, t1) = b.finite_slabs(o, inv, delta);
            (beam[0][l], beam[1][l], beam[2][l]) = (delta, t0, t1);
            // Without short circuits, so that the lanes stay side by side.
            finite[l] = (inv.x.abs() < inf) & (inv.y.abs() < inf) & (inv.z.abs() < inf);
            met[l] = t0 <= t1;
        }
        // Each branch writes its lane itself: merged into one value first,
        // the lane was copied out of a temporary in 32-byte loads that
        // straddled the narrower stores that had just filled it (no store
        // forwarding).
        for (l, (ray, out)) in rays.iter().zip(out).enumerate() {
            if !finite[l] {
                *out = Self::with_wide_hits(ray, bounds);
            } else if met[l] && !ray.is_empty_interval() {
                let (delta, t0, t1) = (beam[0][l], beam[1][l], beam[2][l]);
                *out = Self::from_wide(ray, WideBeam { delta, t0, t1 });
            } else {
                *out = None;
            }
        }
    }

    /// The traversal ray of `ray`'s wide beam ([`WideRay::beam`]), its
    /// half-width, entry and exit each rounded outward to `T`, so that the
    /// beam only grows; `None` when nothing of it is left in the ray's
    /// interval. `beam` must be of this very ray (from
    /// [`WideRay::new`]`(ray)`): another ray's beam would not hold its hits.
    #[inline(always)]
    #[must_use]
    pub fn from_wide(ray: &Ray<T>, beam: WideBeam<T::Wide>) -> Option<Self> {
        Self::clipped(
            ray,
            PreparedRay::reciprocal(ray.direction),
            T::from_wide(beam.delta).next_up(),
            T::from_wide(beam.t0).next_down(),
            T::from_wide(beam.t1).next_up(),
        )
    }

    /// The beam of half-width `delta` whose entry into and exit from the
    /// bounds are `t0`, `t1`, clipped to the ray's interval widened by the
    /// hit tolerance; `None` when nothing is left.
    #[inline(always)]
    fn clipped(ray: &Ray<T>, inv_dir: Vec3<T>, delta: T, t0: T, t1: T) -> Option<Self> {
        let largest = |v: Vec3<T>| greater(greater(v.x, v.y), v.z);
        let t_tol = delta / largest(ray.direction.abs()) * (T::ONE + T::gamma(2));
        // A hit's parameter is rounded to `T` last, so one whose exact
        // parameter lies just outside the interval may be reported inside
        // it: the interval widens by that rounding too (part of `t_tol`
        // already when the beam is `new`'s). Finite even for an unbounded
        // interval whose beam entry or exit overflows (a tiny direction):
        // no hit has an infinite parameter, and walks place the beam at
        // `d·t_start`, where 0·∞ would be NaN.
        let g = T::gamma(4);
        let t_start = t0.max(ray.t_min - t_tol - ray.t_min.abs() * g).max(-T::MAX);
        let t_end = t1.min(ray.t_max + t_tol + ray.t_max.abs() * g).min(T::MAX);
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

    /// The parameter after which no node or cell can hold a hit that ties
    /// with or beats a hit at `t`: `t` plus the hit tolerance and the
    /// rounding of a hit's parameter to `T`.
    #[inline]
    #[must_use]
    pub fn cutoff_after(&self, t: T) -> T {
        t + self.t_tol + t.abs() * T::gamma(4)
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
        // In the wide type, the offset from the origin first: in `T`,
        // `s − delta` or `(s − o) − delta` would round the beam's width
        // away wherever delta is below the rounding unit of the offset (a
        // thin beam, coordinates far from zero, origins close to the plane).
        let (sw, ow, dw, delta) = (s.to_wide(), o.to_wide(), d.to_wide(), self.delta.to_wide());
        let a = ((sw - ow) - delta) / dw;
        let b = ((sw - ow) + delta) / dw;
        let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
        let (lo, hi) = (T::from_wide(lo).next_down(), T::from_wide(hi).next_up());
        let g = T::gamma(4);
        (lo - lo.abs() * g, hi + hi.abs() * g)
    }
}

/// A ray's origin and reciprocal direction in [`Real::Wide`], for its thin
/// beams ([`TraversalRay::with_wide_hits`]) through several boxes: a
/// structure in parts (a small dense part apart, a floor apart) casts and
/// divides once per query, not once per part.
#[derive(Clone, Copy, Debug)]
pub struct WideRay<W> {
    origin: Vec3<W>,
    direction: Vec3<W>,
    inv_dir: Vec3<W>,
}

/// The wide beam of a ray through a box, in [`Real::Wide`], before it is
/// rounded to `T` and clipped to the ray's interval
/// ([`TraversalRay::from_wide`]).
#[derive(Clone, Copy, Debug)]
pub struct WideBeam<W> {
    /// The beam's half-width.
    delta: W,
    /// The beam's entry into the box.
    t0: W,
    /// The beam's exit.
    t1: W,
}

impl<W: Real> WideRay<W> {
    /// The wide ray of `ray` (already validated); `None` when its interval
    /// is empty, so that no beam of it holds anything.
    #[inline(always)]
    #[must_use]
    pub fn new<T: Real<Wide = W>>(ray: &Ray<T>) -> Option<Self> {
        if ray.is_empty_interval() {
            return None;
        }
        // Exact: `T::Wide` holds every `T` value.
        let direction: Vec3<W> = ray.direction.cast();
        Some(Self {
            origin: ray.origin.cast(),
            direction,
            inv_dir: PreparedRay::reciprocal(direction),
        })
    }

    /// The beam of half-width `gamma(64)` (of the wide type) of the
    /// farthest corner of `bounds`, entered in the wide type; `None` when
    /// it misses the bounds.
    #[inline(always)]
    #[must_use]
    pub fn beam<T: Real<Wide = W>>(&self, bounds: &Aabb<T>) -> Option<WideBeam<W>> {
        if bounds.is_empty() {
            return None;
        }
        let b: Aabb<W> = bounds.cast();
        let delta = W::gamma(TRAVERSAL_ROUNDINGS) * reach(&b, self.origin);
        let (t0, t1) = b.beam_interval_inv(self.origin, self.direction, self.inv_dir, delta)?;
        Some(WideBeam { delta, t0, t1 })
    }
}

/// The largest distance, per axis, from `o` to a corner of `b`: what every
/// hit's rounding inside `b` is relative to. Plain selects (no NaN here: the
/// ray is finite, the bounds too, and their differences at worst infinite).
#[inline(always)]
fn reach<W: Real>(b: &Aabb<W>, o: Vec3<W>) -> W {
    let largest = |v: Vec3<W>| greater(greater(v.x, v.y), v.z);
    greater(largest((b.min - o).abs()), largest((b.max - o).abs()))
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

    #[test]
    fn a_ray_leaving_a_flat_box_misses_it_only_with_the_thin_beam() {
        // A floor 80 wide at z = 0, a ray spawned 1e-6 above it going up:
        // f32's beam (gamma(64) of 40, 1.5e-4) still touches the floor, the
        // wide type's (3e-13) does not.
        let floor = Aabb::new(Vec3::new(-40.0f32, -25.0, 0.0), Vec3::new(40.0, 25.0, 0.0));
        let r = Ray::new(Vec3::new(3.0, 2.0, 1e-6), Vec3::new(0.3, -0.2, 0.9)).unwrap();
        assert!(TraversalRay::new(&r, &floor).is_some(), "premise");
        assert!(TraversalRay::with_wide_hits(&r, &floor).is_none());
        // From below, and along the floor just inside the thin beam, it is
        // entered.
        let up = Ray::new(Vec3::new(3.0, 2.0, -1.0), Vec3::new(0.0, 0.0, 1.0)).unwrap();
        let tr = TraversalRay::with_wide_hits(&up, &floor).unwrap();
        assert!(tr.t_start <= 1.0 && tr.t_end >= 1.0);
        let along = Ray::new(Vec3::new(-50.0, 0.0, 1e-14), Vec3::new(1.0, 0.0, 0.0)).unwrap();
        assert!(TraversalRay::with_wide_hits(&along, &floor).is_some());
    }

    /// The parameters at which the line `o + t·d` lies in `b` grown by
    /// `margin`, slab by slab with plain divisions (the reference).
    fn grown_slabs(b: &Aabb<f64>, o: Vec3<f64>, d: Vec3<f64>, margin: f64) -> Option<(f64, f64)> {
        let (mut t0, mut t1) = (f64::NEG_INFINITY, f64::INFINITY);
        for a in 0..3 {
            let (lo, hi) = (b.min[a] - margin - o[a], b.max[a] + margin - o[a]);
            if d[a] == 0.0 {
                if lo > 0.0 || hi < 0.0 {
                    return None;
                }
                continue;
            }
            let (x, y) = (lo / d[a], hi / d[a]);
            t0 = t0.max(x.min(y));
            t1 = t1.min(x.max(y));
        }
        (t0 <= t1).then_some((t0, t1))
    }

    /// A value of either sign spread over many binades.
    fn spread(max_exp: i32) -> impl proptest::strategy::Strategy<Value = f32> {
        use proptest::prelude::*;
        (any::<bool>(), 1.0..2.0f32, -max_exp..=max_exp)
            .prop_map(|(neg, m, e)| if neg { -m } else { m } * 2f32.powi(e))
    }

    fn point(max_exp: i32) -> impl proptest::strategy::Strategy<Value = Vec3<f32>> {
        use proptest::prelude::*;
        (spread(max_exp), spread(max_exp), spread(max_exp)).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    /// A direction component: spread over binades, or a signed zero.
    fn component() -> impl proptest::strategy::Strategy<Value = f32> {
        use proptest::prelude::*;
        prop_oneof![6 => spread(8), 1 => Just(0.0f32), 1 => Just(-0.0f32)]
    }

    /// A valid ray whose direction may have zero components and whose
    /// interval may be empty.
    fn lane_ray() -> impl proptest::strategy::Strategy<Value = Ray<f32>> {
        use proptest::prelude::*;
        (
            point(8),
            (component(), component(), component()),
            -2.0..8.0f32,
            -2.0..64.0f32,
        )
            .prop_filter_map("a zero direction", |(o, (x, y, z), t_min, t_max)| {
                Ray::with_interval(o, Vec3::new(x, y, z), t_min, t_max).ok()
            })
    }

    /// Every field of a traversal ray, as bits.
    fn bits<T: Real>(tr: &TraversalRay<T>) -> Vec<u64> {
        let p = &tr.prepared;
        let v = |v: Vec3<T>| [v.x, v.y, v.z].map(T::to_bits_u64);
        let mut out = Vec::new();
        out.extend(v(p.ray.origin));
        out.extend(v(p.ray.direction));
        out.extend(v(p.inv_dir));
        out.extend(
            [
                p.ray.t_min,
                p.ray.t_max,
                tr.delta,
                tr.t_tol,
                tr.t_start,
                tr.t_end,
            ]
            .map(T::to_bits_u64),
        );
        out.extend(p.axes.map(|a| a as u64));
        out.extend([p.shear.x, p.shear.y, p.shear.z].map(f64::to_bits));
        out
    }

    /// [`TraversalRay::lanes_with_wide_hits`] against
    /// [`TraversalRay::with_wide_hits`] ray by ray, in `T`.
    fn lanes_match<T: Real>(
        rays: &[Ray<f32>],
        bounds: &Aabb<f32>,
    ) -> Result<(), proptest::test_runner::TestCaseError> {
        let rays: Vec<Ray<T>> = rays.iter().map(Ray::cast).collect();
        let bounds: Aabb<T> = bounds.cast();
        let members: [&Ray<T>; 8] = core::array::from_fn(|l| &rays[l]);
        let mut lanes = [None; 8];
        TraversalRay::lanes_with_wide_hits(members, &bounds, &mut lanes);
        for (ray, lane) in rays.iter().zip(&lanes) {
            let single = TraversalRay::with_wide_hits(ray, &bounds);
            proptest::prop_assert_eq!(
                lane.as_ref().map(bits),
                single.as_ref().map(bits),
                "ray {:?}",
                ray
            );
        }
        Ok(())
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(3_000))]
        /// Rays prepared side by side are prepared as one by one, bit for
        /// bit, in both precisions: rays that meet or miss the box, zero
        /// direction components (the single path), empty intervals.
        #[test]
        fn lanes_prepare_rays_as_one_by_one(
            rays in proptest::collection::vec(lane_ray(), 8),
            a in point(6),
            b in point(6),
        ) {
            let bounds = Aabb::new(a.min(b), a.max(b));
            lanes_match::<f32>(&rays, &bounds)?;
            lanes_match::<f64>(&rays, &bounds)?;
        }
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(20_000))]
        /// The thin beam holds every parameter at which the ray passes
        /// within `gamma(16)` of `f64` (the wide hits' allowance, of the
        /// farthest corner) of the box, within the ray's interval widened by
        /// the rounding of a hit's parameter to `f32`: computed in `f64`
        /// with an allowance far below those margins.
        #[test]
        fn the_thin_beam_holds_every_parameter_a_wide_hit_may_have(
            a in point(8),
            b in point(8),
            o in point(8),
            d in point(8),
            t_min in 0.0..4.0f32,
        ) {
            let bounds = Aabb::new(a.min(b), a.max(b));
            let ray = Ray::with_interval(o, d, t_min, f32::INFINITY).unwrap();
            let (ow, dw) = (o.map(f64::from), d.map(f64::from));
            let bw = Aabb::new(bounds.min.map(f64::from), bounds.max.map(f64::from));
            let reach = (bw.min - ow).abs().max((bw.max - ow).abs()).max_component();
            let margin = <f64 as Real>::gamma(16) * reach;
            let Some((t0, t1)) = grown_slabs(&bw, ow, dw, margin) else {
                return Ok(());
            };
            let lo = t0.max(f64::from(t_min) * (1.0 - f64::from(f32::EPSILON)));
            if lo > t1 {
                return Ok(());
            }
            let tr = TraversalRay::with_wide_hits(&ray, &bounds);
            proptest::prop_assert!(tr.is_some(), "missed [{lo}, {t1}]");
            let tr = tr.unwrap();
            proptest::prop_assert!(f64::from(tr.t_start) <= lo, "start {} > {lo}", tr.t_start);
            proptest::prop_assert!(
                f64::from(tr.t_end) >= t1.min(f64::from(f32::MAX)),
                "end {} < {t1}", tr.t_end
            );
        }
    }
}
