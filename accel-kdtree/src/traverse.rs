//! Queries: front-to-back traversal of a thin beam with a small stack.
//!
//! The ray is the beam of [`TraversalRay`]: its interval is clipped to the
//! tree's bounds (widened by rounding), and at each inner node
//! [`TraversalRay::plane_band`] (computed with the reciprocal direction, see
//! [`band`]) gives the parameters at which the beam touches the split plane. The near child is visited up to the band's end and the
//! far child from its start, so a ray running along a split plane, or
//! crossing it where rounding could put it on either side, visits both: no
//! hit is lost at a plane, and primitives lying in a split plane (stored on
//! one side only) are found from both. A component of `±0` visits only the
//! side holding the origin, or both when the origin is within the beam of the
//! plane. Below a node, the beam narrows to the rounding of what the node
//! holds ([`crate::reach`]): a small dense mesh in a large scene is walked
//! with a beam as thin as if it stood alone. A node is skipped once the best hit, plus the hit tolerance
//! `t_tol`, lies before the node's entry; a per-query [`Mailbox`] tests each
//! primitive once. A tree in two parts ([`crate::KdTree::parts`]) is walked
//! part by part, each with the beam of its own bounds, the later ones with
//! the best hit of the earlier.

use crate::build::{KdPart, decode_split};
use crate::reach::node_beam;
use crate::tree::KdTree;
use accel_core::packed::{PackedTriangles, for_each_candidate};
use accel_core::{
    Aabb, AccelStats, Accelerator, CostCounter, Hit, Mailbox, PrimitiveSet, QueryError, Ray, Real,
    TraversalRay, Vec3, WideBeam, WideRay, nearer, region_matches, region_search_box,
    validate_region,
};
use core::borrow::Borrow;

/// Traversal stack entries: at most one per level.
pub(crate) const STACK: usize = crate::KdTreeParams::MAX_DEPTH as usize;

/// What a walk does at leaves, and how far it still needs to go.
pub(crate) trait Visitor<T> {
    /// Nodes entered after this parameter are skipped.
    fn cutoff(&self) -> T;
    /// Tests a leaf's primitives (starting at `start` of the reference
    /// array); `true` ends the walk.
    fn leaf<C: CostCounter>(&mut self, start: usize, prims: &[u32], counter: &mut C) -> bool;
}

/// The nearest hit.
pub(crate) struct Nearest<'q, T: Real, P: ?Sized> {
    pub(crate) prims: &'q P,
    pub(crate) packed: Option<&'q PackedTriangles<T>>,
    pub(crate) tr: &'q TraversalRay<T>,
    pub(crate) mailbox: Mailbox,
    pub(crate) best: Option<Hit<T>>,
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> Visitor<T> for Nearest<'_, T, P> {
    #[inline]
    fn cutoff(&self) -> T {
        self.best.map_or(T::INFINITY, |b| self.tr.cutoff_after(b.t))
    }

    #[inline]
    fn leaf<C: CostCounter>(&mut self, start: usize, prims: &[u32], counter: &mut C) -> bool {
        let tr = self.tr;
        for_each_candidate(self.packed, start, prims, &tr.prepared, |p| {
            if !self.mailbox.seen(p) {
                counter.prim();
                let t_max = self.best.map_or(tr.ray().t_max, |b| b.t);
                if let Some(h) = self.prims.intersect(p as usize, &tr.prepared, t_max) {
                    self.best = nearer(self.best, Hit::new(p, h));
                }
            }
            false
        });
        false
    }
}

/// Any hit.
pub(crate) struct AnyHit<'q, T: Real, P: ?Sized> {
    pub(crate) prims: &'q P,
    pub(crate) packed: Option<&'q PackedTriangles<T>>,
    pub(crate) tr: &'q TraversalRay<T>,
    pub(crate) mailbox: Mailbox,
    pub(crate) found: bool,
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> Visitor<T> for AnyHit<'_, T, P> {
    #[inline]
    fn cutoff(&self) -> T {
        T::INFINITY
    }

    #[inline]
    fn leaf<C: CostCounter>(&mut self, start: usize, prims: &[u32], counter: &mut C) -> bool {
        let tr = self.tr;
        let t_max = tr.ray().t_max;
        self.found = for_each_candidate(self.packed, start, prims, &tr.prepared, |p| {
            if self.mailbox.seen(p) {
                return false;
            }
            counter.prim();
            self.prims
                .intersect(p as usize, &tr.prepared, t_max)
                .is_some()
        });
        self.found
    }
}

/// The rounding allowance, in units of `gamma(1)`, of [`band`]'s centre and
/// of its half-width factor.
pub(crate) const BAND_ROUNDINGS: u32 = 8;

/// [`TraversalRay::plane_band`] by the reciprocal direction instead of two
/// divisions, for a beam of half-width `delta` (the node's, from
/// [`node_beam`], at most the query's): an interval holding every parameter
/// at which the beam touches the plane `x[axis] = s`, which is exactly
/// `(s − o)/d ∓ delta/|d|`.
///
/// It is computed as a centre and a half-width, without sorting two ends.
/// The centre `tc = (s − o)·inv` takes three roundings, so it lies within
/// `gamma(3)·|c|` of the exact `c = (s − o)/d`; `half_inv` is
/// `|inv|·(1 + gamma(8))`, at least `1/|d|` by more than its own and the
/// product's roundings. The half-width `gamma(8)·|tc| + delta·half_inv`
/// therefore exceeds `|tc − c| + delta/|d|` by more than the roundings of the
/// sum and of `tc ∓` it, so each end lies beyond the exact one.
///
/// Components whose reciprocal is not finite (zero or subnormal) take
/// plane_band itself, with the query's own (wider) beam. For a beam parallel
/// to the plane and clear of it, plane_band's empty band becomes `(+∞, +∞)`:
/// the near child (the origin's side) for the whole interval, the far child
/// never; within the beam it is `(−∞, +∞)`, both. An end that overflows, or
/// is `∞ − ∞ = NaN`, makes the walk keep the node's own interval for both
/// children.
#[inline(always)]
fn band<T: Real>(
    tr: &TraversalRay<T>,
    delta: T,
    inv: T,
    half_inv: T,
    axis: usize,
    s: T,
    o: T,
) -> (T, T) {
    if !inv.is_finite() {
        let (lo, hi) = tr.plane_band(axis, s);
        return if lo > hi {
            (T::INFINITY, T::INFINITY)
        } else {
            (lo, hi)
        };
    }
    finite_band(delta, inv, half_inv, s, o)
}

/// [`band`] for a finite reciprocal `inv` of the direction component, with
/// `half_inv = |inv|·(1 + gamma(BAND_ROUNDINGS))`.
#[inline(always)]
pub(crate) fn finite_band<T: Real>(delta: T, inv: T, half_inv: T, s: T, o: T) -> (T, T) {
    let tc = (s - o) * inv;
    let half = tc.abs() * T::gamma(BAND_ROUNDINGS) + delta * half_inv;
    (tc - half, tc + half)
}

/// How a query enters a part: by the wide beam that met the part's bounds
/// ([`WideRay::beam`], for primitives whose hits are accurate to the wide
/// type's rounding), or plainly, with [`TraversalRay::new`]'s beam.
#[derive(Clone, Copy)]
enum Entry<W> {
    /// The wide beam, still to be rounded to `T` and clipped.
    Wide(WideBeam<W>),
    /// The beam of `T`, still to be computed.
    Plain,
}

impl<W: Real> Entry<W> {
    /// The traversal ray of `ray` through a part with `bounds`, entered so;
    /// `None` when nothing there can be hit.
    #[inline(always)]
    fn traversal_ray<T: Real<Wide = W>>(
        self,
        ray: &Ray<T>,
        bounds: &Aabb<T>,
    ) -> Option<TraversalRay<T>> {
        match self {
            Entry::Wide(beam) => TraversalRay::from_wide(ray, beam),
            Entry::Plain => TraversalRay::new(ray, bounds),
        }
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P>> KdTree<'_, T, P, S> {
    /// Walks the leaves the beam touches, front to back, narrowing the beam
    /// below each node where the tree says it pays.
    #[inline]
    fn walk<V: Visitor<T>, C: CostCounter>(
        &self,
        root: usize,
        tr: &TraversalRay<T>,
        v: &mut V,
        counter: &mut C,
    ) {
        let finite = [0, 1, 2]
            .iter()
            .all(|&a| tr.prepared.inv_dir[a].is_finite());
        match (self.reach.is_empty(), finite) {
            (true, true) => self.walk_with::<false, true, V, C>(root, tr, v, counter),
            (true, false) => self.walk_with::<false, false, V, C>(root, tr, v, counter),
            (false, true) => self.walk_with::<true, true, V, C>(root, tr, v, counter),
            (false, false) => self.walk_with::<true, false, V, C>(root, tr, v, counter),
        }
    }

    /// [`KdTree::walk`], with the beam narrowed per node ([`node_beam`]) if
    /// `NARROW`, else the query's beam throughout. `FINITE` promises that
    /// every reciprocal of the direction is finite (so no component is
    /// zero): each node then takes [`finite_band`] without checking, and the
    /// near side is the sign of the component, known per axis in advance
    /// (about 14% fewer instructions per query on dense scenes than checking
    /// at every node). The promise is about speed, not correctness: an
    /// infinite reciprocal there would make a band with a NaN end, and the
    /// walk keeps the node's whole interval for both children then.
    #[inline]
    fn walk_with<const NARROW: bool, const FINITE: bool, V: Visitor<T>, C: CostCounter>(
        &self,
        root: usize,
        tr: &TraversalRay<T>,
        v: &mut V,
        counter: &mut C,
    ) {
        let ray = tr.ray();
        // Per-axis values as arrays of four, indexed by `axis & 3`: one load
        // each, where `Vec3`'s checked index costs a match.
        let lanes = |v: Vec3<T>| [v.x, v.y, v.z, T::ZERO];
        let (o, d, inv) = (
            lanes(ray.origin),
            lanes(ray.direction),
            lanes(tr.prepared.inv_dir),
        );
        let half_inv = lanes(tr.prepared.inv_dir.abs() * (T::ONE + T::gamma(BAND_ROUNDINGS)));
        let max_d = ray.direction.abs().max_component();
        let positive = d.map(|c| c > T::ZERO);
        // The parameter after which nodes are skipped; it only moves at leaves.
        let mut cutoff = v.cutoff();
        let mut stack = [(0u32, T::ZERO, T::ZERO); STACK];
        let mut sp = 0;
        let (mut idx, mut t0, mut t1) = (root, tr.t_start, tr.t_end);
        loop {
            if t0 <= cutoff {
                let node = &self.nodes[idx];
                counter.node();
                if !node.is_leaf() {
                    let axis = node.axis();
                    let s = decode_split(node.split_word(), &self.splits);
                    let (da, oa) = (d[axis & 3], o[axis & 3]);
                    let delta = if NARROW {
                        node_beam(self.reach[idx], t0, t1, max_d, tr.delta)
                    } else {
                        tr.delta
                    };
                    let (lo, hi, below_first) = if FINITE {
                        let (lo, hi) = finite_band(delta, inv[axis & 3], half_inv[axis & 3], s, oa);
                        (lo, hi, positive[axis & 3])
                    } else {
                        let (lo, hi) =
                            band(tr, delta, inv[axis & 3], half_inv[axis & 3], axis, s, oa);
                        // Below first when going up, or parallel on the low side
                        // (bitwise, not short-circuit: no branch to mispredict).
                        (lo, hi, (da > T::ZERO) | ((da == T::ZERO) & (oa <= s)))
                    };
                    // Child index 0 (the root's) stands for an empty leaf,
                    // which is not stored and never visited.
                    let below = if node.has_below() { idx + 1 } else { 0 };
                    let above = node.above_child() as usize;
                    let (near, far) = if below_first {
                        (below, above)
                    } else {
                        (above, below)
                    };
                    // Plain selects, which compile to single min/max
                    // instructions. A band end widened from an infinite
                    // product (∞ − ∞) is NaN; the select then keeps the
                    // node's own parameter, as `min`/`max` did.
                    let near_t1 = if hi < t1 { hi } else { t1 };
                    let far_t0 = if lo > t0 { lo } else { t0 };
                    let visit_far = (far_t0 <= t1) & (far != 0);
                    if (t0 <= near_t1) & (near != 0) {
                        // The far child waits on the stack when the beam
                        // reaches it (written always, kept only then: sp <
                        // STACK here, since an inner node lies above the
                        // depth limit).
                        stack[sp] = (far as u32, far_t0, t1);
                        sp += usize::from(visit_far);
                        idx = near;
                        t1 = near_t1;
                        continue;
                    }
                    if visit_far {
                        // The far child alone: straight there, not through
                        // the stack.
                        idx = far;
                        t0 = far_t0;
                        continue;
                    }
                } else {
                    let (start, prims) = self.leaf_list(node);
                    if v.leaf(start, prims, counter) {
                        return;
                    }
                    cutoff = v.cutoff();
                }
            }
            if sp == 0 {
                return;
            }
            sp -= 1;
            let (i, a, b) = stack[sp];
            (idx, t0, t1) = (i as usize, a, b);
        }
    }

    /// The nearest hit: each part walked in turn, with the best hit so far
    /// (each with the beam of its own bounds). A tree of one part, nearly
    /// every tree, takes a path of its own, without the loop.
    ///
    /// Where the primitives' hits are accurate to the wide type's rounding,
    /// the beam is that thin ([`TraversalRay::with_wide_hits`]; the walk's
    /// plane bands allow for their own rounding, relative to the
    /// parameters): the ray is cast to the wide type and divided there once
    /// for all the parts ([`WideRay`]), and each part's beam is entered in
    /// registers, then rounded to `T` and prepared only where it meets the
    /// part. Otherwise each part takes [`TraversalRay::new`]'s beam.
    pub(crate) fn nearest<C: CostCounter>(
        &self,
        ray: &Ray<T>,
        counter: &mut C,
    ) -> Result<Option<Hit<T>>, QueryError> {
        ray.validate()?;
        let mut best = None;
        self.nearest_parts(ray, &mut best, counter);
        Ok(best)
    }

    /// [`KdTree::nearest`] written into `slot`, for a bundle's ray that goes
    /// alone: each part's walk leaves its best hit in the slot itself.
    /// Returned and copied instead, the answer (32 bytes in `f32`) was read
    /// back in 16-byte loads straddling the narrower stores that had just
    /// written it, so no store forwarded: 80% of the bundle loop's own
    /// samples (`perf`, the flat field's diffuse rays in `studies peers`).
    #[inline(never)]
    pub(crate) fn nearest_into(&self, ray: &Ray<T>, slot: &mut Result<Option<Hit<T>>, QueryError>) {
        *slot = ray.validate().map(|()| None);
        if let Ok(best) = slot {
            self.nearest_parts(ray, best, &mut ());
        }
    }

    /// The nearest of `best` and the hits of every part, left in `best`.
    #[inline(always)]
    fn nearest_parts<C: CostCounter>(
        &self,
        ray: &Ray<T>,
        best: &mut Option<Hit<T>>,
        counter: &mut C,
    ) {
        let Some(wide) = self.wide_ray(ray) else {
            return;
        };
        if self.parts.len() == 1 {
            if let Some(entry) = Self::entry(&wide, &self.first) {
                self.nearest_in(&self.first, ray, entry, best, counter);
            }
            return;
        }
        for part in &self.parts {
            if let Some(entry) = Self::entry(&wide, part) {
                self.nearest_in(part, ray, entry, best, counter);
            }
        }
    }

    /// `ray`'s wide form, cast and divided once for all the parts, where
    /// the primitives' hits are wide (`Some(None)` where they are not);
    /// `None` when the ray's interval is empty, so nothing can be hit.
    #[inline(always)]
    fn wide_ray(&self, ray: &Ray<T>) -> Option<Option<WideRay<T::Wide>>> {
        if self.primitives().wide_hits() {
            WideRay::new(ray).map(Some)
        } else {
            (!ray.is_empty_interval()).then_some(None)
        }
    }

    /// How the ray whose wide form is `wide` ([`KdTree::wide_ray`]) enters
    /// `part`: by its wide beam, `None` when that misses the part's bounds;
    /// plainly where the primitives' hits are not wide.
    #[inline(always)]
    fn entry(wide: &Option<WideRay<T::Wide>>, part: &KdPart<T>) -> Option<Entry<T::Wide>> {
        match wide {
            Some(wide) => wide.beam(&part.bounds).map(Entry::Wide),
            None => Some(Entry::Plain),
        }
    }

    /// The nearest of `best` and the hits in `part`, which `ray` enters by
    /// `entry`, left in `best`. Not inlined: the parts' loop keeps the
    /// ray's wide values in registers (passed through memory, a part's
    /// loads straddled their stores: the flat field's diffuse rays ran 5%
    /// slower with 9% fewer instructions), and the walk's code is not
    /// copied per caller.
    #[inline(never)]
    fn nearest_in<C: CostCounter>(
        &self,
        part: &KdPart<T>,
        ray: &Ray<T>,
        entry: Entry<T::Wide>,
        best: &mut Option<Hit<T>>,
        counter: &mut C,
    ) {
        // Borrowed where it was built: moved out of the option, the ray was
        // copied in 16-byte loads straddling the 4-byte stores that had
        // just written its beam (no store forwarding; 3% of the walk's
        // samples, the sphere's camera rays 4% slower).
        let entered = entry.traversal_ray(ray, &part.bounds);
        let Some(tr) = &entered else {
            return;
        };
        let mut v = self.nearest_visitor(tr, *best);
        self.walk(part.root, tr, &mut v, counter);
        *best = v.best;
    }

    /// Any hit, part by part (each part entered as in
    /// [`KdTree::nearest`]).
    pub(crate) fn any<C: CostCounter>(
        &self,
        ray: &Ray<T>,
        counter: &mut C,
    ) -> Result<bool, QueryError> {
        ray.validate()?;
        let Some(wide) = self.wide_ray(ray) else {
            return Ok(false);
        };
        if self.parts.len() == 1 {
            return Ok(Self::entry(&wide, &self.first)
                .is_some_and(|entry| self.any_in(&self.first, ray, entry, counter)));
        }
        Ok(self.parts.iter().any(|part| {
            Self::entry(&wide, part).is_some_and(|entry| self.any_in(part, ray, entry, counter))
        }))
    }

    /// The nearest-hit visitor of `tr` on this tree's primitives, from
    /// `best` and an empty mailbox (single walks and packets alike).
    #[inline(always)]
    pub(crate) fn nearest_visitor<'q>(
        &'q self,
        tr: &'q TraversalRay<T>,
        best: Option<Hit<T>>,
    ) -> Nearest<'q, T, P> {
        Nearest {
            prims: self.primitives(),
            packed: self.packed.as_ref(),
            tr,
            mailbox: Mailbox::new(),
            best,
        }
    }

    /// The any-hit visitor of `tr` on this tree's primitives, with an
    /// empty mailbox, as [`KdTree::nearest_visitor`].
    #[inline(always)]
    pub(crate) fn any_visitor<'q>(&'q self, tr: &'q TraversalRay<T>) -> AnyHit<'q, T, P> {
        AnyHit {
            prims: self.primitives(),
            packed: self.packed.as_ref(),
            tr,
            mailbox: Mailbox::new(),
            found: false,
        }
    }

    /// Whether anything in `part` is hit, which `ray` enters by `entry`
    /// (not inlined, as [`KdTree::nearest_in`]).
    #[inline(never)]
    fn any_in<C: CostCounter>(
        &self,
        part: &KdPart<T>,
        ray: &Ray<T>,
        entry: Entry<T::Wide>,
        counter: &mut C,
    ) -> bool {
        // Borrowed where it was built, as in `nearest_in`.
        let entered = entry.traversal_ray(ray, &part.bounds);
        let Some(tr) = &entered else {
            return false;
        };
        let mut v = self.any_visitor(tr);
        self.walk(part.root, tr, &mut v, counter);
        v.found
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized, S: Borrow<P> + Sync> Accelerator<T>
    for KdTree<'_, T, P, S>
{
    fn bounds(&self) -> Aabb<T> {
        self.bounds
    }

    accel_core::ray_queries_from_walks!();

    /// Packets of rays of one direction octant walked together (the
    /// crate's bundle docs), other rays one at a time.
    fn intersect_bundle(&self, rays: &[Ray<T>], out: &mut [Result<Option<Hit<T>>, QueryError>]) {
        self.nearest_bundle(rays, out);
    }

    /// As [`Accelerator::intersect_bundle`].
    fn occluded_bundle(&self, rays: &[Ray<T>], out: &mut [Result<bool, QueryError>]) {
        self.any_bundle(rays, out);
    }

    /// Gathers the references of every leaf near the region, then keeps
    /// those the primitive's own overlap test accepts.
    ///
    /// "Near" is the region grown by `gamma(1024)` of the largest coordinate
    /// in play: leaves hold every point of their primitives, and an exact
    /// overlap test (the triangle–box test) may accept a box up to its own
    /// rounding allowance away from the primitive, far less than that.
    fn query_region(&self, region: &Aabb<T>) -> Result<Vec<u32>, QueryError> {
        validate_region(region)?;
        if region.is_empty() || self.bounds.is_empty() {
            return Ok(Vec::new());
        }
        let grown = region_search_box(region, &self.bounds);
        let mut found: Vec<u32> = Vec::new();
        if grown.overlaps(&self.bounds) {
            let mut stack: Vec<usize> = self
                .parts
                .iter()
                .filter(|p| grown.overlaps(&p.bounds))
                .map(|p| p.root)
                .collect();
            while let Some(i) = stack.pop() {
                let node = &self.nodes[i];
                if node.is_leaf() {
                    found.extend_from_slice(self.leaf_primitives(node));
                    continue;
                }
                let (axis, s) = (node.axis(), decode_split(node.split_word(), &self.splits));
                let [below, above] = node.children(i);
                stack.extend(below.filter(|_| grown.min[axis] <= s));
                stack.extend(above.filter(|_| grown.max[axis] >= s));
            }
        }
        Ok(region_matches(self.primitives(), region, found))
    }

    fn stats(&self) -> AccelStats {
        self.shape_stats().clone()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A value of either sign spread over many binades.
    fn spread(max_exp: i32) -> impl Strategy<Value = f32> {
        (any::<bool>(), 1.0..2.0f32, -max_exp..=max_exp)
            .prop_map(|(neg, m, e)| if neg { -m } else { m } * 2f32.powi(e))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(20_000))]
        /// The band holds the exact parameters `(s − o)/d ∓ delta/|d|`,
        /// computed in `f64` (the `f32` difference is exact there, and the
        /// two divisions' roundings are far below the `f32` margins, so a
        /// tolerance of a few `f64` rounding units suffices). Beams from
        /// far thinner than the rounding of `s − o` to far wider.
        #[test]
        fn band_holds_the_exact_interval_where_the_beam_meets_the_plane(
            o in spread(20),
            s in spread(20),
            d in spread(30),
            delta_exp in -40..10i32,
        ) {
            let delta = 2f32.powi(delta_exp);
            let inv = 1.0 / d;
            prop_assume!(inv.is_finite());
            let half_inv = inv.abs() * (1.0 + <f32 as Real>::gamma(BAND_ROUNDINGS));
            let (lo, hi) = finite_band(delta, inv, half_inv, s, o);
            let (o, s, d, delta) = (f64::from(o), f64::from(s), f64::from(d), f64::from(delta));
            let (c, r) = ((s - o) / d, delta / d.abs());
            let slack = (c.abs() + r) * 4.0 * f64::EPSILON;
            prop_assert!(f64::from(lo) <= c - r + slack, "lo {lo} > {}", c - r);
            prop_assert!(f64::from(hi) >= c + r - slack, "hi {hi} < {}", c + r);
        }
    }
}
