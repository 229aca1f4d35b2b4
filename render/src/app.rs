//! The two commands, end to end: check the arguments, load, build, trace,
//! report, write.
//!
//! Everything that can be refused is checked before the expensive work:
//! output paths are opened (as temporary files) and ray files read before the
//! scene is built.

use crate::bench::{self, BenchReport, RayKind, RaySet, SetInfo};
use crate::cli::{self, BenchArgs, Precision, RenderArgs};
use crate::heatmap::heat_map;
use crate::output::PendingFile;
use crate::part_io;
use crate::probe::{ProbeShape, view_probe};
use crate::shard::Shard;
use accel::choose::{self, ProbeRay};
use accel::{AccelConfig, AccelKind};

use crate::scene::{Scene, SceneSource};
use crate::shade::{Pixel, Shader, Tally, to_srgb8};
use crate::tiles::{for_each_tile, progress_bar};
use accel_core::{
    Accelerator, MollerTrumboreMesh, PrimitiveSet, QueryError, Real, TriangleMesh, TriangleTest,
};
use anyhow::{Context, Result, bail};
use std::path::Path;
use std::time::{Duration, Instant};

/// Bytes in a GiB, for `--memory-budget`.
const GIB: f64 = (1u64 << 30) as f64;

/// Sets the number of rayon worker threads, if asked.
fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .with_context(|| format!("cannot start {n} threads"))?;
    }
    Ok(())
}

/// A rayon pool of `threads` workers (all cores when `None`), and that
/// count: what `render bench` and the studies run their passes in.
///
/// # Errors
/// When the pool cannot start.
pub fn thread_pool(threads: Option<usize>) -> Result<(rayon::ThreadPool, usize)> {
    let n = threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, usize::from));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(n)
        .build()
        .with_context(|| format!("cannot start {n} threads"))?;
    Ok((pool, n))
}

/// Refuses output names the PNG encoder would not match.
pub fn check_png_name(path: &Path, option: &str) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if ext.as_deref() != Some("png") {
        bail!(
            "{option} {}: only PNG output is supported (use a .png file name)",
            path.display()
        );
    }
    Ok(())
}

/// The mesh in the query precision, refused (naming the scene, and
/// `--precision f64` in `f32`) when a coordinate does not fit `T` or lies
/// beyond the range the accelerators accept ([`Real::LIMIT`]): every
/// structure, brute force included, would refuse it.
pub fn mesh_in<T: Real>(scene: &Scene) -> Result<TriangleMesh<T>> {
    let mesh = scene.mesh.cast::<T>().with_context(|| {
        format!(
            "{}: the scene does not fit in {} (use --precision f64)",
            scene.name,
            T::NAME
        )
    })?;
    if let Err(e) = accel_core::check_range(&mesh.bounds()) {
        bail!("{}: {e}{}", scene.name, precision_hint::<T>());
    }
    Ok(mesh)
}

/// ` (use --precision f64)` in `f32`, where a wider precision is the remedy
/// for coordinates out of range; nothing in `f64`.
pub(crate) fn precision_hint<T: Real>() -> &'static str {
    if T::NAME == "f32" {
        " (use --precision f64)"
    } else {
        ""
    }
}

/// A failed `--accel auto` choice as one error, with the remedy where a
/// probe ray starts beyond `T`'s range (a camera framed from beyond the
/// `f32` limit): [`precision_hint`], as the pixels' errors have it.
fn choose_failed<T: Real>(e: choose::ChooseError) -> anyhow::Error {
    match e {
        // A query error has no source: its message is the whole story.
        choose::ChooseError::Query(QueryError::OriginOutOfRange { .. }) => {
            anyhow::anyhow!("choosing the accelerator: {e}{}", precision_hint::<T>())
        }
        e => anyhow::Error::new(e).context("choosing the accelerator"),
    }
}

/// Loads the scene named by a SCENE argument, reporting how long it took.
pub fn load_scene(arg: &str) -> Result<Scene> {
    let start = Instant::now();
    let scene = SceneSource::parse(arg)?.load()?;
    let b = scene.mesh.bounds();
    println!(
        "scene {}: {} triangles, bounds ({:.4}, {:.4}, {:.4}) .. ({:.4}, {:.4}, {:.4}), loaded in {:.1} ms",
        scene.name,
        scene.mesh.triangle_count(),
        b.min.x,
        b.min.y,
        b.min.z,
        b.max.x,
        b.max.y,
        b.max.z,
        start.elapsed().as_secs_f64() * 1e3
    );
    for note in &scene.notes {
        println!("  {note}");
    }
    Ok(scene)
}

/// Bytes a render's image buffers take per pixel at their peak: the
/// per-tile results and the assembled image, one [`Pixel`] each
/// (`for_each_tile` holds both while it assembles). Measured: 208 bytes a
/// pixel (`/usr/bin/time -f %M` of `render --accel grid --ao 0 --spp 1` at
/// 1024² and 2048²: 224,004 KB and 863,884 KB), 2 × 104.
pub const RENDER_BYTES_PER_PIXEL: u64 = 2 * size_of::<Pixel>() as u64;

/// Refuses, before any work, a render whose image buffers
/// ([`RENDER_BYTES_PER_PIXEL`] × pixels) would take more than
/// `--memory-budget` (the scene and the structure come on top).
///
/// # Errors
/// A message with the estimate and the budget.
fn check_render_memory(args: &RenderArgs) -> Result<()> {
    let pixels = u64::from(args.width) * u64::from(args.height);
    let needed = pixels.saturating_mul(RENDER_BYTES_PER_PIXEL);
    let budget = args.memory_budget * GIB;
    if needed as f64 > budget {
        bail!(
            "--width {} × --height {} needs about {:.1} GiB for its image buffers \
             ({RENDER_BYTES_PER_PIXEL} bytes a pixel), over the --memory-budget of {} GiB",
            args.width,
            args.height,
            needed as f64 / GIB,
            args.memory_budget
        );
    }
    Ok(())
}

/// Bytes a bench's generated rays take per primary pixel at their peak, in
/// `f32` and `f64`: the three ray sets, the primary hits they are made
/// from, the probe rays of `auto`, a `--write-rays` copy and the answers of
/// the set being measured. Measured (`/usr/bin/time -f %M` of `render bench
/// default --accel grid,auto --write-rays FILE --min-time 0.01` at 1024²
/// and 2048², 2.53 rays a pixel): 245 and 404 bytes a pixel
/// (276,504 → 1,028,816 KB in `f32`, 435,740 → 1,677,652 KB in `f64`),
/// scaled to 3 rays a pixel (every primary ray hits a lit surface) and
/// rounded up.
pub const BENCH_BYTES_PER_PIXEL: [u64; 2] = [300, 480];

/// Refuses, before any work, a bench whose generated rays
/// ([`BENCH_BYTES_PER_PIXEL`] × pixels) would take more than
/// `--memory-budget` (the scene and the structures come on top). A ray
/// file's rays are bounded by the file, which the reader checks.
///
/// # Errors
/// A message with the estimate and the budget.
fn check_bench_memory(args: &BenchArgs) -> Result<()> {
    if args.rays.is_some() {
        return Ok(());
    }
    let per_pixel = match args.precision {
        Precision::F32 => BENCH_BYTES_PER_PIXEL[0],
        Precision::F64 => BENCH_BYTES_PER_PIXEL[1],
    };
    let pixels = u64::from(args.width) * u64::from(args.height);
    let needed = pixels.saturating_mul(per_pixel);
    if needed as f64 > args.memory_budget * GIB {
        bail!(
            "--width {} × --height {} needs about {:.1} GiB for its rays in {} \
             ({per_pixel} bytes a pixel), over the --memory-budget of {} GiB",
            args.width,
            args.height,
            needed as f64 / GIB,
            args.precision.name(),
            args.memory_budget
        );
    }
    Ok(())
}

/// `render [SCENE]`: renders to `--out`, and the heat map if asked.
///
/// # Errors
/// Every refusal, as one line naming the problem.
pub fn run_render(args: &RenderArgs) -> Result<()> {
    cli::check_render_totals(args).map_err(anyhow::Error::msg)?;
    check_render_memory(args)?;
    let shard = args.shard.resolve()?;
    match shard {
        None => check_png_name(&args.out, "--out")?,
        Some(s) => part_io::check_render_shard(s, args)?,
    }
    if let Some(h) = &args.heatmap {
        check_png_name(h, "--heatmap")?;
    }
    let out = PendingFile::create(&args.out)?;
    let heat_out = args
        .heatmap
        .as_deref()
        .map(PendingFile::create)
        .transpose()?;
    set_threads(args.threads)?;
    let kinds: Vec<AccelKind> = args.accel.kind().into_iter().collect();
    args.dials
        .check_structure_options(&kinds, kinds.is_empty())
        .map_err(anyhow::Error::msg)?;
    let scene_arg = args.scene.as_deref().unwrap_or(crate::scene::DEFAULT_SCENE);
    if scene_arg.to_ascii_lowercase().ends_with(".png") {
        bail!(
            "{scene_arg} is an image, not a scene (name the heat map with --heatmap={scene_arg})"
        );
    }
    let scene = load_scene(scene_arg)?;
    match args.precision {
        Precision::F32 => render_in::<f32>(args, &scene, shard, out, heat_out),
        Precision::F64 => render_in::<f64>(args, &scene, shard, out, heat_out),
    }
}

fn render_in<T: Real>(
    args: &RenderArgs,
    scene: &Scene,
    shard: Option<Shard>,
    out: PendingFile,
    heat_out: Option<PendingFile>,
) -> Result<()> {
    let mesh = mesh_in::<T>(scene)?;
    match args.dials.triangle_test.test() {
        TriangleTest::Watertight => render_with(args, scene, &mesh, &mesh, shard, out, heat_out),
        TriangleTest::MollerTrumbore => {
            let fast = MollerTrumboreMesh::new(&mesh);
            render_with(args, scene, &mesh, &fast, shard, out, heat_out)
        }
    }
}

/// The rays a render of `args` traces: pixels × spp × (primary, shadow, AO).
fn expected_render_rays(args: &RenderArgs) -> u64 {
    u64::from(args.width) * u64::from(args.height) * u64::from(args.spp) * (2 + u64::from(args.ao))
}

fn render_with<T: Real, P: PrimitiveSet<T> + ?Sized>(
    args: &RenderArgs,
    scene: &Scene,
    mesh: &TriangleMesh<T>,
    prims: &P,
    shard: Option<Shard>,
    out: PendingFile,
    heat_out: Option<PendingFile>,
) -> Result<()> {
    let offset = args.dials.spawn_offset::<T>();
    let accel = match args.accel.kind() {
        Some(kind) => accel::build_config_within(
            &args.dials.config(kind),
            prims,
            Some((args.memory_budget * GIB) as u64),
        )
        .with_context(|| format!("within --memory-budget {} GiB", args.memory_budget))?,
        None => {
            let choice = accel::choose_with_probe(prims, expected_render_rays(args), |a| {
                view_probe(
                    a,
                    mesh,
                    &scene.view,
                    ProbeShape {
                        width: args.width,
                        height: args.height,
                        ao: args.ao,
                        primaries: choose::PROBE_PRIMARIES,
                    },
                    offset,
                )
            })
            .map_err(choose_failed::<T>)?;
            println!("auto: {} ({})", choice.config, choice.reason);
            choice.accel
        }
    };
    println!(
        "build {} [{} {}, {}, spawn {}]",
        accel.stats(),
        T::NAME,
        args.dials.triangle_test.test(),
        config_note(args.accel.kind().map(|k| args.dials.config(k))),
        offset
    );
    let (w, h) = (args.width, args.height);
    let shader = Shader {
        accel: accel.as_dyn(),
        mesh,
        scene,
        width: w,
        height: h,
        spp: args.spp,
        ao: args.ao,
        count: heat_out.is_some(),
        spawn: offset,
    };
    let bar = progress_bar(u64::from(w) * u64::from(h), "render");
    let start = Instant::now();
    let pixels = for_each_tile(w, h, &bar, |tile| {
        let wanted = |_, y| shard.is_none_or(|s| s.owns_row(y));
        shader.tile(tile, wanted).map_err(|p| {
            let hint = match p.error {
                QueryError::OriginOutOfRange { .. } => precision_hint::<T>(),
                _ => "",
            };
            anyhow::anyhow!("pixel ({}, {}) in {}: {}{hint}", p.x, p.y, T::NAME, p.error)
        })
    })?;
    let elapsed = start.elapsed();
    bar.finish_and_clear();
    let mut tally = Tally::default();
    for p in &pixels {
        tally.add(&p.tally);
    }
    report_trace(&tally, elapsed, w, h, args, accel.as_dyn());
    let rgb: Vec<u8> = pixels
        .iter()
        .flat_map(|p: &Pixel| p.rgb.map(to_srgb8))
        .collect();
    let dest = out.dest().display().to_string();
    match shard {
        None => out.write_png(w, h, &rgb)?,
        Some(s) => out.write_all(&part_io::render_part(s, args, scene, &rgb))?,
    }
    println!("wrote {dest}");
    if let Some(heat_out) = heat_out {
        let work: Vec<_> = pixels.iter().map(|p| p.primary_work).collect();
        let (img, stats) = heat_map(w, h, args.spp, &work);
        println!(
            "heat map: primary rays visit {:.1} cells/nodes (max {:.0}) and test {:.1} primitives (max {:.0}) per ray",
            stats.mean_nodes, stats.max_nodes, stats.mean_tests, stats.max_tests
        );
        let dest = heat_out.dest().display().to_string();
        heat_out.write_png(img.width, img.height, &img.rgb)?;
        println!("wrote {dest}");
    }
    Ok(())
}

fn report_trace<T: Real>(
    t: &Tally,
    elapsed: Duration,
    w: u32,
    h: u32,
    args: &RenderArgs,
    accel: &dyn Accelerator<T>,
) {
    let secs = elapsed.as_secs_f64();
    println!(
        "trace {}x{}, {} spp, {} ao rays, {}: {} rays in {:.3} s ({:.2} Mrays/s on {} threads)",
        w,
        h,
        args.spp,
        args.ao,
        T::NAME,
        t.rays(),
        secs,
        t.rays() as f64 / secs.max(1e-9) / 1e6,
        rayon::current_num_threads()
    );
    println!(
        "hits: primary {}/{}, shadow blocked {}/{}, ao blocked {}/{}, digest {:016x}",
        t.primary_hits, t.primary, t.shadow_blocked, t.shadow, t.ao_blocked, t.ao, t.digest
    );
    if t.work.nodes + t.work.prims > 0 {
        println!(
            "work ({}): {:.1} cells/nodes and {:.1} primitive tests per ray",
            accel.stats().kind,
            t.work.nodes as f64 / t.rays().max(1) as f64,
            t.work.prims as f64 / t.rays().max(1) as f64
        );
    }
}

/// `render bench [SCENE]`: measures the accelerators and prints the table.
///
/// # Errors
/// Every refusal, as one line naming the problem; also when accelerators
/// disagree on any answer (after the table and JSON are written).
pub fn run_bench(args: &BenchArgs) -> Result<()> {
    cli::check_bench_totals(args).map_err(anyhow::Error::msg)?;
    check_bench_memory(args)?;
    let named: Vec<AccelKind> = args.accel.iter().filter_map(|c| c.kind()).collect();
    let structures = if args.accel.is_empty() {
        AccelKind::ALL.to_vec()
    } else {
        named
    };
    args.dials
        .check_structure_options(&structures, args.accel.iter().any(|c| c.kind().is_none()))
        .map_err(anyhow::Error::msg)?;
    let json_out = args.json.as_deref().map(PendingFile::create).transpose()?;
    let rays_out = args
        .write_rays
        .as_deref()
        .map(PendingFile::create)
        .transpose()?;
    let shard = args.shard.resolve()?;
    let hits_out = part_io::hits_output(args, shard)?;
    let mut file_rays = args
        .rays
        .as_deref()
        .map(accel_scenes::rayfile::read)
        .transpose()?;
    // A shard traces its slice; the header keeps the whole file's count and
    // digest, so the parts of one file merge and no other's do.
    let mut slice = None;
    if let Some(rays) = &mut file_rays {
        let digest = crate::shard::fnv1a(&accel_scenes::rayfile::encode(rays));
        let total = rays.len();
        let range = shard.map_or(0..total, |s| s.ray_range(total));
        *rays = rays[range.clone()].to_vec();
        slice = Some(HitsSlice {
            first: range.start,
            total: total as u64,
            rays_digest: digest,
        });
    }
    let (pool, threads) = thread_pool(args.threads)?;
    let scene = load_scene(&args.scene)?;
    let io = BenchIo {
        json_out,
        rays_out,
        file_rays,
        threads,
        hits_out,
        shard,
        slice,
    };
    pool.install(|| match args.precision {
        Precision::F32 => bench_in::<f32>(args, &scene, io),
        Precision::F64 => bench_in::<f64>(args, &scene, io),
    })
}

/// What `run_bench` prepares before the scene is built.
struct BenchIo {
    json_out: Option<PendingFile>,
    rays_out: Option<PendingFile>,
    file_rays: Option<Vec<accel_core::Ray<f32>>>,
    threads: usize,
    /// Where `--hits` goes, for this shard (if any) of the file's rays.
    hits_out: Option<PendingFile>,
    shard: Option<Shard>,
    slice: Option<HitsSlice>,
}

/// Which rays of a ray file a bench traces.
struct HitsSlice {
    /// The index in the file of the first ray traced.
    first: usize,
    /// The file's ray count.
    total: u64,
    /// FNV-1a of the file's rays.
    rays_digest: u64,
}

fn bench_in<T: Real>(args: &BenchArgs, scene: &Scene, io: BenchIo) -> Result<()> {
    let mesh = mesh_in::<T>(scene)?;
    match args.dials.triangle_test.test() {
        TriangleTest::Watertight => bench_with(args, scene, &mesh, &mesh, io),
        TriangleTest::MollerTrumbore => {
            let fast = MollerTrumboreMesh::new(&mesh);
            bench_with(args, scene, &mesh, &fast, io)
        }
    }
}

fn bench_with<T: Real, P: PrimitiveSet<T> + ?Sized>(
    args: &BenchArgs,
    scene: &Scene,
    mesh: &TriangleMesh<T>,
    prims: &P,
    io: BenchIo,
) -> Result<()> {
    // The structures named, without repeats; `auto` is resolved below.
    let mut configs: Vec<AccelConfig> = Vec::new();
    for kind in args.accel.iter().filter_map(|c| c.kind()) {
        let config = args.dials.config(kind);
        if !configs.contains(&config) {
            configs.push(config);
        }
    }
    let (sets, source) = match io.file_rays {
        Some(rays) => (
            vec![RaySet {
                kind: RayKind::File,
                rays: rays.iter().map(accel_core::Ray::cast).collect(),
                image_width: None,
            }],
            args.rays
                .as_deref()
                .map_or_else(String::new, |p| p.display().to_string()),
        ),
        None => {
            let generator = accel::build(bench::RAY_GENERATOR, prims)?;
            let sets = bench::generate_rays_from(
                generator.as_dyn(),
                mesh,
                &scene.view,
                args.width,
                args.height,
                args.dials.spawn_offset(),
            )
            .context("generating rays")?
            .sets;
            (
                sets,
                format!("generated from a {}x{} view", args.width, args.height),
            )
        }
    };
    if args.accel.iter().any(|c| c.kind().is_none()) {
        let total: u64 = sets.iter().map(|s| s.rays.len() as u64).sum();
        let probe: Vec<ProbeRay<T>> = sets
            .iter()
            .flat_map(|s| {
                s.rays.iter().map(|&ray| ProbeRay {
                    ray,
                    any_hit: s.kind.any_hit(),
                })
            })
            .collect();
        let choice =
            accel::choose_with_probe(prims, total, |_| Ok(probe)).map_err(choose_failed::<T>)?;
        println!("auto: {} ({})", choice.config, choice.reason);
        if !configs.contains(&choice.config) {
            configs.push(choice.config);
        }
    }
    let total_rays: usize = sets.iter().map(|s| s.rays.len()).sum();
    if configs.is_empty() {
        configs = bench::default_accels(mesh.triangle_count(), total_rays)
            .into_iter()
            .map(|k| args.dials.config(k))
            .collect();
    }
    println!("rays ({source}): {}", bench::describe_sets(&sets));
    if let Some(out) = io.rays_out {
        let all: Vec<_> = sets.iter().flat_map(|s| s.rays.iter().copied()).collect();
        let dest = out.dest().display().to_string();
        out.write_all(&accel_scenes::rayfile::encode(&all))?;
        println!("wrote {} rays to {dest} (in the order listed)", all.len());
    }
    let min_time = Duration::from_secs_f64(args.min_time);
    println!("{}", bench::table_header(io.threads));
    let mut results = Vec::new();
    for config in &configs {
        let r = bench::measure_accel(config, prims, &sets, min_time)?;
        for row in bench::table_rows(&r) {
            println!("{row}");
        }
        results.push(r);
    }
    if let (Some(out), Some(slice), Some(config)) = (io.hits_out, &io.slice, configs.first()) {
        let accel = accel::build_config(config, prims)?;
        let job = part_io::job_settings(
            "bench hits",
            &[
                format!("precision: {}", T::NAME),
                format!("accel: {:?}", args.accel),
            ],
            &args.dials,
        );
        let digest = part_io::scene_digest(scene)
            .update(&slice.rays_digest.to_le_bytes())
            .finish();
        let bytes = part_io::hits_bytes(
            accel.as_dyn(),
            &sets[0].rays,
            slice.first,
            job,
            digest,
            io.shard.map(|s| (s, slice.total)),
        )?;
        let dest = out.dest().display().to_string();
        out.write_all(&bytes)?;
        println!(
            "wrote the hits of rays {}..{} ({}) to {dest}",
            slice.first,
            slice.first + sets[0].rays.len(),
            config.label()
        );
    }
    let disagreement = bench::disagreement(&results);
    let report = BenchReport {
        scene: scene.name.clone(),
        triangles: mesh.triangle_count() as u64,
        precision: T::NAME,
        threads: io.threads,
        ray_source: source,
        ray_sets: sets
            .iter()
            .map(|s| SetInfo {
                kind: s.kind,
                rays: s.rays.len() as u64,
            })
            .collect(),
        min_time_s: args.min_time,
        accelerators: results,
        agree: disagreement.is_none(),
    };
    if let Some(out) = io.json_out {
        let json = serde_json::to_vec_pretty(&report).context("encoding the JSON report")?;
        let dest = out.dest().display().to_string();
        out.write_all(&json)?;
        println!("wrote {dest}");
    }
    match disagreement {
        Some(msg) => bail!("{msg}"),
        None => {
            if report.accelerators.len() > 1 {
                println!("all accelerators agree on every answer");
            }
            Ok(())
        }
    }
}

/// The structure's parameters for the build line, or "auto".
fn config_note(config: Option<AccelConfig>) -> String {
    config.map_or_else(|| "auto".to_owned(), |c| c.label())
}
