//! A packet's arithmetic at an inner node, all lanes at once: each lane's
//! plane band ([`crate::traverse::finite_band`]), the near child's exit and
//! the far child's entry, and which lanes go on to each child.
//!
//! Every lane computes exactly what the single walk computes for its ray,
//! with the same operations in the same order and no fused multiply–add, so
//! the results are the same bits. The lanes run in one of two instruction
//! sets ([`LaneSet`]): SSE2, part of x86-64's baseline, four `f32` or two
//! `f64` per instruction ([`Baseline`]; elsewhere one lane at a time,
//! [`cross_portable`]), or AVX, eight `f32` or four `f64`, where the CPU has
//! AVX2 ([`Avx`], detected once by [`accel_core::packed::simd_level`], which
//! `ACCEL_SIMD=portable` caps to the baseline). The selects map one to one:
//! `minps(a, b)` is `if a < b { a } else { b }` and `maxps(a, b)` is
//! `if a > b { a } else { b }` (Intel's definition, `NaN` and signed zeros
//! included, the same for their AVX forms), `cmpleps` and AVX's `cmpps`
//! with `_CMP_LE_OS` are `<=`, and `|x|` clears the sign bit.

use crate::traverse::finite_band;
use accel_core::Real;

/// Rays per packet.
pub(crate) const PACKET: usize = 8;

/// A set of a packet's lanes, one bit per lane.
pub(crate) type Lanes = u32;

/// What a packet's rays bring to every node: per axis (indexed by
/// `axis & 3`, the fourth row unused) each lane's origin, reciprocal
/// direction and widened reciprocal (`|inv|·(1 + gamma(8))`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct LaneRays<T> {
    pub(crate) o: [[T; PACKET]; 4],
    pub(crate) inv: [[T; PACKET]; 4],
    pub(crate) half_inv: [[T; PACKET]; 4],
}

/// Where each lane's beam crosses a node's plane.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Crossing<T> {
    /// The near child's exit: the band's end, or the node's exit if sooner.
    pub(crate) near_t1: [T; PACKET],
    /// The far child's entry: the band's start, or the node's entry if later.
    pub(crate) far_t0: [T; PACKET],
    /// Lanes whose interval in the near child is not empty.
    pub(crate) to_near: Lanes,
    /// Lanes whose interval in the far child is not empty.
    pub(crate) to_far: Lanes,
}

/// An instruction set for a packet's lanes.
pub(crate) trait LaneSet: Copy {
    /// The lanes where `a[l] <= b[l]`.
    fn at_or_before<T: Real>(self, a: &[T; PACKET], b: &[T; PACKET]) -> Lanes;

    /// Each lane's crossing of the plane `x[axis] = s` by beams of
    /// half-width `delta`, within the intervals `[t0, t1]`.
    fn cross<T: Real>(
        self,
        rays: &LaneRays<T>,
        axis: usize,
        delta: &[T; PACKET],
        s: T,
        t0: &[T; PACKET],
        t1: &[T; PACKET],
    ) -> Crossing<T>;
}

/// The baseline: SSE2 on x86-64, one lane at a time elsewhere.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Baseline;

impl LaneSet for Baseline {
    #[inline(always)]
    fn at_or_before<T: Real>(self, a: &[T; PACKET], b: &[T; PACKET]) -> Lanes {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE2 is part of x86-64's baseline, so this CPU has it.
        if let Some(m) = unsafe { sse::at_or_before(a, b) } {
            return m;
        }
        (0..PACKET).fold(0, |m, l| m | (Lanes::from(a[l] <= b[l]) << l))
    }

    #[inline(always)]
    fn cross<T: Real>(
        self,
        rays: &LaneRays<T>,
        axis: usize,
        delta: &[T; PACKET],
        s: T,
        t0: &[T; PACKET],
        t1: &[T; PACKET],
    ) -> Crossing<T> {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: SSE2 is part of x86-64's baseline, so this CPU has it.
        if let Some(c) = unsafe { sse::cross(rays, axis, delta, s, t0, t1) } {
            return c;
        }
        cross_portable(rays, axis & 3, delta, s, t0, t1)
    }
}

/// AVX lanes, eight `f32` or four `f64` per instruction: a token that
/// exists only where the CPU has AVX2 ([`Avx::detect`]).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx(());

#[cfg(target_arch = "x86_64")]
impl Avx {
    /// The token, where [`accel_core::packed::simd_level`] allows AVX2.
    #[inline]
    pub(crate) fn detect() -> Option<Avx> {
        (accel_core::packed::simd_level() >= accel_core::packed::SimdLevel::Avx2).then_some(Avx(()))
    }
}

#[cfg(target_arch = "x86_64")]
impl LaneSet for Avx {
    #[inline(always)]
    fn at_or_before<T: Real>(self, a: &[T; PACKET], b: &[T; PACKET]) -> Lanes {
        // SAFETY: an `Avx` exists only where the CPU has AVX2.
        unsafe { avx::at_or_before(a, b) }.unwrap_or_else(|| Baseline.at_or_before(a, b))
    }

    #[inline(always)]
    fn cross<T: Real>(
        self,
        rays: &LaneRays<T>,
        axis: usize,
        delta: &[T; PACKET],
        s: T,
        t0: &[T; PACKET],
        t1: &[T; PACKET],
    ) -> Crossing<T> {
        // SAFETY: an `Avx` exists only where the CPU has AVX2.
        unsafe { avx::cross(rays, axis, delta, s, t0, t1) }
            .unwrap_or_else(|| Baseline.cross(rays, axis, delta, s, t0, t1))
    }
}

/// One instruction set's lanes behind the generic `T`: `$f32` where `T` is
/// `f32`, `$f64` where it is `f64` (the type check is decided when
/// compiling), `None` otherwise.
#[cfg(target_arch = "x86_64")]
macro_rules! typed_lanes {
    ($module:ident, $doc:literal, $f32:ident, $f64:ident) => {
        #[doc = $doc]
        mod $module {
            use super::{Crossing, LaneRays, Lanes, PACKET, cast, cast_mut};
            use accel_core::Real;

            /// [`super::LaneSet::at_or_before`] in this set.
            ///
            /// # Safety
            /// The CPU has this module's instruction set.
            #[inline(always)]
            pub(super) unsafe fn at_or_before<T: Real>(
                a: &[T; PACKET],
                b: &[T; PACKET],
            ) -> Option<Lanes> {
                if let (Some(a), Some(b)) = (cast::<_, [f32; PACKET]>(a), cast(b)) {
                    // SAFETY: the caller's promise.
                    return Some(unsafe { super::$f32::at_or_before(a, b) });
                }
                if let (Some(a), Some(b)) = (cast::<_, [f64; PACKET]>(a), cast(b)) {
                    // SAFETY: the caller's promise.
                    return Some(unsafe { super::$f64::at_or_before(a, b) });
                }
                None
            }

            /// [`super::LaneSet::cross`] in this set.
            ///
            /// # Safety
            /// The CPU has this module's instruction set.
            #[inline(always)]
            pub(super) unsafe fn cross<T: Real>(
                rays: &LaneRays<T>,
                axis: usize,
                delta: &[T; PACKET],
                s: T,
                t0: &[T; PACKET],
                t1: &[T; PACKET],
            ) -> Option<Crossing<T>> {
                let mut out = Crossing {
                    near_t1: [T::ZERO; PACKET],
                    far_t0: [T::ZERO; PACKET],
                    to_near: 0,
                    to_far: 0,
                };
                // The lanes of `$t` (module `$lanes`) where `T` is `$t`.
                macro_rules! typed {
                    ($t:ty, $lanes:ident) => {
                        if let (Some(r), Some(d), Some(&s), Some(a), Some(b), Some(o)) = (
                            cast::<_, LaneRays<$t>>(rays),
                            cast(delta),
                            cast(&s),
                            cast(t0),
                            cast(t1),
                            cast_mut::<_, Crossing<$t>>(&mut out),
                        ) {
                            // SAFETY: the caller's promise.
                            unsafe { super::$lanes::cross(r, axis & 3, d, s, a, b, o) };
                            return Some(out);
                        }
                    };
                }
                typed!(f32, $f32);
                typed!(f64, $f64);
                None
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
typed_lanes!(sse, "SSE2 lanes of `f32` or `f64`.", sse_f32, sse_f64);

#[cfg(target_arch = "x86_64")]
typed_lanes!(avx, "AVX lanes of `f32` or `f64`.", avx_f32, avx_f64);

/// [`LaneSet::cross`] one lane at a time: the single walk's expressions.
#[inline(always)]
pub(crate) fn cross_portable<T: Real>(
    rays: &LaneRays<T>,
    axis: usize,
    delta: &[T; PACKET],
    s: T,
    t0: &[T; PACKET],
    t1: &[T; PACKET],
) -> Crossing<T> {
    let (o, inv, half_inv) = (&rays.o[axis], &rays.inv[axis], &rays.half_inv[axis]);
    let mut out = Crossing {
        near_t1: [T::ZERO; PACKET],
        far_t0: [T::ZERO; PACKET],
        to_near: 0,
        to_far: 0,
    };
    for l in 0..PACKET {
        let (lo, hi) = finite_band(delta[l], inv[l], half_inv[l], s, o[l]);
        out.near_t1[l] = if hi < t1[l] { hi } else { t1[l] };
        out.far_t0[l] = if lo > t0[l] { lo } else { t0[l] };
        out.to_near |= Lanes::from(t0[l] <= out.near_t1[l]) << l;
        out.to_far |= Lanes::from(out.far_t0[l] <= t1[l]) << l;
    }
    out
}

/// `x` as a `U` when it is one (the generic code's `T` is `f32` or `f64`;
/// the check is on types, decided when compiling).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn cast<X: 'static, U: 'static>(x: &X) -> Option<&U> {
    (x as &dyn core::any::Any).downcast_ref()
}

/// [`cast`], mutable.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn cast_mut<X: 'static, U: 'static>(x: &mut X) -> Option<&mut U> {
    (x as &mut dyn core::any::Any).downcast_mut()
}

/// The lanes of one float type in one instruction set (`$feature`): `$t`
/// in `$v` registers of `$w` lanes, with the intrinsics spelled out.
#[cfg(target_arch = "x86_64")]
macro_rules! simd_lanes {
    ($module:ident, $doc:literal, $feature:literal, $t:ty, $v:ty, $w:expr, $load:ident,
     $store:ident, $set1:ident, $add:ident, $sub:ident, $mul:ident, $min:ident, $max:ident,
     $andnot:ident, $cmple:expr, $movemask:ident) => {
        #[doc = $doc]
        mod $module {
            use super::{Crossing, LaneRays, Lanes, PACKET};
            use crate::traverse::BAND_ROUNDINGS;
            use accel_core::Real;
            use core::arch::x86_64::*;

            /// Lanes per register.
            const W: usize = $w;

            /// Lanes `W·c ..` of `a`.
            #[inline]
            #[target_feature(enable = $feature)]
            fn load(a: &[$t; PACKET], c: usize) -> $v {
                debug_assert!(W * c + W <= PACKET);
                // SAFETY: `c < PACKET / W`, so the `W` values read from
                // `W·c` lie within the array; the load is unaligned.
                unsafe { $load(a.as_ptr().add(W * c)) }
            }

            /// Stores `v` to lanes `W·c ..` of `a`.
            #[inline]
            #[target_feature(enable = $feature)]
            fn store(a: &mut [$t; PACKET], c: usize, v: $v) {
                debug_assert!(W * c + W <= PACKET);
                // SAFETY: as in `load`, writing.
                unsafe { $store(a.as_mut_ptr().add(W * c), v) }
            }

            /// [`super::LaneSet::at_or_before`] for one float type.
            #[inline]
            #[target_feature(enable = $feature)]
            pub(super) fn at_or_before(a: &[$t; PACKET], b: &[$t; PACKET]) -> Lanes {
                (0..PACKET / W).fold(0, |m, c| {
                    m | (($movemask(($cmple)(load(a, c), load(b, c))) as Lanes) << (W * c))
                })
            }

            /// [`super::LaneSet::cross`] for one float type.
            #[inline]
            #[target_feature(enable = $feature)]
            pub(super) fn cross(
                rays: &LaneRays<$t>,
                axis: usize,
                delta: &[$t; PACKET],
                s: $t,
                t0: &[$t; PACKET],
                t1: &[$t; PACKET],
                out: &mut Crossing<$t>,
            ) {
                let (o, inv, half_inv) = (&rays.o[axis], &rays.inv[axis], &rays.half_inv[axis]);
                let s = $set1(s);
                let sign = $set1(-0.0);
                let g = $set1(<$t as Real>::gamma(BAND_ROUNDINGS));
                let (mut to_near, mut to_far) = (0, 0);
                for c in 0..PACKET / W {
                    // finite_band: tc = (s − o)·inv, half = |tc|·g + delta·half_inv.
                    let tc = $mul($sub(s, load(o, c)), load(inv, c));
                    let half = $add(
                        $mul($andnot(sign, tc), g),
                        $mul(load(delta, c), load(half_inv, c)),
                    );
                    let (lo, hi) = ($sub(tc, half), $add(tc, half));
                    let (a, b) = (load(t0, c), load(t1, c));
                    let near_t1 = $min(hi, b);
                    let far_t0 = $max(lo, a);
                    store(&mut out.near_t1, c, near_t1);
                    store(&mut out.far_t0, c, far_t0);
                    to_near |= ($movemask(($cmple)(a, near_t1)) as Lanes) << (W * c);
                    to_far |= ($movemask(($cmple)(far_t0, b)) as Lanes) << (W * c);
                }
                out.to_near = to_near;
                out.to_far = to_far;
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
simd_lanes!(
    sse_f32,
    "SSE2 lanes of `f32`.",
    "sse2",
    f32,
    __m128,
    4,
    _mm_loadu_ps,
    _mm_storeu_ps,
    _mm_set1_ps,
    _mm_add_ps,
    _mm_sub_ps,
    _mm_mul_ps,
    _mm_min_ps,
    _mm_max_ps,
    _mm_andnot_ps,
    _mm_cmple_ps,
    _mm_movemask_ps
);

#[cfg(target_arch = "x86_64")]
simd_lanes!(
    sse_f64,
    "SSE2 lanes of `f64`.",
    "sse2",
    f64,
    __m128d,
    2,
    _mm_loadu_pd,
    _mm_storeu_pd,
    _mm_set1_pd,
    _mm_add_pd,
    _mm_sub_pd,
    _mm_mul_pd,
    _mm_min_pd,
    _mm_max_pd,
    _mm_andnot_pd,
    _mm_cmple_pd,
    _mm_movemask_pd
);

#[cfg(target_arch = "x86_64")]
simd_lanes!(
    avx_f32,
    "AVX lanes of `f32`.",
    "avx",
    f32,
    __m256,
    8,
    _mm256_loadu_ps,
    _mm256_storeu_ps,
    _mm256_set1_ps,
    _mm256_add_ps,
    _mm256_sub_ps,
    _mm256_mul_ps,
    _mm256_min_ps,
    _mm256_max_ps,
    _mm256_andnot_ps,
    _mm256_cmp_ps::<_CMP_LE_OS>,
    _mm256_movemask_ps
);

#[cfg(target_arch = "x86_64")]
simd_lanes!(
    avx_f64,
    "AVX lanes of `f64`.",
    "avx",
    f64,
    __m256d,
    4,
    _mm256_loadu_pd,
    _mm256_storeu_pd,
    _mm256_set1_pd,
    _mm256_add_pd,
    _mm256_sub_pd,
    _mm256_mul_pd,
    _mm256_min_pd,
    _mm256_max_pd,
    _mm256_andnot_pd,
    _mm256_cmp_pd::<_CMP_LE_OS>,
    _mm256_movemask_pd
);

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A value of either sign over many binades, or a special one.
    fn value() -> impl Strategy<Value = f64> {
        prop_oneof![
            8 => (any::<bool>(), 1.0..2.0f64, -40..40i32)
                .prop_map(|(neg, m, e)| if neg { -m } else { m } * 2f64.powi(e)),
            1 => prop_oneof![Just(0.0), Just(-0.0), Just(f64::INFINITY),
                Just(f64::NEG_INFINITY), Just(f64::NAN), Just(f64::MAX)],
        ]
    }

    /// The crossing in `set` against the portable one, bit for bit, in `T`.
    fn same_bits<T: Real>(
        set: impl LaneSet,
        v: &[[f64; PACKET]],
        s: f64,
        axis: usize,
    ) -> Result<(), TestCaseError> {
        let t = |a: &[f64; PACKET]| a.map(T::from_f64);
        let rows = |a: &[f64; PACKET]| [t(a), t(a), t(a), t(a)];
        let rays = LaneRays {
            o: rows(&v[0]),
            inv: rows(&v[1]),
            half_inv: rows(&v[2]),
        };
        let (delta, t0, t1) = (t(&v[3]), t(&v[4]), t(&v[5]));
        let s = T::from_f64(s);
        let fast = set.cross(&rays, axis, &delta, s, &t0, &t1);
        let slow = cross_portable(&rays, axis, &delta, s, &t0, &t1);
        let bits = |a: &[T; PACKET]| a.map(|x| x.to_bits_u64());
        prop_assert_eq!(bits(&fast.near_t1), bits(&slow.near_t1));
        prop_assert_eq!(bits(&fast.far_t0), bits(&slow.far_t0));
        prop_assert_eq!(fast.to_near, slow.to_near);
        prop_assert_eq!(fast.to_far, slow.to_far);
        let (a, b) = (t(&v[6]), t(&v[7]));
        let portable = (0..PACKET).fold(0, |m, l| m | (Lanes::from(a[l] <= b[l]) << l));
        prop_assert_eq!(set.at_or_before(&a, &b), portable);
        Ok(())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(4_000))]
        /// In every instruction set this CPU has, every lane's crossing is
        /// the single walk's, bit for bit, signed zeros, infinities and NaN
        /// included.
        #[test]
        fn lanes_cross_as_the_single_walk(
            // Eight rows of lanes, drawn on the heap (arrays of strategies
            // overflow the test thread's stack in debug builds).
            values in proptest::collection::vec(value(), 8 * PACKET),
            s in value(),
            axis in 0..3usize,
        ) {
            let v: Vec<[f64; PACKET]> = values
                .chunks(PACKET)
                .map(|c| core::array::from_fn(|l| c[l]))
                .collect();
            same_bits::<f32>(Baseline, &v, s, axis)?;
            same_bits::<f64>(Baseline, &v, s, axis)?;
            #[cfg(target_arch = "x86_64")]
            if let Some(avx) = Avx::detect() {
                same_bits::<f32>(avx, &v, s, axis)?;
                same_bits::<f64>(avx, &v, s, axis)?;
            }
        }
    }
}
