//! One case of the equivalence suite: build every registered accelerator
//! over a scene and compare each with brute force on the same rays and boxes.

use crate::assertions::{Expected, check_accelerator};
use crate::registry::accelerators;
use crate::{BoxSpec, RayContext, RaySpec, WindowSpec};
use crate::{Landmarks, Scene, SceneSpec};
use accel_core::{Aabb, Accelerator, BruteForce, PrimitiveSet, Ray, Real};
use rayon::prelude::*;

/// Builds the scene in precision `T`, resolves the rays and boxes against it,
/// and checks every registered accelerator.
///
/// # Errors
/// The first failure, readably.
pub fn check_case<T: Real>(
    scene: &SceneSpec,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<(), String> {
    let built = scene.build::<T>();
    let landmarks = Landmarks::of(&built);
    match &built {
        Scene::Mesh(m) => check_specs(m, landmarks, rays, boxes),
        Scene::Mixed(v) => check_specs(v.as_slice(), landmarks, rays, boxes),
    }
}

/// Concrete rays and region boxes, resolved from their descriptions.
#[derive(Clone, Debug)]
pub struct Resolved<T> {
    /// The rays, in the order of their descriptions.
    pub rays: Vec<Ray<T>>,
    /// The region boxes, in the order of their descriptions.
    pub regions: Vec<Aabb<T>>,
}

/// Resolves ray and box descriptions against a primitive set (windows around
/// brute force's hits included).
///
/// # Errors
/// A message if brute force cannot be built (a non-finite scene).
pub fn resolve<T: Real, P: PrimitiveSet<T> + ?Sized>(
    prims: &P,
    landmarks: Landmarks<T>,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<Resolved<T>, String> {
    let brute =
        BruteForce::new(prims).map_err(|e| format!("brute force refused the scene: {e}"))?;
    let ctx = RayContext::new(prims, landmarks);
    let size = ctx.landmarks.size();
    let nearest = |r: &Ray<T>| brute.intersect(r).ok().flatten();
    let rays = rays
        .par_iter()
        .with_min_len(64)
        .map(|(rs, ws)| ws.apply(rs.resolve(&ctx), size, nearest))
        .collect();
    let regions = boxes.iter().map(|b| b.resolve(&ctx)).collect();
    Ok(Resolved { rays, regions })
}

/// [`resolve`], then [`check_all`].
///
/// # Errors
/// The first failure, readably.
pub fn check_specs<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    landmarks: Landmarks<T>,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<(), String> {
    let r = resolve(prims, landmarks, rays, boxes)?;
    check_all(prims, &r.rays, &r.regions)
}

/// Checks every registered accelerator against brute force on concrete rays
/// and regions.
///
/// # Errors
/// The first failure, readably.
pub fn check_all<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    rays: &[Ray<T>],
    regions: &[Aabb<T>],
) -> Result<(), String> {
    let brute =
        BruteForce::new(prims).map_err(|e| format!("brute force refused the scene: {e}"))?;
    let expected = Expected::compute(&brute, rays, regions)?;
    for entry in accelerators::<T, P>() {
        let acc = (entry.build)(prims).map_err(|e| {
            format!(
                "{} ({}): build refused a finite scene of {} primitives: {e}",
                entry.name,
                T::NAME,
                prims.len()
            )
        })?;
        check_accelerator(entry.name, &*acc, prims, rays, regions, &expected)?;
    }
    Ok(())
}
