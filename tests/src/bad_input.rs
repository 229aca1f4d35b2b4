//! Bad input: invalid rays and regions (refused with a typed `QueryError`)
//! and non-finite scenes (refused at build with a `BuildError`).

use crate::Mixed;
use crate::scene::{Item, Placement};
use accel_core::{Aabb, QueryError, Ray, Real, Vec3};

/// A non-finite value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Bad {
    /// NaN.
    Nan,
    /// +∞.
    Inf,
    /// −∞.
    NegInf,
}

impl Bad {
    /// The value.
    #[must_use]
    pub fn value<T: Real>(self) -> T {
        match self {
            Self::Nan => T::from_f64(f64::NAN),
            Self::Inf => T::INFINITY,
            Self::NegInf => T::NEG_INFINITY,
        }
    }
}

/// One way of breaking a ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Corruption {
    /// A non-finite origin component.
    Origin(usize, Bad),
    /// A non-finite direction component.
    Direction(usize, Bad),
    /// The zero direction, each component +0 or −0 (`true`: −0).
    ZeroDirection([bool; 3]),
    /// `t_min` = NaN.
    TMinNan,
    /// `t_max` = NaN.
    TMaxNan,
}

/// Applies the corruptions in order.
#[must_use]
pub fn corrupt<T: Real>(ray: Ray<T>, corruptions: &[Corruption]) -> Ray<T> {
    let mut r = ray;
    for c in corruptions {
        match *c {
            Corruption::Origin(a, b) => r.origin[a % 3] = b.value(),
            Corruption::Direction(a, b) => r.direction[a % 3] = b.value(),
            Corruption::ZeroDirection(neg) => {
                r.direction = Vec3::from(neg.map(|n| if n { -T::ZERO } else { T::ZERO }));
            }
            Corruption::TMinNan => r.t_min = Bad::Nan.value(),
            Corruption::TMaxNan => r.t_max = Bad::Nan.value(),
        }
    }
    r
}

/// Every problem the ray has, found field by field (independently of
/// `Ray::validate`): the errors a query may answer with.
#[must_use]
pub fn problems<T: Real>(r: &Ray<T>) -> Vec<QueryError> {
    let finite = |v: Vec3<T>| v.to_array().iter().all(|x| x.is_finite());
    let mut out = Vec::new();
    if !finite(r.origin) {
        out.push(QueryError::NonFiniteOrigin);
    }
    if !finite(r.direction) {
        out.push(QueryError::NonFiniteDirection);
    }
    if r.direction.to_array().iter().all(|&x| x == T::ZERO) {
        out.push(QueryError::ZeroDirection);
    }
    if r.t_min.is_nan() || r.t_max.is_nan() {
        out.push(QueryError::NanInterval);
    }
    out
}

/// A region with one non-finite corner component.
#[must_use]
pub fn bad_region<T: Real>(good: Aabb<T>, upper: bool, axis: usize, bad: Bad) -> Aabb<T> {
    let mut r = good;
    if upper {
        r.max[axis % 3] = bad.value();
    } else {
        r.min[axis % 3] = bad.value();
    }
    r
}

/// What makes one primitive of a mixed scene non-finite.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Poison {
    /// A coordinate (vertex `v % 3`, axis `a % 3`; the center of a sphere)
    /// set to a value.
    Coordinate(usize, usize, f64),
    /// A sphere's radius set to a value (for a triangle: a coordinate of its
    /// first vertex).
    Radius(f64),
}

/// The values poisons use: NaN, ±∞, a negative radius, and 1e39, which is
/// finite in `f64` but overflows `f32`.
pub const POISON_VALUES: [f64; 5] = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1.0, 1e39];

/// A mixed scene in precision `T` with poisons applied to primitives
/// (`index % len`).
#[must_use]
pub fn poisoned<T: Real>(items: &[Item], poisons: &[(usize, Poison)]) -> Vec<Mixed<T>> {
    let place = Placement::IDENTITY;
    let mut v: Vec<Mixed<f64>> = items
        .iter()
        .map(|item| match item {
            Item::Tri(t) => {
                let [a, b, c] = t.map(|p| place.point(p));
                Mixed::tri(a, b, c)
            }
            Item::Ball(c, r) => Mixed::ball(place.point(*c), *r),
        })
        .collect();
    if !v.is_empty() {
        let n = v.len();
        for &(i, p) in poisons {
            match (&mut v[i % n], p) {
                (Mixed::Tri(t), Poison::Coordinate(vx, a, x)) => t.vertices[vx % 3][a % 3] = x,
                (Mixed::Tri(t), Poison::Radius(x)) => t.vertices[0][0] = x,
                (Mixed::Ball(s), Poison::Coordinate(_, a, x)) => s.center[a % 3] = x,
                (Mixed::Ball(s), Poison::Radius(x)) => s.radius = x,
            }
        }
    }
    v.iter().map(Mixed::cast).collect()
}

/// The first primitive that a build must refuse, found from the values
/// (independently of the accelerators' bounds): a non-finite coordinate, or
/// a sphere radius that is negative or not finite.
#[must_use]
pub fn first_non_finite<T: Real>(v: &[Mixed<T>]) -> Option<usize> {
    let finite = |p: &Vec3<T>| p.to_array().iter().all(|x| x.is_finite());
    v.iter().position(|m| match m {
        Mixed::Tri(t) => !t.vertices.iter().all(finite),
        Mixed::Ball(s) => !(finite(&s.center) && s.radius.is_finite() && s.radius >= T::ZERO),
    })
}
