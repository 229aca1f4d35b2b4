//! Rays, their validation, and the per-ray constants the queries share.

use crate::{Real, Vec3};

/// Why a query was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum QueryError {
    /// The ray origin has a NaN or infinite component.
    #[error("ray origin is not finite")]
    NonFiniteOrigin,
    /// The ray origin is finite but lies beyond `±T::LIMIT`
    /// ([`Real::LIMIT`]), where the accelerators' arithmetic could overflow.
    #[error(
        "ray origin is beyond ±{} on {}, the largest {precision} coordinate the accelerators \
         accept",
        limit_text(precision),
        ["x", "y", "z"][*axis % 3]
    )]
    OriginOutOfRange {
        /// The precision (`"f32"` or `"f64"`).
        precision: &'static str,
        /// The first axis beyond the limit (0, 1, 2 for x, y, z).
        axis: usize,
    },
    /// The ray direction has a NaN or infinite component.
    #[error("ray direction is not finite")]
    NonFiniteDirection,
    /// The ray direction is the zero vector (with either sign of zero).
    #[error("ray direction is zero")]
    ZeroDirection,
    /// `t_min` or `t_max` is NaN.
    #[error("ray interval bound is NaN")]
    NanInterval,
    /// A region query box has a NaN or infinite corner.
    #[error("query region is not finite")]
    NonFiniteRegion,
}

/// [`Real::LIMIT`] of the precision named `precision`, as text.
fn limit_text(precision: &str) -> String {
    if precision == "f32" {
        format!("{:e}", f32::LIMIT)
    } else {
        format!("{:e}", f64::LIMIT)
    }
}

/// A ray `origin + t·direction` restricted to `t ∈ [t_min, t_max]`.
///
/// The direction may have any non-zero length (`t` is measured in units of it)
/// and components of either sign of zero. `t_max` may be `+∞`. An interval
/// with `t_min > t_max` is empty: every query answers "no hit" for it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray<T> {
    /// Where the ray starts (at `t = 0`).
    pub origin: Vec3<T>,
    /// Direction; not normalised.
    pub direction: Vec3<T>,
    /// Smallest accepted hit parameter (inclusive).
    pub t_min: T,
    /// Largest accepted hit parameter (inclusive).
    pub t_max: T,
}

impl<T: Real> Ray<T> {
    /// A ray over `[0, +∞]`, validated.
    ///
    /// # Errors
    /// [`QueryError`] for a non-finite origin or direction, or a zero direction.
    pub fn new(origin: Vec3<T>, direction: Vec3<T>) -> Result<Self, QueryError> {
        Self::with_interval(origin, direction, T::ZERO, T::INFINITY)
    }

    /// A ray over `[t_min, t_max]`, validated.
    ///
    /// # Errors
    /// [`QueryError`] as [`Ray::validate`] reports.
    pub fn with_interval(
        origin: Vec3<T>,
        direction: Vec3<T>,
        t_min: T,
        t_max: T,
    ) -> Result<Self, QueryError> {
        let r = Self {
            origin,
            direction,
            t_min,
            t_max,
        };
        r.validate()?;
        Ok(r)
    }

    /// Checks the ray: every accelerator calls this before answering.
    ///
    /// # Errors
    /// [`QueryError::NonFiniteOrigin`], [`QueryError::OriginOutOfRange`],
    /// [`QueryError::NonFiniteDirection`], [`QueryError::ZeroDirection`] or
    /// [`QueryError::NanInterval`].
    #[inline]
    pub fn validate(&self) -> Result<(), QueryError> {
        if self.is_valid() {
            Ok(())
        } else {
            self.check_one_by_one()
        }
    }

    /// [`Ray::validate`]'s checks one by one, in order, naming the first
    /// that fails.
    #[cold]
    fn check_one_by_one(&self) -> Result<(), QueryError> {
        if !self.origin.is_finite() {
            return Err(QueryError::NonFiniteOrigin);
        }
        let o = self.origin.abs();
        if !(o.x <= T::LIMIT && o.y <= T::LIMIT && o.z <= T::LIMIT) {
            return Err(QueryError::OriginOutOfRange {
                precision: T::NAME,
                axis: (0..3).find(|&a| !(o[a] <= T::LIMIT)).unwrap_or(0),
            });
        }
        if !self.direction.is_finite() {
            return Err(QueryError::NonFiniteDirection);
        }
        if self.direction == Vec3::ZERO {
            return Err(QueryError::ZeroDirection);
        }
        if self.t_min.is_nan() || self.t_max.is_nan() {
            return Err(QueryError::NanInterval);
        }
        Ok(())
    }

    /// Whether [`Ray::validate`] accepts the ray: every check at once,
    /// without a branch (the common case's path; `validate` then names the
    /// check that fails). An origin within [`Real::LIMIT`] is finite.
    #[inline]
    #[must_use]
    pub fn is_valid(&self) -> bool {
        let (o, d) = (self.origin.abs(), self.direction.abs());
        let (limit, zero) = (T::LIMIT, T::ZERO);
        (o.x <= limit)
            & (o.y <= limit)
            & (o.z <= limit)
            & (d.x < T::INFINITY)
            & (d.y < T::INFINITY)
            & (d.z < T::INFINITY)
            & ((d.x > zero) | (d.y > zero) | (d.z > zero))
            & !self.t_min.is_nan()
            & !self.t_max.is_nan()
    }

    /// True when `[t_min, t_max]` holds no value.
    #[inline]
    #[must_use]
    pub fn is_empty_interval(&self) -> bool {
        !(self.t_min <= self.t_max)
    }

    /// Whether the directions of `self` and `other` lie within the angle
    /// whose cosine is `cos` (an angle below 90°: directions 90° or more
    /// apart never do): the test that groups rays into packets of a
    /// bundle query. Computed in `f64`; for a direction whose squared length
    /// overflows or vanishes there the answer may be wrong, so it may decide
    /// speed, never an answer.
    #[inline]
    #[must_use]
    pub fn heads_within(&self, other: &Ray<T>, cos: f64) -> bool {
        let (a, b) = (self.direction.cast::<f64>(), other.direction.cast::<f64>());
        let dot = a.dot(b);
        // Bitwise, not short-circuit: rays heading every way (diffuse
        // bounces) would make the branch a coin toss.
        (dot > 0.0) & (dot * dot >= cos * cos * a.dot(a) * b.dot(b))
    }

    /// How many of `rays` head within the angle of `cos` of `self`
    /// ([`Ray::heads_within`]): a bundle query's first look at whether its
    /// rays can make packets at all.
    #[must_use]
    pub fn count_heading_with(&self, rays: &[Ray<T>], cos: f64) -> usize {
        rays.iter().filter(|r| self.heads_within(r, cos)).count()
    }

    /// The point at parameter `t`.
    #[inline]
    #[must_use]
    pub fn at(&self, t: T) -> Vec3<T> {
        self.origin + self.direction * t
    }

    /// Converts to another precision through `f64`.
    #[must_use]
    pub fn cast<U: Real>(&self) -> Ray<U> {
        Ray {
            origin: self.origin.cast(),
            direction: self.direction.cast(),
            t_min: U::from_f64(self.t_min.to_f64()),
            t_max: U::from_f64(self.t_max.to_f64()),
        }
    }
}

/// A validated ray with the constants that every primitive test reuses:
/// the reciprocal direction and the shear of the watertight triangle test
/// (Woop, Benthin & Wald 2013: the axis `kz` of the largest direction
/// component, the two others `kx`, `ky`, and `S = (dx/dz, dy/dz, 1/dz)`,
/// in `f64`).
#[derive(Clone, Copy, Debug)]
pub struct PreparedRay<T> {
    /// The ray.
    pub ray: Ray<T>,
    /// `1 / direction`, `±∞` for `±0` components.
    pub inv_dir: Vec3<T>,
    /// Permuted axes `[kx, ky, kz]`, `kz` the dominant direction axis.
    pub axes: [usize; 3],
    /// Shear constants `(Sx, Sy, Sz)`, in `f64` whatever `T` (the triangle
    /// test runs in `f64`): for an `f32` ray each is the exact quotient of
    /// its components rounded once to `f64`, not to `f32`, whose rounding
    /// tilts the sheared ray enough to miss a triangle the exact ray
    /// passes through by 1e-10 of its edge functions' scale.
    pub shear: Vec3<f64>,
}

impl<T: Real> PreparedRay<T> {
    /// Prepares a ray that has passed [`Ray::validate`].
    #[inline]
    #[must_use]
    pub fn new(ray: Ray<T>) -> Self {
        Self::with_reciprocal(ray, Self::reciprocal(ray.direction))
    }

    /// `1 / d` componentwise, as [`PreparedRay::inv_dir`] holds it.
    #[inline]
    #[must_use]
    pub fn reciprocal(d: Vec3<T>) -> Vec3<T> {
        Vec3::new(T::ONE / d.x, T::ONE / d.y, T::ONE / d.z)
    }

    /// [`PreparedRay::new`] for a caller that has already computed
    /// `inv_dir = PreparedRay::reciprocal(ray.direction)`.
    #[inline]
    #[must_use]
    pub(crate) fn with_reciprocal(ray: Ray<T>, inv_dir: Vec3<T>) -> Self {
        debug_assert!(ray.validate().is_ok());
        debug_assert!(
            (0..3).all(|a| inv_dir[a].to_bits_u64() == (T::ONE / ray.direction[a]).to_bits_u64())
        );
        let d = ray.direction;
        let kz = d.abs().max_dimension();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Arrays, whose index is an address, where `Vec3`'s is a match.
        let w = d.to_array().map(T::to_f64);
        // Swapping keeps the winding (and so the sign convention) of the edge functions.
        if w[kz] < 0.0 {
            core::mem::swap(&mut kx, &mut ky);
        }
        let shear = Vec3::new(w[kx] / w[kz], w[ky] / w[kz], 1.0 / w[kz]);
        Self {
            ray,
            inv_dir,
            axes: [kx, ky, kz],
            shear,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heading_compares_angles_not_lengths() {
        let o = Vec3::new(1.0f32, 2.0, 3.0);
        let ray = |d: Vec3<f32>| Ray::new(o, d).unwrap();
        let x = ray(Vec3::new(1.0, 0.0, 0.0));
        // 20° and 30° from x, of other lengths: cos 20° > 0.9 > cos 30°.
        let (c20, s20) = (20f32.to_radians().cos(), 20f32.to_radians().sin());
        let (c30, s30) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
        assert!(x.heads_within(&ray(Vec3::new(c20, s20, 0.0) * 1e30), 0.9));
        assert!(!x.heads_within(&ray(Vec3::new(c30, 0.0, s30) * 1e-30), 0.9));
        assert!(x.heads_within(&x, 1.0));
        let y = ray(Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(x.count_heading_with(&[x, y, x, y, y], 0.9), 2);
        // Directions 90° or more apart never are.
        assert!(!x.heads_within(&ray(Vec3::new(-1.0, 0.0, 0.0)), -1.0));
    }

    #[test]
    fn bad_rays_get_typed_errors() {
        let o = Vec3::new(0.0f32, 0.0, 0.0);
        let d = Vec3::new(0.0f32, 0.0, 1.0);
        assert_eq!(
            Ray::new(Vec3::new(f32::NAN, 0.0, 0.0), d),
            Err(QueryError::NonFiniteOrigin)
        );
        assert_eq!(
            Ray::new(o, Vec3::new(0.0, f32::INFINITY, 0.0)),
            Err(QueryError::NonFiniteDirection)
        );
        assert_eq!(
            Ray::new(o, Vec3::new(-0.0, 0.0, -0.0)),
            Err(QueryError::ZeroDirection)
        );
        assert_eq!(
            Ray::with_interval(o, d, f32::NAN, 1.0),
            Err(QueryError::NanInterval)
        );
        // An empty interval is valid and simply holds nothing.
        let r = Ray::with_interval(o, d, 2.0, 1.0).unwrap();
        assert!(r.is_empty_interval());
        assert!(!Ray::new(o, d).unwrap().is_empty_interval());
    }

    /// A value that may make a ray invalid, or keep it valid: special,
    /// huge, tiny or zero.
    fn special() -> impl proptest::strategy::Strategy<Value = f64> {
        use proptest::prelude::*;
        prop_oneof![
            Just(0.0),
            Just(-0.0),
            Just(f64::NAN),
            Just(f64::INFINITY),
            Just(f64::NEG_INFINITY),
            Just(1e300),
            Just(-1e80),
            Just(1e-310),
        ]
    }

    /// [`Ray::is_valid`] accepts exactly the rays that `validate`'s checks
    /// one by one accept, in `T` (the ray built field by field, so that
    /// invalid rays exist).
    fn same_verdicts<T: Real>(c: &[f64]) {
        let v = |i: usize| {
            Vec3::new(
                T::from_f64(c[i]),
                T::from_f64(c[i + 1]),
                T::from_f64(c[i + 2]),
            )
        };
        let ray = Ray {
            origin: v(0),
            direction: v(3),
            t_min: T::from_f64(c[6]),
            t_max: T::from_f64(c[7]),
        };
        assert_eq!(ray.is_valid(), ray.check_one_by_one().is_ok(), "{ray:?}");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2_000))]
        /// Ordinary fields with up to two of them replaced by special
        /// values (a zero direction needs all three of its components).
        #[test]
        fn the_fast_check_agrees_with_validate(
            mut c in proptest::collection::vec(-1e3..1e3f64, 8),
            swaps in proptest::collection::vec((0..8usize, special()), 0..3),
            zero_direction in proptest::bool::weighted(0.1),
        ) {
            for (i, x) in swaps {
                c[i] = x;
            }
            if zero_direction {
                c[3..6].copy_from_slice(&[0.0, -0.0, 0.0]);
            }
            same_verdicts::<f32>(&c);
            same_verdicts::<f64>(&c);
        }
    }

    #[test]
    fn shear_axes_follow_the_dominant_component() {
        let r = Ray::new(Vec3::ZERO, Vec3::new(0.5f64, -3.0, 1.0)).unwrap();
        let p = PreparedRay::new(r);
        assert_eq!(p.axes[2], 1);
        // Negative dominant component swaps kx and ky.
        assert_eq!(p.axes, [0, 2, 1]);
        assert_eq!(p.shear, Vec3::new(0.5 / -3.0, 1.0 / -3.0, 1.0 / -3.0));
    }
}
