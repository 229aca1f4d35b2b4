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
//!    from the caller (e.g. [`view_probe`]: tiles of neighbouring pixels of
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
//! Parameters, from `render choose-bench` (docs/choose-bench-2026-12-01.txt and
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
//!   and leads the kD-trees by up to 1.5×, where a grid wins anyway;
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

use crate::accel::{AccelConfig, AccelError, AccelKind, build_config};
use accel_core::{Aabb, PreparedRay, PrimHit, Vec3};
use accel_core::{Accelerator, PrimitiveSet, QueryError, Ray, Real};
use accel_kdtree::KdTreeParams;
use accel_octree::OctreeParams;
use rayon::prelude::*;
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

/// A probe ray and the query it stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeRay<T> {
    /// The ray.
    pub ray: Ray<T>,
    /// `occluded` (shadow and occlusion rays) rather than `intersect`.
    pub any_hit: bool,
}

/// How a probe ([`probe_per_ray`]) ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProbeStop {
    /// Every probe ray was traced (and traced again, warm).
    Complete,
    /// Stopped at the time budget: priced from the rays traced so far.
    TimeCap,
    /// Stopped because the estimate already lost by the given margin.
    Loses,
}

/// A probe's result: time per ray, and how much of the probe it is from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeTime {
    /// Seconds per ray.
    pub per_ray_s: f64,
    /// Seconds per ray of the rays traced in the spread-out order (the
    /// `per_ray_s` of a probe that stopped early; a complete probe's
    /// `per_ray_s` is the faster of this and a pass in the probe's order).
    /// Probes are compared on this, like with like.
    pub spread_per_ray_s: f64,
    /// Probe rays traced (all of them when [`ProbeStop::Complete`]).
    pub rays: usize,
    /// Why the probe ended.
    pub stop: ProbeStop,
}

/// Why a candidate was not built in full and probed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Skip {
    /// Its predicted build alone is past [`PROBE_SHARE`] of the best total.
    SlowBuild,
    /// The grid: its fullest cell holds this many references (more than
    /// [`GRID_CELL_LIMIT`]).
    FullCell(usize),
    /// The two-level octree: predicted to build about as fast as the default
    /// octree (not below [`TWO_LEVEL_SHARE`] of it), so nearly the same tree.
    SameTree,
}

/// How a candidate was estimated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Status {
    /// Built in full and timed on the probe.
    Probed(ProbeTime),
    /// Not probed, and why.
    Skipped(Skip),
}

/// One candidate's estimate.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    /// The structure and parameters.
    pub config: AccelConfig,
    /// Build time in seconds: measured if probed (or if skipped for a full
    /// cell), predicted otherwise.
    pub build_s: f64,
    /// Seconds per ray, measured on the probe (NaN when not probed).
    pub per_ray_s: f64,
    /// `build_s + expected rays × per_ray_s` (infinite when not probed).
    pub total_s: f64,
    /// Probed, or skipped and why.
    pub status: Status,
    /// Wall-clock seconds the chooser spent on this candidate (prediction,
    /// build and probe).
    pub cost_s: f64,
}

impl Estimate {
    /// Whether it was built in full and timed.
    #[must_use]
    pub fn probed(&self) -> bool {
        matches!(self.status, Status::Probed(_))
    }
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
/// `expected_rays` queries (see the module docs), and returns it built.
///
/// `probe` makes the probe rays: it is given the first structure built (the
/// grid, or the two-level octree where the grid is skipped), so it can trace
/// a few primary rays and spawn their secondary rays. At most [`MAX_PROBE`]
/// of them are timed.
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
    let mut probe_rays = probe(first.as_ref())?;
    thin(&mut probe_rays, MAX_PROBE);
    let t = probe_per_ray(first.as_ref(), &probe_rays, PROBE_TIME, f64::INFINITY)?;
    estimates.push(measured(
        first_config.clone(),
        first_build,
        t,
        rays,
        first_start.elapsed().as_secs_f64(),
    ));
    let mut best: (usize, Box<dyn Accelerator<T> + 'a>) = (estimates.len() - 1, first);
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
        let p = probe_per_ray(accel.as_ref(), &probe_rays, PROBE_TIME, lose_per_ray)?;
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

/// `0..n` as blocks of `block` consecutive indices, the blocks in
/// bit-reversed order (of the next power of two, skipping those past the
/// end): every prefix of whole blocks is spread evenly over `0..n`.
fn spread_order(n: usize, block: usize) -> Vec<usize> {
    let block = block.max(1);
    let blocks = n.div_ceil(block);
    if blocks <= 1 {
        return (0..n).collect();
    }
    let bits = usize::BITS - (blocks - 1).leading_zeros();
    (0..1usize << bits)
        .map(|i| i.reverse_bits() >> (usize::BITS - bits))
        .filter(|&b| b < blocks)
        .flat_map(|b| b * block..((b + 1) * block).min(n))
        .collect()
}

/// Seconds per probe ray for the chooser, stopping early where the rest of
/// the probe cannot change the decision.
///
/// The rays are traced in a spread-out order (blocks of [`PROBE_BLOCK`]
/// rays in bit-reversed order: every prefix samples the whole probe) in
/// chunks, the first of [`FIRST_CHUNK`]
/// rays, each next one doubling but sized to fit in what is left of
/// `budget` at the rate measured so far. The probe stops
/// - at `budget` ([`ProbeStop::TimeCap`]): the time per ray is that of the
///   rays traced so far, so a structure that serves the scene badly (a
///   millisecond or more per ray) cannot make the choice itself slow;
/// - once at least [`LOSE_MIN_RAYS`] rays and [`LOSE_MIN_TIME`] have taken
///   more than
///   `lose_per_ray` each on average ([`ProbeStop::Loses`]; pass infinity to
///   never stop for this; [`choose`] derives it from the best estimate's
///   spread-out pass, so that like is compared with like);
/// - otherwise after every ray ([`ProbeStop::Complete`]), timed again in the
///   probe's own (coherent) order, warm, two to four times (until
///   [`LOSE_MIN_TIME`] is spent), keeping the fastest pass, as [`per_ray`]
///   does.
///
/// # Errors
/// A probe ray the accelerator refuses.
pub fn probe_per_ray<T: Real>(
    accel: &dyn Accelerator<T>,
    rays: &[ProbeRay<T>],
    budget: Duration,
    lose_per_ray: f64,
) -> Result<ProbeTime, QueryError> {
    let budget = budget.as_secs_f64();
    let order = spread_order(rays.len(), PROBE_BLOCK);
    let (mut traced, mut spent) = (0usize, 0.0f64);
    let mut chunk = FIRST_CHUNK;
    while traced < rays.len() {
        let end = (traced + chunk).min(rays.len());
        spent += trace_seconds(accel, order[traced..end].iter().map(|&i| &rays[i]))?;
        traced = end;
        let per = spent / traced as f64;
        if traced == rays.len() {
            break;
        }
        if traced >= LOSE_MIN_RAYS && spent >= LOSE_MIN_TIME.as_secs_f64() && per > lose_per_ray {
            return Ok(ProbeTime {
                per_ray_s: per,
                spread_per_ray_s: per,
                rays: traced,
                stop: ProbeStop::Loses,
            });
        }
        if spent >= budget {
            return Ok(ProbeTime {
                per_ray_s: per,
                spread_per_ray_s: per,
                rays: traced,
                stop: ProbeStop::TimeCap,
            });
        }
        // Double, but only as many rays as fit in the budget left (at least
        // one); up to LOSE_MIN_RAYS first, so the losing test comes early.
        let fit = ((budget - spent) / per.max(1e-12)).ceil() as usize;
        chunk = (2 * chunk).min(fit.max(1));
        if traced < LOSE_MIN_RAYS {
            chunk = chunk.min(LOSE_MIN_RAYS - traced);
        }
    }
    // The whole probe was quick: time it again, warm and in order, at least
    // twice and until LOSE_MIN_TIME is spent (at most WARM_PASSES times),
    // keeping the fastest pass: one preemption on a busy machine can double
    // a pass of a few milliseconds.
    const WARM_PASSES: usize = 4;
    let (mut fastest, mut total) = (spent, spent);
    for pass in 0..WARM_PASSES {
        let t = trace_seconds(accel, rays.iter())?;
        fastest = fastest.min(t);
        total += t;
        if pass >= 1 && total >= LOSE_MIN_TIME.as_secs_f64() {
            break;
        }
    }
    let n = rays.len().max(1) as f64;
    Ok(ProbeTime {
        per_ray_s: fastest / n,
        spread_per_ray_s: spent / n,
        rays: rays.len(),
        stop: ProbeStop::Complete,
    })
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
        .with_min_len(8)
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
///
/// # Errors
/// A probe ray the accelerator refuses.
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

/// How many probe rays [`brute_per_ray`] times for `n` primitives.
fn brute_rays(n: usize, probe: usize) -> usize {
    // About 2·10^5 tests: a millisecond or two.
    (200_000 / n.max(1)).clamp(1, probe.max(1)).min(probe)
}

/// Seconds per ray of brute force: `n` tests, timed on a few probe rays.
pub fn brute_per_ray<T: Real, P: PrimitiveSet<T> + ?Sized>(prims: &P, rays: &[ProbeRay<T>]) -> f64 {
    let n = prims.len().max(1);
    let k = brute_rays(n, rays.len());
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
    fn wide_hits(&self) -> bool {
        self.prims.wide_hits()
    }
    fn watertight_triangle(&self, i: usize) -> Option<[Vec3<T>; 3]> {
        self.prims.watertight_triangle(self.index[i])
    }
    fn clipped_bounds(&self, i: usize, b: &Aabb<T>) -> Aabb<T> {
        self.prims.clipped_bounds(self.index[i], b)
    }
    fn clipped_bounds_split(&self, i: usize, b: &Aabb<T>, axis: usize, s: T) -> [Aabb<T>; 2] {
        self.prims.clipped_bounds_split(self.index[i], b, axis, s)
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

/// Side, in pixels, of the square tiles of a probe's primary rays.
pub const PROBE_TILE: u32 = 4;

/// About `primaries` primary rays through pixel centres of a `width ×
/// height` view, in [`PROBE_TILE`]² tiles spread evenly over it, tile by tile
/// and row by row within a tile. Every pixel once when `primaries` covers
/// the view.
fn tiled_primaries<T: Real>(
    camera: &accel_core::scenes::Camera,
    width: u32,
    height: u32,
    primaries: u32,
) -> Vec<Ray<T>> {
    let (width, height) = (width.max(1), height.max(1));
    let tile = PROBE_TILE.min(width).min(height);
    let (cols, rows) = (width.div_ceil(tile), height.div_ceil(tile));
    let wanted = f64::from(primaries.max(1)) / f64::from(tile * tile);
    let scale = (wanted / (f64::from(cols) * f64::from(rows)))
        .sqrt()
        .min(1.0);
    let pick = |count: u32| ((f64::from(count) * scale).round() as u32).clamp(1, count);
    let (tw, th) = (pick(cols), pick(rows));
    // The k-th of n tiles chosen from `count`, centred in its share.
    let chosen = |k: u32, n: u32, count: u32| {
        ((f64::from(k) + 0.5) * f64::from(count) / f64::from(n)) as u32
    };
    let mut rays = Vec::with_capacity((tw * th * tile * tile) as usize);
    for j in 0..th {
        let y0 = chosen(j, th, rows) * tile;
        for i in 0..tw {
            let x0 = chosen(i, tw, cols) * tile;
            for y in y0..(y0 + tile).min(height) {
                for x in x0..(x0 + tile).min(width) {
                    let (px, py) = (f64::from(x) + 0.5, f64::from(y) + 0.5);
                    rays.push(camera.ray_through(px, py, width, height));
                }
            }
        }
    }
    rays
}

/// Probe rays for a render of `view` at `width × height` with `ao`
/// occlusion rays per sample: about `primaries` primary rays
/// ([`PROBE_PRIMARIES`] for the chooser) in [`PROBE_TILE`]² tiles of
/// neighbouring pixels of the full-resolution view, the tiles spread evenly
/// over it, and from each primary hit the shadow ray and `ao` occlusion rays
/// the shader would trace, each after its primary ray (so that thinning
/// keeps the mix).
///
/// Tiles keep the coherence of the render's own rays: a structure whose
/// speed depends on it is priced as it will run. Primary rays of a coarser
/// view instead (one per 18×18 pixels for the chooser's final budget) priced
/// the kD-tree, whose descent branches on every node, about 1.5× too slow
/// (`render bench default --accel octree,kdtree` at 40×30: the kD-tree 0.95×
/// the octree; at 800×600: 1.7×, with the same nodes and primitives per ray).
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
    let primary: Vec<Ray<T>> = tiled_primaries(&view.camera, width, height, primaries);
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
    use accel_core::scenes::{random_rays, random_soup, sphere_in_tiled_box, uv_sphere};
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

    fn slow(mesh: &TriangleMesh<f64>) -> Slow<'_> {
        Slow {
            inner: BruteForce::new(mesh).unwrap(),
            calls: std::sync::atomic::AtomicUsize::new(0),
        }
    }

    #[test]
    fn a_slow_structure_is_cut_short_at_the_time_cap() {
        // 4096 probe rays at >= 1 ms each would take seconds; with a 10 ms
        // budget the probe stops after its first chunk or two, and still
        // prices the rays at >= 1 ms each (divided by the threads).
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 200);
        let slow = slow(&mesh);
        let rays: Vec<ProbeRay<f64>> = (0..16).flat_map(|_| probe_of(&mesh)).collect();
        assert_eq!(rays.len(), 4096);
        let t = probe_per_ray(&slow, &rays, Duration::from_millis(10), f64::INFINITY).unwrap();
        let calls = slow.calls.into_inner();
        assert_eq!(t.stop, ProbeStop::TimeCap);
        assert_eq!(t.rays, calls);
        // The first chunk overshoots the budget, a second one at most fills it.
        let threads = rayon::current_num_threads();
        assert!(
            calls >= FIRST_CHUNK && calls <= FIRST_CHUNK + 10 * threads,
            "{calls} rays traced"
        );
        assert!(t.per_ray_s >= 1e-3 / threads as f64, "{t:?}");
    }

    #[test]
    fn a_losing_structure_stops_after_its_first_rays() {
        // A generous time budget, but a candidate that needs more than 1 µs
        // per ray to win: it is stopped as losing after its first rays.
        let mesh = uv_sphere(Vec3::ZERO, 1.0, 200);
        let slow = slow(&mesh);
        let rays: Vec<ProbeRay<f64>> = (0..16).flat_map(|_| probe_of(&mesh)).collect();
        let t = probe_per_ray(&slow, &rays, Duration::from_secs(60), 1e-6).unwrap();
        assert_eq!(t.stop, ProbeStop::Loses);
        assert_eq!(slow.calls.into_inner(), t.rays);
        // At 1 ms per ray, LOSE_MIN_TIME is reached after a few chunks.
        let threads = rayon::current_num_threads();
        assert!(t.rays >= LOSE_MIN_RAYS, "{t:?}");
        assert!(t.rays <= LOSE_MIN_RAYS + 128 * threads, "{t:?}");
        assert!(t.per_ray_s >= 1e-3 / threads as f64, "{t:?}");
        // The same structure is not stopped where it may win.
        let few = &rays[..100];
        let slow = self::slow(&mesh);
        let t = probe_per_ray(&slow, few, Duration::from_secs(60), 1.0).unwrap();
        assert_eq!(t.stop, ProbeStop::Complete);
        assert_eq!(t.rays, 100);
        // Every ray, then two to four warm passes.
        let calls = slow.calls.into_inner();
        assert!(
            (300..=500).contains(&calls) && calls.is_multiple_of(100),
            "{calls}"
        );
    }

    #[test]
    fn the_probe_order_is_a_spread_out_permutation() {
        assert_eq!(spread_order(10, 1), [0, 8, 4, 2, 6, 1, 9, 5, 3, 7]);
        assert_eq!(spread_order(10, 3), [0, 1, 2, 6, 7, 8, 3, 4, 5, 9]);
        assert_eq!(spread_order(5, 16), [0, 1, 2, 3, 4]);
        for block in [1, 16] {
            for n in [0, 1, 2, 3, 1000, 4096] {
                let mut o = spread_order(n, block);
                // The first four blocks land in four different quarters.
                if n >= 4 * block {
                    let mut q: Vec<usize> = (0..4).map(|b| 4 * o[b * block] / n).collect();
                    q.sort_unstable();
                    assert_eq!(q, [0, 1, 2, 3], "n = {n}");
                }
                o.sort_unstable();
                assert_eq!(o, (0..n).collect::<Vec<_>>());
            }
        }
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
    fn tiny_work_gets_brute_force_without_a_probe() {
        let tiny = uv_sphere(Vec3::ZERO, 1.0, 20);
        let n = tiny.triangle_count() as u64;
        let rays = TINY_WORK / n;
        let c = choose(&tiny, rays, |_| panic!("no probe for so little work")).unwrap();
        assert_eq!(c.config, AccelConfig::Brute);
        assert!(c.reason.contains("less than a probe"), "{}", c.reason);
        // The same scene with more rays is probed: a grid may pay even here.
        let mut probed = false;
        let c = choose(&tiny, rays + 1, |_| {
            probed = true;
            Ok(probe_of(&tiny))
        })
        .unwrap();
        assert!(probed);
        assert_sound(&c, &tiny, &probe_of(&tiny));
    }

    /// The chosen estimate is probed and the smallest; the structure is the
    /// one named and answers like brute force.
    fn assert_sound(c: &Choice<'_, f64>, mesh: &TriangleMesh<f64>, probe: &[ProbeRay<f64>]) {
        assert_eq!(c.accel.stats().kind, c.config.kind().name());
        assert!(!c.reason.contains('\n'));
        let chosen = c
            .estimates
            .iter()
            .find(|e| e.config == c.config)
            .expect("the choice has an estimate");
        assert!(chosen.probed());
        for e in &c.estimates {
            assert!(chosen.total_s <= e.total_s, "{chosen:?} vs {e:?}");
        }
        let brute = BruteForce::new(mesh).unwrap();
        for p in probe {
            assert_eq!(
                c.accel.intersect(&p.ray).unwrap(),
                brute.intersect(&p.ray).unwrap()
            );
            assert_eq!(
                c.accel.occluded(&p.ray).unwrap(),
                brute.occluded(&p.ray).unwrap()
            );
        }
    }

    #[test]
    fn the_choice_is_valid_explained_and_answers_like_brute_force() {
        let mesh = random_soup(3_000, 9);
        for rays in [100, 100_000_000] {
            let c = choose(&mesh, rays, |a| {
                // The probe sees a built structure answering queries: the
                // grid, which suits a soup.
                assert_eq!(a.stats().primitives, 3_000);
                assert_eq!(a.stats().kind, "grid");
                Ok(probe_of(&mesh))
            })
            .unwrap();
            assert!(c.reason.contains(&format!("{rays} rays")), "{}", c.reason);
            assert_sound(&c, &mesh, &probe_of(&mesh));
            // Every candidate is accounted for, brute force included (the
            // finer grid too: 3000 primitives is a small scene).
            assert_eq!(c.estimates.len(), candidates().len() + 1);
            assert!(c.estimates.iter().any(|e| e.config == candidates()[1]));
            assert!(c.estimates.iter().all(|e| e.cost_s >= 0.0));
        }
    }

    #[test]
    fn a_dense_cell_skips_the_grid_without_probing_it() {
        // 20k triangles in a sphere of radius 1, in a box of side 10^4 whose
        // faces are tiled 20 × 20 (no triangle large enough for the grid to
        // set the sphere apart, `accel_core::parts`): the coarse grid's
        // cells are hundreds of units wide, so the sphere's cell (or cells)
        // hold thousands of references.
        let mesh = sphere_in_tiled_box(20_000, 1.0e4, 20);
        let mut first = "";
        let rays = random_rays(&Aabb::new(Vec3::splat(-2.0), Vec3::splat(2.0)), 512, 5);
        let probe: Vec<ProbeRay<f64>> = rays
            .into_iter()
            .map(|ray| ProbeRay {
                ray,
                any_hit: false,
            })
            .collect();
        for budget in [10_000, 100_000_000] {
            let c = choose(&mesh, budget, |a| {
                first = a.stats().kind;
                Ok(probe.clone())
            })
            .unwrap();
            assert_eq!(first, "octree", "the probe is made without the grid");
            let grid = &c.estimates[0];
            assert_eq!(grid.config, AccelConfig::grid(1.0));
            let Status::Skipped(Skip::FullCell(refs)) = grid.status else {
                panic!("{grid:?}");
            };
            assert!(refs > GRID_CELL_LIMIT, "{refs}");
            assert!(
                c.reason.contains(&format!("holds {refs} of")),
                "{}",
                c.reason
            );
            assert_eq!(
                c.estimates[1].config,
                AccelConfig::Octree(OctreeParams::two_level())
            );
            assert!(c.estimates[1].probed());
            assert_sound(&c, &mesh, &probe);
        }
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

    #[test]
    fn probe_primaries_come_in_tiles_of_neighbouring_pixels() {
        let camera = accel_core::scenes::GeneratedScene::Soup100k.camera();
        let key = |r: &Ray<f64>| r.direction.to_array().map(f64::to_bits);
        // Covering the view: every pixel once (a 10×7 view has partial tiles).
        let mut all: Vec<_> = tiled_primaries::<f64>(&camera, 10, 7, 70)
            .iter()
            .map(key)
            .collect();
        let mut want: Vec<_> = camera.rays::<f64>(10, 7).iter().map(key).collect();
        all.sort_unstable();
        want.sort_unstable();
        assert_eq!(all, want);
        // The chooser's probe of an 800×600 render: about 1,536 rays, in
        // runs of 16 whose directions differ by at most a few pixels.
        let rays = tiled_primaries::<f64>(&camera, 800, 600, PROBE_PRIMARIES);
        assert!((1300..=1800).contains(&rays.len()), "{}", rays.len());
        let pixel = camera.ray_through::<f64>(400.5, 300.5, 800, 600).direction
            - camera.ray_through::<f64>(401.5, 300.5, 800, 600).direction;
        for t in rays.chunks(16) {
            let spread = (t[0].direction - t[15].direction).length();
            assert!(
                spread < 6.0 * pixel.length(),
                "{spread} against {}",
                pixel.length()
            );
        }
        // And the tiles are spread: the first and last are far apart.
        let span = (rays[0].direction - rays[rays.len() - 1].direction).length();
        assert!(span > 300.0 * pixel.length());
    }
}
