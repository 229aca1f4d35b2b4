//! Sharded runs: one deterministic part of an image or of a ray file per
//! process, and the merge that joins the parts (issue 31).
//!
//! A job array (Slurm `--array`, a Kubernetes Indexed Job, HTCondor
//! `queue N`) starts `N` copies of one command that differ only in their
//! index. `render --shard I/N` renders shard `I` (0-based) of `N`: the rows
//! of every `N`-th band of [`TILE`] rows, starting at band `I` (bands dealt
//! round-robin, so every shard gets rows from the top, the middle and the
//! bottom of the image and the work is balanced). `render bench --rays FILE
//! --shard I/N` traces a contiguous slice of the file's rays. Each writes a
//! **part file**; `render merge PARTS... --out FILE` checks that the parts
//! belong to one job, that none is missing, doubled or damaged, and writes
//! the image (or the hits) whole. Every pixel and every hit depends only on
//! its own ray, never on which process traced it, so the merged image is
//! byte for byte the image one process renders, and a retried shard writes
//! the same part again.
//!
//! # Part file (little-endian)
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `ACCPART1` |
//! | 4 | `u32` length `H` of the header |
//! | `H` | header: a UTF-8 JSON object ([`PartHeader`]) |
//! | rest | payload: `payload_bytes` bytes |
//!
//! An image part's payload is the 8-bit RGB rows it owns, top to bottom,
//! `3·width` bytes each. A hits part's payload is one [`HIT_BYTES`]-byte
//! record per ray of its slice, in ray order: `u32` index of the primitive
//! hit ([`NO_HIT`] for none), `u32` zero, `f64` parameter `t` of the hit
//! (exact in `f32` and `f64` runs; `0` for none). The merged hits file is
//! the magic `ACCHITS1`, a `u64` ray count, then the records of every ray
//! in order.

use crate::tiles::TILE;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// The magic bytes of a part file.
pub const PART_MAGIC: [u8; 8] = *b"ACCPART1";
/// The magic bytes of a merged hits file.
pub const HITS_MAGIC: [u8; 8] = *b"ACCHITS1";
/// Bytes per ray in a hits payload.
pub const HIT_BYTES: usize = 16;
/// The primitive index of a ray that hits nothing.
pub const NO_HIT: u32 = u32::MAX;
/// The most shards of one job.
pub const MAX_SHARDS: u32 = 1 << 16;
/// The environment variables a job array sets to the task's index, read in
/// this order by [`Shard::from_env`]: Kubernetes Indexed Jobs, then Slurm.
pub const INDEX_VARIABLES: [&str; 2] = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"];
/// The longest header a part file may announce.
const MAX_HEADER_BYTES: u32 = 1 << 16;

/// Shard `index` of `count` (0-based).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Shard {
    /// Which shard, `0..count`.
    pub index: u32,
    /// How many shards the job has, `1..=MAX_SHARDS`.
    pub count: u32,
}

/// Why a shard, a part file or a set of parts was refused.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum ShardError {
    /// `--shard` is not `I/N` with `0 <= I < N <= MAX_SHARDS`.
    #[error(
        "--shard {given:?}: expected I/N with 0 <= I < N <= {MAX_SHARDS} (the 0-based index of the shard and their count)"
    )]
    Spec {
        /// What was given.
        given: String,
    },
    /// `--shards N` without an index in the environment.
    #[error(
        "--shards {count}: no shard index in the environment (set JOB_COMPLETION_INDEX or SLURM_ARRAY_TASK_ID to 0..{count}, or give --shard I/{count})"
    )]
    NoIndex {
        /// The shard count given.
        count: u32,
    },
    /// An index variable that is not a number below the count.
    #[error("{variable}={value:?} is not a shard index below {count}")]
    BadIndex {
        /// The variable read.
        variable: &'static str,
        /// Its value.
        value: String,
        /// The shard count given.
        count: u32,
    },
    /// A part file that cannot be read or is not a well-formed part.
    #[error("{path}: {problem}")]
    Part {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
    /// `render merge` without parts.
    #[error("no part files to merge")]
    NoParts,
    /// A part of another job (another scene, size, setting or kind).
    #[error("{path} belongs to another job than {first}: {field} {theirs} against {ours}")]
    Foreign {
        /// The odd part.
        path: PathBuf,
        /// The first part, which the others are compared with.
        first: PathBuf,
        /// The field that differs.
        field: &'static str,
        /// Its value in the odd part.
        theirs: String,
        /// Its value in the first part.
        ours: String,
    },
    /// The same shard twice.
    #[error("shard {index}/{count} is given twice: {first} and {second}")]
    Doubled {
        /// The shard.
        index: u32,
        /// The shard count.
        count: u32,
        /// Its first file.
        first: PathBuf,
        /// Its second file.
        second: PathBuf,
    },
    /// Shards without a part.
    #[error("{} of {count} shards missing: {}", missing.len(), list(missing))]
    Missing {
        /// The shard count.
        count: u32,
        /// The missing shards' indices.
        missing: Vec<u32>,
    },
}

/// Up to eight indices, then how many more.
fn list(indices: &[u32]) -> String {
    let shown: Vec<String> = indices.iter().take(8).map(u32::to_string).collect();
    match indices.len() {
        n if n > 8 => format!("{} and {} more", shown.join(", "), n - 8),
        _ => shown.join(", "),
    }
}

/// The `; `-separated items of two settings strings that differ, each
/// side's joined by `, ` (the whole strings if none differ item by item).
fn differing_items(theirs: &str, ours: &str) -> (String, String) {
    let (a, b): (Vec<&str>, Vec<&str>) = (theirs.split("; ").collect(), ours.split("; ").collect());
    let only = |x: &[&str], y: &[&str]| -> Vec<String> {
        x.iter()
            .filter(|i| !y.contains(i))
            .map(|i| (*i).to_owned())
            .collect()
    };
    let (ta, ob) = (only(&a, &b), only(&b, &a));
    if ta.is_empty() && ob.is_empty() {
        (theirs.to_owned(), ours.to_owned())
    } else {
        (ta.join(", "), ob.join(", "))
    }
}

impl FromStr for Shard {
    type Err = ShardError;

    fn from_str(s: &str) -> Result<Self, ShardError> {
        let bad = || ShardError::Spec { given: s.into() };
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: u32 = i.trim().parse().map_err(|_| bad())?;
        let count: u32 = n.trim().parse().map_err(|_| bad())?;
        Self::new(index, count).ok_or_else(bad)
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Shard `index` of `count`; `None` unless `index < count <= MAX_SHARDS`.
    #[must_use]
    pub fn new(index: u32, count: u32) -> Option<Self> {
        (index < count && count <= MAX_SHARDS).then_some(Self { index, count })
    }

    /// The shard of `count` whose index the job array put in the
    /// environment ([`INDEX_VARIABLES`]), read through `var`.
    ///
    /// # Errors
    /// [`ShardError::NoIndex`] when no variable is set,
    /// [`ShardError::BadIndex`] when the first one set is not an index below
    /// `count`, [`ShardError::Spec`] for a count of 0 or over [`MAX_SHARDS`].
    pub fn from_env(count: u32, var: impl Fn(&str) -> Option<String>) -> Result<Self, ShardError> {
        if !(1..=MAX_SHARDS).contains(&count) {
            return Err(ShardError::Spec {
                given: format!("?/{count}"),
            });
        }
        let (variable, value) = INDEX_VARIABLES
            .iter()
            .find_map(|&v| var(v).map(|value| (v, value)))
            .ok_or(ShardError::NoIndex { count })?;
        value
            .trim()
            .parse()
            .ok()
            .and_then(|index| Self::new(index, count))
            .ok_or(ShardError::BadIndex {
                variable,
                value,
                count,
            })
    }

    /// Whether image row `y` is this shard's: its band of [`TILE`] rows is
    /// dealt to this shard.
    #[must_use]
    pub fn owns_row(&self, y: u32) -> bool {
        (y / TILE) % self.count == self.index
    }

    /// The rows of an image `height` rows high that are this shard's, top
    /// to bottom.
    pub fn rows(&self, height: u32) -> impl Iterator<Item = u32> + '_ {
        (0..height).filter(|&y| self.owns_row(y))
    }

    /// This shard's slice of `n` rays: contiguous, the slices of all shards
    /// in index order covering `0..n` once.
    #[must_use]
    pub fn ray_range(&self, n: usize) -> Range<usize> {
        let at = |i: u32| (n as u128 * u128::from(i) / u128::from(self.count)) as usize;
        at(self.index)..at(self.index + 1)
    }
}

/// What a part holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum PartKind {
    /// Rows of an image.
    Image,
    /// Hits of a slice of a ray file.
    Hits,
}

/// The header of a part file: everything the merge checks.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PartHeader {
    /// What the part holds.
    pub kind: PartKind,
    /// Every setting that changes the output, as the command that wrote the
    /// part describes it (scene, size, samples, precision, dials...): parts
    /// merge only when it is the same.
    pub job: String,
    /// FNV-1a (64-bit, hex) of the scene's triangles, or of the ray file's
    /// bytes for hits parts ([`fnv1a`]).
    pub digest: String,
    /// This part's shard index.
    pub shard: u32,
    /// The job's shard count.
    pub shards: u32,
    /// The image's width (image parts; 0 for hits).
    pub width: u32,
    /// The image's height (image parts; 0 for hits).
    pub height: u32,
    /// The rays of the whole ray file (hits parts; 0 for images).
    pub rays: u64,
    /// The payload's length in bytes.
    pub payload_bytes: u64,
    /// FNV-1a (64-bit, hex) of the payload: a damaged part is refused.
    pub payload_fnv: String,
}

impl PartHeader {
    /// The payload length this header's shard must have.
    fn expected_payload(&self) -> Option<u64> {
        let shard = Shard::new(self.shard, self.shards)?;
        match self.kind {
            PartKind::Image => {
                let rows = shard.rows(self.height).count() as u64;
                Some(rows * u64::from(self.width) * 3)
            }
            PartKind::Hits => {
                let n = usize::try_from(self.rays).ok()?;
                Some(shard.ray_range(n).len() as u64 * HIT_BYTES as u64)
            }
        }
    }
}

/// FNV-1a, 64-bit: a digest of bytes, fast and stable across platforms (not
/// a cryptographic hash: it tells apart the jobs and catches damage, it does
/// not resist forgery).
#[must_use]
pub fn fnv1a(bytes: &[u8]) -> u64 {
    Fnv::default().update(bytes).finish()
}

/// An FNV-1a state, fed piece by piece.
#[derive(Clone, Copy, Debug)]
pub struct Fnv(u64);

impl Default for Fnv {
    fn default() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
}

impl Fnv {
    /// Feeds `bytes`.
    #[must_use]
    pub fn update(mut self, bytes: &[u8]) -> Self {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
        self
    }

    /// The digest.
    #[must_use]
    pub fn finish(self) -> u64 {
        self.0
    }
}

/// A part file's bytes: `header` (its payload fields set from `payload`)
/// and `payload`.
#[must_use]
pub fn encode_part(mut header: PartHeader, payload: &[u8]) -> Vec<u8> {
    header.payload_bytes = payload.len() as u64;
    header.payload_fnv = format!("{:016x}", fnv1a(payload));
    let json = serde_json::to_vec(&header).expect("a header serialises");
    let mut out = Vec::with_capacity(12 + json.len() + payload.len());
    out.extend_from_slice(&PART_MAGIC);
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&json);
    out.extend_from_slice(payload);
    out
}

/// The image rows of `shard` out of a whole image's RGB8 bytes (for a
/// payload), top to bottom.
#[must_use]
pub fn rows_of(shard: Shard, width: u32, height: u32, rgb: &[u8]) -> Vec<u8> {
    let row = width as usize * 3;
    shard
        .rows(height)
        .flat_map(|y| &rgb[y as usize * row..(y as usize + 1) * row])
        .copied()
        .collect()
}

/// One hit record of a hits payload: the primitive and parameter, or none.
#[must_use]
pub fn hit_record(hit: Option<(u32, f64)>) -> [u8; HIT_BYTES] {
    let (prim, t) = hit.unwrap_or((NO_HIT, 0.0));
    let mut r = [0u8; HIT_BYTES];
    r[..4].copy_from_slice(&prim.to_le_bytes());
    r[8..].copy_from_slice(&t.to_le_bytes());
    r
}

/// A hits file of `rays` rays: [`HITS_MAGIC`], the count, then the
/// records of `payloads` in order.
#[must_use]
pub fn hits_file<'a>(rays: u64, payloads: impl IntoIterator<Item = &'a [u8]>) -> Vec<u8> {
    let mut out = Vec::with_capacity(16 + rays as usize * HIT_BYTES);
    out.extend_from_slice(&HITS_MAGIC);
    out.extend_from_slice(&rays.to_le_bytes());
    for p in payloads {
        out.extend_from_slice(p);
    }
    out
}

/// A part file, read and checked on its own.
#[derive(Clone, Debug)]
pub struct Part {
    /// Where it was read from.
    pub path: PathBuf,
    /// Its header.
    pub header: PartHeader,
    /// Its payload, checked against the header's length and digest.
    pub payload: Vec<u8>,
}

impl Part {
    /// Parses the bytes of part file `path`.
    ///
    /// # Errors
    /// [`ShardError::Part`] naming what is wrong: magic, header, shard,
    /// payload length or digest.
    pub fn parse(path: &Path, bytes: &[u8]) -> Result<Self, ShardError> {
        let bad = |problem: String| ShardError::Part {
            path: path.into(),
            problem,
        };
        if bytes.len() < 12 || bytes[..8] != PART_MAGIC {
            return Err(bad(
                "not a part file (it does not start with ACCPART1)".into()
            ));
        }
        let h = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
        if h > MAX_HEADER_BYTES || 12 + h as usize > bytes.len() {
            return Err(bad(format!(
                "the header announces {h} bytes, but the file holds {} after the first 12",
                bytes.len() - 12
            )));
        }
        let (json, payload) = bytes[12..].split_at(h as usize);
        let header: PartHeader = serde_json::from_slice(json)
            .map_err(|e| bad(format!("the header is not a part header: {e}")))?;
        let expected = header.expected_payload().ok_or_else(|| {
            bad(format!(
                "shard {}/{} is not a shard (0 <= I < N <= {MAX_SHARDS})",
                header.shard, header.shards
            ))
        })?;
        if header.payload_bytes != expected || payload.len() as u64 != expected {
            return Err(bad(format!(
                "shard {}/{} must hold {expected} bytes of {}; the header says {} and the file holds {} (truncated or not this job's)",
                header.shard,
                header.shards,
                match header.kind {
                    PartKind::Image => "rows",
                    PartKind::Hits => "hits",
                },
                header.payload_bytes,
                payload.len()
            )));
        }
        let fnv = format!("{:016x}", fnv1a(payload));
        if fnv != header.payload_fnv {
            return Err(bad(format!(
                "the payload is damaged: its digest is {fnv}, the header's {}",
                header.payload_fnv
            )));
        }
        Ok(Self {
            path: path.into(),
            header,
            payload: payload.to_vec(),
        })
    }

    /// Reads and parses part file `path`.
    ///
    /// # Errors
    /// As [`Part::parse`], and when the file cannot be read.
    pub fn read(path: &Path) -> Result<Self, ShardError> {
        let bytes = std::fs::read(path).map_err(|e| ShardError::Part {
            path: path.into(),
            problem: format!("cannot read it: {e}"),
        })?;
        Self::parse(path, &bytes)
    }
}

/// What the parts of one job join into.
#[derive(Clone, Debug, PartialEq)]
pub enum Merged {
    /// A whole image, 8-bit RGB rows.
    Image {
        /// Width in pixels.
        width: u32,
        /// Height in pixels.
        height: u32,
        /// `3·width·height` bytes.
        rgb: Vec<u8>,
    },
    /// A whole hits file's bytes ([`HITS_MAGIC`], count, records).
    Hits(Vec<u8>),
}

/// Joins parts already read: all of one job, each shard exactly once.
///
/// # Errors
/// [`ShardError::NoParts`], [`ShardError::Foreign`] (naming the field that
/// differs from the first part's), [`ShardError::Doubled`] or
/// [`ShardError::Missing`].
pub fn merge(parts: &[Part]) -> Result<Merged, ShardError> {
    let first = parts.first().ok_or(ShardError::NoParts)?;
    let f = &first.header;
    for p in &parts[1..] {
        let h = &p.header;
        let fields: [(&'static str, String, String); 7] = [
            ("kind", format!("{:?}", h.kind), format!("{:?}", f.kind)),
            ("scene digest", h.digest.clone(), f.digest.clone()),
            ("settings", h.job.clone(), f.job.clone()),
            ("shard count", h.shards.to_string(), f.shards.to_string()),
            ("width", h.width.to_string(), f.width.to_string()),
            ("height", h.height.to_string(), f.height.to_string()),
            ("ray count", h.rays.to_string(), f.rays.to_string()),
        ];
        if let Some((field, mut theirs, mut ours)) = fields.into_iter().find(|(_, a, b)| a != b) {
            if field == "settings" {
                (theirs, ours) = differing_items(&theirs, &ours);
            }
            return Err(ShardError::Foreign {
                path: p.path.clone(),
                first: first.path.clone(),
                field,
                theirs,
                ours,
            });
        }
    }
    let count = f.shards;
    let mut by_index: Vec<Option<&Part>> = vec![None; count as usize];
    for p in parts {
        let slot = &mut by_index[p.header.shard as usize];
        if let Some(earlier) = slot {
            return Err(ShardError::Doubled {
                index: p.header.shard,
                count,
                first: earlier.path.clone(),
                second: p.path.clone(),
            });
        }
        *slot = Some(p);
    }
    let missing: Vec<u32> = (0..count)
        .filter(|&i| by_index[i as usize].is_none())
        .collect();
    if !missing.is_empty() {
        return Err(ShardError::Missing { count, missing });
    }
    let parts: Vec<&Part> = by_index.into_iter().flatten().collect();
    Ok(match f.kind {
        PartKind::Image => {
            let (w, h) = (f.width, f.height);
            let row = w as usize * 3;
            let mut rgb = vec![0u8; row * h as usize];
            for p in parts {
                let shard = Shard::new(p.header.shard, count).expect("checked by parse");
                for (y, src) in shard.rows(h).zip(p.payload.chunks_exact(row.max(1))) {
                    rgb[y as usize * row..(y as usize + 1) * row].copy_from_slice(src);
                }
            }
            Merged::Image {
                width: w,
                height: h,
                rgb,
            }
        }
        PartKind::Hits => Merged::Hits(hits_file(
            f.rays,
            parts.iter().map(|p| p.payload.as_slice()),
        )),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn image(w: u32, h: u32) -> Vec<u8> {
        (0..w * h * 3).map(|i| (i * 7 % 251) as u8).collect()
    }

    fn image_part(shard: Shard, w: u32, h: u32, rgb: &[u8], job: &str) -> Part {
        let header = PartHeader {
            kind: PartKind::Image,
            job: job.into(),
            digest: "0123456789abcdef".into(),
            shard: shard.index,
            shards: shard.count,
            width: w,
            height: h,
            rays: 0,
            payload_bytes: 0,
            payload_fnv: String::new(),
        };
        let bytes = encode_part(header, &rows_of(shard, w, h, rgb));
        Part::parse(Path::new(&format!("part{}", shard.index)), &bytes).unwrap()
    }

    fn parts(n: u32, w: u32, h: u32, rgb: &[u8]) -> Vec<Part> {
        (0..n)
            .map(|i| image_part(Shard::new(i, n).unwrap(), w, h, rgb, "job"))
            .collect()
    }

    #[test]
    fn shards_parse_as_index_over_count() {
        assert_eq!("2/5".parse(), Ok(Shard { index: 2, count: 5 }));
        assert_eq!("0/1".parse(), Ok(Shard { index: 0, count: 1 }));
        for bad in ["5/5", "1/0", "-1/4", "1", "a/b", "1/4/2", "0/65537", ""] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
    }

    #[test]
    fn the_index_comes_from_the_job_array_variables_in_order() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| (*v).to_string())
            }
        };
        assert_eq!(
            Shard::from_env(4, env(&[("SLURM_ARRAY_TASK_ID", "3")])),
            Ok(Shard { index: 3, count: 4 })
        );
        assert_eq!(
            Shard::from_env(
                4,
                env(&[("JOB_COMPLETION_INDEX", "1"), ("SLURM_ARRAY_TASK_ID", "3")])
            ),
            Ok(Shard { index: 1, count: 4 })
        );
        assert_eq!(
            Shard::from_env(4, env(&[])),
            Err(ShardError::NoIndex { count: 4 })
        );
        assert!(matches!(
            Shard::from_env(4, env(&[("SLURM_ARRAY_TASK_ID", "4")])),
            Err(ShardError::BadIndex {
                variable: "SLURM_ARRAY_TASK_ID",
                ..
            })
        ));
        assert!(Shard::from_env(0, env(&[("SLURM_ARRAY_TASK_ID", "0")])).is_err());
    }

    #[test]
    fn the_merge_restores_the_image() {
        let (w, h) = (37, 70);
        let rgb = image(w, h);
        for n in [1, 2, 3, 5, 8] {
            let mut ps = parts(n, w, h, &rgb);
            ps.reverse(); // any order
            assert_eq!(
                merge(&ps),
                Ok(Merged::Image {
                    width: w,
                    height: h,
                    rgb: rgb.clone()
                }),
                "{n} shards"
            );
        }
    }

    #[test]
    fn missing_doubled_and_foreign_parts_are_named() {
        let (w, h) = (20, 50);
        let rgb = image(w, h);
        let ps = parts(4, w, h, &rgb);
        assert_eq!(
            merge(&[ps[0].clone(), ps[2].clone()]),
            Err(ShardError::Missing {
                count: 4,
                missing: vec![1, 3]
            })
        );
        let doubled = merge(&[ps[0].clone(), ps[1].clone(), ps[1].clone(), ps[2].clone()]);
        assert!(
            matches!(doubled, Err(ShardError::Doubled { index: 1, .. })),
            "{doubled:?}"
        );
        let other = image_part(Shard::new(3, 4).unwrap(), w, h, &rgb, "other settings");
        let foreign = merge(&[ps[0].clone(), ps[1].clone(), ps[2].clone(), other]);
        assert!(
            matches!(
                foreign,
                Err(ShardError::Foreign {
                    field: "settings",
                    ..
                })
            ),
            "{foreign:?}"
        );
        let spp = image_part(
            Shard::new(3, 4).unwrap(),
            w,
            h,
            &rgb,
            "render; spp: 4; ao: 2",
        );
        let first = image_part(
            Shard::new(0, 4).unwrap(),
            w,
            h,
            &rgb,
            "render; spp: 1; ao: 2",
        );
        match merge(&[first, spp]) {
            Err(ShardError::Foreign { theirs, ours, .. }) => {
                assert_eq!((theirs.as_str(), ours.as_str()), ("spp: 4", "spp: 1"));
            }
            other => panic!("{other:?}"),
        }
        let taller = image_part(Shard::new(3, 4).unwrap(), w, h + 1, &image(w, h + 1), "job");
        assert!(matches!(
            merge(&[ps[0].clone(), ps[1].clone(), ps[2].clone(), taller]),
            Err(ShardError::Foreign {
                field: "height",
                ..
            })
        ));
        assert_eq!(merge(&[]), Err(ShardError::NoParts));
    }

    #[test]
    fn damaged_parts_are_refused() {
        let (w, h) = (8, 40);
        let rgb = image(w, h);
        let shard = Shard::new(1, 2).unwrap();
        let good = image_part(shard, w, h, &rgb, "job");
        let bytes = encode_part(good.header.clone(), &good.payload);
        let path = Path::new("p");
        let problem = |bytes: &[u8]| match Part::parse(path, bytes) {
            Err(ShardError::Part { problem, .. }) => problem,
            other => panic!("expected a refusal, got {other:?}"),
        };
        assert!(problem(&bytes[..bytes.len() - 1]).contains("truncated"));
        let mut flipped = bytes.clone();
        *flipped.last_mut().unwrap() ^= 1;
        assert!(problem(&flipped).contains("damaged"));
        assert!(problem(b"PNG...").contains("not a part file"));
        assert!(problem(&bytes[..20]).contains("header announces"));
        let mut header = good.header.clone();
        header.shard = 2;
        assert!(problem(&encode_part(header, &good.payload)).contains("not a shard"));
    }

    #[test]
    fn hits_join_in_ray_order() {
        let n = 1001usize;
        let records: Vec<[u8; HIT_BYTES]> = (0..n)
            .map(|i| hit_record((i % 3 != 0).then_some((i as u32, i as f64 * 0.5))))
            .collect();
        let count = 7;
        let parts: Vec<Part> = (0..count)
            .map(|i| {
                let shard = Shard::new(i, count).unwrap();
                let payload: Vec<u8> = records[shard.ray_range(n)].concat();
                let header = PartHeader {
                    kind: PartKind::Hits,
                    job: "bench".into(),
                    digest: "d".into(),
                    shard: i,
                    shards: count,
                    width: 0,
                    height: 0,
                    rays: n as u64,
                    payload_bytes: 0,
                    payload_fnv: String::new(),
                };
                Part::parse(Path::new("h"), &encode_part(header, &payload)).unwrap()
            })
            .collect();
        let Ok(Merged::Hits(bytes)) = merge(&parts) else {
            panic!("hits expected")
        };
        assert_eq!(bytes[..8], HITS_MAGIC);
        assert_eq!(
            u64::from_le_bytes(bytes[8..16].try_into().unwrap()),
            n as u64
        );
        assert_eq!(bytes[16..], records.concat()[..]);
        assert_eq!(hit_record(None)[..4], NO_HIT.to_le_bytes());
    }

    proptest! {
        /// Every row belongs to exactly one shard, every ray to exactly one
        /// slice, and the slices are in order.
        #[test]
        fn shards_cover_everything_once(count in 1u32..40, height in 0u32..500, n in 0usize..5000) {
            let shards: Vec<Shard> = (0..count).map(|i| Shard::new(i, count).unwrap()).collect();
            for y in 0..height {
                prop_assert_eq!(shards.iter().filter(|s| s.owns_row(y)).count(), 1);
            }
            let mut next = 0;
            for s in &shards {
                let r = s.ray_range(n);
                prop_assert_eq!(r.start, next);
                next = r.end;
            }
            prop_assert_eq!(next, n);
        }
    }
}
