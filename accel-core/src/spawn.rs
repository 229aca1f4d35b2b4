//! Where secondary rays start: the spawn-offset dial.
//!
//! A shadow or ambient-occlusion ray leaves a hit point. Started exactly at
//! the computed point, it can hit the triangle it leaves at `t ≈ 0` (a
//! *self-intersection*: shadow acne), because the point is rounded and lies a
//! little below the surface half the time. Two remedies:
//!
//! - [`SpawnOffset::Fixed`]: the textbook one. Compute the point as
//!   `o + t·d` and push it a fixed distance `ε` along the normal. Cheap and
//!   simple, but no one `ε` fits every scene: too small for coordinates far
//!   from the origin (where one ulp of `f32` exceeds it, and the point's
//!   error grows with `t`), too large near small features (the ray skips
//!   occluders closer than `ε`: lost contact shadows).
//! - [`SpawnOffset::ErrorBound`]: pbrt-v4's `OffsetRayOrigin` (Pharr, Jakob &
//!   Humphreys, *Physically Based Rendering*, 4th ed., §6.8.6). Compute the
//!   point from the barycentrics, bound its rounding error per axis by
//!   `gamma(7)·Σ|b_i·p_i|` ([`SurfacePoint::on_triangle`]), add the triangle
//!   test's own accuracy bound ([`test_margin`]: pbrt's test refuses `t`
//!   below its error bound, ours accepts `t = 0`), push the point along the
//!   geometric normal by that bound (`|n|·error`), then round each
//!   coordinate one more float away from the surface. The offset scales
//!   with the coordinates and the triangle's size, is a few ulps of them,
//!   and no secondary ray can hit the triangle it leaves; it costs a few
//!   more operations per spawn.
//!
//! ```
//! use accel_core::spawn::{SpawnOffset, spawn_origin};
//! use accel_core::{Hit, Ray, Vec3};
//!
//! let tri = [Vec3::new(0.0f32, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)];
//! let ray = Ray::new(Vec3::new(0.25f32, 0.25, 0.0), Vec3::new(0.0, 0.0, 1.0))?;
//! let hit = Hit { t: 1.0, prim: 0, u: 0.25, v: 0.25 };
//! let back = Vec3::new(0.0, 0.0, -1.0);
//! let o = spawn_origin(SpawnOffset::ErrorBound, tri, &ray, &hit, back);
//! assert!(o.z < 1.0 && o.z > 0.999_99); // a few ulps of the triangle below
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::{Hit, Ray, Real, Vec3};
use core::fmt;

/// How far a secondary ray's origin is pushed off the surface it leaves.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum SpawnOffset<T> {
    /// The point `o + t·d`, moved `ε` (in scene units) along the normal.
    Fixed(T),
    /// The point from the barycentrics, moved by its rounding-error bound
    /// along the normal and then one float further (pbrt-v4); the default.
    #[default]
    ErrorBound,
}

impl<T: Real> fmt::Display for SpawnOffset<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Fixed(eps) => write!(f, "epsilon {:e}", eps.to_f64()),
            Self::ErrorBound => f.write_str("error-bound"),
        }
    }
}

/// A point with a per-axis bound on its rounding error: the true surface
/// point lies in `point ± error`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint<T> {
    /// The computed point.
    pub point: Vec3<T>,
    /// Absolute error bound per axis.
    pub error: Vec3<T>,
}

impl<T: Real> SurfacePoint<T> {
    /// The point `b0·p0 + b1·p1 + b2·p2` with `b1 = u`, `b2 = v`,
    /// `b0 = 1 − u − v`, and pbrt-v4's bound `gamma(7)·(|b0·p0| + |b1·p1| + |b2·p2|)`
    /// on the rounding of the interpolation, computed in `T`.
    #[inline]
    #[must_use]
    pub fn on_triangle(p: [Vec3<T>; 3], u: T, v: T) -> Self {
        let b0 = T::ONE - u - v;
        let (a, b, c) = (p[0] * b0, p[1] * u, p[2] * v);
        let point = a + b + c;
        let error = (a.abs() + b.abs() + c.abs()) * T::gamma(7);
        Self { point, error }
    }
}

/// The unit geometric normal `(p1 − p0) × (p2 − p0)` normalised, or `None`
/// for a degenerate triangle (zero, NaN or infinite length).
///
/// Computed in [`Real::Wide`] and rounded once: in `f32` the cross product
/// of edges longer than about 1e19 would overflow (see: issue 32, item 1),
/// and in `f64` edges within [`Real::LIMIT`] leave it finite.
#[inline]
#[must_use]
pub fn geometric_normal<T: Real>(p: [Vec3<T>; 3]) -> Option<Vec3<T>> {
    let q: [Vec3<T::Wide>; 3] = p.map(Vec3::cast);
    let n = (q[1] - q[0]).cross(q[2] - q[0]);
    let len = n.length();
    if !(len > T::Wide::ZERO && len.is_finite()) {
        return None;
    }
    let unit: Vec3<T> = (n / len).cast();
    (unit != Vec3::ZERO).then_some(unit)
}

/// pbrt-v4's `OffsetRayOrigin`: the point moved along `n` (towards the side
/// `w` leaves on) by `|n|·error`, then every coordinate on which `n` has a
/// component rounded one float further away (also where the error is zero,
/// see the comment inside). `n` should have unit length; the result is on the
/// `w` side of the plane through `p` whatever the rounding.
#[inline]
#[must_use]
pub fn offset_ray_origin<T: Real>(p: &SurfacePoint<T>, n: Vec3<T>, w: Vec3<T>) -> Vec3<T> {
    let d = n.abs().dot(p.error);
    let side = if w.dot(n) < T::ZERO { -n } else { n };
    let mut po = p.point + side * d;
    // pbrt-v4 rounds away only where the offset is non-zero, and relies on
    // its triangle test refusing `t` at or below an error bound. Ours accepts
    // `t = 0`, so the point moves one float along every axis the normal has
    // a component on, even when the bound is zero: a floor at exactly
    // `z = 0` has an exact point and no error, yet a ray from it would hit
    // the floor at `t = 0`.
    for axis in 0..3 {
        if side[axis] > T::ZERO {
            po[axis] = po[axis].next_up();
        } else if side[axis] < T::ZERO {
            po[axis] = po[axis].next_down();
        }
    }
    po
}

/// How far the triangle test itself may misplace a hit near `point`: the
/// [`crate::Primitive`] contract's `gamma(16)` of the distance from the ray
/// origin to the triangle's vertices, doubled (the contract bounds the
/// L∞ distance; the offset is Euclidean along the normal).
///
/// pbrt-v4's triangle test refuses any `t` at or below its own error bound,
/// so pbrt's offset only covers the point's rounding. The workspace's
/// watertight test accepts `t = 0` and computes `t` from sheared coordinates
/// whose rounding scales with the triangle's extent, not the point's: a ray
/// leaving a 24-unit floor at `z = 0` from one float above it, upwards at
/// 68°, was measured hitting the floor at `t = 1e-7`. An origin farther from
/// the plane than this margin cannot be reported as a hit of its own
/// triangle by any test that keeps the contract.
#[inline]
#[must_use]
pub fn test_margin<T: Real>(tri: [Vec3<T>; 3], point: Vec3<T>) -> T {
    let reach = (tri[0] - point)
        .abs()
        .max((tri[1] - point).abs())
        .max((tri[2] - point).abs())
        .max_component();
    T::gamma(32) * reach
}

/// The origin of a secondary ray leaving `hit` (of `ray` with triangle `tri`)
/// in direction `w`, by `mode`.
///
/// A degenerate triangle has no normal: its point is then moved along `w`
/// instead (by `ε`, or by the error bound's length).
#[inline]
#[must_use]
pub fn spawn_origin<T: Real>(
    mode: SpawnOffset<T>,
    tri: [Vec3<T>; 3],
    ray: &Ray<T>,
    hit: &Hit<T>,
    w: Vec3<T>,
) -> Vec3<T> {
    let n = geometric_normal(tri);
    match mode {
        SpawnOffset::Fixed(eps) => {
            let p = ray.origin + ray.direction * hit.t;
            let n = n.unwrap_or_else(|| w.normalized());
            let side = if w.dot(n) < T::ZERO { -eps } else { eps };
            p + n * side
        }
        SpawnOffset::ErrorBound => {
            let mut sp = SurfacePoint::on_triangle(tri, hit.u, hit.v);
            sp.error += Vec3::splat(test_margin(tri, sp.point));
            let n = n.unwrap_or_else(|| w.normalized());
            offset_ray_origin(&sp, n, w)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::PreparedRay;
    use crate::triangle::intersect_triangle;
    use crate::triangle::tests::{Rng, v};

    #[test]
    fn an_exact_point_on_an_axis_plane_still_leaves_it() {
        // A floor at z = 0: the interpolated point is exact (zero error), so
        // the offset is zero; the rounding step must still lift it.
        let floor = [
            v::<f32>(-12.0, -12.0, 0.0),
            v(12.0, 12.0, 0.0),
            v(-12.0, 12.0, 0.0),
        ];
        let ray = Ray::new(v::<f32>(0.8, -7.6, 3.3), v(-11.1, 17.5, -3.3)).unwrap();
        let pr = PreparedRay::new(ray);
        let h = intersect_triangle(&pr, floor[0], floor[1], floor[2], f32::INFINITY).unwrap();
        let sp = SurfacePoint::on_triangle(floor, h.u, h.v);
        assert_eq!(sp.error.z, 0.0, "premise: an exact z");
        let up = v::<f32>(0.0, 0.0, 1.0);
        let o = spawn_origin(SpawnOffset::ErrorBound, floor, &ray, &Hit::new(0, h), up);
        assert!(o.z > 0.0);
        // Straight up, and at the angle measured to hit the floor at
        // t = 1e-7 from one float above it (x dominant: the sheared
        // coordinates round with the floor's extent).
        for w in [up, v(0.8089157, -0.4491348, 0.37938556)] {
            let sec = PreparedRay::new(Ray::new(o, w).unwrap());
            let again = intersect_triangle(&sec, floor[0], floor[1], floor[2], f32::INFINITY);
            assert!(again.is_none(), "{w:?}: {again:?}");
        }
    }

    #[test]
    fn the_error_bound_grows_with_the_coordinates() {
        let near = [v::<f32>(0.0, 0.0, 1.0), v(1.0, 0.0, 1.0), v(0.0, 1.0, 1.0)];
        let far = near.map(|p| p + Vec3::splat(1e4));
        let a = SurfacePoint::on_triangle(near, 0.25, 0.25);
        let b = SurfacePoint::on_triangle(far, 0.25, 0.25);
        assert!(b.error.x > a.error.x * 1e3, "{a:?} {b:?}");
        // The bound covers at least one ulp of the point.
        let ulp = b.point.x.next_up() - b.point.x;
        assert!(b.error.x >= ulp * 0.5, "{} vs ulp {ulp}", b.error.x);
    }

    #[test]
    fn offset_origins_lie_on_the_side_of_w() {
        let tri = [v::<f32>(0.0, 0.0, 1.0), v(1.0, 0.0, 1.0), v(0.0, 1.0, 1.0)];
        let sp = SurfacePoint::on_triangle(tri, 0.25, 0.25);
        let n = geometric_normal(tri).unwrap();
        let up = offset_ray_origin(&sp, n, v(0.0, 0.0, 1.0));
        let down = offset_ray_origin(&sp, n, v(0.0, 0.0, -1.0));
        assert!(up.z > 1.0 && down.z < 1.0, "{up:?} {down:?}");
        // A few ulps, not a visible distance.
        assert!(up.z - 1.0 < 1e-5 && 1.0 - down.z < 1e-5);
        assert_eq!(geometric_normal([tri[0], tri[0], tri[1]]), None);
    }

    /// Spawns a ray off random hits on big, tilted triangles far from the
    /// origin and counts those that hit their own triangle again.
    fn self_hits<T: Real>(mode: SpawnOffset<T>, offset: f64, trials: u32) -> u32 {
        spawned::<T>(mode, offset, 50.0, trials).0
    }

    /// [`self_hits`] with triangles of radius `size`: the self-hits, and the
    /// secondary rays tested (an origin past `T::LIMIT` is refused).
    fn spawned<T: Real>(mode: SpawnOffset<T>, offset: f64, size: f64, trials: u32) -> (u32, u32) {
        let mut rng = Rng(11);
        let (mut count, mut tested) = (0, 0);
        for _ in 0..trials {
            let c = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            ) * offset;
            let tri: [Vec3<T>; 3] = [0; 3].map(|_| (c + rng.unit_vector() * size).cast());
            let Some(n) = geometric_normal(tri) else {
                continue;
            };
            let target = (tri[0].cast::<f64>() + tri[1].cast() + tri[2].cast()) * (1.0 / 3.0);
            let origin = target + rng.unit_vector() * (4.0 * size);
            let Ok(ray) = Ray::new(origin.cast::<T>(), (target - origin).cast()) else {
                continue;
            };
            let pr = PreparedRay::new(ray);
            let Some(h) = intersect_triangle(&pr, tri[0], tri[1], tri[2], T::INFINITY) else {
                continue;
            };
            let hit = Hit::new(0, h);
            // Leave on the side the ray came from, in a random direction.
            let facing = if n.dot(ray.direction) < T::ZERO {
                n
            } else {
                -n
            };
            let mut w = rng.unit_vector().cast::<T>();
            if w.dot(facing) < T::ZERO {
                w = -w;
            }
            let o = spawn_origin(mode, tri, &ray, &hit, w);
            assert!(o.is_finite(), "spawned {o:?} off {tri:?}");
            let Ok(sec) = Ray::new(o, w) else { continue };
            let sec = PreparedRay::new(sec);
            tested += 1;
            count +=
                u32::from(intersect_triangle(&sec, tri[0], tri[1], tri[2], T::INFINITY).is_some());
        }
        (count, tested)
    }

    /// See: issue 32, item 1. Triangles as large as the accepted range
    /// ([`Real::LIMIT`]) and against its edge: every spawned origin is
    /// finite and none hits its own triangle again, in both precisions.
    #[test]
    fn the_error_bound_holds_at_the_limit_of_the_range() {
        fn check<T: Real>() {
            let limit = T::LIMIT.to_f64();
            for (offset, size) in [(0.0, 0.2), (0.5, 0.2), (0.9, 0.05), (0.999, 1e-4)] {
                let (hits, tested) =
                    spawned::<T>(SpawnOffset::ErrorBound, offset * limit, size * limit, 2000);
                assert!(
                    tested > 500,
                    "premise: {tested} rays spawned at {offset}, {size}"
                );
                assert_eq!(hits, 0, "{} at {offset}·LIMIT, size {size}·LIMIT", T::NAME);
            }
        }
        check::<f32>();
        check::<f64>();
    }

    #[test]
    fn the_error_bound_never_self_intersects_where_a_fixed_epsilon_does() {
        for offset in [1.0, 1e4, 1e5] {
            let fixed = self_hits::<f32>(SpawnOffset::Fixed(1e-4), offset, 3000);
            let bound = self_hits::<f32>(SpawnOffset::ErrorBound, offset, 3000);
            assert_eq!(
                bound, 0,
                "f32 at {offset}: error-bound spawn self-intersected"
            );
            if offset >= 1e4 {
                assert!(
                    fixed > 0,
                    "premise: epsilon 1e-4 self-intersects at {offset}"
                );
            }
            let bound64 = self_hits::<f64>(SpawnOffset::ErrorBound, offset * 1e9, 1000);
            assert_eq!(bound64, 0, "f64 at {offset}e9");
        }
        // Without any offset, the rounded point is below the surface about
        // half the time: the acne the offsets exist for.
        assert!(self_hits::<f32>(SpawnOffset::Fixed(0.0), 1e3, 1000) > 100);
    }
}
