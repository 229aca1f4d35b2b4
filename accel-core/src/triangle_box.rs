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
        // Plain selects: the projections are finite for finite vertices, and
        // a NaN one only makes its axis separate nothing.
        let span = |a: Wide<T>, b: Wide<T>| (lesser(a, b), greater(a, b));
        for k in 0..3 {
            // An edge's two ends project to the same point of its own axes,
            // and with `q0 = 0` that point is computed exactly for edges 0
            // and 2: `(unit_k × q1)·q1` and `(unit_k × −q2)·q2` are each a
            // difference of two equal products, exactly 0, as is every
            // projection of `q0`. Those edges' intervals are then spanned by
            // 0 and the opposite vertex alone, the same values as from all
            // three; edge 1's ends, `q1` and `q2`, round apart and are both
            // taken.
            let (a, b) = (
                dot_cross_unit(k, edges[1], q[1]),
                dot_cross_unit(k, edges[1], q[2]),
            );
            projections[k] = span(zero, dot_cross_unit(k, edges[0], q[2]));
            projections[3 + k] = (lesser(lesser(zero, a), b), greater(greater(zero, a), b));
            projections[6 + k] = span(zero, dot_cross_unit(k, edges[2], q[1]));
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
        let frame = Frame::of([0, 1, 2].map(|a| self.axis_frame(a, b.min[a], b.max[a])));
        let holds = |k: usize| self.bounds.min[k] >= b.min[k] && self.bounds.max[k] <= b.max[k];
        self.frame_allows(&frame, holds, |k| self.edge_axes_separate(k, &frame))
    }

    /// [`TriangleBoxTest::axes_allow`] of a box seen as `frame`, given
    /// whether it holds the triangle's extent along each axis (`holds`) and
    /// whether each group of edge axes separates (`separates(k)`: the three
    /// axes `unit_k × edge_j`, [`TriangleBoxTest::edge_axes_separate`]).
    #[inline(always)]
    fn frame_allows(
        &self,
        frame: &Frame<Wide<T>>,
        holds: impl Fn(usize) -> bool,
        mut separates: impl FnMut(usize) -> bool,
    ) -> bool {
        if let Some(k) = (0..3).find(|&k| holds(k)) {
            // The box holds the triangle's whole extent along axis `k` (a
            // grid cell one layer thick there: 47% of the 1M terrain's
            // boxes that reach this far, nearly all across x or y):
            // they meet exactly where their shadows on a plane across `k`
            // do. That plane's separating axes are the box's other two
            // faces, which the bounds have passed, and the triangle's edge
            // normals in it, `unit_k × edge_j`: three axes, not ten.
            return !separates(k);
        }
        if (0..3).any(&mut separates) {
            return false;
        }
        // The triangle's plane passes through `origin`: its signed distance
        // from the centre is `−normal · centre`.
        let n = self.normal;
        let abs_n = n.abs();
        let magnitude = frame.magnitude;
        let slack = Wide::<T>::gamma(SLACK_ROUNDINGS);
        let err = slack * (abs_n.dot(magnitude) + self.normal_error * magnitude.max_component());
        n.dot(frame.centre).abs() <= abs_n.dot(frame.half) + err
    }

    /// The box's interval `[min, max]` on axis `a` as the axes see it,
    /// relative to `origin`.
    #[inline(always)]
    fn axis_frame(&self, a: usize, min: T, max: T) -> AxisFrame<Wide<T>> {
        let lo = min.to_wide() - self.origin[a];
        let half = (max.to_wide() - min.to_wide()) * Wide::<T>::HALF;
        let centre = lo + half;
        // Bounds every magnitude a projection below rounds relative to: the
        // vertices, the centre and the box's corners, all from `origin`.
        let magnitude = self.extent[a] + centre.abs() + half;
        // The box's radius on an axis `u` is `|u|·half`; the rounding bound
        // `slack·|u|·magnitude` joins it in one product.
        let widened = half + magnitude * Wide::<T>::gamma(SLACK_ROUNDINGS);
        AxisFrame {
            centre,
            half,
            magnitude,
            widened,
        }
    }

    /// Whether one of the three edge axes `unit_k × edge_j` separates the
    /// triangle from the box of `frame`. They lie across axis `k`, so only
    /// the box's two other axes matter: every box of a column along `k`
    /// gets the same answer.
    #[inline(always)]
    fn edge_axes_separate(&self, k: usize, frame: &Frame<Wide<T>>) -> bool {
        (0..3).any(|j| {
            let c = dot_cross_unit(k, self.edges[j], frame.centre);
            let reach = dot_cross_unit_abs(k, self.abs_edges[j], frame.widened);
            let (pmin, pmax) = self.projections[3 * j + k];
            pmin - c > reach || pmax - c < -reach
        })
    }
}

/// A box's interval on one axis, as the separating axes see it (relative to
/// the test's origin): its centre, half-width, the magnitude its
/// projections round relative to, and the half-width widened by that
/// rounding.
#[derive(Clone, Copy, Debug)]
struct AxisFrame<W> {
    centre: W,
    half: W,
    magnitude: W,
    widened: W,
}

/// A box as the separating axes see it: its three [`AxisFrame`]s.
#[derive(Clone, Copy, Debug)]
struct Frame<W> {
    centre: Vec3<W>,
    half: Vec3<W>,
    magnitude: Vec3<W>,
    widened: Vec3<W>,
}

impl<W: Real> Frame<W> {
    #[inline(always)]
    fn of([x, y, z]: [AxisFrame<W>; 3]) -> Self {
        Self {
            centre: Vec3::new(x.centre, y.centre, z.centre),
            half: Vec3::new(x.half, y.half, z.half),
            magnitude: Vec3::new(x.magnitude, y.magnitude, z.magnitude),
            widened: Vec3::new(x.widened, y.widened, z.widened),
        }
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
        *o = meets(&vertices, &bounds, &mut test, b);
    }
}

/// [`TriangleBoxTest::overlaps`] of the triangle of `vertices` (with
/// `bounds`) for box `b`, preparing `test` the first time a box needs it.
#[inline]
fn meets<T: Real>(
    vertices: &[Vec3<T>; 3],
    bounds: &Aabb<T>,
    test: &mut Option<TriangleBoxTest<T>>,
    b: &Aabb<T>,
) -> bool {
    settled_by_vertices(bounds, vertices, b).unwrap_or_else(|| {
        test.get_or_insert_with(|| TriangleBoxTest::with_bounds(*vertices, *bounds))
            .axes_allow(b)
    })
}

/// The most cells per axis of a block that [`triangle_overlaps_cells`]
/// tests by its tables; larger blocks are tested box by box.
pub const BLOCK_MAX_CELLS: usize = 4;

/// [`TriangleBoxTest::overlaps`] of triangle `p0 p1 p2` for every cell of a
/// block of boxes on a grid: `boundaries[a]` holds the block's boundaries
/// along axis `a` (non-decreasing), and cell `[i, j, k]` is the closed box
/// from `boundaries[0][i]`, `boundaries[1][j]`, `boundaries[2][k]` to the
/// next boundary of each. `accept` is called with every cell the test
/// accepts, x fastest: the same answers as the test box by box.
///
/// Cheaper than that: each per-axis quantity of the test (the interval's
/// place against the triangle's bounds and vertices, its centre and
/// widened half-width) is computed once per interval, and each group of
/// three edge axes `unit_k × edge_j`, which sees only the box's two other
/// axes, once per column of cells along `k` (when a cell of it needs it),
/// so a block of `a × b × c` cells pays for at most `b·c + c·a + a·b`
/// groups, not `3·a·b·c`. Only the plane test is made per cell. Blocks over
/// [`BLOCK_MAX_CELLS`] along an axis are tested box by box.
pub fn triangle_overlaps_cells<T: Real>(
    [p0, p1, p2]: [Vec3<T>; 3],
    boundaries: [&[T]; 3],
    mut accept: impl FnMut([usize; 3]),
) {
    let vertices = [p0, p1, p2];
    let bounds = vertex_bounds(&vertices);
    let n = boundaries.map(|b| b.len().saturating_sub(1));
    if n.contains(&0) {
        return;
    }
    if n.iter().any(|&m| m > BLOCK_MAX_CELLS) {
        let mut test = None;
        for c in block_cells(n) {
            let b = Aabb {
                min: Vec3::new(
                    boundaries[0][c[0]],
                    boundaries[1][c[1]],
                    boundaries[2][c[2]],
                ),
                max: Vec3::new(
                    boundaries[0][c[0] + 1],
                    boundaries[1][c[1] + 1],
                    boundaries[2][c[2] + 1],
                ),
            };
            if meets(&vertices, &bounds, &mut test, &b) {
                accept(c);
            }
        }
        return;
    }
    // Per axis and interval: whether the bounds may meet it (the box
    // non-empty and overlapping the bounds there), which vertices lie in
    // it (a bit each), and whether it holds the bounds' whole extent.
    let mut open = [[false; BLOCK_MAX_CELLS]; 3];
    let mut inside = [[0u8; BLOCK_MAX_CELLS]; 3];
    let mut holds = [[false; BLOCK_MAX_CELLS]; 3];
    for a in 0..3 {
        for i in 0..n[a] {
            let (lo, hi) = (boundaries[a][i], boundaries[a][i + 1]);
            open[a][i] = lo <= hi && bounds.min[a] <= hi && lo <= bounds.max[a];
            inside[a][i] = (0..3)
                .filter(|&v| vertices[v][a] >= lo && vertices[v][a] <= hi)
                .fold(0, |m, v| m | 1 << v);
            holds[a][i] = bounds.min[a] >= lo && bounds.max[a] <= hi;
        }
    }
    // The test and each interval's frame, prepared for the first cell
    // that the bounds and vertices do not settle.
    let mut prepared = None;
    // Per group `k`, per column along `k` (its cells on the two other axes,
    // `k + 1` and `k + 2` mod 3): 0 not yet known, 1 separates, 2 does not.
    let mut columns = [[0u8; BLOCK_MAX_CELLS * BLOCK_MAX_CELLS]; 3];
    for c in block_cells(n) {
        if !(0..3).all(|a| open[a][c[a]]) {
            continue;
        }
        if inside[0][c[0]] & inside[1][c[1]] & inside[2][c[2]] != 0 {
            accept(c);
            continue;
        }
        let (test, frames) = prepared.get_or_insert_with(|| {
            let test = TriangleBoxTest::with_bounds(vertices, bounds);
            let frames: [[AxisFrame<Wide<T>>; BLOCK_MAX_CELLS]; 3] = core::array::from_fn(|a| {
                core::array::from_fn(|i| {
                    let i = i.min(n[a] - 1);
                    test.axis_frame(a, boundaries[a][i], boundaries[a][i + 1])
                })
            });
            (test, frames)
        });
        let frame = Frame::of([0, 1, 2].map(|a| frames[a][c[a]]));
        let separates = |k: usize| {
            let column = &mut columns[k][c[(k + 1) % 3] * BLOCK_MAX_CELLS + c[(k + 2) % 3]];
            if *column == 0 {
                *column = if test.edge_axes_separate(k, &frame) {
                    1
                } else {
                    2
                };
            }
            *column == 1
        };
        if test.frame_allows(&frame, |k| holds[k][c[k]], separates) {
            accept(c);
        }
    }
}

/// The cells of a block of `n[0] × n[1] × n[2]`, x fastest.
fn block_cells(n: [usize; 3]) -> impl Iterator<Item = [usize; 3]> {
    (0..n[2]).flat_map(move |z| (0..n[1]).flat_map(move |y| (0..n[0]).map(move |x| [x, y, z])))
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::tests::{Rng, v};

    /// `n + 1` boundaries from `lo`, with random gaps (some zero: empty
    /// intervals, as a flat grid axis has) in `T`.
    fn boundaries<T: Real>(rng: &mut Rng, lo: f64, n: usize, step: f64) -> Vec<T> {
        let mut b = vec![T::from_f64(lo)];
        let mut x = lo;
        for _ in 0..n {
            if rng.next_f64() > 0.1 {
                x += step * rng.range(0.2, 1.8);
            }
            b.push(T::from_f64(x));
        }
        b
    }

    /// Every cell of random blocks (1 to 6 cells per axis, so blocks over
    /// [`BLOCK_MAX_CELLS`] take the box-by-box path too) gets the box
    /// test's answer, and each accepted cell is reported once.
    fn check_blocks<T: Real>(seed: u64, offset: f64) -> [usize; 2] {
        let mut rng = Rng(seed);
        let (mut met, mut missed) = (0, 0);
        for case in 0..600 {
            let n = [0; 3].map(|_| 1 + (rng.next_f64() * 6.0) as usize);
            let step = rng.range(0.1, 1.0);
            let b: [Vec<T>; 3] = core::array::from_fn(|_| {
                boundaries(&mut rng, offset, n[0].max(n[1]).max(n[2]), step)
            });
            let b: [&[T]; 3] = core::array::from_fn(|a| &b[a][..=n[a]]);
            let extent = n.map(|m| m as f64 * step);
            let mut point = || {
                let p = v::<f64>(
                    rng.range(-0.3, 1.3) * extent[0],
                    rng.range(-0.3, 1.3) * extent[1],
                    rng.range(-0.3, 1.3) * extent[2],
                );
                p.map(|c| T::from_f64(offset + c))
            };
            let mut tri = [point(), point(), point()];
            if case % 5 == 0 {
                // Flat in a boundary plane: the cells on both sides meet it.
                let a = case % 3;
                tri.iter_mut().for_each(|p| p[a] = b[a][n[a] / 2]);
            }
            let mut accepted = Vec::new();
            triangle_overlaps_cells(tri, b, |c| accepted.push(c));
            let test = TriangleBoxTest::new(tri[0], tri[1], tri[2]);
            let mut want = Vec::new();
            for c in block_cells(n) {
                let cell = Aabb {
                    min: Vec3::new(b[0][c[0]], b[1][c[1]], b[2][c[2]]),
                    max: Vec3::new(b[0][c[0] + 1], b[1][c[1] + 1], b[2][c[2] + 1]),
                };
                if test.overlaps(&cell) {
                    want.push(c);
                    met += 1;
                } else {
                    missed += 1;
                }
            }
            assert_eq!(accepted, want, "{tri:?} in {b:?}");
        }
        [met, missed]
    }

    #[test]
    fn block_answers_are_the_box_tests() {
        for (seed, offset) in [(1, 0.0), (2, -3.5), (3, 1.0e4)] {
            let [met, missed] = check_blocks::<f32>(seed, offset);
            assert!(met > 2000 && missed > 2000, "{met} met, {missed} missed");
            let [met, missed] = check_blocks::<f64>(seed + 10, offset);
            assert!(met > 2000 && missed > 2000, "{met} met, {missed} missed");
        }
    }

    /// Each edge axis's projection interval is the one spanned by all three
    /// vertices' projections, each computed as `dot_cross_unit` computes
    /// it (equal as numbers: `−0` and `+0` compare equal), for triangles
    /// of every shape and size near and far from the coordinate origin.
    #[test]
    fn projections_are_spanned_by_the_three_vertices() {
        fn check<T: Real>(rng: &mut Rng, offset: f64, scale: f64) {
            let mut point = || {
                let p = v::<f64>(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                );
                p.map(|c| T::from_f64(offset + c * scale))
            };
            let mut tri = [point(), point(), point()];
            if rng.next_f64() < 0.2 {
                tri[2] = tri[1]; // a segment
            }
            let test = TriangleBoxTest::new(tri[0], tri[1], tri[2]);
            let origin = tri[0].map(T::to_wide);
            let q = tri.map(|p| p.map(T::to_wide) - origin);
            for (j, &e) in test.edges.iter().enumerate() {
                for k in 0..3 {
                    let [a, b, c] = q.map(|p| dot_cross_unit(k, e, p));
                    let (lo, hi) = test.projections[3 * j + k];
                    assert!(
                        lo == a.min(b).min(c) && hi == a.max(b).max(c),
                        "{tri:?} {j} {k}"
                    );
                }
            }
        }
        let mut rng = Rng(5);
        for i in 0..3000 {
            let (offset, scale) = [(0.0, 1.0), (1.0e4, 0.5), (-3.0, 1.0e-3)][i % 3];
            check::<f32>(&mut rng, offset, scale);
            check::<f64>(&mut rng, offset, scale);
        }
    }
}
