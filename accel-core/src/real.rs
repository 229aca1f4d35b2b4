//! The scalar type: one generic implementation serves `f32` and `f64`.
//!
//! [`Real`] is sealed: the crate's robustness arguments (the error bounds of
//! [`Real::gamma`], the exact edge functions of the watertight triangle test) hold
//! for IEEE-754 binary32 and binary64 only.

use core::fmt::{Debug, Display};
use core::ops::{Add, AddAssign, Div, DivAssign, Mul, MulAssign, Neg, Sub, SubAssign};

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

/// An IEEE-754 floating-point scalar: `f32` or `f64`.
///
/// Every accelerator, primitive and query in the workspace is generic over it.
/// Arithmetic that must not overflow or lose its sign (edge functions, sphere
/// discriminants) runs in [`Real::Wide`], which is `f64` for both.
pub trait Real:
    sealed::Sealed
    + Copy
    + Debug
    + Display
    + Default
    + PartialEq
    + PartialOrd
    + Send
    + Sync
    + 'static
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + DivAssign
{
    /// The wider type used for sign-critical arithmetic (`f64` for both).
    type Wide: Real;

    /// 0.
    const ZERO: Self;
    /// 1.
    const ONE: Self;
    /// 0.5.
    const HALF: Self;
    /// +∞.
    const INFINITY: Self;
    /// −∞.
    const NEG_INFINITY: Self;
    /// The largest finite value.
    const MAX: Self;
    /// The smallest positive normal value.
    const MIN_POSITIVE: Self;
    /// The largest coordinate magnitude the accelerators accept. In `f32`,
    /// `MAX / 16` (about 2.1e37): the difference of two coordinates stays
    /// finite with room for the traversals' margins and its reciprocal
    /// stays normal, and the products the triangle, sphere and box tests form
    /// run in `f64`. In `f64`, 2^240 (about 1.8e72): a product of four
    /// coordinate differences (the sphere test's discriminant), which those
    /// tests form in `f64` itself, stays finite. A
    /// scene or a ray origin beyond it is refused
    /// ([`crate::BuildError::OutOfRange`], [`crate::QueryError::OriginOutOfRange`]).
    const LIMIT: Self;
    /// Half the distance from 1 to the next float: the unit roundoff `u`
    /// (pbrt's `MachineEpsilon`).
    const UNIT_ROUNDOFF: Self;
    /// `"f32"` or `"f64"`, for messages and reports.
    const NAME: &'static str;

    /// Converts from `f64`, rounding to nearest.
    fn from_f64(v: f64) -> Self;
    /// Converts to `f64` (exact for both types).
    fn to_f64(self) -> f64;
    /// Widens to [`Real::Wide`] (exact).
    fn to_wide(self) -> Self::Wide;
    /// Narrows from [`Real::Wide`], rounding to nearest.
    fn from_wide(w: Self::Wide) -> Self;
    /// Converts an integer count, rounding to nearest.
    fn from_usize(n: usize) -> Self;
    /// The raw bits, zero-extended to 64: equal bits mean an identical value.
    fn to_bits_u64(self) -> u64;

    /// Absolute value.
    fn abs(self) -> Self;
    /// Square root.
    fn sqrt(self) -> Self;
    /// Cube root.
    fn cbrt(self) -> Self;
    /// Largest integer not above `self`.
    fn floor(self) -> Self;
    /// Four-quadrant arctangent of `self / x`.
    fn atan2(self, x: Self) -> Self;
    /// Arccosine.
    fn acos(self) -> Self;
    /// The smaller value; if exactly one is NaN, the other.
    fn min(self, other: Self) -> Self;
    /// The larger value; if exactly one is NaN, the other.
    fn max(self, other: Self) -> Self;
    /// Neither NaN nor infinite.
    fn is_finite(self) -> bool;
    /// Not a number.
    fn is_nan(self) -> bool;
    /// The least float greater than `self` (pbrt's `NextFloatUp`).
    fn next_up(self) -> Self;
    /// The greatest float less than `self` (pbrt's `NextFloatDown`).
    fn next_down(self) -> Self;
    /// Converts to an integer, truncating toward zero and saturating at the
    /// `i64` range; NaN gives 0.
    fn to_i64_saturating(self) -> i64;

    /// `a * b - c * d`, computed so that its sign is exact whenever the inputs
    /// are exact, and its value accurate to a few ulps (the triangle test
    /// derives `t`, `u`, `v` from these values, not only the hit from their
    /// signs): in `f64` for `f32` inputs (products of two `f32` are exact in
    /// `f64`), and for `f64` inputs with an error-free product expansion
    /// whenever the products cancel (after Woop, Benthin & Wald 2013, section 3.3).
    fn diff_of_products(a: Self, b: Self, c: Self, d: Self) -> Self::Wide;

    /// The hit parameter `tw`, computed in [`Real::Wide`], rounded to `Self`
    /// if it is a hit in `[t_min, t_max]`: the rounded value lies in the
    /// window, and `Self` represents it faithfully. A parameter beyond
    /// `Self`'s range is no hit: not finite (a tiny direction), or below the
    /// normal range without being exactly 0 (a huge direction), where
    /// rounding would report a point far from the primitive, even one behind
    /// `t_min` as `-0.0` (see bug 3 in the tests crate). Primitive tests
    /// accept their hits through this one rule.
    #[inline]
    #[must_use]
    fn hit_parameter(tw: Self::Wide, t_min: Self, t_max: Self) -> Option<Self> {
        let t = Self::from_wide(tw);
        let representable =
            t.is_finite() && (t.abs() >= Self::MIN_POSITIVE || tw == <Self::Wide as Real>::ZERO);
        (representable && t >= t_min && t <= t_max).then_some(t)
    }

    /// pbrt's `gamma(n) = n·u / (1 − n·u)`: a bound on the relative error of `n`
    /// successive roundings (Higham 2002, §3.1).
    #[inline]
    #[must_use]
    fn gamma(n: u32) -> Self {
        let nu = Self::from_usize(n as usize) * Self::UNIT_ROUNDOFF;
        nu / (Self::ONE - nu)
    }
}

/// Veltkamp split of `a` into two halves whose product with another split is exact.
#[inline]
fn split_f64(a: f64) -> (f64, f64) {
    const SPLITTER: f64 = 134_217_729.0; // 2^27 + 1
    let c = SPLITTER * a;
    let hi = c - (c - a);
    (hi, a - hi)
}

/// Dekker's error-free product: `a * b = p + e` exactly, barring overflow.
#[inline]
fn two_product_f64(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split_f64(a);
    let (bh, bl) = split_f64(b);
    let e = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    (p, e)
}

/// Knuth's error-free sum: `a + b = s + err` exactly.
#[inline]
fn two_sum_f64(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a*b - c*d` with the sign of the exact result and a value accurate to a
/// few ulps, for products that cancel.
#[cold]
fn diff_of_products_f64_exact(a: f64, b: f64, c: f64, d: f64) -> f64 {
    let (p, pe) = two_product_f64(a, b);
    let (q, qe) = two_product_f64(c, d);
    // p - q is exact here (the caller saw the products cancel, so they are
    // within a factor of 2: Sterbenz); the residuals carry the rest.
    let (e, e_err) = two_sum_f64(pe, -qe);
    let r = (p - q) + e;
    // A zero sum is exact, and the exact result is then e's own rounding error.
    if r == 0.0 { e_err } else { r }
}

/// [`Real::LIMIT`] of `f64`: 2^240, about 1.8e72.
const F64_LIMIT: f64 = {
    let mut x = 1.0f64;
    let mut i = 0;
    while i < 240 {
        x *= 2.0;
        i += 1;
    }
    x
};

macro_rules! impl_real {
    ($t:ty, $bits:ty, $name:literal, $limit:expr, $diff:expr) => {
        impl Real for $t {
            type Wide = f64;
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const HALF: Self = 0.5;
            const INFINITY: Self = <$t>::INFINITY;
            const NEG_INFINITY: Self = <$t>::NEG_INFINITY;
            const MAX: Self = <$t>::MAX;
            const MIN_POSITIVE: Self = <$t>::MIN_POSITIVE;
            const LIMIT: Self = $limit;
            const UNIT_ROUNDOFF: Self = <$t>::EPSILON * 0.5;
            const NAME: &'static str = $name;

            #[inline]
            fn from_f64(v: f64) -> Self {
                v as $t
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn to_wide(self) -> f64 {
                self as f64
            }
            #[inline]
            fn from_wide(w: f64) -> Self {
                w as $t
            }
            #[inline]
            fn from_usize(n: usize) -> Self {
                n as $t
            }
            #[inline]
            fn to_bits_u64(self) -> u64 {
                self.to_bits() as u64
            }
            #[inline]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline]
            fn sqrt(self) -> Self {
                <$t>::sqrt(self)
            }
            #[inline]
            fn cbrt(self) -> Self {
                <$t>::cbrt(self)
            }
            #[inline]
            fn floor(self) -> Self {
                <$t>::floor(self)
            }
            #[inline]
            fn atan2(self, x: Self) -> Self {
                <$t>::atan2(self, x)
            }
            #[inline]
            fn acos(self) -> Self {
                <$t>::acos(self)
            }
            #[inline]
            fn min(self, other: Self) -> Self {
                <$t>::min(self, other)
            }
            #[inline]
            fn max(self, other: Self) -> Self {
                <$t>::max(self, other)
            }
            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline]
            fn next_up(self) -> Self {
                <$t>::next_up(self)
            }
            #[inline]
            fn next_down(self) -> Self {
                <$t>::next_down(self)
            }
            #[inline]
            fn to_i64_saturating(self) -> i64 {
                self as i64
            }
            #[inline]
            fn diff_of_products(a: Self, b: Self, c: Self, d: Self) -> f64 {
                $diff(a, b, c, d)
            }
        }
    };
}

// f32: a sixteenth of the largest value; products of coordinates run in f64.
impl_real!(
    f32,
    u32,
    "f32",
    f32::MAX / 16.0,
    |a: f32, b: f32, c: f32, d: f32| {
        // Each product of two f32 is exact in f64; only the subtraction rounds,
        // so the sign is exact and nothing overflows or goes subnormal.
        (a as f64) * (b as f64) - (c as f64) * (d as f64)
    }
);

// f64: 2^240, so that a product of four coordinate differences (the sphere
// test's discriminant, (d·oc)²) stays finite: (4·2^240)^4 < f64::MAX.
impl_real!(
    f64,
    u64,
    "f64",
    F64_LIMIT,
    |a: f64, b: f64, c: f64, d: f64| {
        let (p, q) = (a * b, c * d);
        let r = p - q;
        // The plain result errs by up to u·(|p| + |q|): a few ulps of r unless the
        // products cancel. Then (zero included) the products' rounding errors
        // dominate, and a degenerate triangle's edge functions would be noise
        // that `t` is computed from (see bug 2 in the tests crate).
        if r.abs() * 4.0 >= p.abs() + q.abs() {
            r
        } else {
            diff_of_products_f64_exact(a, b, c, d)
        }
    }
);

/// The smaller of `a` and `b` by a plain select: one instruction, where
/// [`Real::min`]'s NaN rule costs several. For values that cannot be NaN
/// (finite geometry and what is derived from it); with a NaN it returns `b`.
#[inline(always)]
pub(crate) fn lesser<T: Real>(a: T, b: T) -> T {
    if a < b { a } else { b }
}

/// The larger of `a` and `b`, as [`lesser`].
#[inline(always)]
pub(crate) fn greater<T: Real>(a: T, b: T) -> T {
    if a > b { a } else { b }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_matches_pbrt_definition() {
        let u = f32::EPSILON as f64 * 0.5;
        let expected = 3.0 * u / (1.0 - 3.0 * u);
        assert!((<f32 as Real>::gamma(3) as f64 - expected).abs() < 1e-12);
        assert!(<f64 as Real>::gamma(1) > f64::EPSILON * 0.5);
    }

    #[test]
    fn f32_edge_function_sign_is_exact_where_f32_arithmetic_loses_it() {
        // 1e20 * 1e20 overflows f32; the wide product does not.
        let r = f32::diff_of_products(1e20, 1e20, 1e20, 0.5e20);
        assert!(r > 0.0 && r.is_finite());
        // Products below f32's normal range keep their sign in f64.
        let r = f32::diff_of_products(1e-25, 3e-25, 1e-25, 2e-25);
        assert!(r > 0.0);
    }

    #[test]
    fn f64_zero_fallback_recovers_the_sign_of_a_tiny_difference() {
        // a*b and c*d differ only below f64 precision: plain arithmetic gives 0.
        let a = 1.0 + f64::EPSILON;
        let b = 1.0 - f64::EPSILON;
        let plain = a * b - 1.0;
        assert_eq!(plain, 0.0, "premise: the plain product rounds to 1");
        let exact = f64::diff_of_products(a, b, 1.0, 1.0);
        // (1+e)(1-e) - 1 = -e², negative.
        assert!(exact < 0.0, "got {exact}");
    }

    #[test]
    fn f64_cancelling_products_keep_their_value() {
        // q is the product's rounding moved one ulp up: the plain difference is
        // -1 ulp, while the exact one is -1 ulp plus the product's rounding error.
        let (a, b) = (0.1f64, 0.3f64);
        let p = a * b;
        let q = p.next_up();
        let exact = a.mul_add(b, -p) - (q - p); // both terms exact; one rounding
        let plain = a * b - q;
        assert_ne!(plain, exact, "premise: the plain result is off");
        let got = f64::diff_of_products(a, b, q, 1.0);
        assert!(
            (got - exact).abs() <= exact.abs() * 1e-15,
            "{got} vs {exact}"
        );
        // Swapping the products negates the result exactly (watertightness).
        assert_eq!(f64::diff_of_products(q, 1.0, a, b), -got);
    }

    #[test]
    fn hit_parameters_beyond_the_range_are_no_hits() {
        assert_eq!(f32::hit_parameter(0.5, 0.0, 1.0), Some(0.5));
        assert_eq!(f32::hit_parameter(1.5, 0.0, 1.0), None);
        // Exactly zero, either sign: the origin is on the primitive.
        assert_eq!(f32::hit_parameter(-0.0, 0.0, 1.0), Some(-0.0));
        // Overflow and underflow of f32; a tiny negative would round to -0.0.
        assert_eq!(f32::hit_parameter(1e39, 0.0, f32::INFINITY), None);
        assert_eq!(f32::hit_parameter(1e-40, 0.0, 1.0), None);
        assert_eq!(f32::hit_parameter(-1e-51, 0.0, 1.0), None);
        assert_eq!(f64::hit_parameter(1e-310, 0.0, 1.0), None);
        assert_eq!(f64::hit_parameter(1e-300, 0.0, 1.0), Some(1e-300));
    }

    #[test]
    fn saturating_conversion() {
        assert_eq!(1e30f32.to_i64_saturating(), i64::MAX);
        assert_eq!((-2.5f64).to_i64_saturating(), -2);
        assert_eq!(f64::NAN.to_i64_saturating(), 0);
    }
}
