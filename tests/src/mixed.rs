//! A user-defined primitive: triangles and spheres in one set.
//!
//! Users can bring their own primitive ([`accel_core::Primitive`]); this enum
//! is such a user type, so the suites exercise accelerators through the
//! generic `&[P]` path as well as through [`accel_core::TriangleMesh`].

use accel_core::{Aabb, PreparedRay, PrimHit, Primitive, Real, Sphere, Triangle, Vec3};

/// A triangle or a sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mixed<T> {
    /// A triangle owning its vertices (exact triangle–box overlap test).
    Tri(Triangle<T>),
    /// A sphere (exact sphere–box overlap test).
    Ball(Sphere<T>),
}

impl<T: Real> Mixed<T> {
    /// A triangle from three vertices.
    #[must_use]
    pub fn tri(a: Vec3<T>, b: Vec3<T>, c: Vec3<T>) -> Self {
        Self::Tri(Triangle {
            vertices: [a, b, c],
        })
    }

    /// A sphere from its center and radius.
    #[must_use]
    pub fn ball(center: Vec3<T>, radius: T) -> Self {
        Self::Ball(Sphere::new(center, radius))
    }

    /// The same primitive in another precision (rounding to nearest).
    #[must_use]
    pub fn cast<U: Real>(&self) -> Mixed<U> {
        match self {
            Self::Tri(t) => Mixed::tri(
                t.vertices[0].cast(),
                t.vertices[1].cast(),
                t.vertices[2].cast(),
            ),
            Self::Ball(s) => Mixed::ball(s.center.cast(), U::from_f64(s.radius.to_f64())),
        }
    }
}

impl<T: Real> Primitive<T> for Mixed<T> {
    #[inline]
    fn bounds(&self) -> Aabb<T> {
        match self {
            Self::Tri(t) => t.bounds(),
            Self::Ball(s) => s.bounds(),
        }
    }

    #[inline]
    fn intersect(&self, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        match self {
            Self::Tri(t) => t.intersect(ray, t_max),
            Self::Ball(s) => s.intersect(ray, t_max),
        }
    }

    #[inline]
    fn overlaps_box(&self, b: &Aabb<T>) -> bool {
        match self {
            Self::Tri(t) => t.overlaps_box(b),
            Self::Ball(s) => s.overlaps_box(b),
        }
    }
}
