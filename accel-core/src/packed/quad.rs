//! Rays four at a time against one triangle: the block test's first stage
//! turned on its side, for structures that walk rays in packets (a packet's
//! rays meet the same leaf's triangles). Each lane holds a ray; the
//! triangle is the same in every lane. A lane it rejects is one the scalar
//! test rejects, bit for bit, so the other lanes alone need the full test.

#[cfg(target_arch = "x86_64")]
use super::avx2;
use super::{sheared, survives};
use crate::{PreparedRay, Real, Vec3};

/// The constants of the watertight test's first stage for up to four rays
/// side by side (one ray per lane): their origins in `f64` and their shear
/// constants. The rays share their permutation of the axes
/// ([`PreparedRay::axes`]), which the first stage needs to be the same in
/// every lane.
#[derive(Clone, Copy, Debug)]
pub struct RayQuad {
    pub(super) origin: [[f64; 4]; 3],
    pub(super) shear_x: [f64; 4],
    pub(super) shear_y: [f64; 4],
    axes: [usize; 3],
}

impl RayQuad {
    /// Rays per quad.
    pub const LANES: usize = 4;

    /// The quad of `rays`, lane `l` holding `rays[l]` (lanes past the last
    /// ray repeat the first; their bits mean nothing), or `None` when there
    /// are none, more than four, or they do not all share their axes.
    #[must_use]
    pub fn new<T: Real>(rays: &[&PreparedRay<T>]) -> Option<Self> {
        let first = rays.first()?;
        if rays.len() > Self::LANES || rays.iter().any(|r| r.axes != first.axes) {
            return None;
        }
        let lane = |l: usize| rays.get(l).unwrap_or(first);
        Some(Self {
            origin: core::array::from_fn(|a| {
                core::array::from_fn(|l| lane(l).ray.origin[a].to_f64())
            }),
            shear_x: core::array::from_fn(|l| lane(l).shear.x),
            shear_y: core::array::from_fn(|l| lane(l).shear.y),
            axes: first.axes,
        })
    }

    /// The lanes (bit `l` for lane `l`) whose ray the first stage of the
    /// watertight test does not reject for `triangle`: a lane left out
    /// surely misses it ([`crate::triangle::intersect_triangle`] returns
    /// `None`). The scalar statement, for CPUs without AVX2 and for tests.
    #[must_use]
    pub fn survivors<T: Real>(&self, triangle: &[Vec3<T>; 3]) -> u32 {
        let p = triangle.map(|v| [v.x.to_f64(), v.y.to_f64(), v.z.to_f64()]);
        (0..Self::LANES).fold(0, |m, l| {
            let o = [0, 1, 2].map(|a| self.origin[a][l]);
            let s = [self.shear_x[l], self.shear_y[l]];
            let v = |k: usize| sheared(p[k], o, s, self.axes);
            m | (u32::from(survives(v(0), v(1), v(2))) << l)
        })
    }

    /// [`RayQuad::survivors`] in AVX2, four lanes per instruction.
    ///
    /// # Safety
    /// The CPU must have AVX2. Call it from a function compiled for AVX2
    /// (`#[target_feature(enable = "avx2")]`), where its intrinsics inline.
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    #[must_use]
    pub unsafe fn survivors_avx2<T: Real>(&self, triangle: &[Vec3<T>; 3]) -> u32 {
        // SAFETY: the caller promises AVX2.
        unsafe { avx2::ray_survivors(triangle, &avx2::RayLanes::of_quad(self), self.axes) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Ray;
    use crate::triangle::intersect_triangle;
    use proptest::prelude::*;

    fn coord() -> impl Strategy<Value = f64> {
        prop_oneof![-2.0..2.0f64, (-4i32..4).prop_map(|i| f64::from(i) * 0.5)]
    }

    /// Directions whose dominant axis is `+z`.
    fn main_z() -> impl Strategy<Value = [f64; 3]> {
        (coord(), coord(), 3.0..5.0f64).prop_map(|(x, y, z)| [x, y, z])
    }

    /// Every lane the scalar test hits survives, in both builds; the AVX2
    /// build's lanes are the scalar statement's.
    fn check<T: Real>(tri: [[f64; 3]; 3], rays: &[([f64; 3], [f64; 3])]) {
        let v = |a: [f64; 3]| Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        let triangle = tri.map(v);
        let prepared: Vec<PreparedRay<T>> = rays
            .iter()
            .filter_map(|&(o, d)| Ray::new(v(o), v(d)).ok())
            .map(PreparedRay::new)
            .collect();
        let refs: Vec<&PreparedRay<T>> = prepared.iter().collect();
        let Some(quad) = RayQuad::new(&refs) else {
            assert!(refs.is_empty() || refs.iter().any(|r| r.axes != refs[0].axes));
            return;
        };
        let scalar = quad.survivors(&triangle);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2.
            let simd = unsafe { quad.survivors_avx2(&triangle) };
            assert_eq!(simd & 0xF, scalar, "AVX2 and scalar lanes differ");
        }
        for (l, r) in refs.iter().enumerate() {
            let [a, b, c] = triangle;
            if intersect_triangle(r, a, b, c, r.ray.t_max).is_some() {
                assert_ne!(scalar & (1 << l), 0, "lane {l} is hit but rejected");
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(2_000))]
        /// No hit is rejected, in either precision, for triangles whose
        /// vertices lie on half-integer points the rays aim at; rays of a
        /// quad share a direction's dominant axis often enough (`+z` main).
        #[test]
        fn quads_reject_no_hit(
            tri in [[coord(), coord(), coord()], [coord(), coord(), coord()], [coord(), coord(), coord()]],
            rays in prop::collection::vec(([coord(), coord(), coord()], main_z()), 1..5),
        ) {
            check::<f32>(tri, &rays);
            check::<f64>(tri, &rays);
        }
    }

    #[test]
    fn a_quad_rejects_the_rays_that_surely_miss() {
        // A triangle in z = 0 around the origin; four rays down -z, the
        // first and third through it, the others well outside.
        let tri = [
            Vec3::new(-1.0f32, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        let down = Vec3::new(0.0, 0.0, -1.0);
        let at = |x: f32, y: f32| PreparedRay::new(Ray::new(Vec3::new(x, y, 1.0), down).unwrap());
        let rays = [at(0.0, 0.0), at(3.0, 0.0), at(0.1, -0.5), at(0.0, 2.0)];
        let quad = RayQuad::new(&rays.each_ref()).expect("one axis order");
        assert_eq!(quad.survivors(&tri), 0b0101);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2.
            assert_eq!(unsafe { quad.survivors_avx2(&tri) } & 0xF, 0b0101);
        }
        let aside =
            PreparedRay::new(Ray::new(Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)).unwrap());
        assert!(RayQuad::new(&[&rays[0], &aside]).is_none(), "axes differ");
    }
}
