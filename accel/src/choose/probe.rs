//! Probes: timing a structure on representative rays, stopping early where
//! the rest cannot change the decision; and the tiled primary rays of a
//! view that make a probe as coherent as a render's own rays.

use super::{
    FIRST_CHUNK, LOSE_MIN_RAYS, LOSE_MIN_TIME, PROBE_BLOCK, PROBE_TILE, ProbeRay, ProbeStop,
    ProbeTime,
};
use accel_core::{Accelerator, PreparedRay, PrimHit, PrimitiveSet, QueryError, Ray, Real};
use accel_scenes::Camera;
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Keeps at most `max` rays, evenly spaced, in their order.
pub(super) fn thin<T: Copy>(rays: &mut Vec<T>, max: usize) {
    if rays.len() > max {
        let step = rays.len() as f64 / max as f64;
        *rays = (0..max).map(|i| rays[(i as f64 * step) as usize]).collect();
    }
}

/// `0..n` as blocks of `block` consecutive indices, the blocks in
/// bit-reversed order (of the next power of two, skipping those past the
/// end): every prefix of whole blocks is spread evenly over `0..n`.
pub(super) fn spread_order(n: usize, block: usize) -> Vec<usize> {
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
///   never stop for this; [`super::choose_with_probe`] derives it from the best estimate's
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
pub(super) fn brute_rays(n: usize, probe: usize) -> usize {
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

/// About `primaries` primary rays through pixel centres of a `width ×
/// height` view, in [`PROBE_TILE`]² tiles spread evenly over it, tile by tile
/// and row by row within a tile. Every pixel once when `primaries` covers
/// the view.
pub fn tiled_primaries<T: Real>(
    camera: &Camera,
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
