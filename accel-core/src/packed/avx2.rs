//! The first stage of the watertight test in AVX2 intrinsics, four lanes
//! per instruction, lane for lane the same operations in `f64` (no fused
//! multiply–add) as the scalar test: four triangles against one ray (the
//! block test, [`TriangleBlock::survivors`]) or one triangle against four
//! rays ([`super::RayQuad::survivors`]).
use super::{BlockRay, LANES, RayQuad, TriangleBlock};
use crate::{Real, Vec3};
use std::arch::x86_64::{
    __m256d, _CMP_GT_OQ, _CMP_LT_OQ, _mm_loadu_ps, _mm256_add_pd, _mm256_and_pd, _mm256_andnot_pd,
    _mm256_cmp_pd, _mm256_cvtps_pd, _mm256_loadu_pd, _mm256_movemask_pd, _mm256_mul_pd,
    _mm256_or_pd, _mm256_set1_pd, _mm256_setzero_pd, _mm256_sub_pd,
};

/// The rays' constants, one per lane.
pub(super) struct RayLanes {
    origin: [__m256d; 3],
    shear_x: __m256d,
    shear_y: __m256d,
}

impl RayLanes {
    /// # Safety
    /// The CPU must have AVX2 (as for every function here).
    #[inline(always)]
    pub(super) unsafe fn broadcast(ray: &BlockRay) -> Self {
        // SAFETY: the caller promises AVX2.
        unsafe {
            Self {
                origin: [
                    _mm256_set1_pd(ray.origin[0]),
                    _mm256_set1_pd(ray.origin[1]),
                    _mm256_set1_pd(ray.origin[2]),
                ],
                shear_x: _mm256_set1_pd(ray.shear_x),
                shear_y: _mm256_set1_pd(ray.shear_y),
            }
        }
    }

    /// The four rays of `quad`, one per lane.
    ///
    /// # Safety
    /// The CPU must have AVX2.
    #[inline(always)]
    pub(super) unsafe fn of_quad(quad: &RayQuad) -> Self {
        // SAFETY: the caller promises AVX2; each array holds four `f64`.
        unsafe {
            Self {
                origin: [
                    _mm256_loadu_pd(quad.origin[0].as_ptr()),
                    _mm256_loadu_pd(quad.origin[1].as_ptr()),
                    _mm256_loadu_pd(quad.origin[2].as_ptr()),
                ],
                shear_x: _mm256_loadu_pd(quad.shear_x.as_ptr()),
                shear_y: _mm256_loadu_pd(quad.shear_y.as_ptr()),
            }
        }
    }
}

/// One vertex of four triangles (a block's `v[k]`), widened to `f64`.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
unsafe fn loaded<T: Real>(p: &[[T; LANES]; 3]) -> [__m256d; 3] {
    // SAFETY: the caller promises AVX2.
    unsafe { [load(&p[0]), load(&p[1]), load(&p[2])] }
}

/// One coordinate of four triangles' vertex, widened to `f64`.
///
/// # Safety
/// The CPU must have AVX2 (as for every function here).
#[inline(always)]
unsafe fn load<T: Real>(lanes: &[T; LANES]) -> __m256d {
    if size_of::<T>() == size_of::<f32>() {
        // SAFETY: `Real` is sealed to f32 and f64, so a `T` of f32's
        // size is f32; the array holds four of them.
        unsafe { _mm256_cvtps_pd(_mm_loadu_ps(lanes.as_ptr().cast::<f32>())) }
    } else {
        // SAFETY: as above, `T` is f64 here; four of them.
        unsafe { _mm256_loadu_pd(lanes.as_ptr().cast::<f64>()) }
    }
}

/// One vertex in every lane, widened to `f64`.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
unsafe fn broadcast<T: Real>(p: Vec3<T>) -> [__m256d; 3] {
    // SAFETY: the caller promises AVX2.
    unsafe {
        [
            _mm256_set1_pd(p.x.to_f64()),
            _mm256_set1_pd(p.y.to_f64()),
            _mm256_set1_pd(p.z.to_f64()),
        ]
    }
}

/// A vertex (its three coordinates, four lanes each) translated to the
/// rays' origins and sheared: its `x` and `y` in each ray's frame. (A
/// function, not a closure: closures here would not inherit the caller's
/// AVX2.)
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
unsafe fn sheared(p: [__m256d; 3], ray: &RayLanes, [kx, ky, kz]: [usize; 3]) -> (__m256d, __m256d) {
    // SAFETY: the caller promises AVX2.
    unsafe {
        let az = _mm256_sub_pd(p[kz], ray.origin[kz]);
        (
            _mm256_sub_pd(
                _mm256_sub_pd(p[kx], ray.origin[kx]),
                _mm256_mul_pd(ray.shear_x, az),
            ),
            _mm256_sub_pd(
                _mm256_sub_pd(p[ky], ray.origin[ky]),
                _mm256_mul_pd(ray.shear_y, az),
            ),
        )
    }
}

/// The lanes where `p − q` is surely below zero, and those where it is
/// surely above (`crate::triangle::sure_sign` on four lanes).
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
unsafe fn sure_sign(p: __m256d, q: __m256d) -> (__m256d, __m256d) {
    // SAFETY: the caller promises AVX2.
    unsafe {
        let sign = _mm256_set1_pd(-0.0);
        let r = _mm256_sub_pd(p, q);
        let bound = _mm256_add_pd(
            _mm256_mul_pd(
                _mm256_set1_pd(2.0 * f64::EPSILON),
                _mm256_add_pd(_mm256_andnot_pd(sign, p), _mm256_andnot_pd(sign, q)),
            ),
            _mm256_set1_pd(f64::MIN_POSITIVE),
        );
        let sure = _mm256_cmp_pd::<_CMP_GT_OQ>(_mm256_andnot_pd(sign, r), bound);
        let zero = _mm256_setzero_pd();
        (
            _mm256_and_pd(sure, _mm256_cmp_pd::<_CMP_LT_OQ>(r, zero)),
            _mm256_and_pd(sure, _mm256_cmp_pd::<_CMP_GT_OQ>(r, zero)),
        )
    }
}

/// The lanes of four triangles that the first stage of the watertight test
/// does not reject for one ray (`ray`'s lanes all alike).
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn survivors<T: Real>(
    block: &TriangleBlock<T>,
    ray: &RayLanes,
    axes: [usize; 3],
) -> u32 {
    // SAFETY: the caller promises AVX2.
    unsafe {
        first_stage(
            sheared(loaded(&block.v[0]), ray, axes),
            sheared(loaded(&block.v[1]), ray, axes),
            sheared(loaded(&block.v[2]), ray, axes),
        )
    }
}

/// The lanes of four rays (`rays`, sharing `axes`) that the first stage of
/// the watertight test does not reject for one triangle.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
pub(super) unsafe fn ray_survivors<T: Real>(
    triangle: &[Vec3<T>; 3],
    rays: &RayLanes,
    axes: [usize; 3],
) -> u32 {
    // SAFETY: the caller promises AVX2.
    unsafe {
        first_stage(
            sheared(broadcast(triangle[0]), rays, axes),
            sheared(broadcast(triangle[1]), rays, axes),
            sheared(broadcast(triangle[2]), rays, axes),
        )
    }
}

/// The lanes not rejected by the sure signs of the plain edge products of
/// the sheared vertices `(ax, ay)`, `(bx, by)`, `(cx, cy)`.
///
/// # Safety
/// The CPU must have AVX2.
#[inline(always)]
unsafe fn first_stage(
    (ax, ay): (__m256d, __m256d),
    (bx, by): (__m256d, __m256d),
    (cx, cy): (__m256d, __m256d),
) -> u32 {
    // SAFETY: the caller promises AVX2.
    unsafe {
        let (un, up) = sure_sign(_mm256_mul_pd(cx, by), _mm256_mul_pd(cy, bx));
        let (vn, vp) = sure_sign(_mm256_mul_pd(ax, cy), _mm256_mul_pd(ay, cx));
        let (wn, wp) = sure_sign(_mm256_mul_pd(bx, ay), _mm256_mul_pd(by, ax));
        let reject = _mm256_and_pd(
            _mm256_or_pd(_mm256_or_pd(un, vn), wn),
            _mm256_or_pd(_mm256_or_pd(up, vp), wp),
        );
        !(_mm256_movemask_pd(reject) as u32) & 0xF
    }
}
