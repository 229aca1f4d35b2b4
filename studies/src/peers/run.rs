//! `studies peers SCENE`: our accelerators and the peers on identical scenes
//! and rays, in one process, on one thread.
//!
//! Every structure is built on one thread (ours in a one-thread rayon pool,
//! Embree with `threads=1`, the Rust peers without their parallel
//! features); build times are wall-clock. The rays are [`mod@render::bench`]'s
//! (primary, shadow, diffuse, generated from the scene's view through our
//! kD-tree) or a binary ray file's. Each tool traces each set once to record
//! every answer; then every figure of the set (each tool's single rays and
//! bundles) repeats passes for at least `--min-time` seconds and
//! [`MIN_PASSES`] passes, in `--rounds` interleaved rounds ([`rounds`]); the
//! figure is the median pass. Nearest hit for primary, diffuse and file
//! rays, any hit for shadow rays.
//!
//! Beside each single-ray figure, a bundle figure: ours through
//! [`Accelerator::intersect_bundle`] and [`Accelerator::occluded_bundle`],
//! [`bench::BUNDLE`] rays at a time, as `render bench`'s `bundles 1T`;
//! Embree through its packet queries, 16 and 8 rays at a time
//! ([`super::Tracer::nearest_packet`]). Every tool's bundles take the same
//! rays in the same order, [`RaySet::bundle_order`]: an image's primary
//! rays by [`bench::TILE`] × [`bench::TILE`] tiles, other sets as they are.
//! Tools without packet queries (obvhs, parry3d, bvh) get no bundle figure,
//! rather than a loop of single rays presented as one. Bundle answers are
//! compared with the tool's own single-ray answers: ours must be the same
//! bit for bit (an error otherwise), Embree's are compared as the peers are.
//!
//! A tool whose pass would take longer than `--max-pass-time` (estimated
//! from a sample of the set) is skipped on that set, with a note. Every
//! tool's answers are compared ray by ray with those of the first of ours
//! measured on the set (the grid unless skipped; ours equal brute force bit
//! for bit): hit against miss, other triangle, `t` differing by more than
//! [`T_TOLERANCE`] relative. Differences are printed, never fatal: the
//! peers' triangle tests are not watertight, and each test rounds `t`
//! its own way.

mod report;
mod rounds;

use super::{Agreement, PeerHit, PeerKind, PeerMesh, SetAnswers, T_TOLERANCE, compare};
use accel::{AccelConfig, AccelKind};
use render::app::{load_scene, mesh_in};
use render::bench::{self, Answers, RayKind, RaySet};
use render::cli::{min_time_parser, side_parser};
use render::output::PendingFile;
pub use report::report_lines;
use rounds::Timed;

use accel_core::{Accelerator, Hit, QueryError, Ray};
use anyhow::{Context, Result, anyhow};
use clap::builder::PossibleValuesParser;
use clap::{Args, ValueEnum};
use serde::Serialize;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// The fewest timed passes per figure.
pub const MIN_PASSES: usize = 3;

/// Differing rays printed per tool and set.
const EXAMPLES: usize = 3;

/// Rays of the sample that estimates a pass's time.
const PROBE_RAYS: usize = 1000;

/// Timed passes over the sample, at most, before a tool is skipped as too
/// slow ([`pass_estimate`]).
const PROBE_TRIES: usize = 3;

/// The tool name of our kD-tree's fast-build preset
/// ([`accel::KdTreeParams::fast_build`], `kdtree fast-build`).
pub const KDTREE_FAST: &str = "kdtree-fast";

/// Our tools in report order, by name: each structure with its default
/// parameters (named as the structure), then the kD-tree's fast-build
/// preset ([`KDTREE_FAST`]).
fn ours() -> [(&'static str, AccelConfig); 4] {
    let default = |k: AccelKind| (k.name(), AccelConfig::default_for(k));
    [
        default(AccelKind::Grid),
        default(AccelKind::Octree),
        default(AccelKind::KdTree),
        (
            KDTREE_FAST,
            AccelConfig::KdTree(accel::KdTreeParams::fast_build()),
        ),
    ]
}

/// Every tool `--tools` may name: ours, then the peers in report order.
fn tool_names() -> Vec<&'static str> {
    ours()
        .iter()
        .map(|(name, _)| *name)
        .chain(super::peer_kinds().iter().map(|p| p.name))
        .collect()
}

/// Options of `studies peers [SCENE]`.
#[derive(Clone, Debug, Args)]
pub struct PeersArgs {
    /// A .gltf/.glb file or a built-in scene name.
    #[arg(value_name = "SCENE", default_value = "default")]
    pub scene: String,
    /// Trace the rays of this binary ray file (nearest hit) instead of
    /// generated ones.
    #[arg(long, value_name = "FILE")]
    pub rays: Option<PathBuf>,
    /// Generated ray kinds to trace, comma-separated.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "primary,shadow,diffuse"
    )]
    pub kinds: Vec<KindChoice>,
    /// Width of the primary-ray image.
    #[arg(long, default_value_t = 512, value_parser = side_parser(), allow_negative_numbers = true)]
    pub width: u32,
    /// Height of the primary-ray image.
    #[arg(long, default_value_t = 512, value_parser = side_parser(), allow_negative_numbers = true)]
    pub height: u32,
    /// Minimum seconds of timed passes per figure (at least 3 passes; the
    /// median pass is reported).
    #[arg(long, default_value_t = 1.0, value_parser = min_time_parser, allow_negative_numbers = true)]
    pub min_time: f64,
    /// Skip a tool on a ray set when one pass would take longer than this
    /// many seconds, estimated from a sample of 1000 rays (the grid on
    /// teapot_in_stadium tests every triangle of the teapot per ray).
    #[arg(long, value_name = "S", default_value_t = 30.0, value_parser = min_time_parser, allow_negative_numbers = true)]
    pub max_pass_time: f64,
    /// Build every tool this many times, in interleaved rounds (ours, then
    /// each peer, then again), and report each one's median build: on a
    /// shared machine one build per tool compares minutes, not tools. Each
    /// timed build follows an untimed one of the same tool.
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=100), allow_negative_numbers = true)]
    pub build_rounds: u32,
    /// Time the figures of each ray set (every tool's single rays and
    /// bundles) in this many interleaved rounds, each giving each figure
    /// `--min-time / N` seconds of passes: the figures share the host's
    /// swings, so their ratios lose most of them.
    #[arg(long, value_name = "N", default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..=1000), allow_negative_numbers = true)]
    pub rounds: u32,
    /// Write the results as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Only these tools, comma-separated (ours: grid, octree, kdtree,
    /// kdtree-fast, the kD-tree's fast-build preset; the peers: obvhs, parry3d, bvh, embree, embree-robust); every one by
    /// default. The first one measured on a set is the reference of the
    /// agreement check.
    #[arg(long, value_name = "TOOLS", value_delimiter = ',', value_parser = PossibleValuesParser::new(tool_names()))]
    pub tools: Vec<String>,
}

impl PeersArgs {
    /// Whether `--tools` takes the tool `name` (every tool without it).
    fn wants(&self, name: &str) -> bool {
        self.tools.is_empty() || self.tools.iter().any(|t| t == name)
    }
}

/// A generated ray kind, as `--kinds` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum KindChoice {
    /// Camera rays (nearest hit).
    Primary,
    /// Hit point to light (any hit).
    Shadow,
    /// Cosine-distributed from hit points (nearest hit).
    Diffuse,
}

impl KindChoice {
    const fn kind(self) -> RayKind {
        match self {
            Self::Primary => RayKind::Primary,
            Self::Shadow => RayKind::Shadow,
            Self::Diffuse => RayKind::Diffuse,
        }
    }
}

/// One tool's build.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BuildFigure {
    /// Tool.
    pub name: String,
    /// Ours or a peer.
    pub ours: bool,
    /// Wall-clock build time on one thread, milliseconds: the median of
    /// the rounds.
    pub build_ms: f64,
    /// Millions of triangles built per second, from `build_ms`.
    pub mtris_per_s: f64,
    /// Each round's build time, milliseconds, in order.
    pub rounds_ms: Vec<f64>,
}

/// One tool on one ray set through its bundle (packet) queries.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BundleFigure {
    /// Rays per bundle: [`bench::BUNDLE`] for ours, the packet width for
    /// Embree.
    pub rays_per_bundle: usize,
    /// Millions of rays per second, one thread, median pass.
    pub mrays: f64,
    /// Timed passes.
    pub passes: usize,
    /// Hits, `t` sum and digest of `(t, triangle)`, in the set's order.
    #[serde(flatten)]
    pub answers: Answers,
    /// Differences from the same tool's single-ray answers (ours are also
    /// checked bit for bit, `u` and `v` included).
    pub agreement: Agreement,
}

/// One tool on one ray set.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SetFigure {
    /// Tool.
    pub name: String,
    /// Ray kind.
    pub kind: RayKind,
    /// Millions of rays per second, one thread, median pass.
    pub mrays: f64,
    /// Timed passes.
    pub passes: usize,
    /// Hits, `t` sum and digest of `(t, triangle)`.
    #[serde(flatten)]
    pub answers: Answers,
    /// The tool compared with: the first measured on the set, ours first
    /// (the grid unless it was skipped or left out by `--tools`).
    pub reference: String,
    /// Differences from the reference.
    pub agreement: Agreement,
    /// The same rays through the tool's bundle queries, one figure per
    /// bundle size; none for a tool without packet queries.
    pub bundles: Vec<BundleFigure>,
}

/// A peer that is not compiled in.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Unavailable {
    /// Peer.
    pub name: &'static str,
    /// The cargo feature that enables it.
    pub feature: &'static str,
}

/// The whole comparison, as printed and written to JSON.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PeersReport {
    /// Scene name or file.
    pub scene: String,
    /// Triangles.
    pub triangles: u64,
    /// Where the rays came from.
    pub ray_source: String,
    /// Rays per set.
    pub ray_sets: Vec<(RayKind, u64)>,
    /// Minimum timing per figure, seconds.
    pub min_time_s: f64,
    /// Interleaved rounds the figures of a set were timed in.
    pub rounds: u32,

    /// Relative `t` tolerance of the agreement checks.
    pub t_tolerance: f64,
    /// Interleaved build rounds per tool.
    pub build_rounds: u32,
    /// Builds, ours first.
    pub builds: Vec<BuildFigure>,
    /// Throughput and agreement per tool and set.
    pub sets: Vec<SetFigure>,
    /// Peers not compiled in.
    pub unavailable: Vec<Unavailable>,
    /// Peers compiled in that failed to build, with the reason.
    pub failed: Vec<(String, String)>,
    /// Tools skipped on a set as too slow: tool, set, estimated seconds per pass.
    pub skipped: Vec<(String, RayKind, f64)>,
}

/// A tool under test.
enum Tool<'a> {
    /// Ours: the tool's name and the structure.
    Ours(&'static str, Box<dyn Accelerator<f32> + 'a>),
    Peer(&'static str, Box<dyn super::Tracer>),
}

impl Tool<'_> {
    fn name(&self) -> &'static str {
        match self {
            Tool::Ours(name, _) => name,
            Tool::Peer(n, _) => n,
        }
    }

    /// Every answer to `set`.
    fn answers(&self, set: &RaySet<f32>) -> Result<SetAnswers> {
        let any = set.kind.any_hit();
        Ok(match self {
            Tool::Ours(k, a) => {
                let err =
                    |i: usize| move |e| anyhow!("{k} refused {} ray {i}: {e}", set.kind.name());
                if any {
                    SetAnswers::Occluded(
                        set.rays
                            .iter()
                            .enumerate()
                            .map(|(i, r)| a.occluded(r).map_err(err(i)))
                            .collect::<Result<_>>()?,
                    )
                } else {
                    SetAnswers::Nearest(
                        set.rays
                            .iter()
                            .enumerate()
                            .map(|(i, r)| {
                                a.intersect(r)
                                    .map(|h| {
                                        h.map(|h| PeerHit {
                                            t: h.t,
                                            prim: h.prim,
                                        })
                                    })
                                    .map_err(err(i))
                            })
                            .collect::<Result<_>>()?,
                    )
                }
            }
            Tool::Peer(_, p) => {
                if any {
                    SetAnswers::Occluded(set.rays.iter().map(|r| p.occluded(r)).collect())
                } else {
                    SetAnswers::Nearest(set.rays.iter().map(|r| p.nearest(r)).collect())
                }
            }
        })
    }

    /// The bundle sizes of the tool's bundle queries: [`bench::BUNDLE`]
    /// for ours, a peer's packet widths (none for a peer without packets).
    fn bundle_sizes(&self) -> Vec<usize> {
        match self {
            Tool::Ours(..) => vec![bench::BUNDLE],
            Tool::Peer(_, p) => p.packet_widths().to_vec(),
        }
    }

    /// Every answer to `set` through the bundle queries, `size` rays at a
    /// time over `ordered`, the set's rays in the order `order` gives
    /// ([`RaySet::bundle_order`]), put back in the set's order. Ours are
    /// checked against their single-ray answers bit for bit.
    ///
    /// # Errors
    /// A ray ours refuse, or an answer of ours that differs from the
    /// single-ray one.
    fn bundle_answers(
        &self,
        size: usize,
        coherent: bool,
        set: &RaySet<f32>,
        ordered: &[Ray<f32>],
        order: &[usize],
    ) -> Result<SetAnswers> {
        let any = set.kind.any_hit();
        let in_bundle_order = match self {
            Tool::Ours(k, a) => {
                let mismatch = |j: usize, bundle: String, single: String| {
                    anyhow!(
                        "{k}: the bundle query answers {} ray {} {bundle}, the single-ray query {single}",
                        set.kind.name(),
                        order[j]
                    )
                };
                let refused =
                    |j: usize, e| anyhow!("{k} refused {} ray {}: {e}", set.kind.name(), order[j]);
                if any {
                    let mut out = vec![Ok(false); ordered.len()];
                    for (rays, answers) in ordered.chunks(size).zip(out.chunks_mut(size)) {
                        a.occluded_bundle(rays, answers);
                    }
                    let mut blocked = Vec::with_capacity(out.len());
                    for (j, (got, ray)) in out.into_iter().zip(ordered).enumerate() {
                        let single = a.occluded(ray);
                        if got != single {
                            return Err(mismatch(j, format!("{got:?}"), format!("{single:?}")));
                        }
                        blocked.push(got.map_err(|e| refused(j, e))?);
                    }
                    SetAnswers::Occluded(blocked)
                } else {
                    let mut out = vec![Ok(None); ordered.len()];
                    for (rays, answers) in ordered.chunks(size).zip(out.chunks_mut(size)) {
                        a.intersect_bundle(rays, answers);
                    }
                    let bits = |r: &Result<Option<Hit<f32>>, QueryError>| {
                        r.as_ref().map(|h| h.map(|h| h.bit_key())).map_err(|e| *e)
                    };
                    let mut hits = Vec::with_capacity(out.len());
                    for (j, (got, ray)) in out.into_iter().zip(ordered).enumerate() {
                        let single = a.intersect(ray);
                        if bits(&got) != bits(&single) {
                            return Err(mismatch(j, format!("{got:?}"), format!("{single:?}")));
                        }
                        hits.push(got.map_err(|e| refused(j, e))?.map(|h| PeerHit {
                            t: h.t,
                            prim: h.prim,
                        }));
                    }
                    SetAnswers::Nearest(hits)
                }
            }
            Tool::Peer(_, p) => super::packet_answers(p.as_ref(), size, coherent, any, ordered),
        };
        Ok(in_bundle_order.in_set_order(order))
    }

    /// One timed pass over `ordered` through the bundle queries, `size`
    /// rays at a time: the hits.
    fn bundle_pass(
        &self,
        size: usize,
        coherent: bool,
        any: bool,
        ordered: &[Ray<f32>],
    ) -> Result<u64> {
        Ok(match self {
            Tool::Ours(_, a) => {
                debug_assert_eq!(size, bench::BUNDLE);
                bench::count_bundle_hits(a.as_ref(), any, ordered)?
            }
            Tool::Peer(_, p) => super::count_packet_hits(p.as_ref(), size, coherent, any, ordered),
        })
    }

    /// One timed pass over `rays`: the hits.
    fn pass(&self, any: bool, rays: &[Ray<f32>]) -> Result<u64> {
        Ok(match self {
            Tool::Ours(_, a) => bench::count_hits(a.as_ref(), any, rays, false)?,
            Tool::Peer(_, p) => {
                let p = p.as_ref();
                if any {
                    rays.iter().map(|r| u64::from(p.occluded(r))).sum()
                } else {
                    rays.iter().map(|r| u64::from(p.nearest(r).is_some())).sum()
                }
            }
        })
    }
}

/// `studies peers [SCENE]`.
///
/// # Errors
/// A refused argument, scene, ray file or output file, or a ray our
/// accelerators refuse. Disagreements are printed, not errors.
pub fn run(args: &PeersArgs) -> Result<()> {
    let json_out = args.json.as_deref().map(PendingFile::create).transpose()?;
    let file_rays = args
        .rays
        .as_deref()
        .map(accel_scenes::rayfile::read)
        .transpose()?;
    let (pool, _) = render::app::thread_pool(Some(1))?;
    let report = pool.install(|| measure(args, file_rays))?;
    if let Some(out) = json_out {
        let json = serde_json::to_vec_pretty(&report).context("encoding the JSON report")?;
        let dest = out.dest().display().to_string();
        out.write_all(&json)?;
        println!("wrote {dest}");
    }
    Ok(())
}

/// What [`build_all`] built.
struct Built<'a> {
    /// Ours ([`ours`]), then the peers that built, from the
    /// first round.
    tools: Vec<Tool<'a>>,
    /// Each tool's median build time over the rounds.
    builds: Vec<BuildFigure>,
    /// Peers not compiled in.
    unavailable: Vec<Unavailable>,
    /// Peers that failed to build in the first round, with the reason.
    failed: Vec<(String, String)>,
}

/// Builds every tool in `rounds` interleaved rounds. A peer that fails in
/// the first round is not tried again; one that fails later keeps the
/// rounds it built.
///
/// Each timed build comes right after an untimed build of the same tool, so
/// that no tool is timed in the state another tool left behind: Embree's
/// default mode, built right after the bvh crate, took 1.5–1.8 times as
/// long as its robust mode built next, and with the two swapped the robust
/// mode was the slow one (the second Embree build matched a standalone C
/// program's).
fn build_all<'m>(
    mesh: &'m accel_core::TriangleMesh<f32>,
    rounds: u32,
    wants: impl Fn(&str) -> bool,
) -> Result<Built<'m>> {
    let n = mesh.triangle_count();
    let peer_mesh = PeerMesh::new(mesh);
    let mut tools = Vec::new();
    let mut times: Vec<(&'static str, bool, Vec<Duration>)> = Vec::new();
    let mut unavailable = Vec::new();
    let mut failed = Vec::new();
    let ours: Vec<(&'static str, AccelConfig)> =
        ours().into_iter().filter(|(name, _)| wants(name)).collect();
    for round in 0..rounds {
        let first = round == 0;
        let mut record = |name: &'static str, is_ours: bool, d: Duration| match times
            .iter_mut()
            .find(|t| t.0 == name)
        {
            Some(t) => t.2.push(d),
            None => times.push((name, is_ours, vec![d])),
        };
        for (name, config) in &ours {
            // Every timed build follows an untimed one of the same tool
            // (see the function's comment).
            drop(accel::build_config(config, mesh)?);
            let start = Instant::now();
            let accel = accel::build_config(config, mesh)?;
            record(name, true, start.elapsed());
            if first {
                tools.push(Tool::Ours(name, accel.into_dyn()));
            }
        }
        for PeerKind {
            name,
            feature,
            build,
            ..
        } in super::peer_kinds()
        {
            if !wants(name) {
                continue;
            }
            let Some(build) = build else {
                if first {
                    unavailable.push(Unavailable { name, feature });
                }
                continue;
            };
            if !first && failed.iter().any(|(f, _): &(String, String)| f == name) {
                continue;
            }
            let warm_then_timed = build(&peer_mesh).and_then(|warm| {
                drop(warm);
                build(&peer_mesh)
            });
            match warm_then_timed {
                Ok(built) => {
                    record(name, false, built.build);
                    if first {
                        tools.push(Tool::Peer(name, built.tracer));
                    }
                }
                Err(why) => {
                    if first {
                        println!("{name}: not measured: {why}");
                        failed.push((name.to_owned(), why));
                    }
                }
            }
        }
    }
    let builds = times
        .into_iter()
        .map(|(name, ours, rounds)| {
            let s = bench::median(&rounds).as_secs_f64();
            BuildFigure {
                name: name.to_owned(),
                ours,
                build_ms: s * 1e3,
                mtris_per_s: if s > 0.0 {
                    n as f64 / s / 1e6
                } else {
                    f64::INFINITY
                },
                rounds_ms: rounds.iter().map(|d| d.as_secs_f64() * 1e3).collect(),
            }
        })
        .collect();
    Ok(Built {
        tools,
        builds,
        unavailable,
        failed,
    })
}

fn measure(args: &PeersArgs, file_rays: Option<Vec<Ray<f32>>>) -> Result<PeersReport> {
    let scene = load_scene(&args.scene)?;
    let mesh = mesh_in::<f32>(&scene)?;
    let n = mesh.triangle_count();
    let Built {
        tools,
        builds,
        unavailable,
        failed,
    } = build_all(&mesh, args.build_rounds, |name| args.wants(name))?;
    let (sets, source) = match file_rays {
        Some(rays) => (
            vec![RaySet {
                kind: RayKind::File,
                rays,
                image_width: None,
            }],
            args.rays
                .as_deref()
                .map_or_else(String::new, |p| p.display().to_string()),
        ),
        None => {
            // The generator measured here, or one built for the rays when
            // `--tools` leaves it out.
            let measured = tools.iter().find_map(|t| match t {
                Tool::Ours(name, a) if *name == bench::RAY_GENERATOR.name() => Some(a.as_ref()),
                _ => None,
            });
            let own;
            let generator = match measured {
                Some(a) => a,
                None => {
                    own = accel::build(bench::RAY_GENERATOR, &mesh)?;
                    &own
                }
            };
            let wanted: Vec<RayKind> = args.kinds.iter().map(|k| k.kind()).collect();
            let sets = bench::generate_rays(generator, &mesh, &scene.view, args.width, args.height)
                .context("generating rays")?
                .into_iter()
                .filter(|s| wanted.contains(&s.kind))
                .collect();
            (
                sets,
                format!("generated from a {}x{} view", args.width, args.height),
            )
        }
    };
    println!("rays ({source}): {}", bench::describe_sets(&sets));
    print_unavailable(&unavailable);
    let min_time = Duration::from_secs_f64(args.min_time);
    let max_pass = Duration::from_secs_f64(args.max_pass_time);
    let mut figures = Vec::new();
    let mut skipped = Vec::new();
    for set in &sets {
        let any = set.kind.any_hit();
        let mut reference: Option<(SetAnswers, &str)> = None;
        // The order of every tool's bundles, and the rays in it.
        let indices: Vec<usize> = (0..set.rays.len()).collect();
        let order = set.bundle_order(&indices);
        let ordered = set.bundle_order(&set.rays);
        // Every figure of the set, timed together once all are recorded.
        let mut timed = Vec::new();
        // Which figure each timed one is: (set figure, bundle figure).
        let mut slots: Vec<(usize, Option<usize>)> = Vec::new();
        let stride = set.rays.len().div_ceil(PROBE_RAYS).max(1);
        let sample: Vec<Ray<f32>> = set.rays.iter().step_by(stride).copied().collect();
        for tool in &tools {
            let scale = set.rays.len() as f64 / sample.len().max(1) as f64;
            let estimate = pass_estimate(scale, max_pass, || tool.pass(any, &sample))?;
            if estimate > max_pass.as_secs_f64() {
                println!(
                    "{}: skipped on {} rays: about {estimate:.0} s per pass (over --max-pass-time {})",
                    tool.name(),
                    set.kind.name(),
                    args.max_pass_time
                );
                skipped.push((tool.name().to_owned(), set.kind, estimate));
                continue;
            }
            let answers = tool.answers(set)?;
            let summary = answers.summary();
            let (reference, ref_name) =
                reference.get_or_insert_with(|| (answers.clone(), tool.name()));
            let agreement = compare(
                reference,
                ref_name,
                &answers,
                tool.name(),
                &set.rays,
                EXAMPLES,
            );
            let figure = figures.len();
            slots.push((figure, None));
            timed.push(Timed::new(summary.hits, move || {
                tool.pass(any, black_box(&set.rays))
            }));
            let mut bundles = Vec::new();
            for size in tool.bundle_sizes() {
                let coherent = coherent(set);
                let bundle = bundle_figure(tool, size, coherent, set, &ordered, &order, &answers)?;
                let ordered = &ordered;
                slots.push((figure, Some(bundles.len())));
                timed.push(Timed::new(bundle.answers.hits, move || {
                    tool.bundle_pass(size, coherent, any, black_box(ordered))
                }));
                bundles.push(bundle);
            }
            figures.push(SetFigure {
                name: tool.name().to_owned(),
                kind: set.kind,
                mrays: 0.0,
                passes: 0,
                answers: summary,
                reference: (*ref_name).to_owned(),
                agreement,
                bundles,
            });
        }
        rounds::time_interleaved(&mut timed, min_time, args.rounds, MIN_PASSES)?;
        for ((figure, bundle), t) in slots.into_iter().zip(timed) {
            let f = &mut figures[figure];
            let (name, hits, mrays, passes) = match bundle {
                None => (f.name.clone(), f.answers.hits, &mut f.mrays, &mut f.passes),
                Some(b) => {
                    let b = &mut f.bundles[b];
                    let name = format!("{} in bundles of {}", f.name, b.rays_per_bundle);
                    (name, b.answers.hits, &mut b.mrays, &mut b.passes)
                }
            };
            *mrays = bench::rays_per_second(set.rays.len(), bench::median(&t.times));
            *passes = t.times.len();
            if let Some(other) = t.unexpected {
                println!(
                    "warning: {name} gave {hits} hits on {} rays when recording answers but {other} when timed",
                    set.kind.name()
                );
            }
        }
    }
    let report = PeersReport {
        scene: scene.name.clone(),
        triangles: n as u64,
        ray_source: source,
        ray_sets: sets.iter().map(|s| (s.kind, s.rays.len() as u64)).collect(),
        min_time_s: args.min_time,
        rounds: args.rounds,
        build_rounds: args.build_rounds,

        t_tolerance: T_TOLERANCE,
        builds,
        sets: figures,
        unavailable,
        failed,
        skipped,
    };
    for line in report_lines(&report) {
        println!("{line}");
    }
    Ok(report)
}

/// The seconds a pass over a set would take, estimated from `probe`, a
/// pass over a sample `scale` times smaller: the fastest of up to
/// [`PROBE_TRIES`] probes, stopping at the first under `max_pass`. One try
/// let a stall of the host skip a tool: Embree on the flat field's primary
/// rays once read 32 s per pass against its usual 0.02 s (2026-12-07).
///
/// # Errors
/// The probe's (a ray the tool refuses).
fn pass_estimate<H>(
    scale: f64,
    max_pass: Duration,
    mut probe: impl FnMut() -> Result<H>,
) -> Result<f64> {
    let mut best = f64::INFINITY;
    for _ in 0..PROBE_TRIES {
        let start = Instant::now();
        probe()?;
        best = best.min(start.elapsed().as_secs_f64() * scale);
        if best <= max_pass.as_secs_f64() {
            break;
        }
    }
    Ok(best)
}

/// Whether the bundles of `set` are coherent: the neighbouring pixels of
/// an image's tiles. A hint for tools that ask for one (Embree's
/// `RTC_INTERSECT_CONTEXT_FLAG_COHERENT`); ours find coherence themselves.
/// Embree with the flag on every set (sphere_100k and the bunny,
/// 2026-12-06, two runs each): diffuse packets at 0.45–0.55× their speed
/// without it, shadow packets at 0.9–1.2× (once 1.6× against a slow run),
/// so only the tiles get it.
fn coherent(set: &RaySet<f32>) -> bool {
    set.image_width.is_some()
}

/// `tool` on `set` through its bundle queries, `size` rays at a time over
/// `ordered` (the set's rays in the order `order` gives): the answers,
/// checked against the tool's single-ray `single` ones; the figure's
/// throughput is left for the interleaved rounds ([`rounds`]).
///
/// # Errors
/// As [`Tool::bundle_answers`].
fn bundle_figure(
    tool: &Tool<'_>,
    size: usize,
    coherent: bool,
    set: &RaySet<f32>,
    ordered: &[Ray<f32>],
    order: &[usize],
    single: &SetAnswers,
) -> Result<BundleFigure> {
    let name = tool.name();
    let answers = tool.bundle_answers(size, coherent, set, ordered, order)?;
    let agreement = compare(
        single,
        &format!("{name} single"),
        &answers,
        &bundle_name(name, size),
        &set.rays,
        EXAMPLES,
    );
    Ok(BundleFigure {
        rays_per_bundle: size,
        mrays: 0.0,
        passes: 0,
        answers: answers.summary(),
        agreement,
    })
}

/// `embree x16`: a tool in bundles of `size` rays, in reports.
fn bundle_name(name: &str, size: usize) -> String {
    format!("{name} x{size}")
}

fn print_unavailable(unavailable: &[Unavailable]) {
    for feature in ["peers", "embree"] {
        let names: Vec<_> = unavailable
            .iter()
            .filter(|u| u.feature == feature)
            .map(|u| u.name)
            .collect();
        if !names.is_empty() {
            let extra = if feature == "embree" {
                " (needs the system library: apt-get install libembree-dev)"
            } else {
                ""
            };
            println!(
                "not built in: {} (build studies with --features {feature}{extra})",
                names.join(", ")
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stalled_probe_is_tried_again_before_a_tool_is_skipped() {
        // The first probe stalls past the limit, the second does not.
        let mut calls = 0;
        let estimate = pass_estimate(1.0, Duration::from_millis(100), || {
            calls += 1;
            if calls == 1 {
                std::thread::sleep(Duration::from_millis(250));
            }
            Ok(())
        })
        .unwrap();
        assert_eq!(calls, 2);
        assert!(estimate < 0.1, "{estimate}");
        // Always over the limit: every try is made, and the fastest kept.
        let mut calls = 0;
        let estimate = pass_estimate(1e9, Duration::ZERO, || {
            calls += 1;
            std::thread::sleep(Duration::from_millis(1));
            Ok(())
        })
        .unwrap();
        assert_eq!(calls, PROBE_TRIES);
        assert!(estimate >= 1e6, "{estimate}");
        let refused = pass_estimate(1.0, Duration::ZERO, || -> Result<()> {
            Err(anyhow!("refused"))
        });
        assert_eq!(refused.unwrap_err().to_string(), "refused");
    }

    #[test]
    fn tool_names_are_ours_then_every_peer_once() {
        let names = tool_names();
        assert_eq!(&names[..4], ["grid", "octree", "kdtree", KDTREE_FAST]);
        assert_eq!(names.len(), 4 + super::super::peer_kinds().len());
        let mut unique = names.clone();
        unique.sort_unstable();
        unique.dedup();
        assert_eq!(unique.len(), names.len(), "{names:?}");
    }
}
