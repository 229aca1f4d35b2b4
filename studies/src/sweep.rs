//! `studies sweep-density`: the seed's claim that grids do best at 8 to 10
//! cells per object (density `m = 2`), measured.
//!
//! For each scene and each density `m`, the uniform grid is built (median of
//! up to `--repeats` builds) and traces the primary, shadow and diffuse rays
//! of `render bench` (generated once per scene: every grid gives the same
//! answers), median of `--repeats` passes on `--threads` threads (1 by
//! default). The table and CSV give cells per object, build time, bytes and
//! Mrays/s; the plot shows throughput (relative to the scene's best density)
//! and build time against cells per object.

use crate::cli::PassArgs;
use crate::plot::{Panel, Series, write_csv_and_plot};
use crate::tradeoff::{scene_list, short_name, time_set};
use accel::{AccelConfig, build_config};
use accel_core::spawn::SpawnOffset;
use accel_core::{Accelerator, Real};
use accel_scenes::GeneratedScene;
use anyhow::{Context, Result};
use clap::Args;
use render::app::{check_png_name, load_scene, mesh_in};
use render::bench::{self, RaySet};
use render::cli::density_parser;
use render::output::PendingFile;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Options of `studies sweep-density`.
#[derive(Clone, Debug, Args)]
pub struct SweepArgs {
    /// A .gltf/.glb file, a built-in scene name, a comma-separated list of
    /// them, or `all` (every scene but
    /// `teapot_in_stadium`: its dense sphere fits in one grid cell at every
    /// density swept, so each point costs minutes and shows only that the
    /// uniform grid cannot serve it; name it to sweep it anyway).
    #[arg(value_name = "SCENE", default_value = "all")]
    pub scene: String,
    /// Densities m to build (comma-separated).
    #[arg(long, value_delimiter = ',', value_parser = density_parser,
          default_value = "0.5,0.75,1,1.25,1.5,2,2.5,3,4")]
    pub densities: Vec<f64>,
    /// Write every row as CSV to this file.
    #[arg(long, value_name = "FILE", default_value = "sweep-density.csv")]
    pub csv: PathBuf,
    /// Write the plot (PNG) to this file.
    #[arg(long, value_name = "FILE", default_value = "sweep-density.png")]
    pub plot: PathBuf,
    /// The view and the effort.
    #[command(flatten)]
    pub pass: PassArgs,
}

/// One grid on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepRow {
    /// Scene (short name).
    pub scene: String,
    /// Triangles.
    pub triangles: usize,
    /// Density m.
    pub density: f64,
    /// Cells per triangle.
    pub cells_per_object: f64,
    /// References per triangle.
    pub refs_per_object: f64,
    /// Median build time, ms.
    pub build_ms: f64,
    /// Bytes.
    pub bytes: usize,
    /// Mrays/s of primary, shadow and diffuse rays.
    pub mrays: [f64; 3],
    /// All rays over the summed times.
    pub mrays_all: f64,
}

/// `studies sweep-density`.
///
/// # Errors
/// Every refusal, as one line naming the problem.
pub fn run(args: &SweepArgs) -> Result<()> {
    check_png_name(&args.plot, "--plot")?;
    let csv_out = PendingFile::create(&args.csv)?;
    let plot_out = PendingFile::create(&args.plot)?;
    let (pool, _) = render::app::thread_pool(Some(args.pass.threads))?;
    println!(
        "{:<18} {:>6} {:>9} {:>8} {:>9} {:>8} {:>7} {:>7} {:>7} {:>7}",
        "scene",
        "m",
        "cells/obj",
        "refs/obj",
        "build ms",
        "MiB",
        "prim",
        "shadow",
        "diffuse",
        "all"
    );
    let mut rows = Vec::new();
    let names: Vec<String> = scene_list(&args.scene)
        .into_iter()
        .filter(|n| args.scene != "all" || n != GeneratedScene::TeapotInStadium.name())
        .collect();
    for name in names {
        let scene = load_scene(&name)?;
        let mesh = mesh_in::<f32>(&scene)?;
        let sets = pool.install(|| -> Result<Vec<RaySet<f32>>> {
            let generator = accel::build(bench::RAY_GENERATOR, &mesh)?;
            Ok(bench::generate_rays_from(
                generator.as_dyn(),
                &mesh,
                &scene.view,
                args.pass.width,
                args.pass.height,
                SpawnOffset::ErrorBound,
            )
            .context("generating rays")?
            .sets)
        })?;
        for &m in &args.densities {
            let row = pool
                .install(|| sweep_one(&mesh, &sets, m, args.pass.repeats))
                .with_context(|| format!("{name}: m = {m}"))?;
            let row = SweepRow {
                scene: short_name(&scene.name),
                ..row
            };
            println!(
                "{:<18} {:>6} {:>9.2} {:>8.2} {:>9.1} {:>8.2} {:>7.2} {:>7.2} {:>7.2} {:>7.2}",
                row.scene,
                row.density,
                row.cells_per_object,
                row.refs_per_object,
                row.build_ms,
                row.bytes as f64 / (1024.0 * 1024.0),
                row.mrays[0],
                row.mrays[1],
                row.mrays[2],
                row.mrays_all
            );
            rows.push(row);
        }
    }
    write_csv_and_plot(csv_out, &csv(&rows), plot_out, &panels(&rows))
}

/// Builds the grid of density `m` and times it on `sets`.
fn sweep_one<T: Real>(
    mesh: &accel_core::TriangleMesh<T>,
    sets: &[RaySet<T>],
    m: f64,
    repeats: u32,
) -> Result<SweepRow> {
    let config = AccelConfig::grid(m);
    let mut builds = Vec::new();
    let mut grid = None;
    let start = Instant::now();
    for _ in 0..repeats {
        let t = Instant::now();
        grid = Some(build_config(&config, mesh)?);
        builds.push(t.elapsed().as_secs_f64() * 1e3);
        if start.elapsed() > Duration::from_secs(1) {
            break;
        }
    }
    let grid = grid.expect("one build");
    let stats = grid.stats();
    let n = mesh.triangle_count().max(1) as f64;
    let mut mrays = [0.0; 3];
    let (mut rays, mut secs) = (0usize, 0.0);
    for (i, set) in sets.iter().enumerate() {
        let s = time_set(grid.as_dyn(), set, repeats)?;
        mrays[i] = if s > 0.0 {
            set.rays.len() as f64 / s / 1e6
        } else {
            0.0
        };
        rays += set.rays.len();
        secs += s;
    }
    Ok(SweepRow {
        scene: String::new(),
        triangles: mesh.triangle_count(),
        density: m,
        cells_per_object: stats.nodes as f64 / n,
        refs_per_object: stats.references as f64 / n,
        build_ms: crate::median(builds),
        bytes: stats.bytes,
        mrays,
        mrays_all: if secs > 0.0 {
            rays as f64 / secs / 1e6
        } else {
            0.0
        },
    })
}

/// Every row as CSV, with a header line.
#[must_use]
pub fn csv(rows: &[SweepRow]) -> String {
    let mut out = String::from(
        "scene,triangles,density,cells_per_object,refs_per_object,build_ms,bytes,\
         mrays_primary,mrays_shadow,mrays_diffuse,mrays_all\n",
    );
    for r in rows {
        out += &format!(
            "{},{},{},{:.4},{:.4},{:.3},{},{:.4},{:.4},{:.4},{:.4}\n",
            r.scene,
            r.triangles,
            r.density,
            r.cells_per_object,
            r.refs_per_object,
            r.build_ms,
            r.bytes,
            r.mrays[0],
            r.mrays[1],
            r.mrays[2],
            r.mrays_all
        );
    }
    out
}

/// Two panels: relative throughput and build time against cells per object,
/// a line per scene.
fn panels(rows: &[SweepRow]) -> Vec<Panel> {
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let per_scene = |f: &dyn Fn(&SweepRow, f64) -> f64| -> Vec<Series> {
        scenes
            .iter()
            .map(|&s| {
                let here: Vec<&SweepRow> = rows.iter().filter(|r| r.scene == s).collect();
                let best = here.iter().map(|r| r.mrays_all).fold(0.0, f64::max);
                Series {
                    name: s.to_owned(),
                    points: here
                        .iter()
                        .map(|r| (r.cells_per_object, f(r, best)))
                        .collect(),
                    line: true,
                }
            })
            .collect()
    };
    let marks = |y: f64| -> Vec<(f64, f64, String)> {
        vec![(8.0, y, "| 8".into()), (10.0, y, "| 10".into())]
    };
    vec![
        Panel {
            title: "Grid throughput against cells per object".into(),
            x_label: "cells per object (m^3 ~ cells/object; seed: 8-10)".into(),
            y_label: "Mrays/s / best of the scene".into(),
            x_log: true,
            y_log: false,
            series: per_scene(&|r, best| if best > 0.0 { r.mrays_all / best } else { 0.0 }),
            labels: marks(0.05),
        },
        Panel {
            title: "Grid build time against cells per object".into(),
            x_label: "cells per object".into(),
            y_label: "build ms".into(),
            x_log: true,
            y_log: true,
            series: per_scene(&|r, _| r.build_ms.max(1e-3)),
            labels: Vec::new(),
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use accel::AccelKind;
    use accel_scenes::random_soup;

    #[test]
    fn denser_grids_have_more_cells_per_object_and_the_same_answers() {
        let mesh = random_soup(2_000, 3).cast::<f32>().unwrap();
        let scene = render::scene::default_scene().unwrap();
        let grid = accel::build(AccelKind::Grid, &mesh).unwrap();
        let sets = bench::generate_rays(&grid, &mesh, &scene.view, 16, 12).unwrap();
        let rows: Vec<SweepRow> = [1.0, 2.0, 4.0]
            .iter()
            .map(|&m| sweep_one(&mesh, &sets, m, 1).unwrap())
            .collect();
        assert!(rows[0].cells_per_object < rows[1].cells_per_object);
        assert!(rows[1].cells_per_object < rows[2].cells_per_object);
        // m = 2 gives about 8 cells per object (m³), the seed's rule.
        assert!((6.0..14.0).contains(&rows[1].cells_per_object), "{rows:?}");
        assert_eq!(csv(&rows).lines().count(), 4);
        assert_eq!(panels(&rows).len(), 2);
    }
}
