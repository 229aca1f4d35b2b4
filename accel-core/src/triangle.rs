//! Triangles: the watertight ray test (Woop, Benthin & Wald 2013) and the
//! separating-axis triangle–box test (Akenine-Möller 2001).

pub use crate::triangle_box::{TriangleBoxTest, triangle_overlaps_boxes};
use crate::{Aabb, PreparedRay, PrimHit, Primitive, Real, Vec3};

/// The watertight ray–triangle test of Woop, Benthin & Wald (JCGT 2013).
///
/// The vertices are translated to the ray origin and sheared so that the ray
/// becomes the +z axis; the three 2D edge functions then decide the hit. A
/// shared edge yields exactly negated edge functions in its two triangles, so a
/// ray through an edge or vertex of a closed mesh always hits one of them.
/// Everything runs in `f64`, so `t` is as accurate as the rounded inputs allow
/// in `f32` too; the edge functions are evaluated with exact sign
/// ([`Real::diff_of_products`]);
/// both faces are hit (no culling); degenerate triangles (`det = 0`) never are.
///
/// Returns the hit with `ray.t_min ≤ t ≤ t_max`; `u`, `v` are the barycentric
/// weights of `p1` and `p2` (the point is `(1−u−v)·p0 + u·p1 + v·p2`).
#[inline]
#[must_use]
pub fn intersect_triangle<T: Real>(
    ray: &PreparedRay<T>,
    p0: Vec3<T>,
    p1: Vec3<T>,
    p2: Vec3<T>,
    t_max: T,
) -> Option<PrimHit<T>> {
    // The axes are per-ray constants: one dispatch per test to a copy of the
    // test with the permutation fixed at compile time turns every component
    // selection into a plain field access (a runtime index is a three-way
    // branch per component). The arithmetic is the same in every arm.
    match ray.axes {
        [1, 2, 0] => watertight(ray, [1, 2, 0], p0, p1, p2, t_max),
        [2, 1, 0] => watertight(ray, [2, 1, 0], p0, p1, p2, t_max),
        [2, 0, 1] => watertight(ray, [2, 0, 1], p0, p1, p2, t_max),
        [0, 2, 1] => watertight(ray, [0, 2, 1], p0, p1, p2, t_max),
        [0, 1, 2] => watertight(ray, [0, 1, 2], p0, p1, p2, t_max),
        [1, 0, 2] => watertight(ray, [1, 0, 2], p0, p1, p2, t_max),
        axes => watertight(ray, axes, p0, p1, p2, t_max),
    }
}

/// The body of [`intersect_triangle`] for the permutation `[kx, ky, kz]`.
#[inline(always)]
fn watertight<T: Real>(
    ray: &PreparedRay<T>,
    [kx, ky, kz]: [usize; 3],
    p0: Vec3<T>,
    p1: Vec3<T>,
    p2: Vec3<T>,
    t_max: T,
) -> Option<PrimHit<T>> {
    // Translation and shear in f64 (exact or nearly so for f32 inputs): in
    // T, `p − o` rounds to T's spacing at |p|, which for a triangle much
    // larger than its distance to the origin moves `t` by far more than an
    // ulp (1e-4 relative in f32 on a floor 1e4 across). The shear
    // constants are `f64` too ([`PreparedRay::shear`]). Every vertex still
    // goes through the same transform, so shared edges stay watertight.
    let w3 = |v: Vec3<T>| v.map(T::to_f64);
    let o = w3(ray.ray.origin);
    let s = ray.shear;
    let a = w3(p0) - o;
    let b = w3(p1) - o;
    let c = w3(p2) - o;
    let (ax, ay) = (a[kx] - s.x * a[kz], a[ky] - s.y * a[kz]);
    let (bx, by) = (b[kx] - s.x * b[kz], b[ky] - s.y * b[kz]);
    let (cx, cy) = (c[kx] - s.x * c[kz], c[ky] - s.y * c[kz]);

    // Most tests miss. The plain products usually settle that already: where
    // their difference surely has the sign of the exact edge function, two
    // opposite signs reject the triangle, exactly as the edge functions below
    // would (their signs are exact), without their cancellation fallback.
    let (su, sv, sw) = (
        sure_sign(cx * by, cy * bx),
        sure_sign(ax * cy, ay * cx),
        sure_sign(bx * ay, by * ax),
    );
    if opposite_signs(su, sv, sw) {
        return None;
    }

    let u = f64::diff_of_products(cx, by, cy, bx);
    let v = f64::diff_of_products(ax, cy, ay, cx);
    let w = f64::diff_of_products(bx, ay, by, ax);
    if opposite_signs(u, v, w) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    // Depths in f64 too: in T they can underflow to 0 (a huge direction),
    // which would report t = 0 for any triangle the line meets.
    let (az, bz, cz) = (s.z * a[kz], s.z * b[kz], s.z * c[kz]);
    let t_scaled = u * az + v * bz + w * cz;
    // A parameter beyond T's range (tiny or huge directions) is no hit.
    let wide = <T::Wide as Real>::from_f64;
    let t = T::hit_parameter(wide(t_scaled / det), ray.ray.t_min, t_max)?;
    let inv_det = 1.0 / det;
    Some(PrimHit {
        t,
        u: T::from_f64(v * inv_det),
        v: T::from_f64(w * inv_det),
    })
}

/// Whether one of `u`, `v`, `w` is below zero and another above: the ray
/// passes outside an edge. Bitwise, not short-circuit: one branch for the
/// caller instead of up to six, each on a sign no branch predictor knows.
#[inline(always)]
pub(crate) fn opposite_signs(u: f64, v: f64, w: f64) -> bool {
    ((u < 0.0) | (v < 0.0) | (w < 0.0)) & ((u > 0.0) | (v > 0.0) | (w > 0.0))
}

/// `p − q` for the rounded products `p ≈ a·b`, `q ≈ c·d` when its sign is
/// surely that of the exact `a·b − c·d`, else 0 (unknown).
///
/// The products and the difference round once each, so
/// `|(p − q) − (a·b − c·d)| ≤ u·(|p| + |q|)/(1 − u)`; the test asks for more
/// than twice that, plus an absolute term for products that underflow.
/// Non-finite products never pass (the comparison is false for NaN and ∞).
#[inline(always)]
pub(crate) fn sure_sign(p: f64, q: f64) -> f64 {
    let r = p - q;
    if r.abs() > 2.0 * f64::EPSILON * (p.abs() + q.abs()) + f64::MIN_POSITIVE {
        r
    } else {
        0.0
    }
}

/// Whether the triangle meets the closed box `b`, by the 13 separating axes of
/// Akenine-Möller ("Fast 3D triangle-box overlap testing", 2001).
///
/// Conservative: it never answers `false` for a triangle that truly meets the
/// box (see [`TriangleBoxTest`], which prepares a triangle once for many
/// boxes). Degenerate triangles (segments, points) are tested as what they
/// are.
#[must_use]
pub fn triangle_overlaps_box<T: Real>(p0: Vec3<T>, p1: Vec3<T>, p2: Vec3<T>, b: &Aabb<T>) -> bool {
    let mut meets = [false];
    triangle_overlaps_boxes([p0, p1, p2], std::slice::from_ref(b), &mut meets);
    meets[0]
}

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

/// A triangle that owns its three vertices: the simplest [`Primitive`] for
/// soups. Meshes with shared vertices use [`crate::TriangleMesh`] instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle<T> {
    /// The vertices, in winding order.
    pub vertices: [Vec3<T>; 3],
}

impl<T: Real> Primitive<T> for Triangle<T> {
    /// The watertight test translates and shears in `f64` from the exact
    /// `T` inputs ([`intersect_triangle`]).
    const WIDE_HITS: bool = true;

    #[inline]
    fn watertight_triangle(&self) -> Option<[Vec3<T>; 3]> {
        Some(self.vertices)
    }

    /// The vertices' bounds; infinite when a vertex is not finite (min and
    /// max would drop a NaN), so that every build refuses the triangle.
    #[inline]
    fn bounds(&self) -> Aabb<T> {
        let [a, b, c] = self.vertices;
        if !(a.is_finite() && b.is_finite() && c.is_finite()) {
            return Aabb {
                min: Vec3::splat(T::NEG_INFINITY),
                max: Vec3::splat(T::INFINITY),
            };
        }
        Aabb::from_point(a).union_point(b).union_point(c)
    }

    #[inline]
    fn intersect(&self, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        let [a, b, c] = self.vertices;
        intersect_triangle(ray, a, b, c, t_max)
    }

    #[inline]
    fn overlaps_box(&self, b: &Aabb<T>) -> bool {
        let [p0, p1, p2] = self.vertices;
        triangle_overlaps_box(p0, p1, p2, b)
    }

    fn overlaps_boxes(&self, boxes: &[Aabb<T>], out: &mut [bool]) {
        triangle_overlaps_boxes(self.vertices, boxes, out);
    }

    #[inline]
    fn clipped_bounds(&self, b: &Aabb<T>) -> Aabb<T> {
        let [p0, p1, p2] = self.vertices;
        clip_triangle_bounds(p0, p1, p2, b)
    }

    fn clipped_bounds_split(&self, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        let [p0, p1, p2] = self.vertices;
        clip_triangle_bounds_split(p0, p1, p2, b, axis, s)
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::Ray;

    /// A point of `T` from `f64` coordinates (the crate's tests share it).
    pub(crate) fn v<T: Real>(x: f64, y: f64, z: f64) -> Vec3<T> {
        Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z))
    }

    /// The prepared ray from `o` along `d` (the crate's tests share it).
    pub(crate) fn ray<T: Real>(o: Vec3<T>, d: Vec3<T>) -> PreparedRay<T> {
        PreparedRay::new(Ray::new(o, d).unwrap())
    }

    fn hit_point_matches<T: Real>() {
        let (p0, p1, p2) = (v::<T>(0.0, 0.0, 2.0), v(4.0, 0.0, 2.0), v(0.0, 4.0, 2.0));
        let r = ray(v(1.0, 2.0, 0.0), v(0.0, 0.0, 1.0));
        let h = intersect_triangle(&r, p0, p1, p2, T::INFINITY).unwrap();
        assert_eq!(h.t, T::from_f64(2.0));
        assert_eq!(h.u, T::from_f64(0.25));
        assert_eq!(h.v, T::from_f64(0.5));
        // The same from behind, with a longer direction: t scales, u and v stay.
        let r = ray(v(1.0, 2.0, 10.0), v(0.0, 0.0, -4.0));
        let h = intersect_triangle(&r, p0, p1, p2, T::INFINITY).unwrap();
        assert_eq!(h.t, T::from_f64(2.0));
        assert_eq!((h.u, h.v), (T::from_f64(0.25), T::from_f64(0.5)));
        // t_max and t_min bound the accepted range inclusively.
        assert!(intersect_triangle(&r, p0, p1, p2, T::from_f64(2.0)).is_some());
        assert!(intersect_triangle(&r, p0, p1, p2, T::from_f64(1.9)).is_none());
    }

    #[test]
    fn hit_point_matches_f32_and_f64() {
        hit_point_matches::<f32>();
        hit_point_matches::<f64>();
    }

    #[test]
    fn t_is_accurate_on_a_triangle_much_larger_than_its_distance() {
        // A floor at z = -1.5 with corners at ±5000 (f32 spacing there is
        // 4.9e-4) and rays from near the origin whose largest component is
        // horizontal: t must be the plane's own answer, (-1.5 - oz) / dz
        // (computed in f64 from the same f32 inputs), to an ulp or two, not
        // off by the rounding of the corners (bug found by `studies peers`:
        // 1e-4 relative before the transform ran in f64).
        let (p0, p1, p2) = (
            v::<f32>(-5000.0, -5000.0, -1.5),
            v(5000.0, -5000.0, -1.5),
            v(0.0, 5000.0, -1.5),
        );
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for _ in 0..1000 {
            let o = v::<f32>(next(), next(), 0.5 + next());
            let d = v::<f32>(3.0 * next(), 3.0 * next(), -0.2 - next().abs());
            let Some(h) = intersect_triangle(&ray(o, d), p0, p1, p2, f32::INFINITY) else {
                panic!("a ray down from near the origin hits the floor");
            };
            let exact = (-1.5 - f64::from(o.z)) / f64::from(d.z);
            let ulp = f64::from((exact as f32).next_up() - exact as f32);
            assert!(
                (f64::from(h.t) - exact).abs() <= 2.0 * ulp,
                "t {} vs {exact} (o {o:?}, d {d:?})",
                h.t
            );
        }
    }

    /// The sign of `d · (a × b)` when it is certain, else `None`: the
    /// side of the plane through the origin, `a` and `b` that the direction
    /// points to. The inputs are exact; the products and sums round, by at
    /// most `gamma(5)` of the same expression in absolute values.
    fn sure_orientation(d: [f64; 3], a: [f64; 3], b: [f64; 3]) -> Option<bool> {
        let mut value = 0.0;
        let mut bound = 0.0;
        for (i, di) in d.into_iter().enumerate() {
            let (j, k) = ((i + 1) % 3, (i + 2) % 3);
            value += di * (a[j] * b[k] - a[k] * b[j]);
            bound += di.abs() * ((a[j] * b[k]).abs() + (a[k] * b[j]).abs());
        }
        let bound = <f64 as Real>::gamma(5) * bound + f64::MIN_POSITIVE;
        (value.abs() > bound).then_some(value > 0.0)
    }

    #[test]
    fn rays_grazing_an_edge_agree_with_exact_orientation() {
        // f32 rays aimed at points within a few 1e-8 of an edge, inside or
        // outside. The oracle: the ray passes through the triangle exactly
        // when the three triple products `d · ((p_i − o) × (p_j − o))` share a
        // sign, computed from exact f64 differences of the f32 inputs with an
        // error bound; only cases whose signs are certain are compared
        // (all of them here). With the shear constants rounded to f32, 13%
        // of these cases got the wrong answer, either way (and 2 of 262,144
        // camera rays of the soup scene missed a nearer triangle they pass
        // through).
        let mut rng = Rng(11);
        let (mut compared, mut hits) = (0, 0);
        for _ in 0..20_000 {
            let p = [0; 3].map(|_| {
                v::<f32>(
                    rng.range(-0.2, 0.2),
                    rng.range(-0.2, 0.2),
                    rng.range(1.5, 2.5),
                )
            });
            let o = v::<f32>(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 0.0),
            );
            // A point on edge (p_i, p_j), moved across it by a tiny amount.
            let i = (rng.next_f64() * 3.0) as usize % 3;
            let (a, b, c) = (
                p[i].cast::<f64>(),
                p[(i + 1) % 3].cast(),
                p[(i + 2) % 3].cast(),
            );
            let along = a + (b - a) * rng.range(0.05, 0.95);
            let target = along + (c - along) * rng.range(-3e-7, 3e-7);
            let d: Vec3<f32> = (target - o.cast()).cast();
            let o64 = o.cast::<f64>();
            let rel = |q: Vec3<f32>| {
                let r = q.cast::<f64>() - o64;
                [r.x, r.y, r.z]
            };
            let d64 = [d.x, d.y, d.z].map(f64::from);
            let signs =
                [(0, 1), (1, 2), (2, 0)].map(|(j, k)| sure_orientation(d64, rel(p[j]), rel(p[k])));
            let [Some(s0), Some(s1), Some(s2)] = signs else {
                continue;
            };
            let exact_hit = s0 == s1 && s1 == s2;
            let got = intersect_triangle(&ray(o, d), p[0], p[1], p[2], f32::INFINITY);
            assert_eq!(
                got.is_some(),
                exact_hit,
                "o {o:?} d {d:?} triangle {p:?}: test says {got:?}"
            );
            compared += 1;
            hits += usize::from(exact_hit);
        }
        // Most cases are certain, and both answers occur.
        assert!(compared > 15_000, "{compared}");
        assert!(
            hits > compared / 4 && hits < 3 * compared / 4,
            "{hits} of {compared}"
        );
    }

    #[test]
    fn shared_edge_is_watertight() {
        // Two triangles of a square share the diagonal; rays through points of
        // the diagonal must hit exactly one or both, never none. (Not its
        // ends: they are corners of the open square, and a rounded direction
        // aimed at a corner may pass just outside it.)
        let q = [
            v::<f32>(0.1, 0.3, 0.0),
            v(1.7, 0.2, 0.05),
            v(1.9, 1.3, 0.1),
            v(0.2, 1.1, -0.05),
        ];
        let mut misses = 0;
        for i in 1..1000 {
            let s = i as f32 / 1000.0;
            let target = q[0] + (q[2] - q[0]) * s;
            let origin = v(0.37, -0.21, 5.0);
            let r = ray(origin, target - origin);
            let a = intersect_triangle(&r, q[0], q[1], q[2], f32::INFINITY);
            let b = intersect_triangle(&r, q[0], q[2], q[3], f32::INFINITY);
            if a.is_none() && b.is_none() {
                misses += 1;
            }
        }
        assert_eq!(misses, 0);
    }

    #[test]
    fn degenerate_and_edge_on_triangles_do_not_hit() {
        let r = ray(v::<f64>(0.0, 0.0, -1.0), v(0.0, 0.0, 1.0));
        // Zero area.
        let h = intersect_triangle(
            &r,
            v(-1.0, -1.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(2.0, 2.0, 0.0),
            1e9,
        );
        assert!(h.is_none());
        // The ray lies in the triangle's plane.
        let r = ray(v::<f64>(-5.0, 0.0, 0.0), v(1.0, 0.0, 0.0));
        let h = intersect_triangle(
            &r,
            v(0.0, -1.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(0.0, 1.0, 0.0),
            1e9,
        );
        assert!(h.is_none());
    }

    #[test]
    fn extreme_scales_do_not_overflow_in_f32() {
        for scale in [1e-20f64, 1e20] {
            let p = [
                v::<f32>(0.0, 0.0, scale),
                v(scale, 0.0, scale),
                v(0.0, scale, scale),
            ];
            let r = ray(v(0.25 * scale, 0.25 * scale, 0.0), v(0.0, 0.0, 1.0));
            let h = intersect_triangle(&r, p[0], p[1], p[2], f32::INFINITY)
                .unwrap_or_else(|| panic!("miss at scale {scale}"));
            assert!((h.t / scale as f32 - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn box_overlap_separates_by_each_axis_kind() {
        let unit = Aabb::new(v::<f64>(0.0, 0.0, 0.0), v(1.0, 2.0, 3.0));
        // A triangle whose bounds overlap the box but which passes beside the
        // corner (separated by an edge axis).
        let t = [v(1.5, 0.8, -1.0), v(0.8, 2.5, -1.0), v(1.5, 2.5, 5.0)];
        assert!(Aabb::from_points(t).overlaps(&unit));
        let sep = !triangle_overlaps_box(t[0], t[1], t[2], &unit);
        // Through the interior: overlaps.
        let t2 = [v(0.5, 1.0, -1.0), v(0.5, 1.0, 5.0), v(3.0, 1.0, 1.0)];
        assert!(triangle_overlaps_box(t2[0], t2[1], t2[2], &unit));
        assert!(sep, "triangle beside the box edge must be separated");
        // Separated by the triangle's plane: a big slanted triangle over the corner.
        let p = [v::<f64>(3.0, 0.0, 0.0), v(0.0, 6.0, 0.0), v(0.0, 0.0, 9.0)];
        let near_corner = Aabb::new(v(0.0, 0.0, 0.0), v(0.5, 0.5, 0.5));
        assert!(!triangle_overlaps_box(p[0], p[1], p[2], &near_corner));
        let touching = Aabb::new(v(0.0, 0.0, 0.0), v(1.0, 2.0, 3.0));
        // The plane x/3 + y/6 + z/9 = 1 touches this box only at its corner (1, 2, 3).
        assert!(triangle_overlaps_box(p[0], p[1], p[2], &touching));
    }

    #[test]
    fn box_overlap_is_closed_for_touching_triangles() {
        let b = Aabb::new(v::<f32>(0.0, 0.0, 0.0), v(1.0, 1.0, 1.0));
        // Lies in the face z = 1.
        let t = [v(0.2, 0.2, 1.0), v(0.8, 0.2, 1.0), v(0.5, 0.9, 1.0)];
        assert!(triangle_overlaps_box(t[0], t[1], t[2], &b));
        // Touches only the corner (1,1,1) with a vertex.
        let t = [v(1.0, 1.0, 1.0), v(2.0, 1.5, 1.0), v(1.5, 2.0, 3.0)];
        assert!(triangle_overlaps_box(t[0], t[1], t[2], &b));
    }

    /// A tiny deterministic generator (the crate's tests share it; the
    /// scenes crate's `SplitMix64` is not a dependency of accel-core).
    pub(crate) struct Rng(pub(crate) u64);

    impl Rng {
        pub(crate) fn next_f64(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
        pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
            lo + (hi - lo) * self.next_f64()
        }
        pub(crate) fn unit_vector(&mut self) -> Vec3<f64> {
            let z = self.range(-1.0, 1.0);
            let phi = self.range(0.0, core::f64::consts::TAU);
            let r = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(r * phi.cos(), r * phi.sin(), z)
        }
    }

    /// Points of the triangle on a dense barycentric lattice, edges included.
    fn samples(p: [Vec3<f64>; 3], n: u32) -> Vec<Vec3<f64>> {
        let mut out = Vec::new();
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
                out.push(p[0] + (p[1] - p[0]) * u + (p[2] - p[0]) * v);
            }
        }
        out
    }

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

    /// Whether the f64 separating-axis test, on unit axes, separates the
    /// triangle from the box by more than `margin` (an independent oracle:
    /// only clear separations count).
    fn clearly_separated(p: [Vec3<f64>; 3], b: &Aabb<f64>, margin: f64) -> bool {
        let centre = (b.min + b.max) * 0.5;
        let half = (b.max - b.min) * 0.5;
        let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
        let units = [v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0), v(0.0, 0.0, 1.0)];
        let mut axes = units.to_vec();
        axes.push(e[0].cross(e[1]));
        for edge in e {
            axes.extend(units.iter().map(|u| u.cross(edge)));
        }
        axes.iter().filter(|a| a.length() > 0.0).any(|a| {
            let a = a.normalized();
            let proj = p.map(|q| a.dot(q - centre));
            let lo = proj[0].min(proj[1]).min(proj[2]);
            let hi = proj[0].max(proj[1]).max(proj[2]);
            let r = a.abs().dot(half);
            lo > r + margin || hi < -(r + margin)
        })
    }

    /// Random triangles against the 4×4×4 cells around them, as a grid asks:
    /// a cell holding a sampled point of the triangle always meets it, a
    /// clearly separated one never does, and the batched, single and
    /// prepared tests agree.
    fn check_box_overlaps<T: Real>(seed: u64, offset: f64, scale: f64) {
        let mut rng = Rng(seed);
        let (mut met, mut separated) = ([0; 2], [0; 2]);
        for _ in 0..150 {
            let pt: [Vec3<T>; 3] = [0; 3].map(|_| {
                v::<f64>(
                    rng.range(0.0, 3.0),
                    rng.range(0.0, 3.0),
                    rng.range(0.0, 3.0),
                )
                .map(|c| offset + c * scale)
                .cast()
            });
            let exact: [Vec3<f64>; 3] = pt.map(|q| q.cast());
            let tb = Aabb::from_points(exact);
            let step = (tb.max - tb.min) * 0.25;
            let mut cells = Vec::new();
            for i in 0..64 {
                let c = v::<f64>(f64::from(i % 4), f64::from(i / 4 % 4), f64::from(i / 16));
                let lo = tb.min + v(step.x * c.x, step.y * c.y, step.z * c.z);
                let cell: Aabb<T> = Aabb::new(lo, lo + step).cast();
                cells.push(cell);
            }
            // Cells one layer thick along an axis, holding the triangle's
            // whole extent there (as a grid asks about most of a terrain's
            // triangles): exactly its bounds on that axis, and wider.
            for axis in 0..3 {
                for i in 0..32 {
                    // The 16 cells of one layer across `axis` (cell `i` of
                    // the 64 is x + 4y + 16z).
                    let (m, n) = (i % 4, i / 4 % 4);
                    let mut cell = cells[[4 * m + 16 * n, m + 16 * n, m + 4 * n][axis]];
                    let grow = if i < 16 { 0.0 } else { step[axis] * 0.5 };
                    let (lo, hi) = (tb.min[axis] - grow, tb.max[axis] + grow);
                    cell.min[axis] = T::from_f64(lo);
                    cell.max[axis] = T::from_f64(hi);
                    cells.push(cell);
                }
            }
            let mut batch = vec![false; cells.len()];
            triangle_overlaps_boxes(pt, &cells, &mut batch);
            let prepared = TriangleBoxTest::new(pt[0], pt[1], pt[2]);
            // The oracle works relative to the first vertex, where these
            // differences are exact and the samples' rounding is tiny.
            let local = exact.map(|q| q - exact[0]);
            let points = samples(local, 60);
            for (i, (cell, &answer)) in cells.iter().zip(&batch).enumerate() {
                assert_eq!(answer, triangle_overlaps_box(pt[0], pt[1], pt[2], cell));
                assert_eq!(answer, prepared.overlaps(cell));
                let cell64: Aabb<f64> = cell.cast();
                let cell64 = Aabb::new(cell64.min - exact[0], cell64.max - exact[0]);
                let layer = usize::from(i >= 64);
                if points.iter().any(|&q| cell64.contains_point(q)) {
                    assert!(answer, "a cell holding a point of {exact:?} was refused");
                    met[layer] += 1;
                }
                let margin = 1e-4 * scale;
                if clearly_separated(local, &cell64, margin) {
                    assert!(!answer, "a cell clearly apart from {exact:?} was accepted");
                    separated[layer] += 1;
                }
            }
        }
        // Both kinds occur often enough for the checks to mean something,
        // among the cells inside the bounds and among the layers.
        assert!(
            met[0] > 1000 && separated[0] > 1000 && met[1] > 1000 && separated[1] > 1000,
            "{met:?} met, {separated:?} separated"
        );
    }

    #[test]
    fn box_overlap_holds_sampled_meetings_and_refuses_clear_separations() {
        check_box_overlaps::<f64>(5, 0.0, 1.0);
        check_box_overlaps::<f32>(6, 0.0, 1.0);
        // Far from the origin, where f32 spacing is coarse.
        check_box_overlaps::<f32>(7, 4096.0, 1.0);
        check_box_overlaps::<f64>(8, 1e9, 1.0);
        // Extreme scales, which must neither overflow nor underflow.
        check_box_overlaps::<f32>(9, 0.0, 1e-20);
        check_box_overlaps::<f32>(10, 0.0, 1e20);
    }
}
