//! Spheres: a robust quadratic ray test and an exact sphere–box test.

use crate::{Aabb, PreparedRay, PrimHit, Primitive, Real, Vec3};

/// A sphere given by its center and radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere<T> {
    /// Center.
    pub center: Vec3<T>,
    /// Radius (non-negative).
    pub radius: T,
}

impl<T: Real> Sphere<T> {
    /// A sphere; a negative or non-finite radius gives non-finite bounds,
    /// which every accelerator's build refuses.
    #[must_use]
    pub const fn new(center: Vec3<T>, radius: T) -> Self {
        Self { center, radius }
    }
}

impl<T: Real> Primitive<T> for Sphere<T> {
    /// The box `center ± radius`, widened by rounding so that it holds every
    /// hit point the ray test can report.
    #[inline]
    fn bounds(&self) -> Aabb<T> {
        if !(self.radius >= T::ZERO) || !self.radius.is_finite() || !self.center.is_finite() {
            // Refused at build time as non-finite.
            return Aabb {
                min: Vec3::splat(T::NEG_INFINITY),
                max: Vec3::splat(T::INFINITY),
            };
        }
        let r = Vec3::splat(self.radius);
        let lo = self.center - r;
        let hi = self.center + r;
        let slack = T::gamma(4) * (lo.abs().max(hi.abs()).max_component());
        Aabb {
            min: lo - Vec3::splat(slack),
            max: hi + Vec3::splat(slack),
        }
    }

    /// Solves `|o + t·d − c|² = r²` in [`Real::Wide`] with the numerically
    /// stable form of pbrt-v4 (the discriminant from the distance of the
    /// closest approach, the roots from `q`), and returns the first root in
    /// `[t_min, t_max]`. `u = φ/2π`, `v = θ/π` of the hit point about the center.
    fn intersect(&self, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        let w = |v: Vec3<T>| v.map(T::to_wide);
        let o = w(ray.ray.origin - self.center);
        let d = w(ray.ray.direction);
        let r = self.radius.to_wide();
        let zero = <T::Wide as Real>::ZERO;
        let a = d.length_squared();
        let b = o.dot(d); // half of the usual b
        let c = o.length_squared() - r * r;
        // Closest approach of the line to the center, for a discriminant free of
        // the cancellation in b² − ac.
        let f = o - d * (b / a);
        let dist = f.length();
        let disc = a * (r + dist) * (r - dist);
        if disc < zero {
            return None;
        }
        let root = disc.sqrt();
        let q = if b < zero { -b + root } else { -b - root };
        let (t0, t1) = if q == zero {
            // Only when b = 0 and the ray is tangent: a double root at the closest approach.
            (-b / a, -b / a)
        } else {
            let (x, y) = (q / a, c / q);
            if x <= y { (x, y) } else { (y, x) }
        };
        let t_min = ray.ray.t_min;
        let pick = |tw: T::Wide| T::hit_parameter(tw, t_min, t_max);
        let (t, tw) = match pick(t0) {
            Some(t) => (t, t0),
            None => (pick(t1)?, t1),
        };
        let p = o + d * tw;
        let two_pi = <T::Wide as Real>::from_f64(core::f64::consts::TAU);
        let pi = <T::Wide as Real>::from_f64(core::f64::consts::PI);
        let mut phi = p.y.atan2(p.x);
        if phi < zero {
            phi += two_pi;
        }
        let cos_theta = if r > zero {
            (p.z / r)
                .max(-<T::Wide as Real>::ONE)
                .min(<T::Wide as Real>::ONE)
        } else {
            <T::Wide as Real>::ONE
        };
        Some(PrimHit {
            t,
            u: T::from_wide(phi / two_pi),
            v: T::from_wide(cos_theta.acos() / pi),
        })
    }

    /// Exact: the squared distance from the center to the box is at most `r²`
    /// (Arvo 1990), in [`Real::Wide`] with a rounding allowance.
    fn overlaps_box(&self, b: &Aabb<T>) -> bool {
        if b.is_empty() {
            return false;
        }
        let mut dist2 = <T::Wide as Real>::ZERO;
        let mut scale = <T::Wide as Real>::ZERO;
        for axis in 0..3 {
            let c = self.center[axis].to_wide();
            let (lo, hi) = (b.min[axis].to_wide(), b.max[axis].to_wide());
            let gap = if c < lo {
                lo - c
            } else if c > hi {
                c - hi
            } else {
                <T::Wide as Real>::ZERO
            };
            dist2 += gap * gap;
            scale = scale.max(c.abs()).max(lo.abs()).max(hi.abs());
        }
        let r = self.radius.to_wide();
        // Rounding of the gaps is relative to the coordinates, not the gaps.
        let slack = <T::Wide as Real>::gamma(8) * scale;
        let reach = r + slack;
        dist2 <= reach * reach
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Ray;

    fn check<T: Real>() {
        let s = Sphere::new(Vec3::new(T::ONE, T::ZERO, T::ZERO), T::from_f64(2.0));
        let r = Ray::new(
            Vec3::new(T::from_f64(-5.0), T::ZERO, T::ZERO),
            Vec3::new(T::from_f64(2.0), T::ZERO, T::ZERO),
        )
        .unwrap();
        let pr = PreparedRay::new(r);
        let h = s.intersect(&pr, T::INFINITY).unwrap();
        assert_eq!(h.t, T::from_f64(2.0)); // x = -5 + 2·2 = -1 = 1 − 2
        // From inside, the far root.
        let r = Ray::new(
            Vec3::new(T::ONE, T::ZERO, T::ZERO),
            Vec3::new(T::ZERO, T::ZERO, T::ONE),
        )
        .unwrap();
        let h = s.intersect(&PreparedRay::new(r), T::INFINITY).unwrap();
        assert_eq!(h.t, T::from_f64(2.0));
        assert_eq!(h.v, T::ZERO); // the pole
        // Missing by a little.
        let r = Ray::new(
            Vec3::new(T::from_f64(-5.0), T::from_f64(2.001), T::ZERO),
            Vec3::new(T::ONE, T::ZERO, T::ZERO),
        )
        .unwrap();
        assert!(s.intersect(&PreparedRay::new(r), T::INFINITY).is_none());
    }

    #[test]
    fn roots_in_f32_and_f64() {
        check::<f32>();
        check::<f64>();
    }

    #[test]
    fn box_overlap_is_exact_at_the_corner() {
        let s = Sphere::new(Vec3::new(0.0f64, 0.0, 0.0), 1.0);
        let d = 1.0 / 3.0f64.sqrt();
        let touching = Aabb::new(Vec3::splat(d * 0.999_999), Vec3::splat(5.0));
        assert!(s.overlaps_box(&touching));
        let apart = Aabb::new(Vec3::splat(d * 1.001), Vec3::splat(5.0));
        assert!(!s.overlaps_box(&apart));
        // Its bounds overlap that box: the exact test is tighter.
        assert!(s.bounds().overlaps(&apart));
    }

    #[test]
    fn invalid_radius_gives_non_finite_bounds() {
        let s = Sphere::new(Vec3::new(0.0f32, 0.0, 0.0), -1.0);
        assert!(!s.bounds().is_finite());
        let s = Sphere::new(Vec3::new(0.0f32, 0.0, 0.0), f32::NAN);
        assert!(!s.bounds().is_finite());
    }

    #[test]
    fn clipped_bounds_is_the_box_intersection_default() {
        let s = Sphere::new(Vec3::new(0.0f64, 0.0, 0.0), 1.0);
        let b = Aabb::new(Vec3::new(0.5, -2.0, -0.25), Vec3::new(3.0, 0.0, 0.75));
        let c = s.clipped_bounds(&b);
        assert_eq!(c, s.bounds().intersection(&b));
        // It holds the sphere's points inside the box, e.g. (1, 0, 0) and (0.6, -0.8, 0).
        assert!(c.contains_point(Vec3::new(1.0, 0.0, 0.0)));
        assert!(c.contains_point(Vec3::new(0.6, -0.8, 0.0)));
        let far = Aabb::new(Vec3::splat(2.0), Vec3::splat(3.0));
        assert!(s.clipped_bounds(&far).is_empty());
    }
}
