//! `render bench`: build time, memory and Mrays/s per accelerator and ray kind.
//!
//! Ray sets, generated once and shared by every accelerator:
//! - **primary**: one ray through the centre of each pixel of a
//!   `--width × --height` view (coherent; nearest hit);
//! - **shadow**: from each primary hit that faces the light, towards it
//!   (`t ∈ [0, 1]`; any hit);
//! - **diffuse**: from each primary hit, one cosine-distributed direction
//!   (incoherent; nearest hit).
//!
//! Or, with `--rays FILE`, the rays of a binary ray file (nearest hit). Each
//! set is traced once with counters (hits, a sum of hit `t` in ray order, a
//! digest of every answer's bits, nodes and tests per ray), then timed on one
//! thread and on all threads, repeating passes for at least `--min-time`
//! seconds. Every accelerator must give the same hits and digest as the
//! first; a disagreement is an error.

use crate::scene::View;
use crate::shade::{cosine_direction, mix, spawn};
use accel::{AccelConfig, AccelKind};
use accel_core::spawn::SpawnOffset;
use accel_core::{
    Accelerator, PrimitiveSet, QueryError, Ray, Real, TraversalCounters, TriangleMesh,
};
use accel_scenes::SplitMix64;
use rayon::prelude::*;
use serde::Serialize;
use std::time::{Duration, Instant};

/// `primary 262144, shadow 73891, …`: each set's kind and size.
#[must_use]
pub fn describe_sets<T>(sets: &[RaySet<T>]) -> String {
    sets.iter()
        .map(|s| format!("{} {}", s.kind.name(), s.rays.len()))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Brute force joins the default list only below this many ray–triangle
/// tests per pass over all sets.
pub const BRUTE_BUDGET: f64 = 2e8;

/// Which rays a set holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum RayKind {
    /// Camera rays.
    Primary,
    /// Hit point to light.
    Shadow,
    /// Cosine-distributed from hit points.
    Diffuse,
    /// Read from a ray file.
    File,
}

impl RayKind {
    /// Name for reports.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::Primary => "primary",
            Self::Shadow => "shadow",
            Self::Diffuse => "diffuse",
            Self::File => "file",
        }
    }

    /// Shadow rays ask for any hit; the others for the nearest.
    #[must_use]
    pub const fn any_hit(self) -> bool {
        matches!(self, Self::Shadow)
    }
}

/// A set of rays of one kind.
#[derive(Clone, Debug)]
pub struct RaySet<T> {
    /// What they are.
    pub kind: RayKind,
    /// The rays.
    pub rays: Vec<Ray<T>>,
    /// For the rays of an image, row by row: its width. The bundle passes
    /// of [`measure_set`] then trace them by tiles of [`TILE`] × [`TILE`]
    /// pixels, as a renderer would ([`RaySet::bundle_order`]).
    pub image_width: Option<u32>,
}

/// The side of the tiles the bundle passes trace an image's rays by.
pub const TILE: usize = 8;

pub use accel_scenes::camera::by_tiles;

impl<T> RaySet<T> {
    /// `items`, one per ray of this set in the set's order (the rays
    /// themselves, their indices, their answers), in the order the bundle
    /// passes trace the rays: an image's by [`TILE`] × [`TILE`] tiles
    /// ([`by_tiles`]), any other set's as they are.
    #[must_use]
    pub fn bundle_order<'a, I: Copy>(&self, items: &'a [I]) -> std::borrow::Cow<'a, [I]> {
        match self.image_width {
            Some(w) => std::borrow::Cow::Owned(by_tiles(items, w as usize, TILE)),
            None => std::borrow::Cow::Borrowed(items),
        }
    }
}

/// The structure that makes generated rays ([`generate_rays`]): any gives
/// the same hits, so the same rays, and the kD-tree is slow on no scene
/// (the grid tests every triangle of a small dense mesh in a huge box per
/// ray: minutes per set on the teapot in a stadium).
pub const RAY_GENERATOR: AccelKind = AccelKind::KdTree;

/// Generates the primary, shadow and diffuse sets for `view`, using `accel`
/// for the primary hits (every accelerator gives the same ones), with
/// secondary rays spawned by the error-bound offset, their pixels taken
/// tile by tile ([`by_tiles`]).
///
/// # Errors
/// A [`QueryError`] if a ray is not valid in this precision.
pub fn generate_rays<T: Real>(
    accel: &dyn Accelerator<T>,
    mesh: &TriangleMesh<T>,
    view: &View,
    width: u32,
    height: u32,
) -> Result<Vec<RaySet<T>>, QueryError> {
    Ok(generate_rays_from(accel, mesh, view, width, height, SpawnOffset::ErrorBound)?.sets)
}

/// Ray sets with, for each secondary ray, the triangle it leaves.
#[derive(Clone, Debug)]
pub struct GeneratedRays<T> {
    /// Primary, shadow and diffuse sets, in that order.
    pub sets: Vec<RaySet<T>>,
    /// The triangle each shadow ray leaves.
    pub shadow_sources: Vec<u32>,
    /// The triangle each diffuse ray leaves.
    pub diffuse_sources: Vec<u32>,
}

/// [`generate_rays`] with the spawn offset given, also telling which
/// triangle each secondary ray leaves (to count self-intersections).
///
/// # Errors
/// A [`QueryError`] if a ray is not valid in this precision.
pub fn generate_rays_from<T: Real>(
    accel: &dyn Accelerator<T>,
    mesh: &TriangleMesh<T>,
    view: &View,
    width: u32,
    height: u32,
    offset: SpawnOffset<T>,
) -> Result<GeneratedRays<T>, QueryError> {
    let primary: Vec<Ray<T>> = view.camera.rays(width, height);
    let hits: Vec<_> = primary
        .par_iter()
        .map(|r| accel.intersect(r))
        .collect::<Result<_, _>>()?;
    let mut shadow = Vec::new();
    let mut diffuse = Vec::new();
    let mut shadow_sources = Vec::new();
    let mut diffuse_sources = Vec::new();
    // The secondary rays of the hits tile by tile (by_tiles's order), as a
    // renderer spawns them: a bundle of them holds neighbouring pixels'.
    let pixels: Vec<usize> = (0..primary.len()).collect();
    for i in by_tiles(&pixels, width as usize, TILE) {
        let (ray, Some(hit)) = (&primary[i], &hits[i]) else {
            continue;
        };
        let s = spawn(mesh, ray, hit, offset);
        let to_light = view.light - s.origin;
        if s.normal.dot(to_light) > 0.0 {
            shadow.push(Ray {
                origin: s.origin.cast(),
                direction: to_light.cast(),
                t_min: T::ZERO,
                t_max: T::ONE,
            });
            shadow_sources.push(hit.prim);
        }
        let mut rng = SplitMix64::new(mix(0xD1FF_u64, i as u64));
        diffuse.push(Ray {
            origin: s.origin.cast(),
            direction: cosine_direction(s.normal, &mut rng).cast(),
            t_min: T::ZERO,
            t_max: T::INFINITY,
        });
        diffuse_sources.push(hit.prim);
    }
    let sets = vec![
        RaySet {
            kind: RayKind::Primary,
            rays: primary,
            image_width: Some(width),
        },
        RaySet {
            kind: RayKind::Shadow,
            rays: shadow,
            image_width: None,
        },
        RaySet {
            kind: RayKind::Diffuse,
            rays: diffuse,
            image_width: None,
        },
    ];
    Ok(GeneratedRays {
        sets,
        shadow_sources,
        diffuse_sources,
    })
}

/// The answers to one ray set, which every accelerator must share.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Answers {
    /// Rays hitting something (nearest hit found, or occluded).
    pub hits: u64,
    /// Sum of the hit parameters `t` in ray order, in `f64` (nearest-hit sets
    /// only): compare with other tools on identical rays.
    pub t_sum: Option<f64>,
    /// Digest of every answer's bits, in ray order (hex): equal digests mean
    /// bit-for-bit equal answers.
    #[serde(serialize_with = "hex")]
    pub digest: u64,
}

impl Answers {
    /// The answers of an any-hit set from each ray's "blocked" flag, in ray
    /// order.
    #[must_use]
    pub fn of_occluded(blocked: impl IntoIterator<Item = bool>) -> Self {
        let mut hits = 0u64;
        let mut digest = 0u64;
        for b in blocked {
            hits += u64::from(b);
            digest = mix(digest, u64::from(b));
        }
        Self {
            hits,
            t_sum: None,
            digest,
        }
    }

    /// The answers of a nearest-hit set from each ray's hit, in ray order:
    /// its `t` and the words to digest (a miss is `None`). With the words of
    /// [`accel_core::Hit::bit_key`] the digest is [`crate::shade::mix_hit`]'s.
    #[must_use]
    pub fn of_nearest<const N: usize>(
        hits: impl IntoIterator<Item = Option<(f64, [u64; N])>>,
    ) -> Self {
        let mut count = 0u64;
        let mut t_sum = 0.0f64;
        let mut digest = 0u64;
        for h in hits {
            match h {
                None => digest = mix(digest, u64::MAX),
                Some((t, words)) => {
                    count += 1;
                    t_sum += t;
                    digest = words.into_iter().fold(digest, mix);
                }
            }
        }
        Self {
            hits: count,
            t_sum: Some(t_sum),
            digest,
        }
    }
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's signature
fn hex<S: serde::Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&format!("{v:016x}"))
}

/// The figures of one accelerator on one ray set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SetResult {
    /// Ray kind.
    pub kind: RayKind,
    /// `intersect` or `occluded`.
    pub query: &'static str,
    /// Rays in the set.
    pub rays: u64,
    /// What they hit.
    #[serde(flatten)]
    pub answers: Answers,
    /// Mean cells or nodes visited per ray.
    pub nodes_per_ray: f64,
    /// Mean primitive tests per ray.
    pub tests_per_ray: f64,
    /// Millions of rays per second on one thread.
    pub mrays_one_thread: f64,
    /// Millions of rays per second on all threads.
    pub mrays_all_threads: f64,
    /// Millions of rays per second on one thread through the bundle
    /// queries ([`Accelerator::intersect_bundle`],
    /// [`Accelerator::occluded_bundle`]), [`BUNDLE`] rays at a time: an
    /// image's rays by tiles ([`RaySet::image_width`]), others in the set's
    /// order (shadow and diffuse rays of neighbouring pixels of a row).
    pub mrays_bundles_one_thread: f64,
}

/// Rays per bundle in [`measure_set`]'s bundle passes.
pub const BUNDLE: usize = 64;

/// Hits of one uncounted pass through the bundle queries, [`BUNDLE`] rays
/// at a time, on this thread.
///
/// # Errors
/// The first ray refused.
pub fn count_bundle_hits<T: Real>(
    accel: &dyn Accelerator<T>,
    any_hit: bool,
    rays: &[Ray<T>],
) -> Result<u64, QueryError> {
    let mut hits = 0;
    let mut nearest = [Ok(None); BUNDLE];
    let mut any = [Ok(false); BUNDLE];
    for bundle in rays.chunks(BUNDLE) {
        let n = bundle.len();
        if any_hit {
            accel.occluded_bundle(bundle, &mut any[..n]);
            for a in &any[..n] {
                hits += u64::from((*a)?);
            }
        } else {
            accel.intersect_bundle(bundle, &mut nearest[..n]);
            for a in &nearest[..n] {
                hits += u64::from(a.as_ref().map_err(|e| *e)?.is_some());
            }
        }
    }
    Ok(hits)
}

/// The figures of one accelerator.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccelResult {
    /// Its name.
    pub accel: &'static str,
    /// Its parameters ([`AccelConfig::label`]).
    pub config: String,
    /// Build time in milliseconds.
    pub build_ms: f64,
    /// Heap bytes of the structure.
    pub bytes: u64,
    /// Cells or nodes.
    pub nodes: u64,
    /// Primitive references.
    pub references: u64,
    /// Cells or leaves that can hold references.
    pub leaves: u64,
    /// Of those, the ones holding none.
    pub empty_leaves: u64,
    /// The most references in one cell or leaf.
    pub max_leaf_references: u64,
    /// Structure-specific figures: a grid's resolution, a tree's depth and
    /// SAH cost ([`accel_core::AccelStats::extra`]).
    pub extra: std::collections::BTreeMap<&'static str, f64>,
    /// One entry per ray set.
    pub sets: Vec<SetResult>,
}

/// A ray set's size, for the report.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SetInfo {
    /// Ray kind.
    pub kind: RayKind,
    /// Number of rays.
    pub rays: u64,
}

/// The whole benchmark, as printed and written to JSON.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BenchReport {
    /// Scene name or file.
    pub scene: String,
    /// Triangles in the scene.
    pub triangles: u64,
    /// `f32` or `f64`.
    pub precision: &'static str,
    /// Threads of the multi-threaded runs.
    pub threads: usize,
    /// Where the rays came from.
    pub ray_source: String,
    /// The ray sets.
    pub ray_sets: Vec<SetInfo>,
    /// Minimum timing per figure, seconds.
    pub min_time_s: f64,
    /// One entry per accelerator.
    pub accelerators: Vec<AccelResult>,
    /// Whether every accelerator gave the same answers on every set.
    pub agree: bool,
}

/// The default accelerator list: every available structure, and brute force
/// when `triangles × rays` stays under [`BRUTE_BUDGET`].
#[must_use]
pub fn default_accels(triangles: usize, rays: usize) -> Vec<AccelKind> {
    let brute_ok = triangles as f64 * rays as f64 <= BRUTE_BUDGET;
    AccelKind::ALL
        .into_iter()
        .filter(|&k| k != AccelKind::Brute || brute_ok)
        .collect()
}

/// One query on one ray: whether it hit, the hit, and the work.
fn answer<T: Real>(
    accel: &dyn Accelerator<T>,
    any_hit: bool,
    ray: &Ray<T>,
) -> Result<(Option<accel_core::Hit<T>>, bool, TraversalCounters), QueryError> {
    let mut c = TraversalCounters::default();
    if any_hit {
        let blocked = accel.occluded_counted(ray, &mut c)?;
        Ok((None, blocked, c))
    } else {
        let hit = accel.intersect_counted(ray, &mut c)?;
        Ok((hit, hit.is_some(), c))
    }
}

/// Hits of one uncounted pass.
pub fn count_hits<T: Real>(
    accel: &dyn Accelerator<T>,
    any_hit: bool,
    rays: &[Ray<T>],
    parallel: bool,
) -> Result<u64, QueryError> {
    let one = |r: &Ray<T>| -> Result<u64, QueryError> {
        Ok(u64::from(if any_hit {
            accel.occluded(r)?
        } else {
            accel.intersect(r)?.is_some()
        }))
    };
    if parallel {
        rays.par_iter()
            .with_min_len(64)
            .map(one)
            .try_reduce(|| 0, |a, b| Ok(a + b))
    } else {
        rays.iter().try_fold(0, |n, r| Ok(n + one(r)?))
    }
}

/// Repeats `pass` until `min_time` has passed and at least `min_passes`
/// passes ran (at least one); returns the time of each pass.
///
/// # Errors
/// The first error of a pass.
pub fn pass_times<E>(
    min_time: Duration,
    min_passes: usize,
    mut pass: impl FnMut() -> Result<(), E>,
) -> Result<Vec<Duration>, E> {
    let start = Instant::now();
    let mut times = Vec::new();
    loop {
        let t0 = Instant::now();
        pass()?;
        times.push(t0.elapsed());
        if times.len() >= min_passes.max(1) && start.elapsed() >= min_time {
            return Ok(times);
        }
    }
}

/// The median of `times` (the mean of the middle two for an even count;
/// zero for none).
#[must_use]
pub fn median(times: &[Duration]) -> Duration {
    let mut sorted = times.to_vec();
    sorted.sort_unstable();
    let n = sorted.len();
    match n {
        0 => Duration::ZERO,
        _ if n % 2 == 1 => sorted[n / 2],
        _ => (sorted[n / 2 - 1] + sorted[n / 2]) / 2,
    }
}

/// Repeats `pass` until `min_time` has passed (at least once); returns the
/// mean time per pass.
fn time_passes(
    min_time: Duration,
    pass: impl FnMut() -> Result<(), QueryError>,
) -> Result<Duration, QueryError> {
    let times = pass_times(min_time, 1, pass)?;
    let total: Duration = times.iter().sum();
    Ok(total / u32::try_from(times.len()).unwrap_or(u32::MAX))
}

/// Why a set could not be measured.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MeasureError {
    /// A ray was refused.
    #[error("{kind} ray {index}: {source}")]
    Query {
        /// Which set.
        kind: &'static str,
        /// Which ray (the first refused one found).
        index: usize,
        /// Why.
        source: QueryError,
    },
    /// A timed pass found other hits than the counted one: a bug.
    #[error("{accel} gave {counted} hits on {kind} rays when counting but {timed} when timed")]
    Unstable {
        /// Accelerator.
        accel: &'static str,
        /// Set.
        kind: &'static str,
        /// Counted-pass hits.
        counted: u64,
        /// Timed-pass hits.
        timed: u64,
    },
}

/// Millions of rays per second for `rays` rays traced in `per_pass`.
#[must_use]
pub fn rays_per_second(rays: usize, per_pass: Duration) -> f64 {
    let s = per_pass.as_secs_f64();
    if s > 0.0 {
        rays as f64 / s / 1e6
    } else {
        f64::INFINITY
    }
}

/// Measures one accelerator on one set: a counted pass (answers, work), then
/// timed passes on one thread and on the current rayon pool.
///
/// # Errors
/// [`MeasureError`] if a ray is refused or the passes disagree.
pub fn measure_set<T: Real>(
    accel: &dyn Accelerator<T>,
    name: &'static str,
    set: &RaySet<T>,
    min_time: Duration,
) -> Result<SetResult, MeasureError> {
    let any_hit = set.kind.any_hit();
    let kind = set.kind.name();
    let answers: Vec<_> = set
        .rays
        .par_iter()
        .enumerate()
        .map(|(index, r)| {
            answer(accel, any_hit, r).map_err(|source| MeasureError::Query {
                kind,
                index,
                source,
            })
        })
        .collect::<Result<_, _>>()?;
    let mut work = TraversalCounters::default();
    for (_, _, c) in &answers {
        work.add(c);
    }
    let summary = if any_hit {
        Answers::of_occluded(answers.iter().map(|a| a.1))
    } else {
        // The digest covers every bit of each hit: t, primitive, u and v.
        Answers::of_nearest(answers.iter().map(|a| {
            a.0.map(|h| {
                let (t, prim, u, v) = h.bit_key();
                (h.t.to_f64(), [t, u64::from(prim), u, v])
            })
        }))
    };
    let hits = summary.hits;
    let n = set.rays.len().max(1) as f64;
    let query_error = |source| MeasureError::Query {
        kind,
        index: 0,
        source,
    };
    let check = |timed: u64| {
        if timed == hits {
            Ok(())
        } else {
            Err(MeasureError::Unstable {
                accel: name,
                kind,
                counted: hits,
                timed,
            })
        }
    };
    let mut timed_hits = 0;
    let one = time_passes(min_time, || {
        timed_hits = count_hits(accel, any_hit, &set.rays, false)?;
        Ok(())
    })
    .map_err(query_error)?;
    check(timed_hits)?;
    let all = time_passes(min_time, || {
        timed_hits = count_hits(accel, any_hit, &set.rays, true)?;
        Ok(())
    })
    .map_err(query_error)?;
    check(timed_hits)?;
    let bundled = set.bundle_order(&set.rays);
    let bundles = time_passes(min_time, || {
        timed_hits = count_bundle_hits(accel, any_hit, &bundled)?;
        Ok(())
    })
    .map_err(query_error)?;
    check(timed_hits)?;
    Ok(SetResult {
        kind: set.kind,
        query: if any_hit { "occluded" } else { "intersect" },
        rays: set.rays.len() as u64,
        answers: summary,
        nodes_per_ray: work.nodes as f64 / n,
        tests_per_ray: work.prims as f64 / n,
        mrays_one_thread: rays_per_second(set.rays.len(), one),
        mrays_all_threads: rays_per_second(set.rays.len(), all),
        mrays_bundles_one_thread: rays_per_second(set.rays.len(), bundles),
    })
}

/// Builds `config` over `prims` and measures it on every set.
///
/// # Errors
/// The build's error, or a [`MeasureError`].
pub fn measure_accel<T: Real, P: PrimitiveSet<T> + ?Sized>(
    config: &AccelConfig,
    prims: &P,
    sets: &[RaySet<T>],
    min_time: Duration,
) -> anyhow::Result<AccelResult> {
    let kind = config.kind();
    let accel = accel::build_config(config, prims)?;
    let stats = accel.stats();
    let sets = sets
        .iter()
        .map(|set| measure_set(accel.as_dyn(), kind.name(), set, min_time))
        .collect::<Result<_, _>>()?;
    Ok(AccelResult {
        accel: kind.name(),
        config: config.label(),
        build_ms: stats.build_time.as_secs_f64() * 1e3,
        bytes: stats.bytes as u64,
        nodes: stats.nodes as u64,
        references: stats.references as u64,
        leaves: stats.leaves as u64,
        empty_leaves: stats.empty_leaves as u64,
        max_leaf_references: stats.max_leaf_references as u64,
        extra: stats.extra.iter().copied().collect(),
        sets,
    })
}

/// The first disagreement between accelerators, if any.
#[must_use]
pub fn disagreement(results: &[AccelResult]) -> Option<String> {
    let first = results.first()?;
    for other in &results[1..] {
        for (a, b) in first.sets.iter().zip(&other.sets) {
            if a.answers.hits != b.answers.hits || a.answers.digest != b.answers.digest {
                return Some(format!(
                    "{} and {} disagree on {} rays: {} vs {} hits, digest {:016x} vs {:016x}",
                    first.accel,
                    other.accel,
                    a.kind.name(),
                    a.answers.hits,
                    b.answers.hits,
                    a.answers.digest,
                    b.answers.digest
                ));
            }
        }
    }
    None
}

/// The table header.
#[must_use]
pub fn table_header(threads: usize) -> String {
    format!(
        "{:<7} {:>9} {:>8}  {:<8} {:>9} {:>9} {:>10} {:>10} {:>10} {:>9} {:>9} {:>15}  {:<16}",
        "accel",
        "build ms",
        "MiB",
        "rays",
        "count",
        "hits",
        "Mrays/s 1T",
        format!("Mrays/s {threads}T"),
        "bundles 1T",
        "nodes/ray",
        "tests/ray",
        "t sum",
        "digest"
    )
}

/// The table rows of one accelerator.
#[must_use]
pub fn table_rows(r: &AccelResult) -> Vec<String> {
    r.sets
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let (name, build, mib) = if i == 0 {
                (
                    r.accel.to_owned(),
                    format!("{:.2}", r.build_ms),
                    format!("{:.2}", r.bytes as f64 / (1024.0 * 1024.0)),
                )
            } else {
                (String::new(), String::new(), String::new())
            };
            format!(
                "{:<7} {:>9} {:>8}  {:<8} {:>9} {:>9} {:>10.2} {:>10.2} {:>10.2} {:>9.1} {:>9.1} {:>15}  {:016x}",
                name,
                build,
                mib,
                s.kind.name(),
                s.rays,
                s.answers.hits,
                s.mrays_one_thread,
                s.mrays_all_threads,
                s.mrays_bundles_one_thread,
                s.nodes_per_ray,
                s.tests_per_ray,
                s.answers.t_sum.map_or("-".to_owned(), |t| format!("{t:.9e}")),
                s.answers.digest
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::default_scene;

    #[test]
    fn only_an_image_s_rays_are_bundled_by_tiles() {
        let ray = |x: f32| Ray {
            origin: accel_core::Vec3::new(x, 0.0, 0.0),
            direction: accel_core::Vec3::new(0.0, 0.0, 1.0),
            t_min: 0.0,
            t_max: 1.0,
        };
        let rays: Vec<Ray<f32>> = (0..20u8).map(|i| ray(f32::from(i))).collect();
        let indices: Vec<usize> = (0..20).collect();
        let mut set = RaySet {
            kind: RayKind::Primary,
            rays,
            image_width: Some(10),
        };
        // Two rows of 10: a tile of 8 × 2, then the last 2 × 2, each in Z
        // order (2 × 2 blocks).
        let order = set.bundle_order(&indices);
        assert_eq!(order[..10], [0, 1, 10, 11, 2, 3, 12, 13, 4, 5]);
        assert_eq!(order[16..], [8, 9, 18, 19]);
        let bundled = set.bundle_order(&set.rays);
        assert_eq!(bundled[2].origin.x, 10.0);
        set.image_width = None;
        assert_eq!(*set.bundle_order(&indices), *indices);
    }

    #[test]
    fn ray_sets_follow_the_primary_hits() {
        let scene = default_scene().unwrap();
        let mesh = scene.mesh.cast::<f32>().unwrap();
        let grid = accel::build(AccelKind::Grid, &mesh).unwrap();
        let sets = generate_rays(&grid, &mesh, &scene.view, 24, 16).unwrap();
        let kinds: Vec<_> = sets.iter().map(|s| s.kind).collect();
        assert_eq!(kinds, [RayKind::Primary, RayKind::Shadow, RayKind::Diffuse]);
        assert_eq!(sets[0].rays.len(), 24 * 16);
        let hits = sets[0]
            .rays
            .iter()
            .filter(|r| grid.intersect(r).unwrap().is_some())
            .count();
        // The floor fills the lower part of the view, the sky the top.
        assert!(hits > 0 && hits < 24 * 16, "{hits}");
        assert_eq!(sets[2].rays.len(), hits);
        // One diffuse ray per hit, leaving the hit point, the hits taken
        // tile by tile.
        let tiled = by_tiles(&sets[0].rays, 24, TILE);
        let points: Vec<_> = tiled
            .iter()
            .filter_map(|r| {
                grid.intersect(r)
                    .unwrap()
                    .map(|h| r.origin + r.direction * h.t)
            })
            .collect();
        for (d, p) in sets[2].rays.iter().zip(&points) {
            assert!(
                (d.origin - *p).length() <= 1e-3 * (1.0 + p.length()),
                "{d:?} leaves {p:?}"
            );
        }
        assert!(sets[1].rays.len() <= hits && !sets[1].rays.is_empty());
        assert!(sets[1].rays.iter().all(|r| r.t_max == 1.0));
    }

    #[test]
    fn measurements_agree_across_accelerators_and_detect_differences() {
        let scene = default_scene().unwrap();
        let mesh = scene.mesh.cast::<f32>().unwrap();
        let grid = accel::build(AccelKind::Grid, &mesh).unwrap();
        let sets = generate_rays(&grid, &mesh, &scene.view, 8, 6).unwrap();
        let results: Vec<_> = [AccelKind::Grid, AccelKind::Brute]
            .into_iter()
            .map(|k| {
                measure_accel(&AccelConfig::default_for(k), &mesh, &sets, Duration::ZERO).unwrap()
            })
            .collect();
        assert_eq!(disagreement(&results), None);
        let primary = &results[0].sets[0];
        assert_eq!(primary.query, "intersect");
        assert_eq!(results[0].sets[1].query, "occluded");
        assert!(primary.answers.t_sum.unwrap() > 0.0);
        assert!(results[0].sets[1].answers.t_sum.is_none());
        // Brute force tests every triangle for every ray it does not skip.
        assert!(results[1].sets[0].tests_per_ray > results[0].sets[0].tests_per_ray);
        let mut broken = results.clone();
        broken[1].sets[2].answers.digest ^= 1;
        let msg = disagreement(&broken).unwrap();
        assert!(msg.contains("diffuse"), "{msg}");
        assert_eq!(table_rows(&results[0]).len(), 3);
    }

    #[test]
    fn brute_force_joins_only_small_runs() {
        assert!(default_accels(100, 1000).contains(&AccelKind::Brute));
        assert!(!default_accels(100_000, 1_000_000).contains(&AccelKind::Brute));
        assert!(default_accels(100_000, 1_000_000).contains(&AccelKind::Grid));
    }
}
