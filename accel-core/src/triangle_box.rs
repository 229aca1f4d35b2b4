//! The separating-axis triangle–box test of Akenine-Möller ("Fast 3D
//! triangle-box overlap testing", 2001), with its per-triangle half done once.
//!
//! A grid asks one triangle about every cell its bounds cover. Of the 13
//! axes, the 9 edge cross products and the plane normal, and the triangle's
//! projections onto them, depend only on the triangle: [`TriangleBoxTest::new`]
//! computes them once, relative to the first vertex, and
//! [`TriangleBoxTest::overlaps`] is left with the box's centre and radius on
//! each axis.

use crate::real::{greater, lesser};
use crate::{Aabb, Real, Vec3};

/// `T`'s wide type, in which the test computes.
type Wide<T> = <T as Real>::Wide;

/// The rounding allowance of every separation, as pbrt's `gamma(n)`.
const SLACK_ROUNDINGS: u32 = 32;

/// One triangle, prepared for conservative overlap tests against many boxes.
///
/// Conservative: [`TriangleBoxTest::overlaps`] never answers `false` for a box
/// the triangle truly meets. A separating axis counts only when the gap
/// exceeds `gamma(32)` of the magnitudes involved, which bounds the rounding of
/// the axis projections (any axis separates, so the rounding of the axes
/// themselves costs nothing). The arithmetic runs in [`Real::Wide`] relative
/// to the first vertex, so `f32` scenes at 1e±20 neither overflow nor
/// underflow and the rounding is relative to the triangle's and the box's
/// sizes and distance, not to how far from the coordinate origin they sit.
/// Degenerate triangles (segments, points) are tested as what they are.
#[derive(Clone, Copy, Debug)]
pub struct TriangleBoxTest<T: Real> {
    /// The triangle's bounds, compared exactly (the three box-face axes).
    bounds: Aabb<T>,
    /// The vertices: a box holding one surely meets the triangle.
    vertices: [Vec3<T>; 3],
    /// The first vertex: the origin of every wide coordinate below.
    origin: Vec3<Wide<T>>,
    /// Per axis, the largest vertex magnitude relative to `origin`.
    extent: Vec3<Wide<T>>,
    /// The edges `q1 − q0`, `q2 − q1`, `q0 − q2`; their cross products with
    /// the coordinate axes, `unit_k × edge_j`, are nine separating axes.
    edges: [Vec3<Wide<T>>; 3],
    /// `|edges|`, componentwise.
    abs_edges: [Vec3<Wide<T>>; 3],
    /// The triangle's projection interval on `unit_k × edge_j`, at `3·j + k`.
    projections: [(Wide<T>, Wide<T>); 9],
    /// The plane normal `edge_0 × edge_1` (zero for a degenerate triangle).
    normal: Vec3<Wide<T>>,
    /// The normal's own rounding, per unit of magnitude: three times the
    /// product of the two edges' largest components.
    normal_error: Wide<T>,
}

impl<T: Real> TriangleBoxTest<T> {
    /// Prepares triangle `p0 p1 p2`.
    #[must_use]
    pub fn new(p0: Vec3<T>, p1: Vec3<T>, p2: Vec3<T>) -> Self {
        let vertices = [p0, p1, p2];
        Self::with_bounds(vertices, vertex_bounds(&vertices))
    }

    /// [`TriangleBoxTest::new`] for a caller that already holds the
    /// triangle's bounds ([`vertex_bounds`]).
    fn with_bounds([p0, p1, p2]: [Vec3<T>; 3], bounds: Aabb<T>) -> Self {
        let w = |v: Vec3<T>| v.map(T::to_wide);
        let origin = w(p0);
        let q = [Vec3::splat(Wide::<T>::ZERO), w(p1) - origin, w(p2) - origin];
        let extent = q[1].abs().max(q[2].abs());
        let edges = [q[1], q[2] - q[1], -q[2]];
        let zero = Wide::<T>::ZERO;
        let mut projections = [(zero, zero); 9];
        for (j, &e) in edges.iter().enumerate() {
            for k in 0..3 {
                // Plain selects: the projections are finite for finite
                // vertices, and a NaN one only makes its axis separate nothing.
                let [a, b, c] = q.map(|v| dot_cross_unit(k, e, v));
                projections[3 * j + k] = (lesser(lesser(a, b), c), greater(greater(a, b), c));
            }
        }
        let normal = edges[0].cross(edges[1]);
        let normal_error = edges[0].abs().max_component()
            * edges[1].abs().max_component()
            * Wide::<T>::from_f64(3.0);
        Self {
            bounds,
            vertices: [p0, p1, p2],
            origin,
            extent,
            edges,
            abs_edges: edges.map(Vec3::abs),
            projections,
            normal,
            normal_error,
        }
    }

    /// Whether the triangle meets the closed box `b` (conservatively; see the
    /// type's documentation).
    #[must_use]
    pub fn overlaps(&self, b: &Aabb<T>) -> bool {
        settled_by_vertices(&self.bounds, &self.vertices, b).unwrap_or_else(|| self.axes_allow(b))
    }

    /// Whether no edge axis nor the plane separates the triangle from `b`.
    fn axes_allow(&self, b: &Aabb<T>) -> bool {
        let w = |v: Vec3<T>| v.map(T::to_wide);
        let lo = w(b.min) - self.origin;
        let half = (w(b.max) - w(b.min)) * Wide::<T>::HALF;
        let centre = lo + half;
        // Bounds every magnitude a projection below rounds relative to: the
        // vertices, the centre and the box's corners, all from `origin`.
        let magnitude = self.extent + centre.abs() + half;
        let slack = Wide::<T>::gamma(SLACK_ROUNDINGS);
        // The box's radius on an axis `a` is `|a|·half`; the rounding bound
        // `slack·|a|·magnitude` joins it in one product.
        let widened = half + magnitude * slack;
        // Whether edge axis `unit_k × edge_j` separates.
        let separates = |j: usize, k: usize| {
            let c = dot_cross_unit(k, self.edges[j], centre);
            let reach = dot_cross_unit_abs(k, self.abs_edges[j], widened);
            let (pmin, pmax) = self.projections[3 * j + k];
            pmin - c > reach || pmax - c < -reach
        };
        if let Some(k) =
            (0..3).find(|&k| self.bounds.min[k] >= b.min[k] && self.bounds.max[k] <= b.max[k])
        {
            // The box holds the triangle's whole extent along axis `k` (a
            // grid cell one layer thick there: 47% of the 1M terrain's
            // boxes that reach this far, nearly all across x or y):
            // they meet exactly where their shadows on a plane across `k`
            // do. That plane's separating axes are the box's other two
            // faces, which the bounds have passed, and the triangle's edge
            // normals in it, `unit_k × edge_j`: three axes, not ten.
            return !(0..3).any(|j| separates(j, k));
        }
        if (0..3).any(|j| (0..3).any(|k| separates(j, k))) {
            return false;
        }
        // The triangle's plane passes through `origin`: its signed distance
        // from the centre is `−normal · centre`.
        let n = self.normal;
        let abs_n = n.abs();
        let err = slack * (abs_n.dot(magnitude) + self.normal_error * magnitude.max_component());
        n.dot(centre).abs() <= abs_n.dot(half) + err
    }
}

/// The answer for box `b` when the triangle's bounds and vertices settle it:
/// `false` when the bounds miss the box (the three box-face axes, exactly),
/// `true` when a vertex lies in it.
#[inline]
fn settled_by_vertices<T: Real>(
    bounds: &Aabb<T>,
    vertices: &[Vec3<T>; 3],
    b: &Aabb<T>,
) -> Option<bool> {
    if b.is_empty() || !bounds.overlaps(b) {
        Some(false)
    } else if vertices.iter().any(|&v| b.contains_point(v)) {
        Some(true)
    } else {
        None
    }
}

/// [`TriangleBoxTest::overlaps`] of triangle `p0 p1 p2` for each of `boxes`,
/// written to the same place in `out`; the test is prepared only if a box
/// needs more than the triangle's bounds and vertices.
pub fn triangle_overlaps_boxes<T: Real>(
    [p0, p1, p2]: [Vec3<T>; 3],
    boxes: &[Aabb<T>],
    out: &mut [bool],
) {
    let vertices = [p0, p1, p2];
    let bounds = vertex_bounds(&vertices);
    let mut test = None;
    for (b, o) in boxes.iter().zip(out) {
        *o = settled_by_vertices(&bounds, &vertices, b).unwrap_or_else(|| {
            test.get_or_insert_with(|| TriangleBoxTest::with_bounds(vertices, bounds))
                .axes_allow(b)
        });
    }
}

/// The bounds of a triangle's vertices, compared exactly by the test (the
/// three box-face axes).
#[inline]
fn vertex_bounds<T: Real>([p0, p1, p2]: &[Vec3<T>; 3]) -> Aabb<T> {
    Aabb::from_point(*p0).union_point(*p1).union_point(*p2)
}

/// `(unit_k × e) · v`, the axis being `(0, −e.z, e.y)`, `(e.z, 0, −e.x)` or
/// `(−e.y, e.x, 0)`: two products, not three (a product with zero does not
/// fold away in floating point).
#[inline(always)]
fn dot_cross_unit<W: Real>(k: usize, e: Vec3<W>, v: Vec3<W>) -> W {
    match k {
        0 => e.y * v.z - e.z * v.y,
        1 => e.z * v.x - e.x * v.z,
        _ => e.x * v.y - e.y * v.x,
    }
}

/// `|unit_k × e| · v` from `|e|`, for the box's radius on that axis.
#[inline(always)]
fn dot_cross_unit_abs<W: Real>(k: usize, abs_e: Vec3<W>, v: Vec3<W>) -> W {
    match k {
        0 => abs_e.z * v.y + abs_e.y * v.z,
        1 => abs_e.z * v.x + abs_e.x * v.z,
        _ => abs_e.y * v.x + abs_e.x * v.y,
    }
}
