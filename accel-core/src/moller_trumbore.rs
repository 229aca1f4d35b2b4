//! The triangle-test dial: the watertight test (the default) or the faster,
//! non-watertight Möller–Trumbore test.
//!
//! Möller & Trumbore, "Fast, minimum storage ray–triangle intersection"
//! (JGT 1997), solves `o + t·d = (1−u−v)·p0 + u·p1 + v·p2` by Cramer's rule
//! with two cross products, in the query precision, and rejects most misses
//! after the first barycentric. It is the test most renderers ship. What it
//! costs: the barycentrics are rounded before they are compared with 0 and 1,
//! so a ray through a shared edge or vertex can miss both triangles (a leak),
//! and `t` is ill-conditioned for rays grazing the plane. The watertight test
//! ([`crate::triangle::intersect_triangle`]) has neither problem.
//!
//! The dial is a [`PrimitiveSet`]: [`MollerTrumboreMesh`] wraps a
//! [`TriangleMesh`] and answers every ray with [`intersect_triangle_mt`],
//! everything else (bounds, box overlap, clipping) as the mesh does. Every
//! accelerator calls the set's test, so every accelerator built over the
//! wrapper is still bit-for-bit equal to [`crate::BruteForce`] over the same
//! wrapper; the default path ([`TriangleMesh`] itself) is untouched.
//!
//! ```
//! use accel_core::{Accelerator, BruteForce, MollerTrumboreMesh, Ray, TriangleMesh, Vec3};
//!
//! let mesh = TriangleMesh::new(
//!     vec![Vec3::new(0.0f32, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)],
//!     vec![[0, 1, 2]],
//! )?;
//! let fast = MollerTrumboreMesh::new(&mesh);
//! let ray = Ray::new(Vec3::new(0.25, 0.25, 0.0), Vec3::new(0.0, 0.0, 1.0))?;
//! let hit = BruteForce::new(&fast)?.intersect(&ray)?.expect("a hit");
//! assert_eq!((hit.t, hit.prim, hit.u, hit.v), (1.0, 0, 0.25, 0.25));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::{Aabb, PreparedRay, PrimHit, PrimitiveSet, Real, TriangleMesh, Vec3};
use core::borrow::Borrow;
use core::fmt;

/// Which ray–triangle test a mesh answers with.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TriangleTest {
    /// Woop, Benthin & Wald (2013): exact edge-function signs, so no ray leaks
    /// through a shared edge or vertex; the default.
    #[default]
    Watertight,
    /// Möller & Trumbore (1997): fewer operations and an early exit on most
    /// misses; rays through shared edges and vertices can leak.
    MollerTrumbore,
}

impl TriangleTest {
    /// Both tests, default first.
    pub const ALL: [Self; 2] = [Self::Watertight, Self::MollerTrumbore];

    /// Short name for reports and the command line.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Watertight => "watertight",
            Self::MollerTrumbore => "moller-trumbore",
        }
    }
}

impl fmt::Display for TriangleTest {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// The Möller–Trumbore ray–triangle test, without back-face culling.
///
/// Returns the hit with `ray.t_min ≤ t ≤ t_max`; `u`, `v` are the barycentric
/// weights of `p1` and `p2`, as [`crate::triangle::intersect_triangle`]
/// reports them. Arithmetic runs in `T`. A NaN or infinite intermediate (a
/// degenerate triangle, coordinates near `T::MAX`) is a miss, never a hit.
///
/// One guard keeps the [`crate::Primitive`] contract that accelerators rely
/// on: a hit is reported only if the point `o + t·d` lies within
/// `gamma(24)·s` of the point the barycentrics name, `s` being the farthest
/// vertex from the origin (L∞). Traversals look for hits within a beam of
/// `gamma(64)` of the farthest scene corner from the origin
/// ([`crate::TraversalRay`]), at least `gamma(64)·s`; the check's own rounding
/// adds at most about `gamma(12)·s`, so every accepted hit is found by every
/// structure. Where `t` is ill-conditioned (rays grazing the plane, slivers)
/// the two points disagree by more and the ray misses, rather than reporting
/// a point off the triangle, which no traversal could find where brute force
/// does. On the generated scenes' camera and random rays, Möller–Trumbore
/// (barycentrics and guard together) refuses 0.04 to 0.3% of the watertight
/// test's hits; with the earlier guard (`gamma(4)` of the summed magnitudes)
/// it was 0.7 to 2.2% (`accel-grid/examples/mt_refusals.rs`). The guard runs
/// only on hits, which are rare among tests.
#[inline]
#[must_use]
pub fn intersect_triangle_mt<T: Real>(
    ray: &PreparedRay<T>,
    p0: Vec3<T>,
    p1: Vec3<T>,
    p2: Vec3<T>,
    t_max: T,
) -> Option<PrimHit<T>> {
    let d = ray.ray.direction;
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pvec = d.cross(e2);
    let det = e1.dot(pvec);
    // Zero, NaN or infinite: no unique solution (NaN fails `>`).
    if !(det.abs() > T::ZERO) || !det.is_finite() {
        return None;
    }
    let inv_det = T::ONE / det;
    let tvec = ray.ray.origin - p0;
    let u = tvec.dot(pvec) * inv_det;
    if !(u >= T::ZERO && u <= T::ONE) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = d.dot(qvec) * inv_det;
    if !(v >= T::ZERO && u + v <= T::ONE) {
        return None;
    }
    let t = e2.dot(qvec) * inv_det;
    if !(t >= ray.ray.t_min && t <= t_max && t.is_finite()) {
        return None;
    }
    let o = ray.ray.origin;
    let farthest = tvec
        .abs()
        .max((o - p1).abs())
        .max((o - p2).abs())
        .max_component();
    consistent(t, d, -tvec, e1, e2, u, v, farthest).then_some(PrimHit { t, u, v })
}

/// The guard's tolerance in roundings of the farthest vertex distance.
const GUARD_ROUNDINGS: u32 = 24;

/// Whether `t·d` (the hit relative to the origin) is within
/// `gamma(GUARD_ROUNDINGS)·farthest` of `a + u·e1 + v·e2` (the barycentric
/// point relative to the origin, inside the triangle since `u, v ≥ 0` and
/// `u + v ≤ 1`).
#[inline]
#[allow(clippy::too_many_arguments)]
fn consistent<T: Real>(
    t: T,
    d: Vec3<T>,
    a: Vec3<T>,
    e1: Vec3<T>,
    e2: Vec3<T>,
    u: T,
    v: T,
    farthest: T,
) -> bool {
    let along = d * t;
    let on = a + e1 * u + e2 * v;
    let gap = (along - on).abs().max_component();
    gap <= T::gamma(GUARD_ROUNDINGS) * farthest
}

/// A [`TriangleMesh`] answering rays with the Möller–Trumbore test
/// ([`intersect_triangle_mt`]) instead of the watertight one. Bounds, box
/// overlap and clipping are the mesh's own, so structures built over it have
/// the same cells and nodes as over the mesh.
///
/// `M` holds the mesh: a borrow by default ([`MollerTrumboreMesh::new`]),
/// or the mesh itself or an [`std::sync::Arc`] of it
/// ([`MollerTrumboreMesh::owning`]), for an application that keeps the
/// wrapper, and a structure sharing it, beside its own data.
#[derive(Clone, Copy, Debug)]
pub struct MollerTrumboreMesh<'a, T, M = &'a TriangleMesh<T>> {
    mesh: M,
    _borrow: core::marker::PhantomData<&'a TriangleMesh<T>>,
}

impl<'a, T: Real> MollerTrumboreMesh<'a, T> {
    /// Wraps a borrowed mesh (nothing is copied).
    #[inline]
    #[must_use]
    pub const fn new(mesh: &'a TriangleMesh<T>) -> Self {
        Self::owning(mesh)
    }
}

impl<T: Real, M: Borrow<TriangleMesh<T>>> MollerTrumboreMesh<'_, T, M> {
    /// Wraps whatever holds the mesh: the mesh itself, an `Arc` of it, or
    /// a borrow (nothing is copied).
    ///
    /// ```
    /// use accel_core::{Accelerator, BruteForce, MollerTrumboreMesh, TriangleMesh, Vec3};
    /// use std::sync::Arc;
    ///
    /// let mesh = Arc::new(TriangleMesh::new(
    ///     vec![Vec3::new(0.0f32, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)],
    ///     vec![[0, 1, 2]],
    /// )?);
    /// // Owns a count of the mesh, so both can live in one struct.
    /// let fast = Arc::new(MollerTrumboreMesh::owning(Arc::clone(&mesh)));
    /// let brute = BruteForce::shared(fast)?;
    /// assert_eq!(brute.primitives().mesh().triangle_count(), 1);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    #[inline]
    #[must_use]
    pub const fn owning(mesh: M) -> Self {
        Self {
            mesh,
            _borrow: core::marker::PhantomData,
        }
    }

    /// The wrapped mesh.
    #[inline]
    #[must_use]
    pub fn mesh(&self) -> &TriangleMesh<T> {
        self.mesh.borrow()
    }
}

impl<T: Real, M: Borrow<TriangleMesh<T>> + Sync> PrimitiveSet<T> for MollerTrumboreMesh<'_, T, M> {
    #[inline]
    fn len(&self) -> usize {
        self.mesh().triangle_count()
    }

    #[inline]
    fn bounds(&self, i: usize) -> Aabb<T> {
        PrimitiveSet::bounds(self.mesh(), i)
    }

    #[inline]
    fn intersect(&self, i: usize, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        let [a, b, c] = self.mesh().triangle(i);
        intersect_triangle_mt(ray, a, b, c, t_max)
    }

    #[inline]
    fn overlaps_box(&self, i: usize, b: &Aabb<T>) -> bool {
        self.mesh().overlaps_box(i, b)
    }

    #[inline]
    fn overlaps_boxes(&self, i: usize, boxes: &[Aabb<T>], out: &mut [bool]) {
        self.mesh().overlaps_boxes(i, boxes, out);
    }

    #[inline]
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        self.mesh().clipped_bounds(i, b)
    }

    #[inline]
    fn clipped_bounds_split(&self, i: usize, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        self.mesh().clipped_bounds_split(i, b, axis, s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::triangle::intersect_triangle;
    use crate::triangle::tests::{ray as prep, v};
    use crate::{Accelerator, BruteForce, Ray};

    fn agrees_with_watertight_inside<T: Real>() {
        let (p0, p1, p2) = (v::<T>(0.0, 0.0, 2.0), v(4.0, 0.0, 2.0), v(0.0, 4.0, 2.0));
        for (o, d) in [
            (v::<T>(1.0, 2.0, 0.0), v::<T>(0.0, 0.0, 1.0)),
            (v(1.0, 2.0, 10.0), v(0.0, 0.0, -4.0)),
            (v(-1.0, -1.0, 0.0), v(2.0, 3.0, 2.0)),
        ] {
            let r = prep(o, d);
            let mt = intersect_triangle_mt(&r, p0, p1, p2, T::INFINITY).unwrap();
            let wt = intersect_triangle(&r, p0, p1, p2, T::INFINITY).unwrap();
            let close = |a: T, b: T| (a - b).abs() <= T::from_f64(1e-5);
            assert!(close(mt.t, wt.t) && close(mt.u, wt.u) && close(mt.v, wt.v));
        }
        // Misses beside each edge, behind the origin, and past t_max.
        let r = prep(v::<T>(3.0, 3.0, 0.0), v(0.0, 0.0, 1.0));
        assert!(intersect_triangle_mt(&r, p0, p1, p2, T::INFINITY).is_none());
        let r = prep(v::<T>(-0.5, 1.0, 0.0), v(0.0, 0.0, 1.0));
        assert!(intersect_triangle_mt(&r, p0, p1, p2, T::INFINITY).is_none());
        let r = prep(v::<T>(1.0, 1.0, 3.0), v(0.0, 0.0, 1.0));
        assert!(intersect_triangle_mt(&r, p0, p1, p2, T::INFINITY).is_none());
        let r = prep(v::<T>(1.0, 1.0, 0.0), v(0.0, 0.0, 1.0));
        assert!(intersect_triangle_mt(&r, p0, p1, p2, T::from_f64(1.5)).is_none());
        assert!(intersect_triangle_mt(&r, p0, p1, p2, T::from_f64(2.0)).is_some());
    }

    #[test]
    fn agrees_with_the_watertight_test_away_from_edges() {
        agrees_with_watertight_inside::<f32>();
        agrees_with_watertight_inside::<f64>();
    }

    #[test]
    fn degenerate_and_overflowing_triangles_never_hit() {
        let r = prep(v::<f32>(0.5, 0.0, -1.0), v(0.0, 0.0, 1.0));
        // A segment (zero area) and a point.
        let seg = [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0)];
        assert!(intersect_triangle_mt(&r, seg[0], seg[1], seg[2], f32::INFINITY).is_none());
        let p = v(0.5, 0.0, 0.0);
        assert!(intersect_triangle_mt(&r, p, p, p, f32::INFINITY).is_none());
        // Cross products overflow f32: NaN and infinity are misses.
        let big = [v(-3e38, -3e38, 0.0), v(3e38, -3e38, 0.0), v(0.0, 3e38, 0.0)];
        assert!(intersect_triangle_mt(&r, big[0], big[1], big[2], f32::INFINITY).is_none());
    }

    #[test]
    fn grazing_rays_with_an_ill_conditioned_t_are_refused() {
        // A ray almost in the triangle's plane: the rounded t puts the point
        // far from where the barycentrics say; the guard refuses the hit
        // rather than report it there.
        let (p0, p1, p2) = (v::<f32>(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0));
        let mut refused = 0;
        for k in 1..200 {
            let eps = 1e-9 * f64::from(k);
            let r = prep(v::<f32>(-1.0, 0.3, eps * 1.3), v(1.0, 0.0, -eps));
            if let Some(h) = intersect_triangle_mt(&r, p0, p1, p2, f32::INFINITY) {
                // Whatever is reported lies on the triangle within rounding.
                let q = r.ray.origin + r.ray.direction * h.t;
                let on = p0 + (p1 - p0) * h.u + (p2 - p0) * h.v;
                assert!((q - on).abs().max_component() < 1e-5, "{q:?} vs {on:?}");
            } else {
                refused += 1;
            }
        }
        assert!(refused < 199, "some grazing rays still hit");
    }

    #[test]
    fn a_ray_through_a_shared_edge_can_leak_where_the_watertight_test_cannot() {
        // A closed fan of triangles around a vertex, hit on its spokes (the
        // edges shared by neighbours) from above: the watertight test finds a
        // triangle every time; Möller–Trumbore misses some (the premise of
        // the dial).
        let n = 64u32;
        let mut positions = vec![v::<f32>(0.1, 0.2, 0.3)];
        for i in 0..n {
            let a = core::f64::consts::TAU * f64::from(i) / f64::from(n);
            positions.push(v(
                0.1 + 0.7 * a.cos(),
                0.2 + 0.7 * a.sin(),
                0.3 + 0.01 * a.sin(),
            ));
        }
        let indices = (0..n).map(|i| [0, 1 + i, 1 + (i + 1) % n]).collect();
        let mesh = TriangleMesh::new(positions, indices).unwrap();
        let mt = MollerTrumboreMesh::new(&mesh);
        let (wt_brute, mt_brute) = (
            BruteForce::new(&mesh).unwrap(),
            BruteForce::new(&mt).unwrap(),
        );
        let p = mesh.positions();
        let mut mt_leaks = 0;
        for k in 0..4000u32 {
            let f = f64::from(k) * 0.618_033_988_749;
            let spoke = p[1 + (k % n) as usize].cast::<f64>();
            let centre = p[0].cast::<f64>();
            let target = centre + (spoke - centre) * (0.05 + 0.9 * (f % 1.0));
            let (s, c) = (f * 7.0).sin_cos();
            let origin = target + Vec3::new(0.3 * s, 0.3 * c, 1.0);
            let ray = Ray::new(origin.cast::<f32>(), (target - origin).cast()).unwrap();
            assert!(
                wt_brute.intersect(&ray).unwrap().is_some(),
                "watertight leaked"
            );
            mt_leaks += usize::from(mt_brute.intersect(&ray).unwrap().is_none());
        }
        assert!(
            mt_leaks > 0,
            "Möller–Trumbore never leaked: the premise failed"
        );
    }

    #[test]
    fn names() {
        assert_eq!(TriangleTest::default(), TriangleTest::Watertight);
        assert_eq!(TriangleTest::MollerTrumbore.to_string(), "moller-trumbore");
    }
}
