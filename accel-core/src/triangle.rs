//! Triangles: the watertight ray test (Woop, Benthin & Wald 2013) and the
//! separating-axis triangle–box test (Akenine-Möller 2001).

use crate::{Aabb, PreparedRay, PrimHit, Primitive, Real, Vec3};

/// The watertight ray–triangle test of Woop, Benthin & Wald (JCGT 2013).
///
/// The vertices are translated to the ray origin and sheared so that the ray
/// becomes the +z axis; the three 2D edge functions then decide the hit. A
/// shared edge yields exactly negated edge functions in its two triangles, so a
/// ray through an edge or vertex of a closed mesh always hits one of them.
/// The edge functions are evaluated with exact sign ([`Real::diff_of_products`]);
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
    let o = ray.ray.origin;
    let [kx, ky, kz] = ray.axes;
    let s = ray.shear;
    let a = p0 - o;
    let b = p1 - o;
    let c = p2 - o;
    let (ax, ay) = (a[kx] - s.x * a[kz], a[ky] - s.y * a[kz]);
    let (bx, by) = (b[kx] - s.x * b[kz], b[ky] - s.y * b[kz]);
    let (cx, cy) = (c[kx] - s.x * c[kz], c[ky] - s.y * c[kz]);

    let u = T::diff_of_products(cx, by, cy, bx);
    let v = T::diff_of_products(ax, cy, ay, cx);
    let w = T::diff_of_products(bx, ay, by, ax);
    let zero = <T::Wide as Real>::ZERO;
    if (u < zero || v < zero || w < zero) && (u > zero || v > zero || w > zero) {
        return None;
    }
    let det = u + v + w;
    if det == zero {
        return None;
    }
    let az = (s.z * a[kz]).to_wide();
    let bz = (s.z * b[kz]).to_wide();
    let cz = (s.z * c[kz]).to_wide();
    let t_scaled = u * az + v * bz + w * cz;
    let t = T::from_wide(t_scaled / det);
    // A parameter beyond T's range (tiny directions) is no hit.
    if !(t >= ray.ray.t_min && t <= t_max && t.is_finite()) {
        return None;
    }
    let inv_det = <T::Wide as Real>::ONE / det;
    Some(PrimHit {
        t,
        u: T::from_wide(v * inv_det),
        v: T::from_wide(w * inv_det),
    })
}

/// Whether the triangle meets the closed box `b`, by the 13 separating axes of
/// Akenine-Möller ("Fast 3D triangle-box overlap testing", 2001).
///
/// Conservative: it never answers `false` for a triangle that truly meets the
/// box. Each separation must exceed a rounding bound (`gamma(32)` of the
/// magnitudes involved) before it counts, and the arithmetic runs in
/// [`Real::Wide`] so that `f32` scenes at 1e±20 neither overflow nor underflow.
/// Degenerate triangles (segments, points) are tested as what they are.
#[must_use]
pub fn triangle_overlaps_box<T: Real>(p0: Vec3<T>, p1: Vec3<T>, p2: Vec3<T>, b: &Aabb<T>) -> bool {
    if b.is_empty() {
        return false;
    }
    // The three box-face axes: exact comparisons of the triangle's bounds.
    let tb = Aabb::from_point(p0).union_point(p1).union_point(p2);
    if !tb.overlaps(b) {
        return false;
    }
    if b.contains(&tb) {
        return true;
    }
    let w = |v: Vec3<T>| v.map(T::to_wide);
    // Work relative to the box's lower corner: differences of nearby values are
    // exact or nearly so, and the box centre is exact in these coordinates, so
    // the rounding is relative to the box and triangle sizes, not to how far
    // from the coordinate origin they sit.
    let lo = w(b.min);
    let h = (w(b.max) - lo) * <T::Wide as Real>::HALF;
    let q = [w(p0) - lo, w(p1) - lo, w(p2) - lo];
    let v = [q[0] - h, q[1] - h, q[2] - h];
    // Magnitudes the rounding errors are relative to, per axis.
    let mag = q[0].abs().max(q[1].abs()).max(q[2].abs()) + h + h;
    let slack = <T::Wide as Real>::gamma(32);

    let separated = |axis: Vec3<T::Wide>| -> bool {
        let p = [axis.dot(v[0]), axis.dot(v[1]), axis.dot(v[2])];
        let pmin = p[0].min(p[1]).min(p[2]);
        let pmax = p[0].max(p[1]).max(p[2]);
        let abs_axis = axis.abs();
        let r = abs_axis.dot(h);
        let err = slack * abs_axis.dot(mag);
        pmin > r + err || pmax < -(r + err)
    };

    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    let zero = <T::Wide as Real>::ZERO;
    for edge in e {
        // unit_x × edge, unit_y × edge, unit_z × edge.
        let axes = [
            Vec3::new(zero, -edge.z, edge.y),
            Vec3::new(edge.z, zero, -edge.x),
            Vec3::new(-edge.y, edge.x, zero),
        ];
        for axis in axes {
            if separated(axis) {
                return false;
            }
        }
    }
    // The triangle's plane. The normal's own rounding is covered by widening
    // the bound with the product of the edge lengths.
    let n = e[0].cross(e[1]);
    let d = n.dot(v[0]);
    let r = n.abs().dot(h);
    let edge_scale = e[0].abs().max_component() * e[1].abs().max_component();
    let err = slack
        * (n.abs().dot(mag) + edge_scale * mag.max_component() * <T::Wide as Real>::from_f64(3.0));
    d.abs() <= r + err
}

/// A triangle that owns its three vertices: the simplest [`Primitive`] for
/// soups. Meshes with shared vertices use [`crate::TriangleMesh`] instead.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle<T> {
    /// The vertices, in winding order.
    pub vertices: [Vec3<T>; 3],
}

impl<T: Real> Primitive<T> for Triangle<T> {
    #[inline]
    fn bounds(&self) -> Aabb<T> {
        let [a, b, c] = self.vertices;
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Ray;

    fn v<T: Real>(x: f64, y: f64, z: f64) -> Vec3<T> {
        Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z))
    }

    fn ray<T: Real>(o: Vec3<T>, d: Vec3<T>) -> PreparedRay<T> {
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
    fn shared_edge_is_watertight() {
        // Two triangles of a square share the diagonal; rays through points of
        // the diagonal must hit exactly one or both, never none.
        let q = [
            v::<f32>(0.1, 0.3, 0.0),
            v(1.7, 0.2, 0.05),
            v(1.9, 1.3, 0.1),
            v(0.2, 1.1, -0.05),
        ];
        let mut misses = 0;
        for i in 0..=1000 {
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
}
