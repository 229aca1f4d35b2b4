//! Choosing the accelerator and its parameters per scene and ray budget.
//!
//! The best structure depends on the scene *and* on how many rays it will
//! answer: for a few thousand rays the cheapest build wins, for millions the
//! fastest traversal. [`choose`] estimates, for each candidate,
//!
//! ```text
//! total = build time + expected rays × time per ray
//! ```
//!
//! and picks the smallest, from scene statistics and a short probe:
//!
//! 1. Fewer than [`TINY_SCENE`] primitives: brute force (nothing to build).
//! 2. The coarsest uniform grid of [`GRID_DENSITIES`] is built (`O(n)`, the
//!    cheapest build) and times a small probe of representative rays (the
//!    caller's, e.g. a low-resolution view with its shadow and
//!    ambient-occlusion rays). Brute force is priced from a few of the probe
//!    rays.
//! 3. The other candidates (the finer grid, the octree, the kD-tree) get
//!    build times predicted from builds on a subsample of [`SUBSAMPLE`]
//!    primitives, scaled by `n` (grids, octree) or `n log n` (kD-tree). A
//!    candidate whose predicted build alone costs more than [`PROBE_SHARE`]
//!    of the best total so far is not probed: it cannot win, or could win too
//!    little to pay for the probe. Otherwise it is built in full and timed on
//!    the same probe.
//! 4. The structure with the smallest estimated total is returned already
//!    built (probing is not wasted on the winner), with a one-line reason.
//!
//! Parameters: the grid's density is probed, not fixed: `render
//! sweep-density` found the best density between `m = 1` and `m = 2`
//! depending on the scene (and the grid's cost per cell, which is being
//! optimised), so both are candidates; the kD-tree gets [`KdTreeParams::fast_build`] when
//! the ray budget is small against the scene (fewer than [`FAST_BUILD_RAYS`]
//! rays per primitive), where its build dominates, and its default
//! (traversal-optimised) costs otherwise.
//!
//! Timings are wall-clock on the current rayon pool, as the render will run;
//! on a busy machine they are noisy, and so is the choice between candidates
//! whose estimates are close (which is also when the choice matters least).

use crate::accel::{AccelConfig, AccelError, AccelKind, build_config};
use accel_core::{Aabb, PreparedRay, PrimHit};
use accel_core::{Accelerator, PrimitiveSet, QueryError, Ray, Real};
use accel_kdtree::KdTreeParams;
use accel_octree::OctreeParams;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Below this many primitives, brute force is chosen without a probe.
pub const TINY_SCENE: usize = 64;
/// Primitives in the subsample that predicts octree and kD-tree build times.
pub const SUBSAMPLE: usize = 8192;
/// A candidate is probed (built in full) only if its predicted build time is
/// below this share of the best estimated total so far.
pub const PROBE_SHARE: f64 = 0.6;
/// Below this many expected rays per primitive, the kD-tree is built with
/// [`KdTreeParams::fast_build`].
pub const FAST_BUILD_RAYS: f64 = 20.0;
/// Most time spent timing one candidate's probe rays (the estimate then
/// comes from the part of the probe traced so far).
pub const PROBE_TIME: Duration = Duration::from_millis(150);
/// Most probe rays timed per candidate.
pub const MAX_PROBE: usize = 4096;
/// The grid densities the chooser considers, coarsest (cheapest) first:
/// the range where `render sweep-density` found each scene's best.
pub const GRID_DENSITIES: [f64; 2] = [1.0, 2.0];

/// A probe ray and the query it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeRay<T> {
    /// The ray.
    pub ray: Ray<T>,
    /// `occluded` (shadow and occlusion rays) rather than `intersect`.
    pub any_hit: bool,
}

/// One candidate's estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The structure and parameters.
    pub config: AccelConfig,
    /// Build time in seconds: measured if `probed`, predicted otherwise.
    pub build_s: f64,
    /// Seconds per ray, measured on the probe (NaN when not probed).
    pub per_ray_s: f64,
    /// `build_s + expected rays × per_ray_s` (infinite when not probed).
    pub total_s: f64,
    /// Whether it was built in full and timed.
    pub probed: bool,
}

/// What [`choose`] picked, and why.
pub struct Choice<'a, T: Real> {
    /// The structure and parameters chosen.
    pub config: AccelConfig,
    /// The chosen structure, built.
    pub accel: Box<dyn Accelerator<T> + 'a>,
    /// One line: the scene statistics and the estimates behind the choice.
    pub reason: String,
    /// Every candidate's estimate, in probe order.
    pub estimates: Vec<Estimate>,
    /// Wall-clock time of the whole choice, the winner's build included.
    pub elapsed: Duration,
}

impl<T: Real> core::fmt::Debug for Choice<'_, T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Choice")
            .field("config", &self.config)
            .field("reason", &self.reason)
            .field("estimates", &self.estimates)
            .field("elapsed", &self.elapsed)
            .finish_non_exhaustive()
    }
}

/// Why a choice failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ChooseError {
    /// A candidate could not be built.
    #[error(transparent)]
    Build(#[from] AccelError),
    /// A probe ray was refused.
    #[error("probe ray: {0}")]
    Query(#[from] QueryError),
}

/// Picks the accelerator and its parameters for `prims` and about
/// `expected_rays` queries (see the module docs), and returns it built.
///
/// `probe` makes the probe rays: it is given the first structure built (the
/// grid), so it can trace a few primary rays and spawn their secondary rays.
/// At most [`MAX_PROBE`] of them are timed.
///
/// # Errors
/// [`ChooseError`] if a candidate refuses the scene or a probe ray is invalid.
pub fn choose<'a, T, P, F>(
    prims: &'a P,
    expected_rays: u64,
    probe: F,
) -> Result<Choice<'a, T>, ChooseError>
where
    T: Real,
    P: PrimitiveSet<T> + ?Sized,
    F: FnOnce(&dyn Accelerator<T>) -> Result<Vec<ProbeRay<T>>, QueryError>,
{
    let start = Instant::now();
    let n = prims.len();
    let rays = expected_rays as f64;
    if n < TINY_SCENE {
        let config = AccelConfig::Brute;
        let accel = build_config(&config, prims)?;
        return Ok(Choice {
            reason: format!("{n} primitives: fewer than {TINY_SCENE}, nothing to build"),
            config,
            accel,
            estimates: Vec::new(),
            elapsed: start.elapsed(),
        });
    }

    // 2. The coarse grid: cheapest to build, and the probe's first structure.
    let grid_config = AccelConfig::Grid {
        density: GRID_DENSITIES[0],
    };
    let (grid, grid_build) = timed_build(&grid_config, prims)?;
    let mut probe_rays = probe(grid.as_ref())?;
    thin(&mut probe_rays, MAX_PROBE);
    let grid_per_ray = probe_per_ray(grid.as_ref(), &probe_rays, PROBE_TIME)?;
    let mut estimates = vec![measured(grid_config, grid_build, grid_per_ray, rays)];
    let mut best: (usize, Box<dyn Accelerator<T> + 'a>) = (0, grid);

    // Brute force, priced from a handful of probe rays.
    let brute_per_ray = brute_per_ray(prims, &probe_rays);
    estimates.push(measured(AccelConfig::Brute, 0.0, brute_per_ray, rays));
    if estimates[1].total_s < estimates[0].total_s {
        best = (1, build_config(&AccelConfig::Brute, prims)?);
    }

    // 3. The rest: predicted builds, full probes where they may pay.
    let kd_params = if rays < FAST_BUILD_RAYS * n as f64 {
        KdTreeParams::fast_build()
    } else {
        KdTreeParams::default()
    };
    let sample = Subsample::new(prims, SUBSAMPLE);
    let rest = GRID_DENSITIES[1..]
        .iter()
        .map(|&density| AccelConfig::Grid { density })
        .chain([
            AccelConfig::Octree(OctreeParams::default()),
            AccelConfig::KdTree(kd_params),
        ]);
    for config in rest {
        let predicted = predict_build(&config, &sample, n)?;
        let best_total = estimates[best.0].total_s;
        if predicted >= PROBE_SHARE * best_total {
            estimates.push(Estimate {
                config,
                build_s: predicted,
                per_ray_s: f64::NAN,
                total_s: f64::INFINITY,
                probed: false,
            });
            continue;
        }
        let (accel, build) = timed_build(&config, prims)?;
        let t = probe_per_ray(accel.as_ref(), &probe_rays, PROBE_TIME)?;
        estimates.push(measured(config, build, t, rays));
        if estimates[estimates.len() - 1].total_s < best_total {
            best = (estimates.len() - 1, accel);
        }
    }

    let chosen = &estimates[best.0];
    let reason = reason(n, expected_rays, probe_rays.len(), chosen, &estimates);
    Ok(Choice {
        config: chosen.config.clone(),
        accel: best.1,
        reason,
        estimates,
        elapsed: start.elapsed(),
    })
}

fn measured(config: AccelConfig, build_s: f64, per_ray_s: f64, rays: f64) -> Estimate {
    Estimate {
        config,
        build_s,
        per_ray_s,
        total_s: build_s + rays * per_ray_s,
        probed: true,
    }
}

/// The one-line reason: the winner's estimate against the others'.
fn reason(n: usize, rays: u64, probe: usize, chosen: &Estimate, all: &[Estimate]) -> String {
    let fmt_s = |s: f64| {
        if s >= 1.0 {
            format!("{s:.2} s")
        } else {
            format!("{:.1} ms", s * 1e3)
        }
    };
    let others: Vec<String> = all
        .iter()
        .filter(|e| e.config != chosen.config)
        .map(|e| {
            if e.probed {
                format!("{} {}", e.config, fmt_s(e.total_s))
            } else {
                format!("{} not probed (build ~{})", e.config, fmt_s(e.build_s))
            }
        })
        .collect();
    format!(
        "{n} primitives, {rays} rays: est. build {} + rays {} = {} (probe of {probe} rays); {}",
        fmt_s(chosen.build_s),
        fmt_s(chosen.total_s - chosen.build_s),
        fmt_s(chosen.total_s),
        others.join(", ")
    )
}

/// Builds and times one configuration.
fn timed_build<'a, T: Real, P: PrimitiveSet<T> + ?Sized>(
    config: &AccelConfig,
    prims: &'a P,
) -> Result<(Box<dyn Accelerator<T> + 'a>, f64), AccelError> {
    let start = Instant::now();
    let accel = build_config(config, prims)?;
    Ok((accel, start.elapsed().as_secs_f64()))
}

/// Keeps at most `max` rays, evenly spaced, in their order.
fn thin<T: Copy>(rays: &mut Vec<T>, max: usize) {
    if rays.len() > max {
        let step = rays.len() as f64 / max as f64;
        *rays = (0..max).map(|i| rays[(i as f64 * step) as usize]).collect();
    }
}

/// Seconds per probe ray for the chooser: [`per_ray`] when the probe is
/// quick, otherwise estimated from interleaved slices of the probe (every
/// 16th ray, then the next 16th, …) traced until `budget` is spent, so a
/// structure that serves the scene badly (the uniform grid on a teapot in a
/// stadium: a millisecond or more per ray) cannot make the choice itself
/// slow.
///
/// # Errors
/// A probe ray the accelerator refuses.
pub fn probe_per_ray<T: Real>(
    accel: &dyn Accelerator<T>,
    rays: &[ProbeRay<T>],
    budget: Duration,
) -> Result<f64, QueryError> {
    const SLICES: usize = 16;
    let (mut traced, mut spent) = (0usize, 0.0f64);
    for first in 0..SLICES.min(rays.len()) {
        let slice: Vec<&ProbeRay<T>> = rays.iter().skip(first).step_by(SLICES).collect();
        spent += trace_seconds(accel, slice.into_iter())?;
        traced += rays.len().saturating_sub(first).div_ceil(SLICES);
        if spent > budget.as_secs_f64() {
            return Ok(spent / traced.max(1) as f64);
        }
    }
    // The whole probe was quick: time it again, warm, as `per_ray` does.
    let warm = trace_seconds(accel, rays.iter())?;
    Ok(spent.min(warm) / rays.len().max(1) as f64)
}

/// Wall-clock seconds to trace `rays` in parallel, as a render would.
fn trace_seconds<'r, T: Real>(
    accel: &dyn Accelerator<T>,
    rays: impl Iterator<Item = &'r ProbeRay<T>>,
) -> Result<f64, QueryError> {
    let rays: Vec<&ProbeRay<T>> = rays.collect();
    let start = Instant::now();
    let hits: u64 = rays
        .par_iter()
        .with_min_len(32)
        .map(|p| {
            Ok(u64::from(if p.any_hit {
                accel.occluded(&p.ray)?
            } else {
                accel.intersect(&p.ray)?.is_some()
            }))
        })
        .try_reduce(|| 0, |a, b| Ok(a + b))?;
    std::hint::black_box(hits);
    Ok(start.elapsed().as_secs_f64())
}

/// Seconds per probe ray, traced in parallel as a render would (the faster
/// of two passes: the first warms the caches).
pub fn per_ray<T: Real>(
    accel: &dyn Accelerator<T>,
    rays: &[ProbeRay<T>],
) -> Result<f64, QueryError> {
    if rays.is_empty() {
        return Ok(0.0);
    }
    let mut best = f64::INFINITY;
    for _ in 0..2 {
        best = best.min(trace_seconds(accel, rays.iter())?);
    }
    Ok(best / rays.len() as f64)
}

/// Seconds per ray of brute force: `n` tests, timed on a few probe rays.
pub fn brute_per_ray<T: Real, P: PrimitiveSet<T> + ?Sized>(prims: &P, rays: &[ProbeRay<T>]) -> f64 {
    let n = prims.len().max(1);
    // About 2·10^5 tests: a millisecond or two.
    let k = (200_000 / n).clamp(1, rays.len().max(1)).min(rays.len());
    if k == 0 {
        return 0.0;
    }
    let start = Instant::now();
    let mut hits = 0u32;
    for p in rays.iter().take(k) {
        let pr = PreparedRay::new(p.ray);
        for i in 0..n {
            let h: Option<PrimHit<T>> = prims.intersect(i, &pr, p.ray.t_max);
            hits += u32::from(h.is_some());
        }
    }
    std::hint::black_box(hits);
    let single = start.elapsed().as_secs_f64() / k as f64;
    single / rayon::current_num_threads() as f64
}

/// A random subsample of a primitive set (every primitive with equal
/// probability, deterministic), for predicting build times.
struct Subsample<'p, T, P: ?Sized> {
    prims: &'p P,
    index: Vec<usize>,
    _t: core::marker::PhantomData<T>,
}

impl<'p, T: Real, P: PrimitiveSet<T> + ?Sized> Subsample<'p, T, P> {
    fn new(prims: &'p P, max: usize) -> Self {
        let n = prims.len();
        let index = if n <= max {
            (0..n).collect()
        } else {
            // Every k-th primitive from a scrambled start: meshes store
            // neighbours together, so a stride samples all parts evenly.
            let mut rng = accel_core::scenes::SplitMix64::new(0x5A3F);
            let step = n as f64 / max as f64;
            let offset = rng.next_f64() * step;
            (0..max)
                .map(|i| ((offset + i as f64 * step) as usize).min(n - 1))
                .collect()
        };
        Self {
            prims,
            index,
            _t: core::marker::PhantomData,
        }
    }
}

impl<T: Real, P: PrimitiveSet<T> + ?Sized> PrimitiveSet<T> for Subsample<'_, T, P> {
    fn len(&self) -> usize {
        self.index.len()
    }
    fn bounds(&self, i: usize) -> Aabb<T> {
        self.prims.bounds(self.index[i])
    }
    fn intersect(&self, i: usize, ray: &PreparedRay<T>, t_max: T) -> Option<PrimHit<T>> {
        self.prims.intersect(self.index[i], ray, t_max)
    }
    fn overlaps_box(&self, i: usize, b: &Aabb<T>) -> bool {
        self.prims.overlaps_box(self.index[i], b)
    }
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        self.prims.clipped_bounds(self.index[i], b)
    }
}

/// Predicted full build time from a build on the subsample: scaled by `n`
/// for grids and octrees, by `n log n` for the kD-tree.
fn predict_build<T: Real, P: PrimitiveSet<T> + ?Sized>(
    config: &AccelConfig,
    sample: &Subsample<'_, T, P>,
    n: usize,
) -> Result<f64, AccelError> {
    let s = sample.len();
    let (_, t) = timed_build(config, sample)?;
    if s == n || s == 0 {
        return Ok(t);
    }
    let ratio = n as f64 / s as f64;
    Ok(match config.kind() {
        AccelKind::KdTree => t * ratio * (n as f64).ln() / (s as f64).ln(),
        _ => t * ratio,
    })
}

/// The render a probe stands for, and how many primary rays it traces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ProbeShape {
    /// Image width of the render.
    pub width: u32,
    /// Image height of the render.
    pub height: u32,
    /// Occlusion rays per sample.
    pub ao: u32,
    /// Primary rays of the probe (a coarser view of the same camera).
    pub primaries: u32,
}

/// The number of primary rays of [`view_probe`] for [`choose`].
pub const PROBE_PRIMARIES: u32 = 1536;

/// Probe rays for a render of `view` at `width × height` with `ao`
/// occlusion rays per sample: primary rays of a coarser view (about
/// `primaries` of them, [`PROBE_PRIMARIES`] for the chooser), and from each
/// primary hit the shadow ray and `ao` occlusion rays the shader would
/// trace, each after its primary ray (so that thinning keeps the mix).
///
/// # Errors
/// A [`QueryError`] if a ray is not valid in this precision.
pub fn view_probe<T: Real>(
    accel: &dyn Accelerator<T>,
    mesh: &accel_core::TriangleMesh<T>,
    view: &crate::scene::View,
    shape: ProbeShape,
    offset: accel_core::spawn::SpawnOffset<T>,
) -> Result<Vec<ProbeRay<T>>, QueryError> {
    use accel_core::Vec3;
    let ProbeShape {
        width,
        height,
        ao,
        primaries,
    } = shape;
    let scale = (f64::from(primaries) / (f64::from(width) * f64::from(height)))
        .sqrt()
        .min(1.0);
    let w = ((f64::from(width) * scale).round() as u32).max(1);
    let h = ((f64::from(height) * scale).round() as u32).max(1);
    let primary: Vec<Ray<T>> = view.camera.rays(w, h);
    let hits: Vec<_> = primary
        .par_iter()
        .map(|r| accel.intersect(r))
        .collect::<Result<_, _>>()?;
    let mut out = Vec::with_capacity(primary.len() * (2 + ao as usize));
    let mut rng = accel_core::scenes::SplitMix64::new(0xC405);
    for (ray, hit) in primary.iter().zip(&hits) {
        out.push(ProbeRay {
            ray: *ray,
            any_hit: false,
        });
        let Some(hit) = hit else { continue };
        let s = crate::shade::spawn(mesh, ray, hit, offset);
        let to_light = view.light - s.origin;
        if s.normal.dot(to_light) > 0.0 {
            out.push(ProbeRay {
                ray: Ray {
                    origin: s.origin.cast(),
                    direction: to_light.cast(),
                    t_min: T::ZERO,
                    t_max: T::ONE,
                },
                any_hit: true,
            });
        }
        for _ in 0..ao {
            let d: Vec3<f64> = crate::shade::cosine_direction(s.normal, &mut rng);
            out.push(ProbeRay {
                ray: Ray {
                    origin: s.origin.cast(),
                    direction: d.cast(),
                    t_min: T::ZERO,
                    t_max: T::from_f64(view.ao_distance),
                },
                any_hit: true,
            });
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel_core::scenes::{random_rays, random_soup, uv_sphere};
    use accel_core::{BruteForce, TriangleMesh, Vec3};

    /// Brute force that takes at least a millisecond per ray and counts them.
    struct Slow<'a> {
        inner: BruteForce<'a, f64, TriangleMesh<f64>>,
        calls: std::sync::atomic::AtomicUsize,
    }

    impl Slow<'_> {
        fn wait(&self) {
            self.calls
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            std::thread::sleep(Duration::from_millis(1));
        }
    }

    impl Accelerator<f64> for Slow<'_> {
        fn bounds(&self) -> Aabb<f64> {
            self.inner.bounds()
        }
        fn intersect(&self, ray: &Ray<f64>) -> Result<Option<accel_core::Hit<f64>>, QueryError> {
            self.wait();
            self.inner.intersect(ray)
        }
        fn occluded(&self, ray: &Ray<f64>) -> Result<bool, QueryError> {
            self.wait();
            self.inner.occluded(ray)
        }
        fn intersect_counted(
            &self,
            ray: &Ray<f64>,
            c: &mut accel_core::TraversalCounters,
        ) -> Result<Option<accel_core::Hit<f64>>, QueryError> {
            self.wait();
            self.inner.intersect_counted(ray, c)
        }
        fn occluded_counted(
            &self,
            ray: &Ray<f64>,
            c: &mut accel_core::TraversalCounters,
        ) -> Result<bool, QueryError> {
            self.wait();
            self.inner.occluded_counted(ray, c)
        }
        fn query_region(&self, region: &Aabb<f64>) -> Result<Vec<u32>, QueryError> {
            self.inner.query_region(region)
        }
        fn stats(&self) -> accel_core::AccelStats {
            self.inner.stats()
        }
    }

    #[test]
    fn a_slow_structure_is_probed_on_a_slice_only() {
        // 4096 probe rays at >= 1 ms each would take seconds; with a 10 ms
        // budget the probe stops after its first slice (every 16th ray), and
        // still prices the rays at >= 1 ms each (divided by the threads).
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 200);
        let slow = Slow {
            inner: BruteForce::new(&mesh).unwrap(),
            calls: std::sync::atomic::AtomicUsize::new(0),
        };
        let rays: Vec<ProbeRay<f64>> = (0..16).flat_map(|_| probe_of(&mesh)).collect();
        assert_eq!(rays.len(), 4096);
        let t = probe_per_ray(&slow, &rays, Duration::from_millis(10)).unwrap();
        assert_eq!(slow.calls.into_inner(), 4096 / 16);
        let threads = rayon::current_num_threads() as f64;
        assert!(t >= 1e-3 / threads, "{t} s per ray");
    }

    fn probe_of(mesh: &TriangleMesh<f64>) -> Vec<ProbeRay<f64>> {
        random_rays(&mesh.bounds(), 256, 3)
            .into_iter()
            .enumerate()
            .map(|(i, ray)| ProbeRay {
                ray,
                any_hit: i % 2 == 1,
            })
            .collect()
    }

    #[test]
    fn tiny_scenes_get_brute_force_without_a_probe() {
        let tiny = uv_sphere(Vec3::ZERO, 1.0, 20);
        let c = choose(&tiny, 1_000_000, |_| panic!("no probe for a tiny scene")).unwrap();
        assert_eq!(c.config, AccelConfig::Brute);
        assert!(c.reason.contains("fewer than 64"), "{}", c.reason);
    }

    #[test]
    fn the_choice_is_valid_explained_and_answers_like_brute_force() {
        let mesh = random_soup(3_000, 9);
        let brute = BruteForce::new(&mesh).unwrap();
        for rays in [100, 100_000_000] {
            let c = choose(&mesh, rays, |a| {
                // The probe sees a built structure answering queries.
                assert!(a.stats().primitives == 3_000);
                Ok(probe_of(&mesh))
            })
            .unwrap();
            // The built structure is the one named.
            assert_eq!(c.accel.stats().kind, c.config.kind().name());
            // Explained in one line, naming the numbers it used.
            assert!(!c.reason.contains('\n'));
            assert!(c.reason.contains(&format!("{rays} rays")), "{}", c.reason);
            // The chosen estimate is the smallest probed one.
            let chosen = c
                .estimates
                .iter()
                .find(|e| e.config == c.config)
                .expect("the choice has an estimate");
            assert!(chosen.probed);
            for e in &c.estimates {
                assert!(chosen.total_s <= e.total_s, "{chosen:?} vs {e:?}");
            }
            for p in probe_of(&mesh) {
                assert_eq!(
                    c.accel.intersect(&p.ray).unwrap(),
                    brute.intersect(&p.ray).unwrap()
                );
            }
        }
    }

    #[test]
    fn few_rays_per_primitive_pick_the_fast_kdtree_build() {
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 2_000);
        let c = choose(&mesh, 1_000, |_| Ok(probe_of(&mesh))).unwrap();
        let kd = c
            .estimates
            .iter()
            .find(|e| e.config.kind() == AccelKind::KdTree)
            .unwrap();
        assert_eq!(kd.config, AccelConfig::KdTree(KdTreeParams::fast_build()));
        let c = choose(&mesh, 10_000_000, |_| Ok(probe_of(&mesh))).unwrap();
        let kd = c
            .estimates
            .iter()
            .find(|e| e.config.kind() == AccelKind::KdTree)
            .unwrap();
        assert_eq!(kd.config, AccelConfig::KdTree(KdTreeParams::default()));
    }

    #[test]
    fn a_refused_probe_ray_is_an_error() {
        let mesh = random_soup(500, 2);
        let bad = Ray {
            origin: Vec3::new(f64::NAN, 0.0, 0.0),
            direction: Vec3::new(1.0, 0.0, 0.0),
            t_min: 0.0,
            t_max: 1.0,
        };
        let err = choose(&mesh, 1000, |_| {
            Ok(vec![ProbeRay {
                ray: bad,
                any_hit: false,
            }])
        })
        .unwrap_err();
        assert!(err.to_string().contains("not finite"), "{err}");
    }
}
