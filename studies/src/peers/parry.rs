//! The parry3d peer: a [`TriMesh`] (parry's own BVH over the triangles),
//! queried by ray casts on the composite shape: `cast_local_ray` for the
//! nearest hit (it reports the triangle) and `intersects_local_ray` for any
//! hit, with `solid = true`.
//!
//! parry's rays start at their origin and end at a time of impact strictly
//! below the one given: rays with `t_min > 0` are moved to start at `t_min`
//! ([`super::start_at_zero`]), and an infinite `t_max` is passed as
//! `f32::MAX`. parry3d 0.31's `intersects_local_ray` on a `TriMesh` is its
//! nearest-hit cast (no early exit): that is what the library offers.

use super::{BuiltPeer, PeerHit, PeerMesh, Tracer, start_at_zero};
use accel_core::Ray as OurRay;
use parry3d::math::Vector;
use parry3d::query::{Ray, RayCast};
use parry3d::shape::{CompositeShapeRef, TriMesh};
use std::time::Instant;

/// A parry3d triangle mesh over the scene.
pub struct ParryPeer {
    mesh: TriMesh,
}

/// Builds the peer (one thread: parry3d is built without its `parallel`
/// feature).
///
/// # Errors
/// parry's refusal of the mesh.
pub fn build(mesh: &PeerMesh) -> Result<BuiltPeer, String> {
    let start = Instant::now();
    let vertices = mesh
        .positions
        .iter()
        .map(|p| Vector::new(p[0], p[1], p[2]))
        .collect();
    let trimesh = TriMesh::new(vertices, mesh.indices.clone())
        .map_err(|e| format!("parry3d refused the mesh: {e:?}"))?;
    let build = start.elapsed();
    Ok(BuiltPeer {
        tracer: Box::new(ParryPeer { mesh: trimesh }),
        build,
    })
}

/// parry's ray and time-of-impact bound, and the offset to add to its `t`.
fn ray_of(r: &OurRay<f32>) -> (Ray, f32, f32) {
    let (r, offset) = start_at_zero(r);
    let ray = Ray::new(
        Vector::new(r.origin.x, r.origin.y, r.origin.z),
        Vector::new(r.direction.x, r.direction.y, r.direction.z),
    );
    let max = if r.t_max.is_finite() {
        r.t_max
    } else {
        f32::MAX
    };
    (ray, max, offset)
}

impl Tracer for ParryPeer {
    fn nearest(&self, ray: &OurRay<f32>) -> Option<PeerHit> {
        let (r, max, offset) = ray_of(ray);
        CompositeShapeRef(&self.mesh)
            .cast_local_ray(&r, max, true)
            .map(|(prim, t)| PeerHit {
                t: t + offset,
                prim,
            })
    }

    fn occluded(&self, ray: &OurRay<f32>) -> bool {
        let (r, max, _) = ray_of(ray);
        self.mesh.intersects_local_ray(&r, max)
    }
}
