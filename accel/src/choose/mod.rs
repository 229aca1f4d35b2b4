//! Choosing the accelerator and its parameters per scene and ray budget.
//!
//! The best structure depends on the scene *and* on how many rays it will
//! answer: for a few thousand rays the cheapest build wins, for millions the
//! fastest traversal. [`choose_with_probe`] (and [`choose`], with a default probe) estimates, for each candidate,
//!
//! ```text
//! total = build time + expected rays × time per ray
//! ```
//!
//! and picks the smallest, from scene statistics and a short probe:
//!
//! 1. Brute force without a probe where it costs next to nothing: at most
//!    [`TINY_WORK`] primitive tests in all (`n × expected rays`).
//! 2. The uniform grid of density [`GRID_DENSITY`] is built (`O(n)`, the
//!    cheapest build). Its statistics decide whether a grid can serve the
//!    scene at all: if its fullest cell holds more than [`GRID_CELL_LIMIT`]
//!    references (a small dense object in a large space the grid does not
//!    set apart as a part of its own: a sphere in a box of finely tiled
//!    walls), every ray through that cell tests them all, and the grid is
//!    skipped without a probe; the octree's two-level preset, which refines
//!    exactly such cells, takes its place as the first structure.
//! 3. The first structure makes and times the probe: representative rays
//!    from the caller (e.g. `render`'s `view_probe`: tiles of neighbouring pixels of
//!    the render's view, as coherent as its own rays, with their shadow and
//!    ambient-occlusion rays). Brute force is priced from a few of them.
//! 4. The other candidates (the finer grid [`FINE_GRID_DENSITY`] on scenes
//!    of at most [`FINE_GRID_MAX`] primitives, [`OctreeParams::two_level`],
//!    [`OctreeParams::default`], [`KdTreeParams::fast_build`]) get build
//!    times predicted from builds on a subsample of [`SUBSAMPLE`] primitives,
//!    scaled by `n` (grid, octree) or `n log n` (kD-tree), or, for the default
//!    octree after the two-level one, by the two-level octree's measured
//!    full build. A candidate whose
//!    predicted build alone costs more than [`PROBE_SHARE`] of the best
//!    total so far is not probed: it cannot win, or could win too little to
//!    pay for the probe. The two-level octree is the default octree cut
//!    after its first level of child grids, so it is probed only where it is
//!    predicted to build in less than [`TWO_LEVEL_SHARE`] of the default's
//!    time (where the default refines deep); elsewhere the two are nearly
//!    the same tree. The others are built in full and timed on the same
//!    probe.
//! 5. The structure with the smallest estimated total is returned already
//!    built (probing is not wasted on the winner), with a one-line reason.
//!
//! Every probe ([`probe_per_ray`]) traces the rays in a spread-out order
//! (blocks of neighbouring rays in bit-reversed order, so every prefix
//! covers the whole view) in chunks that start at [`FIRST_CHUNK`] rays, and
//! stops early: after [`PROBE_TIME`] (a slow structure is priced from the
//! rays traced so far), or, once it has run for [`LOSE_MIN_TIME`], when a
//! candidate's estimate is [`LOSE_FACTOR`] times the best total so far (it
//! loses: the rest of its probe would only confirm it). So no structure,
//! however bad for the scene, makes the choice itself slow, and no
//! structure fast enough to finish its probe in a few scheduler time slices
//! is judged on a few rays.
//!
//! Parameters, from `studies choose-bench` (docs/choose-bench-2026-12-01.txt and
//! docs/choose-bench-2026-12-01-quiet.txt):
//! - on scenes of 19k primitives and more, the grid wins only where its
//!   build dominates the total (small ray budgets), and there its cheapest
//!   build (`m = 1`) wins or comes within 2%: the finer grid (`m = 2`, the
//!   library default) is not probed there (its build is the chooser's
//!   largest cost on `terrain_1m`); on small meshes (1k–4k triangles:
//!   teapot, duck, low-resolution bunny) `m = 2` traces 1.3–1.9× faster than
//!   `m = 1` and wins small budgets, so it is probed up to
//!   [`FINE_GRID_MAX`] primitives;
//! - the kD-tree's fast-build preset was the best or within 6% of the best
//!   kD-tree on every scene and budget (its larger leaves trace as fast as
//!   the default's on triangles), so it is the kD-tree candidate; since
//!   (docs/choose-bench-2026-12-02.txt, -2026-12-03.txt) it is within 10% on every final
//!   render, and on previews of the scans the pbrt preset builds faster
//!   and leads the kD-trees by up to 1.5×, where a grid wins anyway. Those
//!   runs predate the preset's binned build (2026-12-06), which builds
//!   5–9× faster (2× on the 1M terrain) and traces 0.73–0.99× as fast as
//!   the default kD-tree; its
//!   build is still predicted from a subsample by `n log n` and its rays
//!   timed on the probe, so the estimates follow the new costs, but the
//!   choose-bench runs have not been repeated;
//! - the octree's two-level preset builds about 4× faster than the default
//!   on "teapot in a stadium" (1.3× since the octree builds the sphere
//!   apart) and wins its small budget.
//!
//! Timings are wall-clock on the current rayon pool, as the render will run;
//! on a busy machine they are noisy, and so is the choice between candidates
//! whose estimates are close (which is also when the choice matters least).
//! What is decided from statistics (the grid's fullest cell) or by a wide
//! margin (builds past [`PROBE_SHARE`], probes past [`LOSE_FACTOR`]) does not
//! depend on the noise.

mod estimate;
mod predict;
mod probe;
#[cfg(test)]
mod tests;

pub use estimate::{Choice, ChooseError, Estimate, ProbeRay, ProbeStop, ProbeTime, Skip, Status};
pub use probe::{brute_per_ray, per_ray, probe_per_ray, tiled_primaries};

use crate::{AccelConfig, AccelKind, AnyAccelerator, build_config};
use accel_core::{Accelerator, PrimitiveSet, QueryError, Ray, Real};
use accel_kdtree::KdTreeParams;
use accel_octree::OctreeParams;
use accel_scenes::{Camera, Z_UP, random_rays};
use predict::{Subsample, predict_build, timed_build};
use probe::{brute_rays, thin};
use std::time::{Duration, Instant};

/// Brute force is chosen without a probe when `primitives × expected rays`
/// is at most this many tests (about a millisecond): less than the probe
/// would cost. (Even 12 triangles are traced 4× faster with a grid, so
/// the size of the scene alone does not decide.)
pub const TINY_WORK: u64 = 200_000;
/// Primitives in the subsample that predicts octree and kD-tree build times.
pub const SUBSAMPLE: usize = 8192;
/// A candidate is probed (built in full) only if its predicted build time is
/// below this share of the best estimated total so far.
pub const PROBE_SHARE: f64 = 0.6;
/// The two-level octree is probed only if its predicted build time is below
/// this share of the default octree's (otherwise they are nearly the same
/// tree).
pub const TWO_LEVEL_SHARE: f64 = 0.6;
/// Most time spent timing one candidate's probe rays (the estimate then
/// comes from the part of the probe traced so far).
pub const PROBE_TIME: Duration = Duration::from_millis(150);
/// A probe stops once the candidate's estimated total is this many times the
/// best total so far (after at least [`LOSE_MIN_RAYS`] rays).
pub const LOSE_FACTOR: f64 = 2.0;
/// Rays a candidate's probe traces before it may be stopped as losing.
pub const LOSE_MIN_RAYS: usize = 64;
/// Time a candidate's probe spends before it may be stopped as losing: a
/// few scheduler time slices, so that one preemption on a busy machine
/// cannot make a fast structure look slow. A structure that traces the
/// whole probe in less (a few µs per ray) is never stopped as losing: its
/// probe is cheap anyway.
pub const LOSE_MIN_TIME: Duration = Duration::from_millis(30);
/// Probe rays are reordered in blocks of this many consecutive rays (a few
/// neighbouring primary rays with their shadow and occlusion rays), so that
/// a prefix of the probe is spread over the view but keeps the render's
/// local coherence.
pub const PROBE_BLOCK: usize = 16;
/// Rays in a probe's first timed chunk: a structure that takes milliseconds
/// per ray spends at most this many of them before the probe can stop.
pub const FIRST_CHUNK: usize = 16;
/// Most probe rays timed per candidate.
pub const MAX_PROBE: usize = 4096;
/// The grid density the chooser always considers: the cheapest build, and
/// the fastest grid wherever a grid wins on large scenes (see the module
/// docs).
pub const GRID_DENSITY: f64 = 1.0;
/// The finer grid density, considered on small scenes only.
pub const FINE_GRID_DENSITY: f64 = 2.0;
/// The most primitives for which the finer grid is considered.
pub const FINE_GRID_MAX: usize = 32_768;
/// The grid is not considered when its fullest cell (at [`GRID_DENSITY`])
/// holds more references than this: a ray through that cell tests every one
/// of them (a tree tests a handful), and probing it would be slow too.
pub const GRID_CELL_LIMIT: usize = 1024;

/// The candidates [`choose`] considers besides brute force, in probe order
/// (the second, the finer grid, only up to [`FINE_GRID_MAX`] primitives).
#[must_use]
pub fn candidates() -> [AccelConfig; 5] {
    [
        AccelConfig::grid(GRID_DENSITY),
        AccelConfig::grid(FINE_GRID_DENSITY),
        AccelConfig::Octree(OctreeParams::two_level()),
        AccelConfig::Octree(OctreeParams::default()),
        AccelConfig::KdTree(KdTreeParams::fast_build()),
    ]
}

/// Picks the accelerator and its parameters for `prims` and about
/// `expected_rays` queries, timed on [`default_probe`] rays, and returns it
/// built with a one-line reason. [`choose_with_probe`] takes the caller's
/// own probe rays (a renderer's: as coherent as its own rays) and reports
/// every candidate's estimate.
///
/// ```
/// use accel::{Accelerator, Ray, Vec3, choose};
///
/// let mesh = accel::scenes::uv_sphere(Vec3::new(0.0, 0.0, 0.0), 1.0, 2_000);
/// let (accel, reason) = choose(&mesh, 1_000_000)?;
/// println!("{}: {reason}", accel.kind());
/// let ray = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::new(0.0, 0.0, 1.0))?;
/// assert!(accel.intersect(&ray)?.is_some());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
///
/// # Errors
/// [`ChooseError`] if a candidate refuses the scene.
pub fn choose<T, P>(
    prims: &P,
    expected_rays: u64,
) -> Result<(AnyAccelerator<'_, T, P>, String), ChooseError>
where
    T: Real,
    P: PrimitiveSet<T> + ?Sized,
{
    let choice = choose_with_probe(prims, expected_rays, default_probe)?;
    Ok((choice.accel, choice.reason))
}

/// The probe [`choose`] uses: [`PROBE_PRIMARIES`] primary rays (nearest
/// hit) of an 800×600 view framing the structure's bounds
/// ([`Camera::frame`] from [`Camera::DEFAULT_SIDE`]), in tiles of
/// neighbouring pixels ([`tiled_primaries`]), each followed by a random
/// ray through the bounds as an any-hit query ([`random_rays`]: incoherent,
/// as secondary rays are).
///
/// # Errors
/// Never for finite bounds; a [`QueryError`] is passed on from the
/// structure otherwise.
pub fn default_probe<T: Real>(accel: &dyn Accelerator<T>) -> Result<Vec<ProbeRay<T>>, QueryError> {
    let bounds = accel.bounds();
    if bounds.is_empty() {
        return Ok(Vec::new());
    }
    let b = bounds.cast::<f64>();
    let camera = Camera::frame(&b, Camera::DEFAULT_SIDE, Z_UP);
    let primary: Vec<Ray<T>> = tiled_primaries(&camera, 800, 600, PROBE_PRIMARIES);
    let random: Vec<Ray<T>> = random_rays(&b, primary.len(), 0xC405);
    Ok(primary
        .into_iter()
        .zip(random)
        .flat_map(|(p, r)| {
            [
                ProbeRay {
                    ray: p,
                    any_hit: false,
                },
                ProbeRay {
                    ray: r,
                    any_hit: true,
                },
            ]
        })
        .collect())
}

/// Picks the accelerator and its parameters for `prims` and about
/// `expected_rays` queries (see the module docs), and returns it built.
///
/// `probe` makes the probe rays: it is given the first structure built (the
/// grid, or the two-level octree where the grid is skipped), so it can trace
/// a few primary rays and spawn their secondary rays. At most [`MAX_PROBE`]
/// of them are timed.
///
/// # Errors
/// [`ChooseError`] if a candidate refuses the scene or a probe ray is invalid.
pub fn choose_with_probe<'a, T, P, F>(
    prims: &'a P,
    expected_rays: u64,
    probe: F,
) -> Result<Choice<'a, T, P>, ChooseError>
where
    T: Real,
    P: PrimitiveSet<T> + ?Sized,
    F: FnOnce(&dyn Accelerator<T>) -> Result<Vec<ProbeRay<T>>, QueryError>,
{
    let start = Instant::now();
    let n = prims.len();
    let rays = expected_rays as f64;
    if (n as u64).saturating_mul(expected_rays) <= TINY_WORK {
        let config = AccelConfig::Brute;
        let accel = build_config(&config, prims)?;
        return Ok(Choice {
            reason: format!(
                "{n} primitives × {expected_rays} rays: at most {TINY_WORK} tests, less than a probe"
            ),
            config,
            accel,
            estimates: Vec::new(),
            elapsed: start.elapsed(),
        });
    }
    let [grid_config, fine_grid, two_level, octree, kdtree] = candidates();
    let mut estimates = Vec::new();

    // 2. The grid: cheapest to build; its fullest cell says whether it can
    // serve the scene.
    let (grid, grid_build) = timed_build(&grid_config, prims)?;
    let fullest = grid.stats().max_leaf_references;
    let (first_config, first, first_build, first_start) = if fullest > GRID_CELL_LIMIT {
        drop(grid);
        estimates.push(Estimate {
            config: grid_config,
            build_s: grid_build,
            per_ray_s: f64::NAN,
            total_s: f64::INFINITY,
            status: Status::Skipped(Skip::FullCell(fullest)),
            cost_s: start.elapsed().as_secs_f64(),
        });
        let t = Instant::now();
        let (accel, build) = timed_build(&two_level, prims)?;
        (two_level.clone(), accel, build, t)
    } else {
        (grid_config, grid, grid_build, start)
    };

    // 3. The probe, made and timed by the first structure; brute force
    // priced from a few of its rays.
    let mut probe_rays = probe(&first)?;
    thin(&mut probe_rays, MAX_PROBE);
    let t = probe_per_ray(&first, &probe_rays, PROBE_TIME, f64::INFINITY)?;
    estimates.push(measured(
        first_config.clone(),
        first_build,
        t,
        rays,
        first_start.elapsed().as_secs_f64(),
    ));
    let mut best: (usize, AnyAccelerator<'a, T, P>) = (estimates.len() - 1, first);
    let t = Instant::now();
    let brute = brute_per_ray(prims, &probe_rays);
    let brute_probe = ProbeTime {
        per_ray_s: brute,
        spread_per_ray_s: brute,
        rays: brute_rays(n, probe_rays.len()),
        stop: ProbeStop::Complete,
    };
    estimates.push(measured(
        AccelConfig::Brute,
        0.0,
        brute_probe,
        rays,
        t.elapsed().as_secs_f64(),
    ));
    if estimates[estimates.len() - 1].total_s < estimates[best.0].total_s {
        best = (
            estimates.len() - 1,
            build_config(&AccelConfig::Brute, prims)?,
        );
    }

    // 4. The rest: predicted builds, full probes where they may pay.
    let t = Instant::now();
    let sample = Subsample::new(prims, SUBSAMPLE);
    let mut rest: Vec<(AccelConfig, f64)> = Vec::new();
    // A structure of the first one's kind is predicted from the first one's
    // full build, scaled by their ratio on the subsample (a deep octree
    // builds slower than linearly in n: its subsample is shallower).
    let first_sample = if first_config.kind() == AccelKind::Octree {
        Some(predict_build(&first_config, &sample, n)?)
    } else {
        None
    };
    let fine = (n <= FINE_GRID_MAX && first_config.kind() == AccelKind::Grid).then_some(fine_grid);
    for config in fine.into_iter().chain([two_level, octree, kdtree]) {
        if config != first_config {
            let mut predicted = predict_build(&config, &sample, n)?;
            if let Some(f) = first_sample.filter(|_| config.kind() == first_config.kind()) {
                predicted *= first_build / f.max(1e-9);
            }
            rest.push((config, predicted));
        }
    }
    // The predictions' cost is shared out among the candidates predicted.
    let predict_cost = t.elapsed().as_secs_f64() / rest.len().max(1) as f64;
    let default_octree_build = rest
        .iter()
        .find(|(c, _)| *c == AccelConfig::Octree(OctreeParams::default()))
        .map(|r| r.1);
    for (config, predicted) in rest {
        let t = Instant::now();
        let best_total = estimates[best.0].total_s;
        let skip = if config == AccelConfig::Octree(OctreeParams::two_level())
            && default_octree_build.is_some_and(|d| predicted >= TWO_LEVEL_SHARE * d)
        {
            Some(Skip::SameTree)
        } else if predicted >= PROBE_SHARE * best_total {
            Some(Skip::SlowBuild)
        } else {
            None
        };
        if let Some(skip) = skip {
            estimates.push(Estimate {
                config,
                build_s: predicted,
                per_ray_s: f64::NAN,
                total_s: f64::INFINITY,
                status: Status::Skipped(skip),
                cost_s: predict_cost,
            });
            continue;
        }
        let (accel, build) = timed_build(&config, prims)?;
        // Like with like: the best's total from its spread-out pass.
        let best_spread = match estimates[best.0].status {
            Status::Probed(p) => estimates[best.0].build_s + rays * p.spread_per_ray_s,
            Status::Skipped(_) => best_total,
        };
        let lose_per_ray = (LOSE_FACTOR * best_spread - build) / rays;
        let p = probe_per_ray(&accel, &probe_rays, PROBE_TIME, lose_per_ray)?;
        let cost = predict_cost + t.elapsed().as_secs_f64();
        estimates.push(measured(config, build, p, rays, cost));
        if estimates[estimates.len() - 1].total_s < best_total {
            best = (estimates.len() - 1, accel);
        }
    }

    let chosen = &estimates[best.0];
    let reason = reason(n, expected_rays, chosen, &estimates);
    Ok(Choice {
        config: chosen.config.clone(),
        accel: best.1,
        reason,
        estimates,
        elapsed: start.elapsed(),
    })
}

fn measured(
    config: AccelConfig,
    build_s: f64,
    probe: ProbeTime,
    rays: f64,
    cost_s: f64,
) -> Estimate {
    Estimate {
        config,
        build_s,
        per_ray_s: probe.per_ray_s,
        total_s: build_s + rays * probe.per_ray_s,
        status: Status::Probed(probe),
        cost_s,
    }
}

fn fmt_s(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2} s")
    } else {
        format!("{:.1} ms", s * 1e3)
    }
}

/// The one-line reason: the winner's estimate against the others'.
fn reason(n: usize, rays: u64, chosen: &Estimate, all: &[Estimate]) -> String {
    let others: Vec<String> = all
        .iter()
        .filter(|e| e.config != chosen.config)
        .map(|e| match e.status {
            Status::Probed(p) => match p.stop {
                ProbeStop::Complete => format!("{} {}", e.config, fmt_s(e.total_s)),
                ProbeStop::TimeCap => format!(
                    "{} {} (time cap after {} rays)",
                    e.config,
                    fmt_s(e.total_s),
                    p.rays
                ),
                ProbeStop::Loses => format!(
                    "{} ~{} (loses: stopped after {} rays)",
                    e.config,
                    fmt_s(e.total_s),
                    p.rays
                ),
            },
            Status::Skipped(Skip::SlowBuild) => {
                format!("{} not probed (build ~{})", e.config, fmt_s(e.build_s))
            }
            Status::Skipped(Skip::FullCell(refs)) => format!(
                "{} skipped (its fullest cell holds {refs} of {n} primitives: a ray through it tests them all)",
                e.config
            ),
            Status::Skipped(Skip::SameTree) => format!(
                "{} not probed (build ~{}, about the default's: same tree)",
                e.config,
                fmt_s(e.build_s)
            ),
        })
        .collect();
    let probe = match chosen.status {
        Status::Probed(p) => p.rays,
        Status::Skipped(_) => 0,
    };
    format!(
        "{n} primitives, {rays} rays: est. build {} + rays {} = {} (probe of {probe} rays); {}",
        fmt_s(chosen.build_s),
        fmt_s(chosen.total_s - chosen.build_s),
        fmt_s(chosen.total_s),
        others.join(", ")
    )
}

/// The number of primary rays of a probe: [`default_probe`]'s, and a
/// renderer's view probe's (`render`'s `view_probe`).
pub const PROBE_PRIMARIES: u32 = 1536;

/// Side, in pixels, of the square tiles of a probe's primary rays.
pub const PROBE_TILE: u32 = 4;
