//! The command line: `render [SCENE] [options]` and `render bench [SCENE] [options]`.
//!
//! Every numeric option has a range checked by clap, so absurd sizes are
//! refused before any work starts (see [`limits`]).

use crate::shard::Shard;
use accel::{
    AccelConfig, AccelKind, GRID_LAYOUT, KDTREE_PRESETS, OCTREE_PRESETS, kdtree_preset,
    octree_preset,
};
use accel_core::packed::Layout;
use accel_core::spawn::SpawnOffset;
use accel_core::{Real, TriangleTest};
use clap::builder::PossibleValuesParser;
use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

/// What `--accel` accepts: a kind, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum AccelChoice {
    /// The uniform grid.
    Grid,
    /// The octree of nested grids.
    Octree,
    /// The SAH kD-tree.
    Kdtree,
    /// Brute force (the reference; slow on large scenes).
    Brute,
    /// Chosen per scene and ray budget (structure and parameters) from a
    /// short probe of build and query cost; the reason is printed.
    Auto,
}

impl AccelChoice {
    /// The kind named, or `None` for `auto`.
    #[must_use]
    pub const fn kind(self) -> Option<AccelKind> {
        match self {
            Self::Grid => Some(AccelKind::Grid),
            Self::Octree => Some(AccelKind::Octree),
            Self::Kdtree => Some(AccelKind::KdTree),
            Self::Brute => Some(AccelKind::Brute),
            Self::Auto => None,
        }
    }
}

/// The ranges the command line accepts.
pub mod limits {
    /// Largest `--width` or `--height`.
    pub const MAX_SIDE: u32 = 16_384;
    /// Largest number of pixels (`--width × --height`): 64 Mpx.
    pub const MAX_PIXELS: u64 = 1 << 26;
    /// Largest `--spp`.
    pub const MAX_SPP: u32 = 4_096;
    /// Largest `--ao`.
    pub const MAX_AO: u32 = 256;
    /// Largest `--threads`.
    pub const MAX_THREADS: usize = 1_024;
    /// Largest rays traced for one render: pixels × spp × (2 + ao).
    pub const MAX_RAYS: u64 = 1 << 36;
    /// Default `--memory-budget`, in GiB.
    pub const MEMORY_BUDGET_GIB: f64 = 8.0;
}

/// Render a glTF file or a built-in scene with any accelerator, or benchmark
/// the accelerators on it.
///
/// SCENE is a `.gltf`/`.glb` file or a built-in scene: `default` (the
/// embedded procedural scene, used when SCENE is omitted), `sphere_100k`,
/// `soup_100k`, `terrain_1m`, `teapot_in_stadium`, `flat_field`.
#[derive(Debug, Parser)]
#[command(
    name = "render",
    version,
    args_conflicts_with_subcommands = true,
    after_help = EXAMPLES
)]
pub struct Cli {
    /// `bench`, or nothing to render.
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Options of a render (when no subcommand is given).
    #[command(flatten)]
    pub render: RenderArgs,
}

const EXAMPLES: &str = "\
Examples:
  render                                   the default scene to render.png
  render scene.glb --accel kdtree --spp 4 --out scene.png
  render teapot_in_stadium --heatmap=heat.png
  render bench soup_100k --json soup.json
  render bench scene.glb --rays rays.bin --accel grid,brute
  render scene.glb --shard 0/4 --out part-0.part   one of 4 shards (docs/cluster.md)
  render merge part-*.part --out scene.png

The studies (tradeoff, sweep-density, choose-bench, peers) are the studies binary:
  cargo run --release -p studies -- --help";

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Measure build time, memory and Mrays/s per accelerator and ray kind.
    Bench(Box<BenchArgs>),
    /// Join the part files of a sharded render (`--shard`) into the image,
    /// or of a sharded ray file (`bench --hits`) into the hits file.
    Merge(MergeArgs),
}

/// Options of `render merge`.
#[derive(Clone, Debug, Args)]
pub struct MergeArgs {
    /// The part files, in any order: every shard of one job exactly once.
    #[arg(value_name = "PARTS", required = true)]
    pub parts: Vec<PathBuf>,
    /// The merged output: a PNG for image parts, a hits file for hits parts.
    #[arg(long, value_name = "FILE")]
    pub out: PathBuf,
}

/// Which shard of a job array this process runs (docs/cluster.md).
#[derive(Clone, Debug, Default, Args)]
pub struct ShardArgs {
    /// Run shard I of N (0-based) and write a part file (`--out NAME.part`)
    /// for `render merge`: the image rows in every N-th band of 16 rows
    /// from band I, or the I-th of N contiguous slices of a ray file.
    #[arg(long, value_name = "I/N", conflicts_with = "shards")]
    pub shard: Option<Shard>,
    /// Run one of N shards, its index read from the job array's
    /// environment: JOB_COMPLETION_INDEX (Kubernetes Indexed Jobs), then
    /// SLURM_ARRAY_TASK_ID (Slurm `--array=0-(N-1)`).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=i64::from(crate::shard::MAX_SHARDS)))]
    pub shards: Option<u32>,
}

impl ShardArgs {
    /// The shard this process runs, if any.
    ///
    /// # Errors
    /// When `--shards` is given and the environment holds no valid index.
    pub fn resolve(&self) -> Result<Option<Shard>, crate::shard::ShardError> {
        match (self.shard, self.shards) {
            (Some(s), _) => Ok(Some(s)),
            (None, Some(n)) => Shard::from_env(n, |k| std::env::var(k).ok()).map(Some),
            (None, None) => Ok(None),
        }
    }
}

/// Floating-point precision of the geometry, rays and queries.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Precision {
    /// Single precision (interactive scenes).
    #[default]
    F32,
    /// Double precision (large worlds).
    F64,
}

impl Precision {
    /// `"f32"` or `"f64"`.
    #[must_use]
    pub const fn name(self) -> &'static str {
        match self {
            Self::F32 => "f32",
            Self::F64 => "f64",
        }
    }
}

/// Options of `render [SCENE]`.
#[derive(Clone, Debug, Args)]
pub struct RenderArgs {
    /// A .gltf/.glb file or a built-in scene name [default: default].
    #[arg(value_name = "SCENE")]
    pub scene: Option<String>,
    /// Accelerator (auto: the structure and parameters with the least
    /// estimated build + trace time for this render, with the reason).
    #[arg(long, value_enum, default_value_t = AccelChoice::Auto)]
    pub accel: AccelChoice,
    /// Image width in pixels.
    #[arg(long, default_value_t = 800, value_parser = side_parser(), allow_negative_numbers = true)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 600, value_parser = side_parser(), allow_negative_numbers = true)]
    pub height: u32,
    /// Samples (primary rays) per pixel.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=i64::from(limits::MAX_SPP)), allow_negative_numbers = true)]
    pub spp: u32,
    /// Ambient-occlusion rays per sample (0 turns ambient occlusion off).
    #[arg(long, default_value_t = 4, value_parser = clap::value_parser!(u32).range(0..=i64::from(limits::MAX_AO)), allow_negative_numbers = true)]
    pub ao: u32,
    /// Output PNG file.
    #[arg(long, value_name = "FILE", default_value = "render.png")]
    pub out: PathBuf,
    /// Precision of geometry and queries.
    #[arg(long, value_enum, default_value_t = Precision::F32)]
    pub precision: Precision,
    /// Also write a heat map of traversal cost per pixel (cells or nodes
    /// visited and primitive tests of the primary rays) with a colour legend;
    /// `--heatmap` alone writes heatmap.png, `--heatmap=FILE` names it.
    #[arg(
        long,
        value_name = "FILE",
        num_args = 0..=1,
        require_equals = true,
        default_missing_value = "heatmap.png"
    )]
    pub heatmap: Option<PathBuf>,
    /// Worker threads [default: all cores].
    #[arg(long, value_parser = threads_parser(), allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Memory the render's image buffers may take, in GiB: a render whose
    /// estimate (bytes per pixel × pixels) is larger is refused, with the
    /// figure, before any work. The structure a named `--accel` builds gets
    /// the same budget of its own, and its build stops, with the figure, as
    /// soon as it counts past it.
    #[arg(long, value_name = "GIB", default_value_t = limits::MEMORY_BUDGET_GIB, value_parser = memory_budget_parser, allow_negative_numbers = true)]
    pub memory_budget: f64,
    /// One shard of the image, for a job array.
    #[command(flatten)]
    pub shard: ShardArgs,
    /// The speed-against-accuracy dials.
    #[command(flatten)]
    pub dials: DialArgs,
}

/// Options of `render bench [SCENE]`.
#[derive(Clone, Debug, Args)]
pub struct BenchArgs {
    /// A .gltf/.glb file or a built-in scene name.
    #[arg(value_name = "SCENE", default_value = "default")]
    pub scene: String,
    /// Accelerators to measure, comma-separated [default: every structure,
    /// and brute force when it would finish quickly].
    #[arg(long, value_enum, value_delimiter = ',')]
    pub accel: Vec<AccelChoice>,
    /// Trace the rays of this binary ray file instead of generated ones.
    #[arg(long, value_name = "FILE")]
    pub rays: Option<PathBuf>,
    /// Write the generated ray sets (primary, then shadow, then diffuse) to
    /// this binary ray file.
    #[arg(long, value_name = "FILE")]
    pub write_rays: Option<PathBuf>,
    /// Write the results as JSON to this file.
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Threads of the multi-threaded runs [default: all cores].
    #[arg(long, value_parser = threads_parser(), allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Width of the primary-ray image.
    #[arg(long, default_value_t = 512, value_parser = side_parser(), allow_negative_numbers = true)]
    pub width: u32,
    /// Height of the primary-ray image.
    #[arg(long, default_value_t = 512, value_parser = side_parser(), allow_negative_numbers = true)]
    pub height: u32,
    /// Precision of geometry and queries.
    #[arg(long, value_enum, default_value_t = Precision::F32)]
    pub precision: Precision,
    /// Minimum seconds spent timing each figure (passes repeat until then).
    #[arg(long, default_value_t = 0.5, value_parser = min_time_parser, allow_negative_numbers = true)]
    pub min_time: f64,
    /// Memory the generated ray sets may take, in GiB: a bench whose
    /// estimate (bytes per primary pixel × pixels) is larger is refused,
    /// with the figure, before any work. Rays read with `--rays` are
    /// bounded by their file instead.
    #[arg(long, value_name = "GIB", default_value_t = limits::MEMORY_BUDGET_GIB, value_parser = memory_budget_parser, allow_negative_numbers = true)]
    pub memory_budget: f64,
    /// Write the nearest hit of every ray of `--rays` (found by the first
    /// accelerator of `--accel`) to this file: a hits file, or with
    /// `--shard`/`--shards` the part file of this shard's slice of the rays.
    #[arg(long, value_name = "FILE", requires = "rays")]
    pub hits: Option<PathBuf>,
    /// One slice of the ray file, for a job array (needs `--hits`).
    #[command(flatten)]
    pub shard: ShardArgs,
    /// The speed-against-accuracy dials.
    #[command(flatten)]
    pub dials: DialArgs,
}

/// The ray–triangle test, as `--triangle-test` names it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum TestChoice {
    /// Woop, Benthin & Wald's watertight test: no ray leaks through shared
    /// edges or vertices (the default).
    #[default]
    Watertight,
    /// Möller–Trumbore: fewer operations, early exit on most misses; rays
    /// through shared edges and vertices can leak.
    MollerTrumbore,
}

impl TestChoice {
    /// The library's name for it.
    #[must_use]
    pub const fn test(self) -> TriangleTest {
        match self {
            Self::Watertight => TriangleTest::Watertight,
            Self::MollerTrumbore => TriangleTest::MollerTrumbore,
        }
    }
}

/// How cells and leaves keep their triangles, as `--layout` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum LayoutChoice {
    /// Copied into blocks of four, tested together with SIMD.
    Packed,
    /// Indices into the mesh only: the least memory.
    Indexed,
}

impl LayoutChoice {
    /// The library's name for it.
    #[must_use]
    pub const fn layout(self) -> Layout {
        match self {
            Self::Packed => Layout::Packed,
            Self::Indexed => Layout::Indexed,
        }
    }
}

/// Where secondary rays start, as `--spawn` names it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum SpawnChoice {
    /// pbrt-v4's offset by the hit point's rounding-error bound (the default):
    /// never self-intersects, a few ulps from the surface.
    #[default]
    ErrorBound,
    /// The hit point pushed `--epsilon` scene units along the normal: too
    /// small far from the origin (self-intersections), too large near small
    /// features (missed occluders).
    Epsilon,
}

/// The speed-against-accuracy dials shared by `render` and `render bench`
/// (precision is `--precision`). Each buys speed or memory with accuracy or
/// the reverse; `studies tradeoff` measures them.
#[derive(Clone, Debug, Default, Args)]
pub struct DialArgs {
    /// Ray–triangle test (moller-trumbore: faster, leaks through shared edges).
    #[arg(long, value_enum, default_value_t = TestChoice::Watertight)]
    pub triangle_test: TestChoice,
    /// Origin of shadow and occlusion rays (epsilon: the textbook fixed offset).
    #[arg(long, value_enum, default_value_t = SpawnChoice::ErrorBound)]
    pub spawn: SpawnChoice,
    /// The offset of `--spawn epsilon`, in scene units.
    #[arg(long, default_value_t = 1e-4, value_parser = epsilon_parser, allow_negative_numbers = true)]
    pub epsilon: f64,
    /// How the structures keep the triangles of their cells and leaves:
    /// packed in blocks tested four at a time with SIMD (more memory), or
    /// indexed into the mesh only [default: each structure's own, indexed
    /// for all three, the faster on most scenes measured].
    #[arg(long, value_enum)]
    pub layout: Option<LayoutChoice>,
    /// Grid density m (about m³ cells per object; default 2). Needs --accel grid.
    #[arg(long, value_name = "M", value_parser = density_parser, allow_negative_numbers = true)]
    pub grid_density: Option<f64>,
    /// One grid over the whole scene (the seed's), even where a small dense
    /// part or a floor would get a grid of its own. Needs --accel grid.
    #[arg(long)]
    pub grid_no_parts: bool,
    /// Octree preset. Needs --accel octree.
    #[arg(long, value_name = "PRESET", value_parser = PossibleValuesParser::new(OCTREE_PRESETS))]
    pub octree_preset: Option<String>,
    /// Octree split threshold: a cell with more references becomes a grid.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..), allow_negative_numbers = true)]
    pub octree_threshold: Option<u32>,
    /// Octree depth limit: levels of child grids below the root (0 to 24).
    #[arg(long, value_name = "D", allow_negative_numbers = true)]
    pub octree_depth: Option<u32>,
    /// Octree without a flat part: primitives lying flat in one plane (a
    /// floor) stay under the root grid with the rest.
    #[arg(long)]
    pub octree_no_flat_part: bool,
    /// kD-tree preset. Needs --accel kdtree.
    #[arg(long, value_name = "PRESET", value_parser = PossibleValuesParser::new(KDTREE_PRESETS))]
    pub kdtree_preset: Option<String>,
    /// kD-tree SAH cost of a primitive test (relative to a traversal step).
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub kdtree_intersect_cost: Option<f64>,
    /// kD-tree SAH cost of a traversal step.
    #[arg(long, value_name = "C", allow_negative_numbers = true)]
    pub kdtree_traversal_cost: Option<f64>,
    /// kD-tree SAH bonus for cutting off empty space, in [0, 1).
    #[arg(long, value_name = "B", allow_negative_numbers = true)]
    pub kdtree_empty_bonus: Option<f64>,
    /// kD-tree nodes over more primitives than N split by the binned SAH
    /// (faster builds of large scenes); `max` makes every split exact.
    #[arg(long, value_name = "N", value_parser = binned_above_parser)]
    pub kdtree_binned_above: Option<usize>,
    /// Bins per axis of the kD-tree's binned SAH (2 to 4096).
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    pub kdtree_bins: Option<u32>,
    /// The constant of the kD-tree's depth limit, round(D + 1.3·floor(log2
    /// n)): 8 is pbrt's (the default), lower builds faster.
    #[arg(long, value_name = "D", allow_negative_numbers = true)]
    pub kdtree_depth_base: Option<f64>,
    /// kD-tree without a flat part: primitives lying flat in one plane (a
    /// floor) stay in one tree with the rest, so rays leaving the floor walk
    /// down to the leaf they start in.
    #[arg(long)]
    pub kdtree_no_flat_part: bool,
    /// kD-tree nodes of at most N primitives become leaves without an SAH
    /// search (0: the SAH alone decides).
    #[arg(long, value_name = "N")]
    pub kdtree_leaf_size: Option<u32>,
    /// The fast build's (--kdtree-binned-above 0) exact clipping of
    /// straddling triangles, in nodes over N primitives; `max` never.
    #[arg(long, value_name = "N", value_parser = binned_above_parser)]
    pub kdtree_clip_above: Option<usize>,
    /// The fast build's cheaper tightening of straddlers' boxes to the
    /// triangle's halves, in nodes over N primitives; `max` never.
    #[arg(long, value_name = "N", value_parser = binned_above_parser)]
    pub kdtree_tighten_above: Option<usize>,
}

impl DialArgs {
    /// The spawn offset in precision `T`.
    #[must_use]
    pub fn spawn_offset<T: Real>(&self) -> SpawnOffset<T> {
        match self.spawn {
            SpawnChoice::ErrorBound => SpawnOffset::ErrorBound,
            SpawnChoice::Epsilon => SpawnOffset::Fixed(T::from_f64(self.epsilon)),
        }
    }

    /// The structure options given, by the kind they belong to.
    fn structure_options(&self) -> Vec<(&'static str, AccelKind)> {
        let mut given = Vec::new();
        let mut add = |set: bool, name, kind| {
            if set {
                given.push((name, kind));
            }
        };
        add(
            self.grid_density.is_some(),
            "--grid-density",
            AccelKind::Grid,
        );
        add(self.grid_no_parts, "--grid-no-parts", AccelKind::Grid);
        add(
            self.octree_preset.is_some(),
            "--octree-preset",
            AccelKind::Octree,
        );
        add(
            self.octree_threshold.is_some(),
            "--octree-threshold",
            AccelKind::Octree,
        );
        add(
            self.octree_depth.is_some(),
            "--octree-depth",
            AccelKind::Octree,
        );
        add(
            self.octree_no_flat_part,
            "--octree-no-flat-part",
            AccelKind::Octree,
        );
        add(
            self.kdtree_preset.is_some(),
            "--kdtree-preset",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_intersect_cost.is_some(),
            "--kdtree-intersect-cost",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_traversal_cost.is_some(),
            "--kdtree-traversal-cost",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_empty_bonus.is_some(),
            "--kdtree-empty-bonus",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_binned_above.is_some(),
            "--kdtree-binned-above",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_bins.is_some(),
            "--kdtree-bins",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_depth_base.is_some(),
            "--kdtree-depth-base",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_no_flat_part,
            "--kdtree-no-flat-part",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_leaf_size.is_some(),
            "--kdtree-leaf-size",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_clip_above.is_some(),
            "--kdtree-clip-above",
            AccelKind::KdTree,
        );
        add(
            self.kdtree_tighten_above.is_some(),
            "--kdtree-tighten-above",
            AccelKind::KdTree,
        );
        given
    }

    /// Refuses structure options for structures that will not be built.
    ///
    /// # Errors
    /// A message naming the option and the `--accel` it needs.
    pub fn check_structure_options(&self, kinds: &[AccelKind], auto: bool) -> Result<(), String> {
        for (option, kind) in self.structure_options() {
            if !kinds.contains(&kind) {
                let why = if auto {
                    " (--accel auto chooses its own parameters)"
                } else {
                    ""
                };
                return Err(format!(
                    "{option} sets the {kind}'s parameters: it needs --accel {kind}{why}"
                ));
            }
        }
        Ok(())
    }

    /// The configuration of `kind`: its defaults, then the preset, then the
    /// single options given.
    #[must_use]
    pub fn config(&self, kind: AccelKind) -> AccelConfig {
        match kind {
            AccelKind::Grid => AccelConfig::Grid {
                density: self.grid_density.unwrap_or(2.0),
                layout: self.layout.map_or(GRID_LAYOUT, LayoutChoice::layout),
                parts: !self.grid_no_parts,
            },
            AccelKind::Octree => {
                let mut p = self
                    .octree_preset
                    .as_deref()
                    .and_then(octree_preset)
                    .unwrap_or_default();
                if let Some(t) = self.octree_threshold {
                    p.split_threshold = t as usize;
                }
                if let Some(d) = self.octree_depth {
                    p.max_depth = d;
                }
                if self.octree_no_flat_part {
                    p.flat_part = false;
                }
                if let Some(l) = self.layout {
                    p.layout = l.layout();
                }
                AccelConfig::Octree(p)
            }
            AccelKind::KdTree => {
                let mut p = self
                    .kdtree_preset
                    .as_deref()
                    .and_then(kdtree_preset)
                    .unwrap_or_default();
                if let Some(c) = self.kdtree_intersect_cost {
                    p.intersect_cost = c;
                }
                if let Some(c) = self.kdtree_traversal_cost {
                    p.traversal_cost = c;
                }
                if let Some(b) = self.kdtree_empty_bonus {
                    p.empty_bonus = b;
                }
                if let Some(n) = self.kdtree_binned_above {
                    p.binned_above = n;
                }
                if let Some(k) = self.kdtree_bins {
                    p.bins = k;
                }
                if let Some(d) = self.kdtree_depth_base {
                    p.depth_base = d;
                }
                if self.kdtree_no_flat_part {
                    p.flat_part = false;
                }
                if let Some(n) = self.kdtree_leaf_size {
                    p.leaf_size = n;
                }
                if let Some(n) = self.kdtree_clip_above {
                    p.clip_above = n;
                }
                if let Some(n) = self.kdtree_tighten_above {
                    p.tighten_above = n;
                }
                if let Some(l) = self.layout {
                    p.layout = l.layout();
                }
                AccelConfig::KdTree(p)
            }
            AccelKind::Brute => AccelConfig::Brute,
        }
    }
}

/// A primitive count, or `max` for no limit.
fn binned_above_parser(s: &str) -> Result<usize, String> {
    if s == "max" {
        return Ok(usize::MAX);
    }
    s.parse()
        .map_err(|e| format!("{e}: expected a primitive count or `max`"))
}

fn epsilon_parser(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} is not a finite offset >= 0"))
    }
}

/// Parses a grid density: finite, above 0, at most 64.
///
/// # Errors
/// A message naming the accepted range.
pub fn density_parser(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v > 0.0 && v <= 64.0 {
        Ok(v)
    } else {
        Err(format!("{v} is not a density in (0, 64]"))
    }
}

/// The accepted image sides.
#[must_use]
pub fn side_parser() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..=i64::from(limits::MAX_SIDE))
}

/// The accepted `--threads` values.
#[must_use]
pub fn threads_parser() -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(1..=limits::MAX_THREADS as u64)
}

/// Parses a duration in seconds, 0 to 3600.
///
/// # Errors
/// A message naming the value.
pub fn min_time_parser(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if (0.0..=3600.0).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{v} is not in 0..=3600 seconds"))
    }
}

/// Parses `--memory-budget`: a finite number of GiB above 0.
///
/// # Errors
/// A message for anything else.
pub fn memory_budget_parser(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} is not a number of GiB above 0"))
    }
}

/// Checks what clap's per-option ranges cannot: the pixel and ray totals.
///
/// # Errors
/// A message naming the product that is too large.
pub fn check_render_totals(args: &RenderArgs) -> Result<(), String> {
    let pixels = u64::from(args.width) * u64::from(args.height);
    if pixels > limits::MAX_PIXELS {
        return Err(format!(
            "--width {} × --height {} = {pixels} pixels is over the limit of {}",
            args.width,
            args.height,
            limits::MAX_PIXELS
        ));
    }
    let rays = pixels * u64::from(args.spp) * (2 + u64::from(args.ao));
    if rays > limits::MAX_RAYS {
        return Err(format!(
            "{pixels} pixels × --spp {} × (2 + --ao {}) = {rays} rays is over the limit of {}",
            args.spp,
            args.ao,
            limits::MAX_RAYS
        ));
    }
    Ok(())
}

/// Checks the bench's primary-ray image size.
///
/// # Errors
/// A message when `width × height` is over [`limits::MAX_PIXELS`].
pub fn check_bench_totals(args: &BenchArgs) -> Result<(), String> {
    let pixels = u64::from(args.width) * u64::from(args.height);
    if pixels > limits::MAX_PIXELS {
        return Err(format!(
            "--width {} × --height {} = {pixels} primary rays is over the limit of {}",
            args.width,
            args.height,
            limits::MAX_PIXELS
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("render").chain(args.iter().copied()))
    }

    #[test]
    fn defaults_render_the_embedded_scene() {
        let cli = parse(&[]).unwrap();
        assert!(cli.command.is_none());
        assert_eq!(cli.render.scene, None);
        assert_eq!(cli.render.out, PathBuf::from("render.png"));
        assert_eq!((cli.render.width, cli.render.height), (800, 600));
        assert_eq!(cli.render.heatmap, None);
    }

    #[test]
    fn heatmap_takes_an_optional_value_with_equals() {
        let cli = parse(&["--heatmap", "scene.glb"]).unwrap();
        assert_eq!(cli.render.heatmap, Some(PathBuf::from("heatmap.png")));
        assert_eq!(cli.render.scene.as_deref(), Some("scene.glb"));
        let cli = parse(&["--heatmap=h.png"]).unwrap();
        assert_eq!(cli.render.heatmap, Some(PathBuf::from("h.png")));
    }

    #[test]
    fn bench_is_a_subcommand_and_lists_accelerators() {
        let cli = parse(&["bench", "soup_100k", "--accel", "grid,brute"]).unwrap();
        let Some(Command::Bench(b)) = cli.command else {
            panic!("not bench")
        };
        assert_eq!(b.scene, "soup_100k");
        assert_eq!(b.accel, vec![AccelChoice::Grid, AccelChoice::Brute]);
        // A file whose name starts with "bench" is a scene, not the subcommand.
        let cli = parse(&["bench.glb"]).unwrap();
        assert!(cli.command.is_none());
        assert_eq!(cli.render.scene.as_deref(), Some("bench.glb"));
    }

    #[test]
    fn dials_parse_into_configs_and_offsets() {
        let cli = parse(&[
            "--accel",
            "kdtree",
            "--kdtree-preset",
            "pbrt",
            "--kdtree-intersect-cost",
            "20",
            "--kdtree-binned-above",
            "max",
            "--kdtree-bins",
            "16",
            "--kdtree-depth-base",
            "5.5",
            "--triangle-test",
            "moller-trumbore",
            "--spawn",
            "epsilon",
            "--epsilon",
            "0.001",
        ])
        .unwrap();
        let d = &cli.render.dials;
        assert_eq!(d.triangle_test.test(), TriangleTest::MollerTrumbore);
        assert_eq!(d.spawn_offset::<f64>(), SpawnOffset::Fixed(0.001));
        let AccelConfig::KdTree(p) = d.config(AccelKind::KdTree) else {
            panic!("not a kd-tree")
        };
        assert_eq!((p.intersect_cost, p.empty_bonus), (20.0, 0.5));
        assert_eq!((p.binned_above, p.bins), (usize::MAX, 16));
        assert_eq!(p.depth_base, 5.5);
        assert!(p.flat_part, "a flat part unless refused");
        let cli = parse(&["--accel", "kdtree", "--kdtree-no-flat-part"]).unwrap();
        let AccelConfig::KdTree(p) = cli.render.dials.config(AccelKind::KdTree) else {
            panic!("not a kd-tree")
        };
        assert!(!p.flat_part);
        assert_eq!(
            AccelConfig::KdTree(p).label(),
            "kdtree ci=5 ct=1 eb=0.3 no-flat"
        );
        // The fast build's own dials, on top of its preset, and named.
        let cli = parse(&[
            "--accel",
            "kdtree",
            "--kdtree-preset",
            "fast-build",
            "--kdtree-leaf-size",
            "4",
            "--kdtree-clip-above",
            "1000",
            "--kdtree-tighten-above",
            "max",
        ])
        .unwrap();
        let AccelConfig::KdTree(p) = cli.render.dials.config(AccelKind::KdTree) else {
            panic!("not a kd-tree")
        };
        assert_eq!(
            (p.leaf_size, p.clip_above, p.tighten_above),
            (4, 1000, usize::MAX)
        );
        assert_eq!(p.bins, kdtree_preset("fast-build").unwrap().bins);
        assert_eq!(
            AccelConfig::KdTree(p).label(),
            "kdtree ci=5 ct=2 eb=0.3 binned>0/32 db=3 ls=4 clip>1000"
        );
        assert!(parse(&["--accel", "kdtree", "--kdtree-clip-above", "some"]).is_err());
        let cli = parse(&["--accel", "octree", "--octree-no-flat-part"]).unwrap();
        let AccelConfig::Octree(p) = cli.render.dials.config(AccelKind::Octree) else {
            panic!("not an octree")
        };
        assert!(!p.flat_part);
        assert_eq!(AccelConfig::Octree(p).label(), "octree t=12 d=6 no-flat");
        let err = cli
            .render
            .dials
            .check_structure_options(&[AccelKind::KdTree], false)
            .unwrap_err();
        assert!(err.contains("--octree-no-flat-part"), "{err}");
        // --layout turns every structure's layout; unset, each keeps its own
        // default, and labels name only a layout that differs from it.
        let l = parse(&["--accel", "grid"]).unwrap().render.dials;
        assert_eq!(l.config(AccelKind::Grid).label(), "grid m=2");
        assert_eq!(l.config(AccelKind::KdTree).label(), "kdtree");
        let l = parse(&["--layout", "packed"]).unwrap().render.dials;
        assert_eq!(l.config(AccelKind::Grid).label(), "grid m=2 packed");
        let l = parse(&["--layout", "indexed"]).unwrap().render.dials;
        assert_eq!(l.config(AccelKind::Grid).label(), "grid m=2");
        assert_eq!(l.config(AccelKind::Octree).label(), "octree");
        let l = parse(&["--layout", "packed", "--kdtree-preset", "pbrt"])
            .unwrap()
            .render
            .dials;
        assert_eq!(l.config(AccelKind::KdTree).label(), "kdtree pbrt packed");
        assert_eq!(l.config(AccelKind::Octree).label(), "octree packed");
        assert!(parse(&["--layout", "soa"]).is_err());
        assert!(parse(&["--accel", "kdtree", "--kdtree-binned-above", "lots"]).is_err());
        assert!(
            d.check_structure_options(&[AccelKind::KdTree], false)
                .is_ok()
        );
        let err = d
            .check_structure_options(&[AccelKind::Grid], true)
            .unwrap_err();
        assert!(
            err.contains("--kdtree-preset") && err.contains("auto"),
            "{err}"
        );
        let cli = parse(&[
            "--accel",
            "octree",
            "--octree-threshold",
            "4",
            "--octree-depth",
            "2",
        ])
        .unwrap();
        let AccelConfig::Octree(p) = cli.render.dials.config(AccelKind::Octree) else {
            panic!("not an octree")
        };
        assert_eq!((p.split_threshold, p.max_depth), (4, 2));
        assert_eq!(
            parse(&[]).unwrap().render.dials.config(AccelKind::Grid),
            AccelConfig::grid(2.0)
        );
        for bad in [
            &["--grid-density", "0"][..],
            &["--grid-density", "nan"],
            &["--epsilon", "-1"],
            &["--octree-preset", "huge"],
            &["--octree-threshold", "0"],
            &["--triangle-test", "fast"],
        ] {
            assert!(parse(bad).is_err(), "{bad:?} accepted");
        }
    }

    #[test]
    fn absurd_sizes_are_refused() {
        for bad in [
            &["--width", "0"][..],
            &["--height", "100000"],
            &["--spp", "0"],
            &["--spp", "1000000000"],
            &["--width", "-3"],
            &["--ao", "100000"],
            &["--threads", "0"],
        ] {
            assert!(parse(bad).is_err(), "{bad:?} accepted");
        }
        let cli = parse(&["--width", "16384", "--height", "16384"]).unwrap();
        let err = check_render_totals(&cli.render).unwrap_err();
        assert!(err.contains("pixels"), "{err}");
        let cli = parse(&["--width", "8192", "--height", "8192", "--spp", "4096"]).unwrap();
        let err = check_render_totals(&cli.render).unwrap_err();
        assert!(err.contains("rays"), "{err}");
        assert!(check_render_totals(&parse(&[]).unwrap().render).is_ok());
    }

    #[test]
    fn choices_name_their_kinds() {
        assert_eq!(AccelChoice::Kdtree.kind(), Some(AccelKind::KdTree));
        assert_eq!(AccelChoice::Auto.kind(), None);
        for k in AccelKind::ALL {
            let parsed = AccelChoice::from_str(k.name(), false).unwrap();
            assert_eq!(parsed.kind(), Some(k));
        }
    }
}
