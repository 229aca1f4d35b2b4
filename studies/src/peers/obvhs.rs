//! The obvhs peer: a BVH2 from obvhs's PLOC builder with its medium-quality
//! parameters ([`BvhBuildParams::medium_build`]), traversed by
//! [`Bvh2::ray_traverse`] (nearest hit) and [`Bvh2::ray_traverse_miss`]
//! (any hit) with obvhs's own Möller–Trumbore triangle test.
//!
//! The triangles are stored in the BVH's primitive order, as obvhs's
//! documentation advises, so a leaf indexes them directly.

use super::{BuiltPeer, PeerHit, PeerMesh, Tracer};
use ::obvhs::BvhBuildParams;
use ::obvhs::bvh2::Bvh2;
use ::obvhs::bvh2::builder::build_bvh2_from_tris;
use ::obvhs::ray::{Ray, RayHit};
use ::obvhs::triangle::Triangle;
use accel_core::Ray as OurRay;
use glam::Vec3A;
use std::time::{Duration, Instant};

/// An obvhs BVH2 over the scene.
pub struct ObvhsPeer {
    bvh: Bvh2,
    /// The triangles in `bvh.primitive_indices` order.
    triangles: Vec<Triangle>,
}

fn vec3a(p: [f32; 3]) -> Vec3A {
    Vec3A::new(p[0], p[1], p[2])
}

fn ray_of(r: &OurRay<f32>) -> Ray {
    Ray::new(
        Vec3A::new(r.origin.x, r.origin.y, r.origin.z),
        Vec3A::new(r.direction.x, r.direction.y, r.direction.z),
        r.t_min,
        r.t_max,
    )
}

/// Builds the peer (one thread: obvhs is built without its `parallel` feature).
///
/// # Errors
/// Never; the signature is the one of [`super::BuildFn`].
pub fn build(mesh: &PeerMesh) -> Result<BuiltPeer, String> {
    let start = Instant::now();
    let triangles: Vec<Triangle> = (0..mesh.triangle_count())
        .map(|i| {
            let [v0, v1, v2] = mesh.triangle(i).map(vec3a);
            Triangle { v0, v1, v2 }
        })
        .collect();
    let mut core = Duration::ZERO;
    let bvh = build_bvh2_from_tris(&triangles, BvhBuildParams::medium_build(), &mut core);
    let triangles = bvh
        .primitive_indices
        .iter()
        .map(|&i| triangles[i as usize])
        .collect();
    let build = start.elapsed();
    Ok(BuiltPeer {
        tracer: Box::new(ObvhsPeer { bvh, triangles }),
        build,
    })
}

impl Tracer for ObvhsPeer {
    fn nearest(&self, ray: &OurRay<f32>) -> Option<PeerHit> {
        let mut hit = RayHit::none();
        let found = self.bvh.ray_traverse(ray_of(ray), &mut hit, |r, id| {
            self.triangles[id].intersect(r)
        });
        found.then(|| PeerHit {
            t: hit.t,
            prim: self.bvh.primitive_indices[hit.primitive_id as usize],
        })
    }

    fn occluded(&self, ray: &OurRay<f32>) -> bool {
        !self
            .bvh
            .ray_traverse_miss(ray_of(ray), |r, id| self.triangles[id].intersect(r))
    }
}
