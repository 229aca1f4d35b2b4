//! Shading one pixel: primary rays, a shadow ray to the light, and
//! ambient-occlusion rays.
//!
//! Primary rays are coherent; ambient-occlusion rays (cosine-distributed over
//! the hemisphere) are not, so a render exercises both kinds. Everything a
//! pixel computes depends only on its position and the hits it gets: random
//! numbers come from a [`SplitMix64`] seeded by pixel and sample. Since every
//! accelerator returns bit-for-bit the same hits, every accelerator renders
//! bit-for-bit the same image.
//!
//! Secondary rays start where [`spawn`] puts them: by default pbrt-v4's
//! error-bound offset ([`accel_core::spawn`]), a few ulps off the surface on
//! the side the ray came from, so that they never hit the triangle they
//! leave; or, with `--spawn epsilon`, the textbook fixed offset.

use crate::scene::Scene;
use accel_core::spawn::{SpawnOffset, spawn_origin};
use accel_core::{Accelerator, Hit, QueryError, Ray, Real, TraversalCounters, TriangleMesh, Vec3};
use accel_scenes::SplitMix64;

/// What the shader needs for every pixel.
pub struct Shader<'a, T: Real> {
    /// The structure answering the queries.
    pub accel: &'a dyn Accelerator<T>,
    /// The triangles (for normals).
    pub mesh: &'a TriangleMesh<T>,
    /// Materials, camera, light.
    pub scene: &'a Scene,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Ambient-occlusion rays per sample.
    pub ao: u32,
    /// Whether to count traversal work (heat maps).
    pub count: bool,
    /// Where secondary rays start.
    pub spawn: SpawnOffset<T>,
}

/// Rays traced and their outcomes, summed over pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Tally {
    /// Primary rays.
    pub primary: u64,
    /// Primary rays that hit.
    pub primary_hits: u64,
    /// Shadow rays.
    pub shadow: u64,
    /// Shadow rays blocked before the light.
    pub shadow_blocked: u64,
    /// Ambient-occlusion rays.
    pub ao: u64,
    /// Ambient-occlusion rays blocked within the distance.
    pub ao_blocked: u64,
    /// Order-independent digest of every query's answer (the bits of each
    /// primary hit, each shadow and occlusion answer): equal digests mean the
    /// same answers.
    pub digest: u64,
    /// Work of every ray, when counted.
    pub work: TraversalCounters,
}

impl Tally {
    /// Adds another tally.
    pub fn add(&mut self, o: &Self) {
        self.primary += o.primary;
        self.primary_hits += o.primary_hits;
        self.shadow += o.shadow;
        self.shadow_blocked += o.shadow_blocked;
        self.ao += o.ao;
        self.ao_blocked += o.ao_blocked;
        self.digest = self.digest.wrapping_add(o.digest);
        self.work.add(&o.work);
    }

    /// Every ray traced.
    #[must_use]
    pub fn rays(&self) -> u64 {
        self.primary + self.shadow + self.ao
    }
}

/// One pixel's result.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pixel {
    /// Linear RGB, averaged over samples.
    pub rgb: [f32; 3],
    /// Work of the primary rays, summed over samples (when counted).
    pub primary_work: TraversalCounters,
    /// The pixel's rays and answers.
    pub tally: Tally,
}

/// A 64-bit mix (SplitMix64's finaliser) of a running hash and a value.
#[must_use]
pub fn mix(h: u64, v: u64) -> u64 {
    let mut z = (h ^ v).wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Mixes a hit's bits (or its absence) into a hash.
#[must_use]
pub fn mix_hit<T: Real>(h: u64, hit: Option<&Hit<T>>) -> u64 {
    match hit {
        None => mix(h, u64::MAX),
        Some(hit) => {
            let (t, prim, u, v) = hit.bit_key();
            mix(mix(mix(mix(h, t), u64::from(prim)), u), v)
        }
    }
}

const SKY_HORIZON: [f64; 3] = [0.85, 0.9, 1.0];
const SKY_ZENITH: [f64; 3] = [0.3, 0.5, 0.9];
const AMBIENT: f64 = 0.55;
const LIGHT: [f64; 3] = [1.0, 0.94, 0.85];

fn lerp(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    core::array::from_fn(|i| a[i] + (b[i] - a[i]) * t)
}

/// An orthonormal basis around unit `n` (Duff et al., JCGT 2017).
fn basis(n: Vec3<f64>) -> (Vec3<f64>, Vec3<f64>) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// A cosine-distributed direction around unit `n`.
pub fn cosine_direction(n: Vec3<f64>, rng: &mut SplitMix64) -> Vec3<f64> {
    let (s, t) = basis(n);
    let r2 = rng.next_f64();
    let phi = core::f64::consts::TAU * rng.next_f64();
    let r = r2.sqrt();
    s * (r * phi.cos()) + t * (r * phi.sin()) + n * (1.0 - r2).max(0.0).sqrt()
}

/// The unit normal of a triangle facing against `d`, or `−d` for a degenerate one.
fn facing_normal<T: Real>(mesh: &TriangleMesh<T>, prim: u32, d: Vec3<f64>) -> Vec3<f64> {
    let [a, b, c] = mesh.triangle(prim as usize).map(|p| p.cast::<f64>());
    let n = (b - a).cross(c - a);
    let len = n.length();
    if !(len > 0.0) || !len.is_finite() {
        return -d.normalized();
    }
    let n = n * (1.0 / len);
    if n.dot(d) > 0.0 { -n } else { n }
}

/// Where secondary rays leave a hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spawn {
    /// The hit point `o + t·d` (in `f64`, for shading).
    pub point: Vec3<f64>,
    /// The unit normal on the side the ray came from.
    pub normal: Vec3<f64>,
    /// The origin of secondary rays leaving on that side: a value of the
    /// query precision `T`, exactly (casting it to `T` does not round).
    pub origin: Vec3<f64>,
}

/// The spawn point of secondary rays at `hit`, leaving on the side the ray
/// came from, by `offset` ([`accel_core::spawn::spawn_origin`], computed in
/// the query precision).
#[must_use]
pub fn spawn<T: Real>(
    mesh: &TriangleMesh<T>,
    ray: &Ray<T>,
    hit: &Hit<T>,
    offset: SpawnOffset<T>,
) -> Spawn {
    let o: Vec3<f64> = ray.origin.cast();
    let d: Vec3<f64> = ray.direction.cast();
    let point = o + d * hit.t.to_f64();
    let normal = facing_normal(mesh, hit.prim, d);
    let tri = mesh.triangle(hit.prim as usize);
    let origin = spawn_origin(offset, tri, ray, hit, normal.cast::<T>());
    Spawn {
        point,
        normal,
        origin: origin.cast(),
    }
}

/// A hit surface and the secondary rays it sends, before they are answered:
/// what the per-pixel path ([`Shader::pixel`]) and the tile path
/// ([`crate::tile_shade`]) both compute, with [`Shader::surface`], and both
/// finish with [`Shader::lit`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface<T> {
    /// The surface's albedo at the hit point.
    pub albedo: [f64; 3],
    /// The shadow ray to the light and the cosine of the light's direction
    /// to the normal, when the light is above the surface (and not at the
    /// spawn point itself); `None` when no shadow ray is traced.
    pub shadow: Option<(Ray<T>, f64)>,
}

/// One sample's camera ray and what shading it needs next.
#[derive(Clone, Debug)]
pub struct CameraSample<T> {
    /// The camera ray through the (jittered) sample position.
    pub ray: Ray<T>,
    /// The pixel's random numbers for this sample, after the jitter: the
    /// ambient-occlusion directions come next.
    pub rng: SplitMix64,
    /// The digest's seed for this pixel and sample.
    pub seed: u64,
}

/// A pixel's sums over the samples shaded so far.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSum {
    /// Linear RGB summed over samples.
    pub sum: [f64; 3],
    /// Work and tally so far (`rgb` is set by [`PixelSum::finish`]).
    pub pixel: Pixel,
}

impl PixelSum {
    /// Counts a sample's primary ray and its answer; returns the sample's
    /// running digest, seeded by `seed` and mixed with the hit's bits.
    pub fn primary<T: Real>(&mut self, seed: u64, hit: Option<&Hit<T>>) -> u64 {
        self.pixel.tally.primary += 1;
        self.pixel.tally.primary_hits += u64::from(hit.is_some());
        mix_hit(seed, hit)
    }

    /// Adds a finished sample: its colour and its digest `h`.
    pub fn add_sample(&mut self, c: [f64; 3], h: u64) {
        self.pixel.tally.digest = self.pixel.tally.digest.wrapping_add(h);
        for (sum, c) in self.sum.iter_mut().zip(c) {
            *sum += c;
        }
    }

    /// The pixel: the colour averaged over `spp` samples.
    #[must_use]
    pub fn finish(mut self, spp: u32) -> Pixel {
        let inv = 1.0 / f64::from(spp);
        self.pixel.rgb = self.sum.map(|c| (c * inv) as f32);
        self.pixel
    }
}

impl<T: Real> Shader<'_, T> {
    fn intersect(
        &self,
        ray: &Ray<T>,
        work: &mut TraversalCounters,
    ) -> Result<Option<Hit<T>>, QueryError> {
        if self.count {
            self.accel.intersect_counted(ray, work)
        } else {
            self.accel.intersect(ray)
        }
    }

    fn occluded(&self, ray: &Ray<T>, work: &mut TraversalCounters) -> Result<bool, QueryError> {
        if self.count {
            self.accel.occluded_counted(ray, work)
        } else {
            self.accel.occluded(ray)
        }
    }

    /// Sample `s` of pixel `(x, y)`: its random numbers (seeded by pixel
    /// and sample), the jitter drawn from them (none at one sample per
    /// pixel: the pixel's centre) and the camera ray through that point.
    #[must_use]
    pub fn camera_sample(&self, x: u32, y: u32, s: u32) -> CameraSample<T> {
        let index = u64::from(y) * u64::from(self.width) + u64::from(x);
        let seed = mix(index, u64::from(s));
        let mut rng = SplitMix64::new(seed);
        let (jx, jy) = if self.spp == 1 {
            (0.5, 0.5)
        } else {
            (rng.next_f64(), rng.next_f64())
        };
        let ray = self.scene.view.camera.ray_through(
            f64::from(x) + jx,
            f64::from(y) + jy,
            self.width,
            self.height,
        );
        CameraSample { ray, rng, seed }
    }

    /// Shades pixel `(x, y)` (`(0, 0)` top left) one ray at a time: the
    /// reference the tile path ([`crate::tile_shade`]) matches bit for bit,
    /// and the path that counts traversal work (`count`), which has no
    /// bundle query.
    ///
    /// # Errors
    /// A [`QueryError`] if a ray is not valid in this precision (a camera or
    /// hit point that overflows `f32`, for example): the first met, in the
    /// order the rays are traced (by sample; the camera ray, the shadow ray,
    /// then the ambient-occlusion rays).
    pub fn pixel(&self, x: u32, y: u32) -> Result<Pixel, QueryError> {
        let mut acc = PixelSum::default();
        let mut ao_rays = Vec::with_capacity(self.ao as usize);
        for s in 0..self.spp {
            let CameraSample { ray, mut rng, seed } = self.camera_sample(x, y, s);
            let mut work = TraversalCounters::default();
            let hit = self.intersect(&ray, &mut work)?;
            acc.pixel.primary_work.add(&work);
            acc.pixel.tally.work.add(&work);
            let mut h = acc.primary(seed, hit.as_ref());
            let c = match hit {
                None => self.sky(ray.direction.cast()),
                Some(hit) => {
                    ao_rays.clear();
                    let surface = self.surface(&ray, &hit, &mut rng, &mut ao_rays);
                    let mut work = TraversalCounters::default();
                    let blocked = match &surface.shadow {
                        Some((shadow, _)) => Some(self.occluded(shadow, &mut work)?),
                        None => None,
                    };
                    let mut ao_blocked = 0;
                    for ao_ray in &ao_rays {
                        ao_blocked += u32::from(self.occluded(ao_ray, &mut work)?);
                    }
                    acc.pixel.tally.work.add(&work);
                    self.lit(&surface, blocked, ao_blocked, &mut acc.pixel.tally, &mut h)
                }
            };
            acc.add_sample(c, h);
        }
        Ok(acc.finish(self.spp))
    }

    /// The sky's colour in direction `d` (a camera ray that hits nothing).
    #[must_use]
    pub fn sky(&self, d: Vec3<f64>) -> [f64; 3] {
        let up = d.normalized().dot(self.scene.view.up);
        lerp(SKY_HORIZON, SKY_ZENITH, up.clamp(0.0, 1.0).sqrt())
    }

    /// The surface `ray` hits at `hit` and its secondary rays: the shadow
    /// ray, and the `ao` ambient-occlusion rays, appended to `ao_rays` in
    /// the order their directions are drawn from `rng`.
    pub fn surface(
        &self,
        ray: &Ray<T>,
        hit: &Hit<T>,
        rng: &mut SplitMix64,
        ao_rays: &mut Vec<Ray<T>>,
    ) -> Surface<T> {
        let view = &self.scene.view;
        let Spawn {
            point: p,
            normal: n,
            origin,
        } = spawn(self.mesh, ray, hit, self.spawn);
        let origin_t: Vec3<T> = origin.cast();
        let albedo = self.scene.albedo(hit.prim, p);

        // Direct light: one shadow ray, if the light is above the surface.
        let to_light = view.light - origin;
        let cos = n.dot(to_light.normalized());
        let shadow = Ray {
            origin: origin_t,
            direction: to_light.cast(),
            t_min: T::ZERO,
            t_max: T::ONE,
        };
        let shadow = (cos > 0.0 && shadow.direction != Vec3::ZERO).then_some((shadow, cos));

        // Ambient occlusion: cosine-distributed rays.
        for _ in 0..self.ao {
            let dir = cosine_direction(n, rng);
            ao_rays.push(Ray {
                origin: origin_t,
                direction: dir.cast(),
                t_min: T::ZERO,
                t_max: T::from_f64(view.ao_distance),
            });
        }
        Surface { albedo, shadow }
    }

    /// The colour of `surface` given the answers to its secondary rays:
    /// whether the shadow ray is blocked (`None` when none was traced) and
    /// how many of the `ao` ambient-occlusion rays are. Counts the rays in
    /// `tally` and mixes the answers into the sample's digest `h`.
    pub fn lit(
        &self,
        surface: &Surface<T>,
        shadow_blocked: Option<bool>,
        ao_blocked: u32,
        tally: &mut Tally,
        h: &mut u64,
    ) -> [f64; 3] {
        let mut direct = 0.0;
        if let (Some((_, cos)), Some(blocked)) = (surface.shadow, shadow_blocked) {
            tally.shadow += 1;
            tally.shadow_blocked += u64::from(blocked);
            *h = mix(*h, u64::from(blocked));
            if !blocked {
                direct = cos;
            }
        }

        // The fraction of ambient-occlusion rays that escape.
        let mut open = 1.0;
        if self.ao > 0 {
            let escaped = self.ao - ao_blocked;
            tally.ao += u64::from(self.ao);
            tally.ao_blocked += u64::from(ao_blocked);
            *h = mix(*h, u64::from(escaped));
            open = f64::from(escaped) / f64::from(self.ao);
        }

        let sky = lerp(SKY_HORIZON, SKY_ZENITH, 0.5);
        let albedo = surface.albedo;
        core::array::from_fn(|i| albedo[i] * (AMBIENT * open * sky[i] + direct * LIGHT[i]))
    }
}

/// Linear to sRGB-encoded 8 bits (the sRGB transfer function, clamped).
#[must_use]
pub fn to_srgb8(linear: f32) -> u8 {
    let c = f64::from(linear).clamp(0.0, 1.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_encoding_matches_the_standard() {
        assert_eq!(to_srgb8(0.0), 0);
        assert_eq!(to_srgb8(1.0), 255);
        assert_eq!(to_srgb8(2.0), 255);
        assert_eq!(to_srgb8(-1.0), 0);
        // Linear 0.5 is sRGB 0.7354 (188 of 255); sRGB 128/255 is linear 0.21586.
        assert_eq!(to_srgb8(0.5), 188);
        assert_eq!(to_srgb8(0.2159), 128);
        // The linear toe: 0.002 · 12.92 · 255 = 6.6.
        assert_eq!(to_srgb8(0.002), 7);
    }

    #[test]
    fn basis_is_orthonormal_and_directions_face_the_normal() {
        let mut rng = SplitMix64::new(3);
        for n in [
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.0, 0.0, -1.0),
            Vec3::new(0.6, -0.8, 0.0),
            Vec3::new(1.0, 2.0, -3.0).normalized(),
        ] {
            let (s, t) = basis(n);
            for (a, b) in [(s, t), (s, n), (t, n)] {
                assert!(a.dot(b).abs() < 1e-12);
            }
            assert!((s.length() - 1.0).abs() < 1e-12 && (t.length() - 1.0).abs() < 1e-12);
            for _ in 0..100 {
                let d = cosine_direction(n, &mut rng);
                assert!(d.dot(n) >= 0.0 && (d.length() - 1.0).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn digests_see_every_bit() {
        let a = Hit {
            t: 1.0f32,
            prim: 2,
            u: 0.25,
            v: 0.5,
        };
        let b = Hit {
            t: f32::from_bits(1.0f32.to_bits() + 1),
            ..a
        };
        assert_ne!(mix_hit(0, Some(&a)), mix_hit(0, Some(&b)));
        assert_ne!(mix_hit(0, Some(&a)), mix_hit::<f32>(0, None));
        assert_eq!(mix_hit(7, Some(&a)), mix_hit(7, Some(&a)));
    }
}
