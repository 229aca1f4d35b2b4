//! The command line: `studies <SUBCOMMAND> [options]`. Each subcommand's
//! options are its own module's (`TradeoffArgs` in [`crate::tradeoff`], and
//! so on); this only names them.

use clap::{Args, Parser, Subcommand};
use render::cli::{side_parser, threads_parser};

/// The workspace's studies: speed against accuracy, the grid density
/// sweep, the chooser's check, the peers, and builds timed in alternation.
///
/// SCENE is a `.gltf`/`.glb` file or a built-in scene, as for `render`:
/// `default`, `sphere_100k`, `soup_100k`, `terrain_1m`,
/// `teapot_in_stadium`, `flat_field`.
#[derive(Debug, Parser)]
#[command(name = "studies", version, after_help = EXAMPLES)]
pub struct Cli {
    /// The study to run.
    #[command(subcommand)]
    pub command: Command,
}

const EXAMPLES: &str = "\
Examples:
  studies tradeoff all --csv docs/tradeoff.csv --plot docs/tradeoff.png
  studies sweep-density all --plot docs/sweep-density.png
  studies choose-bench all
  studies peers terrain_1m                 (peers: cargo run --release -p studies --features peers,embree)
  BUNDLES_ONLY=single studies alternate --figure single --run '/tmp/old/bundles sphere_100k' --run 'target/release/examples/bundles sphere_100k'";

/// Subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Measure every speed-against-accuracy dial: throughput, build time,
    /// memory, mismatches, leaks and self-intersections per setting.
    Tradeoff(crate::tradeoff::TradeoffArgs),
    /// Sweep the grid density m: Mrays/s and build time against cells per object.
    SweepDensity(crate::sweep::SweepArgs),
    /// Run every accelerator on every scene and compare `render --accel
    /// auto`'s choice with the best (total time: build + rays).
    ChooseBench(crate::choose_bench::ChooseBenchArgs),
    /// Run our accelerators and the peers (obvhs, parry3d, bvh with
    /// `--features peers`; Embree 3 with `--features embree`) on the same
    /// scene and rays on one thread: Mrays/s, ratios, build times, agreement.
    Peers(crate::peers::run::PeersArgs),
    /// Time two or more commands (two builds of one benchmark) in
    /// alternation, round after round: medians, maxima and ratios.
    Alternate(crate::alternate::AlternateArgs),
}

/// The options `tradeoff` and `sweep-density` share: the primary-ray view
/// and how many threads and timed passes each figure takes.
#[derive(Clone, Debug, Args)]
pub struct PassArgs {
    /// Width of the primary-ray view.
    #[arg(long, default_value_t = 256, value_parser = side_parser(), allow_negative_numbers = true)]
    pub width: u32,
    /// Height of the primary-ray view.
    #[arg(long, default_value_t = 192, value_parser = side_parser(), allow_negative_numbers = true)]
    pub height: u32,
    /// Threads for builds and timed passes.
    #[arg(long, default_value_t = 1, value_parser = threads_parser(), allow_negative_numbers = true)]
    pub threads: usize,
    /// Timed passes (and at most this many builds) per figure; the median is kept.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100), allow_negative_numbers = true)]
    pub repeats: u32,
}
