//! The bounds of a triangle's part of a box, conservative despite rounding:
//! every vertex of the clipped polygon computed from the input with an
//! explicit error bound, for the kD-tree's perfect splits
//! ([`crate::PrimitiveSet::clipped_bounds`]).

use crate::{Aabb, Real, Vec3};

/// The bounds of the part of triangle `p0 p1 p2` inside the closed box `b`,
/// computed so that they always **contain** the true triangle ∩ box despite
/// rounding, then intersected with `b` and the triangle's own bounds. Empty
/// when the triangle surely misses the box.
///
/// Sutherland–Hodgman clipping computes each new vertex from the previous
/// ones, so its errors compound, and an edge nearly parallel to a later
/// clipping plane can move its crossing arbitrarily far along the edge. This
/// clipper therefore computes every vertex of the clipped polygon directly
/// from the input, with an explicit error bound. A vertex of triangle ∩ box
/// is one of:
/// 1. a triangle vertex inside the box (exact);
/// 2. a crossing of a triangle edge with a box face plane (the edge must
///    cross the plane strictly), kept when it may lie inside the face;
/// 3. a crossing of a box edge with the triangle, found in the projection
///    along the box edge's axis by 2D edge functions (kept when the box edge
///    may pierce the triangle), its height interpolated from barycentric
///    weights; where the projection is too thin to trust, the triangle's whole
///    extent on that axis is taken instead.
///
/// Only planes the triangle's bounds cross strictly can hold crossings, so a
/// small triangle straddling one plane costs two edge crossings. Every
/// candidate whose membership is uncertain under the error bounds is kept:
/// extra candidates only enlarge the result. The arithmetic runs in
/// [`Real::Wide`]; the result is rounded outward to `T`.
#[must_use]
pub fn clip_triangle_bounds<T: Real>(
    p0: Vec3<T>,
    p1: Vec3<T>,
    p2: Vec3<T>,
    b: &Aabb<T>,
) -> Aabb<T> {
    let tb = Aabb::from_point(p0).union_point(p1).union_point(p2);
    if b.is_empty() || !tb.overlaps(b) {
        return Aabb::empty();
    }
    if b.contains(&tb) {
        return tb;
    }
    let limit = tb.intersection(b);
    let clip = Clip::new([p0, p1, p2], b, &tb);
    let mut acc = WideBox::<T::Wide>::empty();
    // 1. Vertices inside the box.
    for p in &clip.v {
        if (0..3).all(|a| p[a] >= clip.bmin[a] && p[a] <= clip.bmax[a]) {
            acc.add(*p, *p);
        }
    }
    // 2. Edges crossing a face plane.
    let crossed = [0, 1, 2].map(|a| clip.crossed(a));
    clip.edge_crossings::<0, 1, 2>(crossed[0], &mut acc);
    clip.edge_crossings::<1, 2, 0>(crossed[1], &mut acc);
    clip.edge_crossings::<2, 0, 1>(crossed[2], &mut acc);
    // 3. Box edges piercing the triangle.
    clip.box_edges::<0, 1, 2>(crossed[1], crossed[2], &mut acc);
    clip.box_edges::<1, 2, 0>(crossed[2], crossed[0], &mut acc);
    clip.box_edges::<2, 0, 1>(crossed[0], crossed[1], &mut acc);
    rounded(&acc, &limit)
}

/// [`clip_triangle_bounds`] of the triangle for both halves of box `b` cut
/// at `x[axis] = s` (`axis` in `0..3`; below, then above, as
/// [`Aabb::split_at`]): equal to the two calls, but sharing their work. The
/// halves have four faces and the cut in common, so the triangle's crossings
/// with those planes, and the box edges on them, are computed once; only
/// the node's two faces on `axis` belong to one half each. A kD-tree build
/// clips each primitive its split straddles this way.
#[must_use]
pub fn clip_triangle_bounds_split<T: Real>(
    p0: Vec3<T>,
    p1: Vec3<T>,
    p2: Vec3<T>,
    b: &Aabb<T>,
    axis: usize,
    s: T,
) -> [Aabb<T>; 2] {
    let (below, above) = b.split_at(axis, s);
    let tb = Aabb::from_point(p0).union_point(p1).union_point(p2);
    // A half the triangle misses or lies in ends the single clipper at once.
    let at_once = |h: &Aabb<T>| h.is_empty() || !tb.overlaps(h) || h.contains(&tb);
    if at_once(&below) || at_once(&above) {
        return [
            clip_triangle_bounds(p0, p1, p2, &below),
            clip_triangle_bounds(p0, p1, p2, &above),
        ];
    }
    let clip = Clip::new([p0, p1, p2], b, &tb);
    let acc = match axis {
        0 => clip.split::<0, 1, 2>(s.to_wide()),
        1 => clip.split::<1, 2, 0>(s.to_wide()),
        _ => clip.split::<2, 0, 1>(s.to_wide()),
    };
    [
        rounded(&acc[0], &tb.intersection(&below)),
        rounded(&acc[1], &tb.intersection(&above)),
    ]
}

/// The bounds of the parts of triangle `p0 p1 p2` below and above the plane
/// `x[axis] = s` (`axis` in `0..3`), each holding its part despite
/// rounding: the vertices on that side and the edges' crossings with the
/// plane, no box faces. They are [`clip_triangle_bounds`] of each half of
/// the triangle's own bounds, computed the cheaper way. A kD-tree build
/// tightens the box of a primitive its split straddles with them where
/// clipping to the node ([`clip_triangle_bounds_split`]) costs too much. A
/// half the triangle does not reach is empty.
#[must_use]
pub fn triangle_halves_bounds<T: Real>(
    p0: Vec3<T>,
    p1: Vec3<T>,
    p2: Vec3<T>,
    axis: usize,
    s: T,
) -> [Aabb<T>; 2] {
    let tb = Aabb::from_point(p0).union_point(p1).union_point(p2);
    let (below, above) = tb.split_at(axis, s);
    if !(tb.min[axis] < s && s < tb.max[axis]) {
        // The plane does not cut the triangle's extent: one half holds it
        // all, or meets it in a face.
        return [below, above].map(|h| clip_triangle_bounds(p0, p1, p2, &h));
    }
    // The triangle's own bounds as the box: its faces cross nothing.
    let clip = Clip::new([p0, p1, p2], &tb, &tb);
    let acc = match axis {
        0 => clip.halves::<0, 1, 2>(s.to_wide()),
        1 => clip.halves::<1, 2, 0>(s.to_wide()),
        _ => clip.halves::<2, 0, 1>(s.to_wide()),
    };
    [rounded(&acc[0], &below), rounded(&acc[1], &above)]
}

/// The inputs of one [`clip_triangle_bounds`] in the wide type, per axis.
struct Clip<W> {
    /// The triangle's vertices.
    v: [[W; 3]; 3],
    bmin: [W; 3],
    bmax: [W; 3],
    /// The triangle's bounds.
    tmin: [W; 3],
    tmax: [W; 3],
}

impl<W: Real> Clip<W> {
    /// Triangle `p`, whose bounds are `tb`, and box `b` in the wide type.
    /// Per-axis values are arrays, so that the axes of the methods below,
    /// fixed at compile time, select components without `Vec3`'s checked
    /// index.
    #[inline(always)]
    fn new<T: Real<Wide = W>>(p: [Vec3<T>; 3], b: &Aabb<T>, tb: &Aabb<T>) -> Self {
        let w = |v: Vec3<T>| [v.x.to_wide(), v.y.to_wide(), v.z.to_wide()];
        Self {
            v: p.map(w),
            bmin: w(b.min),
            bmax: w(b.max),
            tmin: w(tb.min),
            tmax: w(tb.max),
        }
    }

    /// The box's face planes on axis `a` that the triangle's bounds cross
    /// strictly (the only ones that can hold crossings).
    #[inline(always)]
    fn crossed(&self, a: usize) -> [Option<W>; 2] {
        [self.bmin[a], self.bmax[a]].map(|c| (self.tmin[a] < c && c < self.tmax[a]).then_some(c))
    }

    /// The accumulated candidates of [`clip_triangle_bounds_split`] for the
    /// halves below and above `x[K] = s` (axes `U`, `V` the other two), each
    /// as [`clip_triangle_bounds`] gathers them for that half alone. A
    /// candidate's test against a half's faces differs between the halves
    /// only on `K`, so the shared candidates are computed once and checked
    /// on `K` per half.
    #[inline(always)]
    fn split<const K: usize, const U: usize, const V: usize>(&self, s: W) -> [WideBox<W>; 2] {
        let (lo_k, hi_k) = ([self.bmin[K], s], [s, self.bmax[K]]);
        let on_k = |lo: &[W; 3], hi: &[W; 3], h: usize| hi[K] >= lo_k[h] && lo[K] <= hi_k[h];
        let mut acc = [WideBox::empty(), WideBox::empty()];
        // 1. Vertices inside a half.
        for p in &self.v {
            if [U, V]
                .iter()
                .all(|&a| p[a] >= self.bmin[a] && p[a] <= self.bmax[a])
            {
                for (h, acc) in acc.iter_mut().enumerate() {
                    if on_k(p, p, h) {
                        acc.add(*p, *p);
                    }
                }
            }
        }
        // The planes on K each half has: its outer face and the cut.
        let cut = |c: W| (self.tmin[K] < c && c < self.tmax[K]).then_some(c);
        let k_planes = [
            (cut(self.bmin[K]), [true, false]),
            (cut(s), [true, true]),
            (cut(self.bmax[K]), [false, true]),
        ];
        let (on_u, on_v) = (self.crossed(U), self.crossed(V));
        // Each candidate goes to the halves it may lie in.
        let mut add = |(lo, hi): ([W; 3], [W; 3]), halves: [bool; 2]| {
            for (acc, _) in acc.iter_mut().zip(halves).filter(|(_, has)| *has) {
                acc.add(lo, hi);
            }
        };
        let by_k = |(lo, hi): &([W; 3], [W; 3])| [0, 1].map(|h| on_k(lo, hi, h));
        // 2. Edges crossing a face plane: on U and V, shared, then checked
        // on K per half; on K, checked on U and V alone, so each belongs to
        // the halves that have its plane.
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            for c in on_u.into_iter().flatten() {
                if let Some(x) = self.edge_crossing::<U, V, K, K>(i, j, c) {
                    add(x, by_k(&x));
                }
            }
            for c in on_v.into_iter().flatten() {
                if let Some(x) = self.edge_crossing::<V, K, U, K>(i, j, c) {
                    add(x, by_k(&x));
                }
            }
            for (c, halves) in k_planes {
                if let Some(x) = c.and_then(|c| self.edge_crossing::<K, U, V, 3>(i, j, c)) {
                    add(x, halves);
                }
            }
        }
        // 3. Box edges piercing the triangle. Along K: shared, checked on K
        // per half. Along U (on a plane of V and one of K) and along V (on a
        // plane of K and one of U): for the halves with that K plane.
        for cu in on_u.into_iter().flatten() {
            for cv in on_v.into_iter().flatten() {
                if let Some(x) = self.box_edge_corners::<K, U, V, false>(cu, cv) {
                    add(x, by_k(&x));
                }
            }
        }
        for (ck, halves) in k_planes {
            let Some(ck) = ck else { continue };
            for cv in on_v.into_iter().flatten() {
                if let Some(x) = self.box_edge_corners::<U, V, K, true>(cv, ck) {
                    add(x, halves);
                }
            }
            for cu in on_u.into_iter().flatten() {
                if let Some(x) = self.box_edge_corners::<V, K, U, true>(ck, cu) {
                    add(x, halves);
                }
            }
        }
        acc
    }

    /// [`triangle_halves_bounds`]'s candidates below and above `x[K] = s`
    /// (`U`, `V` the other two axes): the vertices on each side, and the
    /// edges' crossings with the plane on both.
    #[inline(always)]
    fn halves<const K: usize, const U: usize, const V: usize>(&self, s: W) -> [WideBox<W>; 2] {
        let mut acc = [WideBox::empty(), WideBox::empty()];
        for p in &self.v {
            if p[K] <= s {
                acc[0].add(*p, *p);
            }
            if p[K] >= s {
                acc[1].add(*p, *p);
            }
        }
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            if let Some((lo, hi)) = self.edge_crossing::<K, U, V, 3>(i, j, s) {
                acc[0].add(lo, hi);
                acc[1].add(lo, hi);
            }
        }
        acc
    }

    /// Case 2 on axis `A` (`B`, `C` the other two): each triangle edge
    /// crossing one of the crossed face planes.
    #[inline(always)]
    fn edge_crossings<const A: usize, const B: usize, const C: usize>(
        &self,
        planes: [Option<W>; 2],
        acc: &mut WideBox<W>,
    ) {
        for c in planes.into_iter().flatten() {
            for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                if let Some((lo, hi)) = self.edge_crossing::<A, B, C, 3>(i, j, c) {
                    acc.add(lo, hi);
                }
            }
        }
    }

    /// Where the edge `v[i] v[j]` crosses the plane `x[A] = c` (which it must
    /// cross strictly), as an interval per axis that holds the true crossing;
    /// `None` when the crossing surely lies outside the box's face (on axes
    /// other than `SKIP`, which the caller checks; 3 checks both).
    #[inline(always)]
    fn edge_crossing<const A: usize, const B: usize, const C: usize, const SKIP: usize>(
        &self,
        i: usize,
        j: usize,
        c: W,
    ) -> Option<([W; 3], [W; 3])> {
        let (p, q) = (&self.v[i], &self.v[j]);
        if !((p[A] < c && c < q[A]) || (q[A] < c && c < p[A])) {
            return None;
        }
        // t in (0, 1) exactly; its computed value has a relative error of a
        // few roundings, so clamping it only moves it toward the truth. An
        // overflow (coordinates near the largest float) gives up on the
        // interpolation.
        let raw = (c - p[A]) / (q[A] - p[A]);
        let t = raw.max(W::ZERO).min(W::ONE);
        let mut lo = [c; 3];
        let mut hi = lo;
        for ax in [B, C] {
            let (pa, qa) = (p[ax], q[ax]);
            let (edge_lo, edge_hi) = (pa.min(qa), pa.max(qa));
            let x = pa + t * (qa - pa);
            // t: 3 roundings (relative), the difference, product and sum: 3 more.
            let err = W::gamma(8) * (pa.abs() + pa.abs() + qa.abs()) + tiny::<W>();
            let (l, h) = if raw.is_finite() && x.is_finite() && err.is_finite() {
                ((x - err).max(edge_lo), (x + err).min(edge_hi))
            } else {
                (edge_lo, edge_hi)
            };
            if ax != SKIP && (h < self.bmin[ax] || l > self.bmax[ax]) {
                return None;
            }
            lo[ax] = l;
            hi[ax] = h;
        }
        Some((lo, hi))
    }

    /// Case 3 for the box edges along axis `A`: those on a crossed plane of
    /// each other axis (`B`'s in `on_b`, `C`'s in `on_c`).
    #[inline(always)]
    fn box_edges<const A: usize, const B: usize, const C: usize>(
        &self,
        on_b: [Option<W>; 2],
        on_c: [Option<W>; 2],
        acc: &mut WideBox<W>,
    ) {
        for cb in on_b.into_iter().flatten() {
            for cc in on_c.into_iter().flatten() {
                if let Some((lo, hi)) = self.box_edge_corners::<A, B, C, true>(cb, cc) {
                    acc.add(lo, hi);
                }
            }
        }
    }

    /// The box edge `{x[B] = cb, x[C] = cc}`'s crossing with the triangle
    /// ([`Clip::box_edge_crossing`]) as a pair of corners; `None` when it
    /// surely misses the triangle or, if `CHECK_A`, the box's extent on `A`
    /// (else the caller checks that).
    #[inline(always)]
    fn box_edge_corners<const A: usize, const B: usize, const C: usize, const CHECK_A: bool>(
        &self,
        cb: W,
        cc: W,
    ) -> Option<([W; 3], [W; 3])> {
        let (lo_a, hi_a) = self.box_edge_crossing::<A, B, C>(cb, cc)?;
        if CHECK_A && !(hi_a >= self.bmin[A] && lo_a <= self.bmax[A]) {
            return None;
        }
        let mut lo = [W::ZERO; 3];
        lo[A] = lo_a;
        lo[B] = cb;
        lo[C] = cc;
        let mut hi = lo;
        hi[A] = hi_a;
        Some((lo, hi))
    }

    /// Where the box edge `{x[B] = cb, x[C] = cc}` pierces the triangle: an
    /// interval of `x[A]` that holds the crossing, or `None` when the edge
    /// surely misses the triangle. The triangle's extent on `A` is the
    /// answer when the projection is too thin to interpolate.
    #[inline(always)]
    fn box_edge_crossing<const A: usize, const B: usize, const C: usize>(
        &self,
        cb: W,
        cc: W,
    ) -> Option<(W, W)> {
        let v = &self.v;
        let p = v.map(|p| (p[B], p[C]));
        let x = (cb, cc);
        let (e0, r0) = orient(p[1], p[2], x);
        let (e1, r1) = orient(p[2], p[0], x);
        let (e2, r2) = orient(p[0], p[1], x);
        let pos = e0 > r0 || e1 > r1 || e2 > r2;
        let neg = e0 < -r0 || e1 < -r1 || e2 < -r2;
        if pos && neg {
            return None;
        }
        // Barycentric interpolation of x[A]; trusted only when the projected
        // area is well above its error.
        let d = e0 + e1 + e2;
        let rd = r0 + r1 + r2 + W::gamma(2) * (e0.abs() + e1.abs() + e2.abs());
        let range = (self.tmin[A], self.tmax[A]);
        if !(d.abs() > rd + rd) || !d.is_finite() {
            return Some(range);
        }
        let clamp = |l: W| l.max(W::ZERO).min(W::ONE);
        let (l1, l2) = (clamp(e1 / d), clamp(e2 / d));
        let (d1, d2) = (v[1][A] - v[0][A], v[2][A] - v[0][A]);
        let xa = v[0][A] + l1 * d1 + l2 * d2;
        // |d_true| >= |d|/2 here, so each weight is off by at most
        // 2·(r_i + rd)/|d| plus its own rounding.
        let dl1 = (r1 + rd) * W::from_f64(2.0) / d.abs() + W::gamma(2);
        let dl2 = (r2 + rd) * W::from_f64(2.0) / d.abs() + W::gamma(2);
        let err = dl1 * d1.abs()
            + dl2 * d2.abs()
            + W::gamma(8) * (v[0][A].abs() + d1.abs() + d2.abs())
            + tiny::<W>();
        if !(xa.is_finite() && err.is_finite()) {
            return Some(range);
        }
        Some(((xa - err).max(range.0), (xa + err).min(range.1)))
    }
}

/// A box in the wide type that grows by corner pairs.
struct WideBox<W> {
    lo: [W; 3],
    hi: [W; 3],
}

impl<W: Real> WideBox<W> {
    fn empty() -> Self {
        Self {
            lo: [W::INFINITY; 3],
            hi: [W::NEG_INFINITY; 3],
        }
    }

    #[inline(always)]
    fn add(&mut self, lo: [W; 3], hi: [W; 3]) {
        for a in 0..3 {
            self.lo[a] = self.lo[a].min(lo[a]);
            self.hi[a] = self.hi[a].max(hi[a]);
        }
    }
}

/// The candidates' box rounded outward to `T`, within `limit`; empty when
/// there were none.
fn rounded<T: Real>(acc: &WideBox<T::Wide>, limit: &Aabb<T>) -> Aabb<T> {
    if acc.lo[0] > acc.hi[0] {
        return Aabb::empty();
    }
    let (lo, hi) = (acc.lo, acc.hi);
    Aabb {
        min: Vec3::new(
            round_down::<T>(lo[0]),
            round_down::<T>(lo[1]),
            round_down::<T>(lo[2]),
        ),
        max: Vec3::new(
            round_up::<T>(hi[0]),
            round_up::<T>(hi[1]),
            round_up::<T>(hi[2]),
        ),
    }
    .intersection(limit)
}

/// The largest `T` not above `x`.
fn round_down<T: Real>(x: T::Wide) -> T {
    let r = T::from_wide(x);
    if r.to_wide() > x { r.next_down() } else { r }
}

/// The smallest `T` not below `x`.
fn round_up<T: Real>(x: T::Wide) -> T {
    let r = T::from_wide(x);
    if r.to_wide() < x { r.next_up() } else { r }
}

/// An absolute error floor for results that may underflow (far below any
/// coordinate that matters, far above the subnormal rounding unit).
fn tiny<W: Real>() -> W {
    W::from_f64(1e-290)
}

/// A 2D edge function `(q − p) × (x − p)` with a bound on its rounding error.
#[inline(always)]
fn orient<W: Real>(p: (W, W), q: (W, W), x: (W, W)) -> (W, W) {
    let t1 = (q.0 - p.0) * (x.1 - p.1);
    let t2 = (q.1 - p.1) * (x.0 - p.0);
    // Each difference and product rounds (three roundings per term), then the
    // subtraction: gamma(4) of the terms, doubled for margin.
    let err = W::gamma(8) * (t1.abs() + t2.abs()) + tiny::<W>();
    (t1 - t2, err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::tests::{Rng, samples, v};

    /// The clipped box holds every sampled point of the triangle inside the
    /// box, lies in the box and the triangle's bounds, and is not much larger
    /// than the sampled part (the sample spacing bounds the difference).
    fn check_clip<T: Real>(p: [Vec3<f64>; 3], b: &Aabb<f64>, n: u32) {
        let pt: [Vec3<T>; 3] = p.map(|v| v.cast());
        let bt: Aabb<T> = b.cast();
        let exact: [Vec3<f64>; 3] = pt.map(|v| v.cast());
        let clipped = clip_triangle_bounds(pt[0], pt[1], pt[2], &bt);
        let tb = Aabb::from_points(pt);
        let inside: Vec<Vec3<f64>> = samples(exact, n)
            .into_iter()
            .filter(|q| bt.cast::<f64>().contains_point(*q) && tb.cast::<f64>().contains_point(*q))
            .collect();
        if inside.is_empty() {
            return;
        }
        assert!(
            !clipped.is_empty(),
            "{p:?} {b:?}: empty clip of a meeting triangle"
        );
        let c64: Aabb<f64> = clipped.cast();
        // A sample's own rounding (a few f64 ulps of the coordinates) is
        // allowed for; the f32 clipper rounds outward by whole f32 ulps.
        let tol = 8.0 * f64::EPSILON * Aabb::from_points(exact).max_abs_coordinate();
        for q in &inside {
            assert!(
                c64.expanded(tol).contains_point(*q),
                "{p:?} in {b:?}: {q:?} outside {clipped:?}"
            );
        }
        assert!(bt.contains(&clipped) && tb.contains(&clipped));
        // Tightness: within rounding of a plain Sutherland–Hodgman clip in f64
        // (accurate to a few ulps here, but not conservative).
        let reference = sutherland_hodgman(exact, &bt.cast());
        let slack = 1e-6 * b.max_abs_coordinate().max(1.0);
        for a in 0..3 {
            assert!(
                c64.min[a] >= reference.min[a] - slack,
                "{p:?} {b:?}: loose min {a}: {c64:?} vs {reference:?}"
            );
            assert!(
                c64.max[a] <= reference.max[a] + slack,
                "{p:?} {b:?}: loose max {a}: {c64:?} vs {reference:?}"
            );
        }
    }

    /// The textbook clipper: the polygon clipped by each of the six half-spaces.
    fn sutherland_hodgman(p: [Vec3<f64>; 3], b: &Aabb<f64>) -> Aabb<f64> {
        let mut poly: Vec<Vec3<f64>> = p.to_vec();
        for a in 0..3 {
            for (c, keep_below) in [(b.min[a], false), (b.max[a], true)] {
                let inside = |q: &Vec3<f64>| if keep_below { q[a] <= c } else { q[a] >= c };
                let mut out = Vec::new();
                for k in 0..poly.len() {
                    let (s, e) = (poly[k], poly[(k + 1) % poly.len()]);
                    if inside(&s) {
                        out.push(s);
                    }
                    if inside(&s) != inside(&e) {
                        let t = (c - s[a]) / (e[a] - s[a]);
                        let mut x = s + (e - s) * t;
                        x[a] = c;
                        out.push(x);
                    }
                }
                poly = out;
            }
        }
        Aabb::from_points(poly)
    }

    #[test]
    fn clip_holds_dense_samples_of_random_triangles_in_a_1_2_3_box() {
        let mut rng = Rng(17);
        let b = Aabb::new(v::<f64>(0.5, -1.0, 2.0), v(1.5, 1.0, 5.0));
        for _ in 0..400 {
            let p = [0; 3].map(|_| {
                v::<f64>(
                    rng.range(-0.5, 2.5),
                    rng.range(-2.0, 2.0),
                    rng.range(1.0, 6.0),
                )
            });
            check_clip::<f64>(p, &b, 160);
            check_clip::<f32>(p, &b, 160);
        }
    }

    /// The split clipper against the single one on each half: equal boxes
    /// (or both empty), for triangles from much smaller than the box to much
    /// larger, cuts anywhere in it, on its faces and through vertices.
    fn check_split<T: Real>(rng: &mut Rng, cases: usize) -> usize {
        let b = Aabb::new(v::<T>(0.5, -1.0, 2.0), v(1.5, 1.0, 5.0));
        let mut shared = 0;
        for _ in 0..cases {
            let (centre, size) = (
                [
                    rng.range(0.0, 2.0),
                    rng.range(-1.5, 1.5),
                    rng.range(1.5, 5.5),
                ],
                rng.range(0.05, 8.0),
            );
            let p = [0; 3].map(|_| {
                let mut c = [0; 3].map(|_| rng.range(-size, size));
                for (x, m) in c.iter_mut().zip(centre) {
                    *x += m;
                }
                v::<T>(c[0], c[1], c[2])
            });
            let axis = (rng.next_f64() * 3.0) as usize % 3;
            let pick = rng.next_f64();
            let s = if pick < 0.2 {
                p[(rng.next_f64() * 3.0) as usize % 3][axis]
            } else if pick < 0.3 {
                b.min[axis]
            } else {
                T::from_f64(rng.range(b.min[axis].to_f64(), b.max[axis].to_f64()))
            };
            let (below, above) = b.split_at(axis, s);
            let want = [below, above].map(|h| clip_triangle_bounds(p[0], p[1], p[2], &h));
            let got = clip_triangle_bounds_split(p[0], p[1], p[2], &b, axis, s);
            for (w, g) in want.iter().zip(&got) {
                assert!(
                    (w.is_empty() && g.is_empty()) || (w.min == g.min && w.max == g.max),
                    "{p:?} cut at x[{axis}] = {s:?}: {g:?}, single clips {want:?}"
                );
            }
            let tb = Aabb::from_points(p);
            let own_work = |h: &Aabb<T>| tb.overlaps(h) && !h.contains(&tb);
            shared += usize::from(own_work(&below) && own_work(&above));
        }
        shared
    }

    /// The halves of a triangle's own bounds, cheaply, against the single
    /// clipper on each half, bit for bit, for cuts through its extent, at
    /// its vertices and outside it.
    fn check_halves<T: Real>(rng: &mut Rng, cases: usize) {
        for _ in 0..cases {
            let size = rng.range(0.01, 100.0);
            let p = [0; 3].map(|_| {
                v::<T>(
                    rng.range(-size, size),
                    rng.range(-size, size) + 3.0,
                    rng.range(-size, size) - 1.0,
                )
            });
            let tb = Aabb::from_points(p);
            let axis = (rng.next_f64() * 3.0) as usize % 3;
            let pick = rng.next_f64();
            let s = if pick < 0.2 {
                p[(rng.next_f64() * 3.0) as usize % 3][axis]
            } else if pick < 0.3 {
                T::from_f64(tb.max[axis].to_f64() + rng.range(0.0, size))
            } else {
                T::from_f64(rng.range(tb.min[axis].to_f64(), tb.max[axis].to_f64()))
            };
            let (below, above) = tb.split_at(axis, s);
            let want = [below, above].map(|h| clip_triangle_bounds(p[0], p[1], p[2], &h));
            let got = triangle_halves_bounds(p[0], p[1], p[2], axis, s);
            for (w, g) in want.iter().zip(&got) {
                assert!(
                    (w.is_empty() && g.is_empty()) || (w.min == g.min && w.max == g.max),
                    "{p:?} cut at x[{axis}] = {s:?}: {g:?}, clips of the own bounds' halves {want:?}"
                );
            }
        }
    }

    #[test]
    fn halves_bounds_are_the_clips_of_the_own_bounds_halves() {
        let mut rng = Rng(23);
        check_halves::<f32>(&mut rng, 20_000);
        check_halves::<f64>(&mut rng, 20_000);
    }

    #[test]
    fn split_clip_equals_the_single_clip_of_each_half() {
        let mut rng = Rng(5);
        // About half the cases take the shared path (the others return early).
        assert!(check_split::<f32>(&mut rng, 20_000) > 5_000);
        assert!(check_split::<f64>(&mut rng, 20_000) > 5_000);
    }

    #[test]
    fn clip_of_a_corner_cut_is_exact_where_it_can_be() {
        // The plane x + y + z = 1.5 cuts the corner of the unit box; the
        // triangle is far larger than the box, so every vertex of the clipped
        // polygon comes from a box edge (case 3): (0.5,0,1)...(1,0.5,0)...
        let p = [
            v::<f64>(-10.0, -10.0, 21.5),
            v(21.5, -10.0, -10.0),
            v(-10.0, 21.5, -10.0),
        ];
        let b = Aabb::new(v(0.0, 0.0, 0.0), v(1.0, 2.0, 3.0));
        let c = clip_triangle_bounds(p[0], p[1], p[2], &b);
        // The polygon spans x in [0, 1], y in [0, 1.5], z in [0, 1.5].
        let want = Aabb::new(v(0.0, 0.0, 0.0), v(1.0, 1.5, 1.5));
        assert!(c.contains(&want), "{c:?}");
        for a in 0..3 {
            assert!((c.max[a] - want.max[a]).abs() < 1e-12, "{c:?}");
        }
        check_clip::<f32>(p, &b, 400);
    }

    #[test]
    fn clip_in_a_face_plane_through_a_corner_and_missing() {
        let b = Aabb::new(v::<f64>(0.0, 0.0, 0.0), v(1.0, 2.0, 3.0));
        // A large triangle lying in the face z = 3: the clip is the face.
        let p = [v(-5.0, -5.0, 3.0), v(10.0, -5.0, 3.0), v(-5.0, 10.0, 3.0)];
        let c = clip_triangle_bounds(p[0], p[1], p[2], &b);
        assert_eq!(c, Aabb::new(v(0.0, 0.0, 3.0), v(1.0, 2.0, 3.0)));
        // Its bounds overlap the box but the triangle passes beside it.
        let p = [v(1.5, 0.8, -1.0), v(0.8, 2.5, -1.0), v(1.5, 2.5, 5.0)];
        assert!(Aabb::from_points(p).overlaps(&b));
        assert!(clip_triangle_bounds(p[0], p[1], p[2], &b).is_empty());
        // Touching the box at its corner (1, 2, 3) only.
        let p = [v(1.0, 2.0, 3.0), v(4.0, 2.5, 3.0), v(2.0, 5.0, 7.0)];
        let c = clip_triangle_bounds(p[0], p[1], p[2], &b);
        assert_eq!(c, Aabb::from_point(v(1.0, 2.0, 3.0)));
        // Degenerate (a segment through the box).
        let p = [v(-1.0, 1.0, 1.0), v(3.0, 1.0, 2.0), v(1.0, 1.0, 1.5)];
        check_clip::<f64>(p, &b, 200);
        let c = clip_triangle_bounds(p[0], p[1], p[2], &b);
        assert!((c.min.x, c.max.x) == (0.0, 1.0) && (c.min.z - 1.25).abs() < 1e-12);
    }

    #[test]
    fn clip_is_conservative_far_from_the_origin_in_f32() {
        // Slivers and near-parallel edges at an offset where f32 spacing is
        // coarse: the samples (in f64, from the f32 vertices) stay inside.
        let mut rng = Rng(99);
        let o = 4096.0;
        let b = Aabb::new(
            v::<f64>(o + 0.25, o - 0.5, o),
            v(o + 0.75, o + 0.5, o + 1.5),
        );
        for _ in 0..300 {
            let base = v::<f64>(
                rng.range(o - 1.0, o + 2.0),
                rng.range(o - 1.0, o + 1.0),
                rng.range(o - 1.0, o + 2.5),
            );
            let e = v::<f64>(
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
                rng.range(-2.0, 2.0),
            );
            let f = e * rng.range(-1.0, 1.0) + v(0.0, rng.range(-1e-3, 1e-3), 0.0);
            check_clip::<f32>([base, base + e, base + f], &b, 120);
        }
    }
}
