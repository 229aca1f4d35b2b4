//! `studies choose-bench`: is `--accel auto` within 10% of the best choice?
//!
//! For every scene and two ray budgets of a render (`preview`: 160×120,
//! 1 spp, 1 occlusion ray; `final`: 800×600, 2 spp, 4 occlusion rays; each
//! `pixels × spp × (2 + ao)` rays), every accelerator and preset is built
//! once (timed) and traces a sample of that render's ray mix (primary,
//! shadow and occlusion rays from a view of about `--sample-primaries`
//! primary rays; the faster of two passes). Its total for a budget is
//! `build + rays × time per ray`. A candidate whose pass would take longer
//! than `--max-pass-time` (the uniform grid on a teapot in a stadium) is
//! priced from the part of the sample traced in that time (spread over the
//! whole view, see [`accel::choose::probe_per_ray`]). Then [`accel::choose_with_probe`] runs as
//! `render --accel auto` would, and its choice's total (from the same table,
//! so that both sides share one measurement) is compared with the best.
//! The chooser's own cost (its probe, less the winner's build) is reported
//! beside it. On a shared machine, `--rounds` measures every candidate
//! several times in interleaved rounds and keeps the fastest.

use crate::tradeoff::{scene_list, short_name};
use accel::choose::{self, ProbeRay, brute_per_ray, probe_per_ray};
use accel::{AccelConfig, build_config, kdtree_preset, octree_preset};
use accel_core::spawn::SpawnOffset;
use anyhow::Result;
use clap::Args;
use render::app::{load_scene, mesh_in};
use render::cli::threads_parser;
use render::output::PendingFile;
use render::probe::{ProbeShape, view_probe};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Options of `studies choose-bench`.
#[derive(Clone, Debug, Args)]
pub struct ChooseBenchArgs {
    /// A .gltf/.glb file, a built-in scene name, a comma-separated list of
    /// them, or `all`.
    #[arg(value_name = "SCENE", default_value = "all")]
    pub scene: String,
    /// Write every candidate's estimate as CSV to this file.
    #[arg(long, value_name = "FILE", default_value = "choose-bench.csv")]
    pub csv: PathBuf,
    /// Threads (builds, traces and the chooser) [default: all cores].
    #[arg(long, value_parser = threads_parser(), allow_negative_numbers = true)]
    pub threads: Option<usize>,
    /// Primary rays of the sampled view (plus their shadow and occlusion rays).
    #[arg(long, default_value_t = 12_288, value_parser = clap::value_parser!(u32).range(16..=4_000_000), allow_negative_numbers = true)]
    pub sample_primaries: u32,
    /// Seconds one candidate may spend tracing the sample; a slower one is
    /// priced from the rays traced by then.
    #[arg(long, value_name = "SECONDS", default_value_t = 3.0, value_parser = positive_seconds)]
    pub max_pass_time: f64,
    /// Measure every candidate this many times, in interleaved rounds, and
    /// keep its fastest build and fastest time per ray: on a shared machine
    /// a burst of load lasting seconds then hits one round, not the result.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=10))]
    pub rounds: u32,
    /// Run only the chooser (its choice and its own cost), not the table of
    /// every candidate: no ratio to the best, and an empty CSV.
    #[arg(long)]
    pub auto_only: bool,
}

fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("{s:?} is not a positive number of seconds")),
    }
}

/// A render budget.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// Name.
    pub name: &'static str,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Occlusion rays per sample.
    pub ao: u32,
}

impl Budget {
    /// Rays of the render: `pixels × spp × (2 + ao)`.
    #[must_use]
    pub fn rays(&self) -> u64 {
        u64::from(self.width)
            * u64::from(self.height)
            * u64::from(self.spp)
            * (2 + u64::from(self.ao))
    }
}

/// The two budgets measured.
pub const BUDGETS: [Budget; 2] = [
    Budget {
        name: "preview",
        width: 160,
        height: 120,
        spp: 1,
        ao: 1,
    },
    Budget {
        name: "final",
        width: 800,
        height: 600,
        spp: 2,
        ao: 4,
    },
];

/// Every candidate the benchmark measures: each structure with its presets.
#[must_use]
pub fn candidates() -> Vec<AccelConfig> {
    let mut out: Vec<AccelConfig> = [1.0, 1.5, 2.0, 3.0]
        .into_iter()
        .map(AccelConfig::grid)
        .collect();
    out.extend(
        accel::OCTREE_PRESETS
            .iter()
            .filter_map(|p| octree_preset(p))
            .map(AccelConfig::Octree),
    );
    out.extend(
        accel::KDTREE_PRESETS
            .iter()
            .filter_map(|p| kdtree_preset(p))
            .map(AccelConfig::KdTree),
    );
    out.push(AccelConfig::Brute);
    out
}

/// `studies choose-bench`.
///
/// # Errors
/// Every refusal, as one line naming the problem.
pub fn run(args: &ChooseBenchArgs) -> Result<()> {
    let csv_out = PendingFile::create(&args.csv)?;
    let (pool, _) = render::app::thread_pool(args.threads)?;
    let mut csv = String::from(
        "scene,triangles,budget,rays,config,build_ms,ns_per_ray,timed_rays,total_s,chosen,best\n",
    );
    let mut summary = Vec::new();
    println!(
        "{:<18} {:<8} {:>9} {:<22} {:>9} {:<22} {:>9} {:>7} {:>10}",
        "scene", "budget", "rays", "best", "total s", "auto", "total s", "ratio", "auto ms"
    );
    for name in scene_list(&args.scene) {
        let scene = load_scene(&name)?;
        let mesh = mesh_in::<f32>(&scene)?;
        for budget in BUDGETS {
            let rays = budget.rays();
            let (table, choice) = pool.install(|| -> Result<_> {
                // Every structure answers alike: the sample is made with the
                // octree, which no scene makes slow (the grid can be).
                let octree = accel::build(accel::AccelKind::Octree, &mesh)?;
                // The budget's view, with `primaries` primary rays.
                let shape = |primaries| ProbeShape {
                    width: budget.width,
                    height: budget.height,
                    ao: budget.ao,
                    primaries,
                };
                let sample: Vec<ProbeRay<f32>> = view_probe(
                    &octree,
                    &mesh,
                    &scene.view,
                    shape(args.sample_primaries),
                    SpawnOffset::ErrorBound,
                )?;
                drop(octree);
                let max_pass = Duration::from_secs_f64(args.max_pass_time);
                let all = if args.auto_only {
                    Vec::new()
                } else {
                    candidates()
                };
                // (build s, s per ray, rays timed), the fastest of the rounds.
                let mut fastest = vec![(f64::INFINITY, f64::INFINITY, 0usize); all.len()];
                for _ in 0..args.rounds {
                    for (config, best) in all.iter().zip(&mut fastest) {
                        let (build_s, per, timed) = if *config == AccelConfig::Brute {
                            (0.0, brute_per_ray(&mesh, &sample), 0)
                        } else {
                            let t = Instant::now();
                            let accel = build_config(config, &mesh)?;
                            let b = t.elapsed().as_secs_f64();
                            let p = probe_per_ray(&accel, &sample, max_pass, f64::INFINITY)?;
                            (b, p.per_ray_s, p.rays)
                        };
                        best.0 = best.0.min(build_s);
                        if per < best.1 {
                            best.1 = per;
                            best.2 = timed;
                        }
                    }
                }
                let table: Vec<_> = all
                    .into_iter()
                    .zip(fastest)
                    .map(|(config, (build_s, per, timed))| {
                        (config, build_s, per, timed, build_s + rays as f64 * per)
                    })
                    .collect();
                let choice = accel::choose_with_probe(&mesh, rays, |a| {
                    view_probe(
                        a,
                        &mesh,
                        &scene.view,
                        shape(choose::PROBE_PRIMARIES),
                        SpawnOffset::ErrorBound,
                    )
                })?;
                let chosen_build = choice
                    .estimates
                    .iter()
                    .find(|e| e.config == choice.config)
                    .map_or(0.0, |e| e.build_s);
                let overhead = choice.elapsed.as_secs_f64() - chosen_build;
                let costs: Vec<String> = choice
                    .estimates
                    .iter()
                    .map(|e| format!("{} {:.0} ms", e.config, e.cost_s * 1e3))
                    .collect();
                let reason = format!("{}\n    cost: {}", choice.reason, costs.join(", "));
                Ok((table, (choice.config, overhead, reason)))
            })?;
            let (best, best_total) = table
                .iter()
                .min_by(|a, b| a.4.total_cmp(&b.4))
                .map_or((None, f64::NAN), |b| (Some(b.0.clone()), b.4));
            let (chosen, overhead, reason) = choice;
            let chosen_total = table
                .iter()
                .find(|c| c.0 == chosen)
                .map_or(f64::NAN, |c| c.4);
            let ratio = chosen_total / best_total;
            let short = short_name(&scene.name);
            println!(
                "{:<18} {:<8} {:>9} {:<22} {:>9.3} {:<22} {:>9.3} {:>7.3} {:>10.1}",
                short,
                budget.name,
                rays,
                best.as_ref()
                    .map_or_else(|| "-".to_owned(), AccelConfig::label),
                best_total,
                chosen.label(),
                chosen_total,
                ratio,
                overhead * 1e3
            );
            println!("    auto: {reason}");
            for (config, build_s, per, timed, total) in &table {
                csv += &format!(
                    "{},{},{},{},{},{:.3},{:.2},{},{:.5},{},{}\n",
                    short,
                    mesh.triangle_count(),
                    budget.name,
                    rays,
                    config.label(),
                    build_s * 1e3,
                    per * 1e9,
                    timed,
                    total,
                    u8::from(*config == chosen),
                    u8::from(Some(config) == best.as_ref())
                );
            }
            if !args.auto_only {
                summary.push((short, budget.name, ratio));
            }
        }
    }
    let within = summary.iter().filter(|s| s.2 <= 1.10).count();
    println!(
        "auto within 10% of the best: {within} of {} scene × budget pairs{}",
        summary.len(),
        if within == summary.len() {
            String::new()
        } else {
            format!(
                "; not: {}",
                summary
                    .iter()
                    .filter(|s| s.2 > 1.10)
                    .map(|s| format!("{} {} ({:.2}×)", s.0, s.1, s.2))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }
    );
    let dest = csv_out.dest().display().to_string();
    csv_out.write_all(csv.as_bytes())?;
    println!("wrote {dest}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_and_candidates() {
        assert_eq!(BUDGETS[0].rays(), 160 * 120 * 3);
        assert_eq!(BUDGETS[1].rays(), 800 * 600 * 2 * 6);
        let c = candidates();
        assert_eq!(c.len(), 4 + 4 + 4 + 1);
        // Everything the chooser may pick is measured.
        for config in choose::candidates() {
            assert!(c.contains(&config), "{config}");
        }
    }
}
