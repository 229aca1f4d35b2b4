//! What a sharded render or bench writes, and `render merge`
//! ([`crate::shard`] holds the format and the checks; docs/cluster.md the
//! job-array scripts).
//!
//! A part's header names its job by the settings that change the output
//! (never the output path, the thread count or the shard) and by a digest
//! of the scene (its triangles, materials and view) or, for hits, of the
//! scene and the rays: parts of different scenes or settings do not merge.

use crate::cli::{BenchArgs, MergeArgs, RenderArgs};
use crate::output::PendingFile;
use crate::scene::Scene;
use crate::shard::{
    Fnv, Merged, Part, PartHeader, PartKind, Shard, ShardError, encode_part, hit_record, merge,
    rows_of,
};
use accel_core::{Accelerator, Ray, Real};
use anyhow::{Context, Result, bail};
use rayon::prelude::*;
use std::path::Path;

/// Whether `path` names a part file (`.part`).
fn is_part_name(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("part"))
}

/// Refuses a sharded render whose output is not a part file or that asks
/// for a heat map (its colour scale spans the whole image).
///
/// # Errors
/// Naming the option at fault.
pub fn check_render_shard(shard: Shard, args: &RenderArgs) -> Result<()> {
    if !is_part_name(&args.out) {
        bail!(
            "--shard {shard}: --out {} must name the shard's part file (NAME.part), which render merge joins into the image",
            args.out.display()
        );
    }
    if args.heatmap.is_some() {
        bail!(
            "--shard {shard}: --heatmap is not available for a shard (its colour scale spans the whole image); render the heat map in one process"
        );
    }
    Ok(())
}

/// The digest of a scene: every vertex and index, the materials and the
/// view (camera, light, occlusion distance).
#[must_use]
pub fn scene_digest(scene: &Scene) -> Fnv {
    let mut h = Fnv::default();
    for p in scene.mesh.positions() {
        for c in [p.x, p.y, p.z] {
            h = h.update(&c.to_bits().to_le_bytes());
        }
    }
    for t in scene.mesh.indices() {
        for i in t {
            h = h.update(&i.to_le_bytes());
        }
    }
    h.update(format!("{:?}{:?}", scene.materials, scene.view).as_bytes())
}

/// The part file of a render's shard: its rows of `rgb` (the whole image's
/// RGB8 bytes, other shards' rows unused).
#[must_use]
pub fn render_part(shard: Shard, args: &RenderArgs, scene: &Scene, rgb: &[u8]) -> Vec<u8> {
    let job = job_settings(
        "render",
        &[
            format!("spp: {}", args.spp),
            format!("ao: {}", args.ao),
            format!("precision: {}", args.precision.name()),
            format!("accel: {:?}", args.accel),
        ],
        &args.dials,
    );
    let header = PartHeader {
        kind: PartKind::Image,
        job,
        digest: format!("{:016x}", scene_digest(scene).finish()),
        shard: shard.index,
        shards: shard.count,
        width: args.width,
        height: args.height,
        rays: 0,
        payload_bytes: 0,
        payload_fnv: String::new(),
    };
    encode_part(header, &rows_of(shard, args.width, args.height, rgb))
}

/// A job's settings as `; `-separated `name: value` items (the dials one
/// item each), so that a merge can name the items that differ.
#[must_use]
pub fn job_settings(command: &str, items: &[String], dials: &crate::cli::DialArgs) -> String {
    let dials = format!("{dials:?}");
    let fields = dials
        .split_once('{')
        .map_or(dials.as_str(), |(_, rest)| rest.trim_end_matches('}'))
        .split(", ")
        .map(str::trim)
        .filter(|f| !f.is_empty());
    core::iter::once(command.to_owned())
        .chain(items.iter().cloned())
        .chain(fields.map(str::to_owned))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Checks `render bench`'s `--hits` and `--shard` before any work, and
/// opens the hits output.
///
/// # Errors
/// A shard without `--hits`, or a part output not named `.part`.
pub fn hits_output(args: &BenchArgs, shard: Option<Shard>) -> Result<Option<PendingFile>> {
    match (&args.hits, shard) {
        (None, None) => Ok(None),
        (None, Some(s)) => bail!(
            "--shard {s}: a bench shard writes the hits of its slice of --rays: give --hits NAME.part"
        ),
        (Some(path), Some(s)) if !is_part_name(path) => bail!(
            "--shard {s}: --hits {} must name the shard's part file (NAME.part), which render merge joins",
            path.display()
        ),
        (Some(path), _) => Ok(Some(PendingFile::create(path)?)),
    }
}

/// The hits of `rays` by `accel` (in parallel, in ray order), as a hits
/// file (no shard) or as the part file of `shard`'s slice (`rays` is the
/// slice; `total` the file's ray count, `digest` the scene's and rays').
///
/// # Errors
/// A ray the structure refuses, named by its index in the file.
pub fn hits_bytes<T: Real>(
    accel: &dyn Accelerator<T>,
    rays: &[Ray<T>],
    first: usize,
    job: String,
    digest: u64,
    shard: Option<(Shard, u64)>,
) -> Result<Vec<u8>> {
    let records: Vec<[u8; crate::shard::HIT_BYTES]> = rays
        .par_iter()
        .enumerate()
        .map(|(i, ray)| {
            let hit = accel
                .intersect(ray)
                .with_context(|| format!("ray {} of the file", first + i))?;
            Ok(hit_record(hit.map(|h| (h.prim, h.t.to_f64()))))
        })
        .collect::<Result<_>>()?;
    let payload = records.concat();
    Ok(match shard {
        None => crate::shard::hits_file(rays.len() as u64, [payload.as_slice()]),
        Some((s, total)) => encode_part(
            PartHeader {
                kind: PartKind::Hits,
                job,
                digest: format!("{digest:016x}"),
                shard: s.index,
                shards: s.count,
                width: 0,
                height: 0,
                rays: total,
                payload_bytes: 0,
                payload_fnv: String::new(),
            },
            &payload,
        ),
    })
}

/// `render merge`: reads every part, checks they make one whole job, and
/// writes the image or the hits file, whole or not at all.
///
/// # Errors
/// An unwritable output (before any part is read), an unreadable or
/// damaged part, parts of other jobs, missing or doubled shards, an image
/// merged into a name that is not `.png`.
pub fn run_merge(args: &MergeArgs) -> Result<()> {
    let out = PendingFile::create(&args.out)?;
    let parts: Vec<Part> = args
        .parts
        .iter()
        .map(|p| Part::read(p))
        .collect::<Result<_, ShardError>>()?;
    let merged = merge(&parts)?;
    let dest = out.dest().display().to_string();
    match merged {
        Merged::Image { width, height, rgb } => {
            crate::app::check_png_name(&args.out, "--out")?;
            out.write_png(width, height, &rgb)?;
            println!(
                "merged {} shards into a {width}x{height} image: wrote {dest}",
                parts.len()
            );
        }
        Merged::Hits(bytes) => {
            let rays = (bytes.len() - 16) / crate::shard::HIT_BYTES;
            out.write_all(&bytes)?;
            println!(
                "merged {} shards into the hits of {rays} rays: wrote {dest}",
                parts.len()
            );
        }
    }
    Ok(())
}
