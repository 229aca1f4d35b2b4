//! Triangles: the watertight ray test (Woop, Benthin & Wald 2013), the
//! separating-axis triangle–box test (Akenine-Möller 2001) and the
//! conservative bounds of a triangle's part of a box
//! ([`clip_triangle_bounds`] and its kin).

mod clip;

pub use clip::{clip_triangle_bounds, clip_triangle_bounds_split, triangle_halves_bounds};

pub use crate::triangle_box::{
    BLOCK_MAX_CELLS, TriangleBoxTest, triangle_overlaps_boxes, triangle_overlaps_cells,
};
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

    /// Points of the triangle on a dense barycentric lattice, edges included (the
    /// clipper's tests share it).
    pub(crate) fn samples(p: [Vec3<f64>; 3], n: u32) -> Vec<Vec3<f64>> {
        let mut out = Vec::new();
        for i in 0..=n {
            for j in 0..=n - i {
                let (u, v) = (f64::from(i) / f64::from(n), f64::from(j) / f64::from(n));
                out.push(p[0] + (p[1] - p[0]) * u + (p[2] - p[0]) * v);
            }
        }
        out
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
