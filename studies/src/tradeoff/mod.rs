//! `studies tradeoff SCENE`: every speed-against-accuracy dial, measured.
//!
//! For each [`settings::Setting`] (one point each): build time (median of up
//! to `--repeats` builds), bytes, Mrays/s of the primary, shadow and diffuse
//! sets of `render bench` (median of `--repeats` passes, on `--threads`
//! threads, 1 by default: steadier on a shared machine), and three error
//! rates:
//!
//! - **mismatch**: of `--samples` rays (half camera rays, half random rays
//!   from around the scene), the share whose nearest hit (primitive, or hit
//!   against miss) differs from the `f64` watertight brute-force reference.
//!   For scenes where brute force would take long, the reference is an `f64`
//!   kD-tree, which is bit-for-bit equal to brute force (the workspace's
//!   central invariant, checked by the test suites);
//! - **leaks**: of `--leak-rays` rays aimed from outside at shared edges and
//!   vertices of the scene's closed parts ([`accel_scenes::aimed`]), the share that hit
//!   nothing;
//! - **self-hits**: of the shadow and diffuse (ambient-occlusion) rays, the
//!   share whose nearest hit is the triangle they leave.
//!
//! The table goes to stdout, every row to `--csv`, and a plot of throughput
//! against the summed error rates, one point per setting and a panel per
//! scene, to `--plot`.

pub mod settings;

use crate::cli::PassArgs;
use crate::plot::{Panel, Series, write_csv_and_plot};
use accel::build_config;
use accel_core::spawn::SpawnOffset;
use accel_core::{
    Accelerator, MollerTrumboreMesh, PrimitiveSet, Ray, Real, TriangleMesh, TriangleTest,
};
use accel_scenes::gltf::shared_scene_files;
use accel_scenes::{GeneratedScene, random_rays};
use anyhow::{Context, Result};
use clap::Args;
use rayon::prelude::*;
use render::app::{load_scene, mesh_in};
use render::bench::{self, RaySet};
use render::cli::Precision;
use render::output::PendingFile;
use render::scene::Scene;
use settings::{Setting, Spawn, all_settings};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Options of `studies tradeoff`.
#[derive(Clone, Debug, Args)]
pub struct TradeoffArgs {
    /// A .gltf/.glb file, a built-in scene name, a comma-separated list of
    /// them, or `all` (the default scene,
    /// the generated scenes and every file of ../shared/scenes).
    #[arg(value_name = "SCENE", default_value = "default")]
    pub scene: String,
    /// Write every row as CSV to this file.
    #[arg(long, value_name = "FILE", default_value = "tradeoff.csv")]
    pub csv: PathBuf,
    /// Write the plot of throughput against error (PNG) to this file.
    #[arg(long, value_name = "FILE", default_value = "tradeoff.png")]
    pub plot: PathBuf,
    /// The view and the effort.
    #[command(flatten)]
    pub pass: PassArgs,
    /// Rays compared with the f64 reference per scene.
    #[arg(long, default_value_t = 4096, value_parser = clap::value_parser!(u32).range(2..=1_000_000), allow_negative_numbers = true)]
    pub samples: u32,
    /// Rays aimed at shared edges and vertices per scene.
    #[arg(long, default_value_t = 20_000, value_parser = clap::value_parser!(u32).range(0..=10_000_000), allow_negative_numbers = true)]
    pub leak_rays: u32,
    /// Only settings whose name contains one of these (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
}

/// The scenes a SCENE argument names: one, a comma-separated list, or `all`.
#[must_use]
pub fn scene_list(arg: &str) -> Vec<String> {
    if arg != "all" {
        return arg.split(',').map(str::to_owned).collect();
    }
    std::iter::once(render::scene::DEFAULT_SCENE.to_owned())
        .chain(GeneratedScene::ALL.iter().map(|g| g.name().to_owned()))
        .chain(
            shared_scene_files()
                .into_iter()
                .map(|p| p.display().to_string()),
        )
        .collect()
}

/// A short scene name for tables and plots (the file stem for files).
#[must_use]
pub fn short_name(scene: &str) -> String {
    std::path::Path::new(scene)
        .file_stem()
        .map_or_else(|| scene.to_owned(), |s| s.to_string_lossy().into_owned())
}

/// One measured setting on one scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Scene (short name).
    pub scene: String,
    /// Triangles.
    pub triangles: usize,
    /// The setting.
    pub setting: Setting,
    /// Median build time, ms.
    pub build_ms: f64,
    /// Bytes of the structure.
    pub bytes: usize,
    /// Mrays/s of primary, shadow and diffuse rays.
    pub mrays: [f64; 3],
    /// All three sets' rays over their summed times, Mrays/s.
    pub mrays_all: f64,
    /// Sampled rays compared, and the ones that differ from the reference.
    pub mismatches: (usize, usize),
    /// Leak rays traced, and the ones that leaked.
    pub leaks: (usize, usize),
    /// Shadow rays, and the ones hitting their own triangle.
    pub shadow_self: (usize, usize),
    /// Diffuse (occlusion) rays, and the ones hitting their own triangle.
    pub ao_self: (usize, usize),
}

fn pct((n, bad): (usize, usize)) -> f64 {
    if n == 0 {
        0.0
    } else {
        100.0 * bad as f64 / n as f64
    }
}

impl Row {
    /// The summed error rates in percent: mismatch + leaks + self-hits
    /// (shadow and occlusion together).
    #[must_use]
    pub fn error_pct(&self) -> f64 {
        let selfs = (
            self.shadow_self.0 + self.ao_self.0,
            self.shadow_self.1 + self.ao_self.1,
        );
        pct(self.mismatches) + pct(self.leaks) + pct(selfs)
    }
}

/// The reference answers of one scene, in f64 with the watertight test.
struct Reference {
    rays: Vec<Ray<f64>>,
    /// Nearest primitive hit, per ray.
    answers: Vec<Option<u32>>,
    leak_rays: Vec<Ray<f64>>,
    how: &'static str,
}

/// Brute force serves as the reference below this many ray–triangle tests.
const BRUTE_REFERENCE_BUDGET: f64 = 1e8;

fn reference(scene: &Scene, args: &TradeoffArgs) -> Result<Reference> {
    let mesh = &scene.mesh;
    let n = args.samples as usize;
    let mut primary: Vec<Ray<f64>> = scene.view.camera.rays(args.pass.width, args.pass.height);
    thin(&mut primary, n / 2);
    let random = random_rays::<f64>(&mesh.bounds(), n - primary.len(), 0x7AD3);
    let rays: Vec<Ray<f64>> = primary.into_iter().chain(random).collect();
    let brute = mesh.triangle_count() as f64 * rays.len() as f64 <= BRUTE_REFERENCE_BUDGET;
    let kind = if brute {
        accel::AccelKind::Brute
    } else {
        accel::AccelKind::KdTree
    };
    let accel = accel::build(kind, mesh)?;
    let answers = rays
        .par_iter()
        .map(|r| accel.intersect(r).map(|h| h.map(|h| h.prim)))
        .collect::<Result<_, _>>()
        .context("reference rays")?;
    Ok(Reference {
        rays,
        answers,
        leak_rays: accel_scenes::aimed::leak_rays(mesh, args.leak_rays as usize, 0x1EA4),
        how: if brute {
            "f64 brute force"
        } else {
            "f64 kD-tree (bit-for-bit equal to brute force)"
        },
    })
}

/// Keeps at most `max` items, evenly spaced.
fn thin<T: Copy>(v: &mut Vec<T>, max: usize) {
    if v.len() > max && max > 0 {
        let step = v.len() as f64 / max as f64;
        *v = (0..max).map(|i| v[(i as f64 * step) as usize]).collect();
    }
}

/// `studies tradeoff`: measures every setting on every scene named.
///
/// # Errors
/// Every refusal, as one line naming the problem.
pub fn run(args: &TradeoffArgs) -> Result<()> {
    render::app::check_png_name(&args.plot, "--plot")?;
    let csv_out = PendingFile::create(&args.csv)?;
    let plot_out = PendingFile::create(&args.plot)?;
    let (pool, _) = render::app::thread_pool(Some(args.pass.threads))?;
    let settings: Vec<Setting> = all_settings()
        .into_iter()
        .filter(|s| args.only.is_empty() || args.only.iter().any(|o| s.name.contains(o.as_str())))
        .collect();
    if settings.is_empty() {
        anyhow::bail!("--only {}: no setting matches", args.only.join(","));
    }
    let mut rows = Vec::new();
    for name in scene_list(&args.scene) {
        let scene = load_scene(&name)?;
        let reference = pool.install(|| reference(&scene, args))?;
        println!(
            "reference: {} rays, {}; {} leak rays; {} threads, median of {} passes",
            reference.rays.len(),
            reference.how,
            reference.leak_rays.len(),
            args.pass.threads,
            args.pass.repeats
        );
        println!("{}", table_header());
        for s in &settings {
            let row = pool
                .install(|| measure(s, &scene, &reference, args))
                .with_context(|| format!("{}: {}", short_name(&name), s.name))?;
            println!("{}", table_row(&row));
            rows.push(row);
        }
    }
    write_csv_and_plot(csv_out, &csv(&rows), plot_out, &plot_panels(&rows))
}

fn measure(s: &Setting, scene: &Scene, r: &Reference, args: &TradeoffArgs) -> Result<Row> {
    match s.precision {
        Precision::F32 => measure_in::<f32>(s, scene, r, args),
        Precision::F64 => measure_in::<f64>(s, scene, r, args),
    }
}

fn measure_in<T: Real>(
    s: &Setting,
    scene: &Scene,
    r: &Reference,
    args: &TradeoffArgs,
) -> Result<Row> {
    let mesh = mesh_in::<T>(scene)?;
    match s.test {
        TriangleTest::Watertight => measure_with(s, scene, &mesh, &mesh, r, args),
        TriangleTest::MollerTrumbore => {
            let fast = MollerTrumboreMesh::new(&mesh);
            measure_with(s, scene, &mesh, &fast, r, args)
        }
    }
}

fn measure_with<T: Real, P: PrimitiveSet<T> + ?Sized>(
    s: &Setting,
    scene: &Scene,
    mesh: &TriangleMesh<T>,
    prims: &P,
    r: &Reference,
    args: &TradeoffArgs,
) -> Result<Row> {
    // Builds: the median of up to `repeats`, fewer once a second is spent.
    let mut builds = Vec::new();
    let mut accel = None;
    let start = Instant::now();
    for _ in 0..args.pass.repeats {
        let t = Instant::now();
        accel = Some(build_config(&s.config, prims)?);
        builds.push(t.elapsed().as_secs_f64() * 1e3);
        if start.elapsed() > Duration::from_secs(1) {
            break;
        }
    }
    let accel = accel.expect("at least one build");
    let accel = accel.as_dyn();
    let offset = match s.spawn {
        Spawn::ErrorBound => SpawnOffset::ErrorBound,
        Spawn::Fixed(e) => SpawnOffset::Fixed(T::from_f64(e)),
    };
    let generated = bench::generate_rays_from(
        accel,
        mesh,
        &scene.view,
        args.pass.width,
        args.pass.height,
        offset,
    )
    .context("generating rays")?;
    let mut mrays = [0.0; 3];
    let (mut rays_total, mut secs_total) = (0usize, 0.0);
    for (i, set) in generated.sets.iter().enumerate() {
        let secs = time_set(accel, set, args.pass.repeats)?;
        mrays[i] = if secs > 0.0 {
            set.rays.len() as f64 / secs / 1e6
        } else {
            0.0
        };
        rays_total += set.rays.len();
        secs_total += secs;
    }
    let mismatches = r
        .rays
        .par_iter()
        .zip(&r.answers)
        .map(|(ray, want)| {
            let got = accel.intersect(&ray.cast::<T>())?.map(|h| h.prim);
            Ok(usize::from(got != *want))
        })
        .try_reduce(|| 0, |a, b| Ok(a + b))
        .map_err(|e: accel_core::QueryError| anyhow::anyhow!("reference ray: {e}"))?;
    let leaked = r
        .leak_rays
        .par_iter()
        .map(|ray| Ok(usize::from(!accel.occluded(&ray.cast::<T>())?)))
        .try_reduce(|| 0, |a, b| Ok(a + b))
        .map_err(|e: accel_core::QueryError| anyhow::anyhow!("leak ray: {e}"))?;
    let self_hits = |set: &RaySet<T>, sources: &[u32]| -> Result<usize> {
        set.rays
            .par_iter()
            .zip(sources)
            .map(|(ray, &src)| {
                Ok(usize::from(
                    accel.intersect(ray)?.is_some_and(|h| h.prim == src),
                ))
            })
            .try_reduce(|| 0, |a, b| Ok(a + b))
            .map_err(|e: accel_core::QueryError| anyhow::anyhow!("secondary ray: {e}"))
    };
    let shadow = &generated.sets[1];
    let diffuse = &generated.sets[2];
    let stats = accel.stats();
    Ok(Row {
        scene: short_name(&scene.name),
        triangles: mesh.triangle_count(),
        setting: s.clone(),
        build_ms: crate::median(builds),
        bytes: stats.bytes,
        mrays,
        mrays_all: if secs_total > 0.0 {
            rays_total as f64 / secs_total / 1e6
        } else {
            0.0
        },
        mismatches: (r.rays.len(), mismatches),
        leaks: (r.leak_rays.len(), leaked),
        shadow_self: (
            shadow.rays.len(),
            self_hits(shadow, &generated.shadow_sources)?,
        ),
        ao_self: (
            diffuse.rays.len(),
            self_hits(diffuse, &generated.diffuse_sources)?,
        ),
    })
}

/// Median seconds of `repeats` passes over the set, on the current pool,
/// after an untimed pass (the sweep times its grids with it too).
///
/// # Errors
/// A ray the structure refuses.
pub(crate) fn time_set<T: Real>(
    accel: &dyn Accelerator<T>,
    set: &RaySet<T>,
    repeats: u32,
) -> Result<f64> {
    let any = set.kind.any_hit();
    // One untimed pass first: caches and clocks warm up.
    std::hint::black_box(
        bench::count_hits(accel, any, &set.rays, true)
            .map_err(|e| anyhow::anyhow!("{} ray: {e}", set.kind.name()))?,
    );
    let mut times = Vec::new();
    for _ in 0..repeats {
        let t = Instant::now();
        let hits = bench::count_hits(accel, any, &set.rays, true)
            .map_err(|e| anyhow::anyhow!("{} ray: {e}", set.kind.name()))?;
        std::hint::black_box(hits);
        times.push(t.elapsed().as_secs_f64());
    }
    Ok(crate::median(times))
}

fn table_header() -> String {
    format!(
        "{:<18} {:<26} {:>9} {:>8} {:>7} {:>7} {:>7} {:>9} {:>8} {:>8} {:>8}",
        "scene",
        "setting",
        "build ms",
        "MiB",
        "prim",
        "shadow",
        "diffuse",
        "mismatch%",
        "leak%",
        "shad.self%",
        "ao.self%"
    )
}

fn table_row(r: &Row) -> String {
    format!(
        "{:<18} {:<26} {:>9.1} {:>8.2} {:>7.2} {:>7.2} {:>7.2} {:>9.3} {:>8.3} {:>8.3} {:>8.3}",
        r.scene,
        r.setting.name,
        r.build_ms,
        r.bytes as f64 / (1024.0 * 1024.0),
        r.mrays[0],
        r.mrays[1],
        r.mrays[2],
        pct(r.mismatches),
        pct(r.leaks),
        pct(r.shadow_self),
        pct(r.ao_self)
    )
}

/// Every row as CSV, with a header line.
#[must_use]
pub fn csv(rows: &[Row]) -> String {
    let mut out = String::from(
        "scene,triangles,setting,dial,precision,triangle_test,spawn,structure,build_ms,bytes,\
         mrays_primary,mrays_shadow,mrays_diffuse,mrays_all,sampled,mismatches,leak_rays,leaks,\
         shadow_rays,shadow_self_hits,ao_rays,ao_self_hits,error_pct\n",
    );
    for r in rows {
        let s = &r.setting;
        out += &format!(
            "{},{},{},{},{},{},{},{},{:.3},{},{:.4},{:.4},{:.4},{:.4},{},{},{},{},{},{},{},{},{:.5}\n",
            r.scene,
            r.triangles,
            s.name,
            s.dial,
            s.precision.name(),
            s.test,
            s.spawn.name(),
            s.config.label(),
            r.build_ms,
            r.bytes,
            r.mrays[0],
            r.mrays[1],
            r.mrays[2],
            r.mrays_all,
            r.mismatches.0,
            r.mismatches.1,
            r.leaks.0,
            r.leaks.1,
            r.shadow_self.0,
            r.shadow_self.1,
            r.ao_self.0,
            r.ao_self.1,
            r.error_pct()
        );
    }
    out
}

/// The plotted error of a zero: the left edge of the log axis.
pub const ZERO_ERROR: f64 = 1e-4;

/// One panel per scene: throughput (all rays) against the summed error
/// rates, a point per setting, grouped by the dial it turns.
fn plot_panels(rows: &[Row]) -> Vec<Panel> {
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    scenes
        .into_iter()
        .map(|scene| {
            let here: Vec<&Row> = rows.iter().filter(|r| r.scene == scene).collect();
            let mut series: Vec<Series> = Vec::new();
            let mut labels = Vec::new();
            for r in &here {
                let x = r.error_pct().max(ZERO_ERROR);
                let name = r.setting.dial.to_owned();
                match series.iter_mut().find(|s| s.name == name) {
                    Some(s) => s.points.push((x, r.mrays_all)),
                    None => series.push(Series {
                        name,
                        points: vec![(x, r.mrays_all)],
                        line: false,
                    }),
                }
                labels.push((x, r.mrays_all, format!(" {}", r.setting.name)));
            }
            Panel {
                title: format!(
                    "{scene} ({} triangles)",
                    here.first().map_or(0, |r| r.triangles)
                ),
                x_label: "wrong answers: mismatch + leak + self-hit % (0 at left edge)".into(),
                y_label: "Mrays/s (all rays)".into(),
                x_log: true,
                y_log: false,
                series,
                labels,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::draw_panels;

    fn args() -> TradeoffArgs {
        TradeoffArgs {
            scene: "default".into(),
            csv: "t.csv".into(),
            plot: "t.png".into(),
            pass: PassArgs {
                width: 24,
                height: 16,
                threads: 1,
                repeats: 1,
            },
            samples: 64,
            leak_rays: 400,
            only: Vec::new(),
        }
    }

    #[test]
    fn dials_show_their_costs_on_the_default_scene() {
        let scene = render::scene::default_scene().unwrap();
        let a = args();
        let r = reference(&scene, &a).unwrap();
        assert_eq!(r.rays.len(), 64);
        assert!(r.leak_rays.len() > 300, "{} leak rays", r.leak_rays.len());
        let rows: Vec<Row> = all_settings()
            .iter()
            .filter(|s| s.name.starts_with("grid m=2") || s.name == "kdtree f64")
            .map(|s| measure(s, &scene, &r, &a).unwrap())
            .collect();
        let by = |name: &str| rows.iter().find(|r| r.setting.name == name).unwrap();
        let base = by("grid m=2");
        // The watertight test never leaks, in either precision; f64 with the
        // watertight test is the reference itself.
        assert_eq!(base.leaks.1, 0);
        assert_eq!(by("grid m=2 f64").mismatches.1, 0);
        assert_eq!(by("kdtree f64").mismatches.1, 0);
        // The error-bound spawn never self-intersects.
        assert_eq!((base.shadow_self.1, base.ao_self.1), (0, 0));
        assert!(base.shadow_self.0 > 0 && base.ao_self.0 > 0);
        assert!(base.mrays.iter().all(|&m| m > 0.0));
        let table = csv(&rows);
        assert_eq!(table.lines().count(), rows.len() + 1);
        assert!(table.lines().nth(1).unwrap().starts_with("default,"));
        let (w, _, _) = draw_panels(&plot_panels(&rows), 2, 320, 240).unwrap();
        assert_eq!(w, 320);
    }

    #[test]
    fn scene_lists_and_names() {
        assert_eq!(scene_list("teapot_in_stadium"), vec!["teapot_in_stadium"]);
        assert_eq!(
            scene_list("default,soup_100k"),
            vec!["default", "soup_100k"]
        );
        let all = scene_list("all");
        assert_eq!(all[0], "default");
        assert!(all.iter().any(|s| s == "terrain_1m"));
        assert_eq!(short_name("../shared/scenes/duck_4k.glb"), "duck_4k");
        assert_eq!(crate::median(vec![3.0, 1.0, 2.0]), 2.0);
    }
}
