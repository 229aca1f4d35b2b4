//! A three-component vector generic over [`Real`].
//!
//! glam's vectors are concrete (`Vec3`, `DVec3`); the accelerators need one
//! implementation for both precisions, so this small type carries the
//! arithmetic and converts to and from glam at the edges.
//!
//! The `From` conversions to and from glam are for the one glam version this
//! crate depends on (re-exported as [`crate::glam`]): a `glam::Vec3` of
//! another version is another type. Arrays are the version-tolerant path:
//! every glam version converts its vectors to and from `[f32; 3]` /
//! `[f64; 3]` (`to_array`, `from_array`, `From`), and so does [`Vec3`]
//! (`From<[T; 3]>` both ways):
//!
//! ```
//! use accel_core::Vec3;
//!
//! // A vector of whatever glam version the application uses, as an array.
//! let theirs: [f32; 3] = [1.0, -2.0, 0.5];
//! let v = Vec3::from(theirs);
//! let back: [f32; 3] = v.into();
//! assert_eq!(back, theirs);
//! ```

use crate::Real;
use core::ops::{Add, AddAssign, Div, Index, IndexMut, Mul, Neg, Sub, SubAssign};

/// A point or direction in 3D.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub struct Vec3<T> {
    /// x component.
    pub x: T,
    /// y component.
    pub y: T,
    /// z component.
    pub z: T,
}

impl<T: Real> Vec3<T> {
    /// The zero vector.
    pub const ZERO: Self = Self {
        x: T::ZERO,
        y: T::ZERO,
        z: T::ZERO,
    };

    /// A vector from its components.
    #[inline]
    #[must_use]
    pub const fn new(x: T, y: T, z: T) -> Self {
        Self { x, y, z }
    }

    /// All three components equal to `v`.
    #[inline]
    #[must_use]
    pub const fn splat(v: T) -> Self {
        Self { x: v, y: v, z: v }
    }

    /// Components as an array.
    #[inline]
    #[must_use]
    pub const fn to_array(self) -> [T; 3] {
        [self.x, self.y, self.z]
    }

    /// Applies `f` to each component.
    #[inline]
    #[must_use]
    pub fn map<U>(self, mut f: impl FnMut(T) -> U) -> Vec3<U> {
        Vec3 {
            x: f(self.x),
            y: f(self.y),
            z: f(self.z),
        }
    }

    /// Combines two vectors component by component.
    #[inline]
    #[must_use]
    pub fn zip_with(self, o: Self, mut f: impl FnMut(T, T) -> T) -> Self {
        Self::new(f(self.x, o.x), f(self.y, o.y), f(self.z, o.z))
    }

    /// Component-wise minimum.
    #[inline]
    #[must_use]
    pub fn min(self, o: Self) -> Self {
        self.zip_with(o, T::min)
    }

    /// Component-wise maximum.
    #[inline]
    #[must_use]
    pub fn max(self, o: Self) -> Self {
        self.zip_with(o, T::max)
    }

    /// Component-wise absolute value.
    #[inline]
    #[must_use]
    pub fn abs(self) -> Self {
        self.map(T::abs)
    }

    /// Dot product.
    #[inline]
    #[must_use]
    pub fn dot(self, o: Self) -> T {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product.
    #[inline]
    #[must_use]
    pub fn cross(self, o: Self) -> Self {
        Self::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Squared Euclidean length.
    #[inline]
    #[must_use]
    pub fn length_squared(self) -> T {
        self.dot(self)
    }

    /// Euclidean length.
    #[inline]
    #[must_use]
    pub fn length(self) -> T {
        self.length_squared().sqrt()
    }

    /// This vector scaled to unit length (undefined for the zero vector).
    #[inline]
    #[must_use]
    pub fn normalized(self) -> Self {
        self / self.length()
    }

    /// The largest component.
    #[inline]
    #[must_use]
    pub fn max_component(self) -> T {
        self.x.max(self.y).max(self.z)
    }

    /// The smallest component.
    #[inline]
    #[must_use]
    pub fn min_component(self) -> T {
        self.x.min(self.y).min(self.z)
    }

    /// The axis (0, 1, 2) of the largest component; ties go to the lower axis.
    #[inline]
    #[must_use]
    pub fn max_dimension(self) -> usize {
        if self.x >= self.y {
            if self.x >= self.z { 0 } else { 2 }
        } else if self.y >= self.z {
            1
        } else {
            2
        }
    }

    /// All components finite.
    #[inline]
    #[must_use]
    pub fn is_finite(self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// Converts to another precision through `f64`.
    #[inline]
    #[must_use]
    pub fn cast<U: Real>(self) -> Vec3<U> {
        Vec3::new(
            U::from_f64(self.x.to_f64()),
            U::from_f64(self.y.to_f64()),
            U::from_f64(self.z.to_f64()),
        )
    }
}

impl<T> Index<usize> for Vec3<T> {
    type Output = T;
    #[inline]
    fn index(&self, axis: usize) -> &T {
        match axis {
            0 => &self.x,
            1 => &self.y,
            2 => &self.z,
            _ => panic!("axis {axis} out of range 0..3"),
        }
    }
}

impl<T> IndexMut<usize> for Vec3<T> {
    #[inline]
    fn index_mut(&mut self, axis: usize) -> &mut T {
        match axis {
            0 => &mut self.x,
            1 => &mut self.y,
            2 => &mut self.z,
            _ => panic!("axis {axis} out of range 0..3"),
        }
    }
}

impl<T: Real> Add for Vec3<T> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        self.zip_with(o, |a, b| a + b)
    }
}

impl<T: Real> AddAssign for Vec3<T> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl<T: Real> Sub for Vec3<T> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        self.zip_with(o, |a, b| a - b)
    }
}

impl<T: Real> SubAssign for Vec3<T> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}

impl<T: Real> Mul<T> for Vec3<T> {
    type Output = Self;
    #[inline]
    fn mul(self, s: T) -> Self {
        self.map(|a| a * s)
    }
}

impl<T: Real> Mul for Vec3<T> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        self.zip_with(o, |a, b| a * b)
    }
}

impl<T: Real> Div<T> for Vec3<T> {
    type Output = Self;
    #[inline]
    fn div(self, s: T) -> Self {
        self.map(|a| a / s)
    }
}

impl<T: Real> Neg for Vec3<T> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        self.map(|a| -a)
    }
}

/// From an array `[x, y, z]`: the path for vectors of any glam version
/// (`v.to_array().into()`), or of any other vector crate.
impl<T> From<[T; 3]> for Vec3<T> {
    #[inline]
    fn from([x, y, z]: [T; 3]) -> Self {
        Self { x, y, z }
    }
}

/// To an array `[x, y, z]`: the path to vectors of any glam version
/// (`glam::Vec3::from(<[f32; 3]>::from(v))`), or of any other vector crate.
impl<T> From<Vec3<T>> for [T; 3] {
    #[inline]
    fn from(v: Vec3<T>) -> Self {
        [v.x, v.y, v.z]
    }
}

impl From<glam::Vec3> for Vec3<f32> {
    #[inline]
    fn from(v: glam::Vec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl From<Vec3<f32>> for glam::Vec3 {
    #[inline]
    fn from(v: Vec3<f32>) -> Self {
        glam::Vec3::new(v.x, v.y, v.z)
    }
}

impl From<glam::DVec3> for Vec3<f64> {
    #[inline]
    fn from(v: glam::DVec3) -> Self {
        Self::new(v.x, v.y, v.z)
    }
}

impl From<Vec3<f64>> for glam::DVec3 {
    #[inline]
    fn from(v: Vec3<f64>) -> Self {
        glam::DVec3::new(v.x, v.y, v.z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_is_right_handed_and_orthogonal() {
        let a = Vec3::new(1.0f64, 2.0, 3.0);
        let b = Vec3::new(-4.0, 0.5, 2.0);
        let c = a.cross(b);
        assert_eq!(c, Vec3::new(2.5, -14.0, 8.5));
        assert_eq!(c.dot(a), 0.0);
        assert_eq!(c.dot(b), 0.0);
    }

    #[test]
    fn max_dimension_ties_go_low() {
        assert_eq!(Vec3::new(1.0f32, 1.0, 0.0).max_dimension(), 0);
        assert_eq!(Vec3::new(0.0f32, 2.0, 2.0).max_dimension(), 1);
        assert_eq!(Vec3::new(0.0f32, 1.0, 2.0).max_dimension(), 2);
    }

    #[test]
    fn array_round_trip() {
        // Distinct components, so a swapped pair would show.
        let a = [1.5f32, -0.0, 3.0e38];
        let v = Vec3::from(a);
        assert_eq!((v.x, v.y, v.z), (1.5, -0.0, 3.0e38));
        assert!(v.y.is_sign_negative());
        let back: [f32; 3] = v.into();
        assert_eq!(back.map(f32::to_bits), a.map(f32::to_bits));
        let d = [f64::MIN_POSITIVE, 2.0, -7.25];
        assert_eq!(<[f64; 3]>::from(Vec3::from(d)), d);
        assert_eq!(Vec3::from(d).to_array(), d);
    }

    #[test]
    fn glam_through_arrays() {
        // The path for another glam version: its arrays, not its types.
        let g = crate::glam::Vec3::new(0.25, -4.0, 9.5);
        let v = Vec3::from(g.to_array());
        assert_eq!(v, Vec3::new(0.25, -4.0, 9.5));
        assert_eq!(crate::glam::Vec3::from_array(v.into()), g);
        let dg = crate::glam::DVec3::new(1e300, -1e-300, 3.0);
        assert_eq!(
            crate::glam::DVec3::from(<[f64; 3]>::from(Vec3::from(dg.to_array()))),
            dg
        );
    }

    #[test]
    fn glam_round_trip() {
        let v = glam::DVec3::new(1.5, -2.0, 3.25);
        let w: Vec3<f64> = v.into();
        assert_eq!(glam::DVec3::from(w), v);
    }
}
