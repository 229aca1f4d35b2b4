//! The bvh-crate peer: its SAH [`Bvh`] over the triangles, traversed with
//! [`Bvh::nearest_traverse_iterator`] and a plain Möller–Trumbore test
//! without back-face culling ([`moller_trumbore`]; the crate's own
//! `intersects_triangle` culls back faces, which no other tool here does).
//!
//! The crate's rays are unbounded and normalise their direction, so the
//! peer gives it the unit direction and rescales: the iterator yields the
//! triangles in order of their boxes' entry distance along the unit ray
//! (a box's entry is never before its parent's), so the search stops at the
//! first box entered beyond the best hit (or beyond `t_max`), converted to
//! unit-ray distance with a margin for rounding. The triangle test runs on
//! the ray as given, so `t` is in its units.

use super::{BuiltPeer, PeerHit, PeerMesh, Tracer};
use ::bvh::aabb::{Aabb, Bounded};
use ::bvh::bounding_hierarchy::BHShape;
use ::bvh::bvh::Bvh;
use ::bvh::ray::Ray;
use accel_core::{Ray as OurRay, Vec3};
use nalgebra::{Point3, Vector3};
use std::time::Instant;

/// Relative margin on the unit-ray distance at which the search stops.
const STOP_MARGIN: f32 = 1e-5;

/// A triangle as the bvh crate sees it.
#[derive(Clone, Debug)]
struct Tri {
    corners: [Vec3<f32>; 3],
    bounds: Aabb<f32, 3>,
    prim: u32,
    node: usize,
}

impl Bounded<f32, 3> for Tri {
    fn aabb(&self) -> Aabb<f32, 3> {
        self.bounds
    }
}

impl BHShape<f32, 3> for Tri {
    fn set_bh_node_index(&mut self, index: usize) {
        self.node = index;
    }

    fn bh_node_index(&self) -> usize {
        self.node
    }
}

/// A bvh-crate BVH over the scene.
pub struct BvhPeer {
    bvh: Bvh<f32, 3>,
    tris: Vec<Tri>,
}

/// Builds the peer with [`Bvh::build`] (one thread).
///
/// # Errors
/// Never; the signature is the one of [`super::BuildFn`].
pub fn build(mesh: &PeerMesh) -> Result<BuiltPeer, String> {
    let start = Instant::now();
    let mut tris: Vec<Tri> = (0..mesh.triangle_count())
        .map(|i| {
            let corners = mesh.triangle(i).map(|p| Vec3::new(p[0], p[1], p[2]));
            let lo = corners[0].min(corners[1]).min(corners[2]);
            let hi = corners[0].max(corners[1]).max(corners[2]);
            Tri {
                corners,
                bounds: Aabb::with_bounds(
                    Point3::new(lo.x, lo.y, lo.z),
                    Point3::new(hi.x, hi.y, hi.z),
                ),
                prim: i as u32,
                node: 0,
            }
        })
        .collect();
    let bvh = Bvh::build(&mut tris);
    let build = start.elapsed();
    Ok(BuiltPeer {
        tracer: Box::new(BvhPeer { bvh, tris }),
        build,
    })
}

/// Möller & Trumbore's test as renderers ship it: no back-face culling, no
/// guard; the hit's `t` if it lies in `[ray.t_min, t_max]`.
#[inline]
#[must_use]
pub fn moller_trumbore(
    ray: &OurRay<f32>,
    p0: Vec3<f32>,
    p1: Vec3<f32>,
    p2: Vec3<f32>,
    t_max: f32,
) -> Option<f32> {
    let d = ray.direction;
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pvec = d.cross(e2);
    let det = e1.dot(pvec);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = ray.origin - p0;
    let u = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let v = d.dot(qvec) * inv_det;
    if !(v >= 0.0 && u + v <= 1.0) {
        return None;
    }
    let t = e2.dot(qvec) * inv_det;
    (t >= ray.t_min && t <= t_max).then_some(t)
}

impl BvhPeer {
    /// The nearest hit, or with `any` the first hit found.
    fn search(&self, ray: &OurRay<f32>, any: bool) -> Option<PeerHit> {
        let d = ray.direction;
        let len = d.length();
        let unit = Ray::new(
            Point3::new(ray.origin.x, ray.origin.y, ray.origin.z),
            Vector3::new(d.x, d.y, d.z),
        );
        let mut best: Option<PeerHit> = None;
        let mut t_max = ray.t_max;
        for tri in self.bvh.nearest_traverse_iterator(&unit, &self.tris) {
            if let Some((entry, _)) = unit.intersection_slice_for_aabb(&tri.bounds)
                && entry > t_max * len * (1.0 + STOP_MARGIN)
            {
                break;
            }
            let [p0, p1, p2] = tri.corners;
            if let Some(t) = moller_trumbore(ray, p0, p1, p2, t_max) {
                let hit = PeerHit { t, prim: tri.prim };
                if any {
                    return Some(hit);
                }
                if best.is_none_or(|b| t < b.t) {
                    best = Some(hit);
                    t_max = t;
                }
            }
        }
        best
    }
}

impl Tracer for BvhPeer {
    fn nearest(&self, ray: &OurRay<f32>) -> Option<PeerHit> {
        self.search(ray, false)
    }

    fn occluded(&self, ray: &OurRay<f32>) -> bool {
        self.search(ray, true).is_some()
    }
}
