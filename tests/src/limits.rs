//! Scenes at the largest finite coordinates of a precision.
//!
//! [`Placement`](crate::Placement) scales by powers of ten and stops at
//! 1e±20. Here a scene is stretched instead until its bounds fill a share of
//! [`Real::LIMIT`] (`T::MAX / 16`, the largest coordinate the accelerators
//! accept) or reach past it, up to `T::MAX` ([`Limit`]), around the origin or
//! against `+T::LIMIT`. The promise checked ([`check_case_at_limit`]): either every accelerator equals
//! brute force bit for bit, or every one, brute force included, refuses the
//! scene with the same [`BuildError::OutOfRange`] (or, for a sphere
//! whose own bounds overflow, [`BuildError::NonFinitePrimitive`]). Never a
//! panic.

use crate::assertions::{Expected, check_accelerator};
use crate::registry::accelerators;
use crate::suite::resolve;
use crate::{BoxSpec, Landmarks, Mixed, RaySpec, Scene, SceneSpec, WindowSpec};
use accel_core::{Aabb, BruteForce, BuildError, PrimitiveSet, Ray, Real, TriangleMesh, Vec3};

/// Where a scene is stretched to: its largest half-extent becomes
/// `half_width · T::LIMIT` (at most `T::MAX`), centered at the origin or,
/// with `at_top`, with its top at `+T::LIMIT` on every axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limit {
    /// The scene's largest half-extent, as a share of [`Real::LIMIT`]: above
    /// 1 the scene is refused.
    pub half_width: f64,
    /// Whether the scene's top corner sits at `+T::LIMIT` (else it is
    /// centered at the origin).
    pub at_top: bool,
}

impl Limit {
    /// The center of the placed scene, in `f64`.
    fn center<T: Real>(&self) -> f64 {
        if self.at_top {
            T::LIMIT.to_f64() - self.target::<T>()
        } else {
            0.0
        }
    }

    /// Places `p` of a scene with bounds `b`, clamped into `±T::MAX` (the
    /// last rounding of `o + h` may step past it). The offset from the
    /// center is divided by the half-extent before it is scaled up, so that
    /// nothing overflows on the way.
    fn point<T: Real>(&self, b: &Aabb<f64>, p: Vec3<f64>) -> Vec3<T> {
        let max = T::MAX.to_f64();
        let h = half_extent(b);
        let unit = if h > 0.0 {
            (p - b.center()) / h
        } else {
            Vec3::ZERO
        };
        let q = unit * self.target::<T>() + Vec3::splat(self.center::<T>());
        q.map(|x| x.clamp(-max, max)).cast()
    }

    /// The half-extent the scene's largest one becomes.
    fn target<T: Real>(&self) -> f64 {
        (self.half_width * T::LIMIT.to_f64()).min(T::MAX.to_f64())
    }

    /// The scene, stretched to this limit in precision `T`.
    ///
    /// # Panics
    /// Never for the scenes of [`SceneSpec`]: every coordinate is clamped
    /// into `±T::MAX`, so the mesh is finite.
    #[must_use]
    pub fn place<T: Real>(&self, scene: &Scene<f64>) -> Scene<T> {
        match scene {
            Scene::Mesh(m) => {
                let b = Aabb::from_points(m.positions().iter().copied());
                let p = m.positions().iter().map(|&p| self.point(&b, p)).collect();
                Scene::Mesh(TriangleMesh::new(p, m.indices().to_vec()).expect("clamped to ±T::MAX"))
            }
            Scene::Mixed(v) => {
                let b = (0..v.len()).fold(Aabb::empty(), |u, i| u.union(&v.as_slice().bounds(i)));
                let (h, max) = (half_extent(&b), T::MAX.to_f64());
                let placed = v
                    .iter()
                    .map(|item| match item {
                        Mixed::Tri(t) => {
                            let [a, b2, c] = t.vertices.map(|p| self.point(&b, p));
                            Mixed::tri(a, b2, c)
                        }
                        Mixed::Ball(ball) => Mixed::ball(
                            self.point(&b, ball.center),
                            T::from_f64(if h > 0.0 {
                                (ball.radius / h * self.target::<T>()).min(max)
                            } else {
                                ball.radius
                            }),
                        ),
                    })
                    .collect();
                Scene::Mixed(placed)
            }
        }
    }
}

/// Half the largest extent of `b`.
fn half_extent(b: &Aabb<f64>) -> f64 {
    0.5 * b.diagonal().max_component()
}

/// A ray made valid at the limit: an origin past `±T::LIMIT` (a frame grown
/// around a scene that fills the range) is clamped to it, and a direction
/// that overflowed (`target − origin` across the whole range) keeps its
/// signs at `±T::MAX`.
#[must_use]
pub fn clamped_ray<T: Real>(r: &Ray<T>) -> Ray<T> {
    let clamp = |x: T, to: T| {
        if x.is_nan() {
            T::ZERO
        } else {
            x.max(-to).min(to)
        }
    };
    let mut direction = r.direction.map(|x| clamp(x, T::MAX));
    if direction == Vec3::ZERO {
        direction = Vec3::new(T::ONE, T::ZERO, T::ZERO);
    }
    Ray {
        origin: r.origin.map(|x| clamp(x, T::LIMIT)),
        direction,
        t_min: r.t_min,
        t_max: r.t_max,
    }
}

/// A box clamped into `±T::MAX` (an empty, inverted box stays inverted).
fn clamped_box<T: Real>(b: &Aabb<T>) -> Aabb<T> {
    let clamp = |x: T| x.max(-T::MAX).min(T::MAX);
    Aabb {
        min: b.min.map(clamp),
        max: b.max.map(clamp),
    }
}

/// Builds the scene of `spec` at `limit` in precision `T` and checks every
/// registered accelerator: equal to brute force on the rays and boxes, or,
/// when brute force refuses the scene with [`BuildError::OutOfRange`]
/// (or [`BuildError::NonFinitePrimitive`]: a sphere whose bounds overflow),
/// refusing it with the very same error.
///
/// # Errors
/// The first failure, readably.
pub fn check_case_at_limit<T: Real>(
    spec: &SceneSpec,
    limit: &Limit,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<(), String> {
    let scene = limit.place::<T>(&spec.build_f64());
    let landmarks = Landmarks::of(&scene);
    match &scene {
        Scene::Mesh(m) => check_prims(m, landmarks, rays, boxes),
        Scene::Mixed(v) => check_prims(v.as_slice(), landmarks, rays, boxes),
    }
}

fn check_prims<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    landmarks: Landmarks<T>,
    rays: &[(RaySpec, WindowSpec)],
    boxes: &[BoxSpec],
) -> Result<(), String> {
    let brute = match BruteForce::new(prims) {
        Ok(b) => b,
        Err(refusal @ (BuildError::OutOfRange { .. } | BuildError::NonFinitePrimitive { .. })) => {
            return check_refused(prims, &refusal);
        }
        Err(e) => return Err(format!("brute force refused a finite scene: {e}")),
    };
    let resolved = resolve(prims, landmarks, rays, boxes)?;
    let rays: Vec<Ray<T>> = resolved.rays.iter().map(clamped_ray).collect();
    let regions: Vec<Aabb<T>> = resolved.regions.iter().map(clamped_box).collect();
    let expected = Expected::compute(&brute, &rays, &regions)?;
    for entry in accelerators::<T, P>() {
        let acc = (entry.build)(prims).map_err(|e| {
            format!(
                "{} ({}): refused a scene brute force accepts: {e}",
                entry.name,
                T::NAME
            )
        })?;
        check_accelerator(entry.name, &*acc, prims, &rays, &regions, &expected)?;
    }
    Ok(())
}

/// Every registered accelerator refuses the scene with `refusal`.
fn check_refused<T: Real, P: PrimitiveSet<T> + ?Sized + 'static>(
    prims: &P,
    refusal: &BuildError,
) -> Result<(), String> {
    for entry in accelerators::<T, P>() {
        match (entry.build)(prims) {
            Err(e) if e == *refusal => {}
            Err(e) => {
                return Err(format!(
                    "{} ({}): refused with {e:?}, brute force with {refusal:?}",
                    entry.name,
                    T::NAME
                ));
            }
            Ok(_) => {
                return Err(format!(
                    "{} ({}): built a scene brute force refuses ({refusal})",
                    entry.name,
                    T::NAME
                ));
            }
        }
    }
    Ok(())
}
