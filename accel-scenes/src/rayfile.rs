//! The binary ray file of DESIGN.md, for cross-checking against other tools.
//!
//! Little-endian. A 16-byte header: ASCII `RAYS`, `u32` version 1, `u64`
//! count; then per ray 8 `f32`: `ox oy oz dx dy dz tmin tmax`.
//!
//! Reading checks everything: the header, that the file holds exactly
//! `count` rays, and every ray ([`Ray::validate`]: finite origin and
//! direction, non-zero direction, no NaN bound). An infinite `tmax` is valid.

use accel_core::{QueryError, Ray, Real, Vec3};
use std::path::{Path, PathBuf};

/// The magic bytes at the start of the file.
pub const MAGIC: [u8; 4] = *b"RAYS";
/// The only version.
pub const VERSION: u32 = 1;
/// Bytes of the header.
pub const HEADER_BYTES: usize = 16;
/// Bytes per ray.
pub const RAY_BYTES: usize = 32;

/// Why a ray file was refused.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RayFileError {
    /// The file could not be read.
    #[error("{path}: cannot read the ray file: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// Fewer than 16 bytes.
    #[error("{path}: not a ray file: {len} bytes is shorter than the 16-byte header")]
    Short {
        /// The file.
        path: PathBuf,
        /// Its length.
        len: usize,
    },
    /// The first four bytes are not `RAYS`.
    #[error("{path}: not a ray file: it starts with {found:?}, not \"RAYS\"")]
    Magic {
        /// The file.
        path: PathBuf,
        /// The bytes found, lossily decoded.
        found: String,
    },
    /// A version other than 1.
    #[error("{path}: ray file version {version} is not supported (only version 1)")]
    Version {
        /// The file.
        path: PathBuf,
        /// The version found.
        version: u32,
    },
    /// The length does not match the count.
    #[error(
        "{path}: the header announces {count} rays ({expected} bytes with the header) but the file holds {len} bytes"
    )]
    CountMismatch {
        /// The file.
        path: PathBuf,
        /// The count in the header.
        count: u64,
        /// The length that count implies (saturated).
        expected: u64,
        /// The actual length.
        len: usize,
    },
    /// A ray is not valid.
    #[error("{path}: ray {index} is invalid: {source}")]
    BadRay {
        /// The file.
        path: PathBuf,
        /// Which ray (from 0).
        index: usize,
        /// Why.
        source: QueryError,
    },
}

/// A ray's eight numbers in the file's order: origin, direction, `t_min`,
/// `t_max`.
#[must_use]
pub fn ray_values<T: Real>(r: &Ray<T>) -> [T; 8] {
    [
        r.origin.x,
        r.origin.y,
        r.origin.z,
        r.direction.x,
        r.direction.y,
        r.direction.z,
        r.t_min,
        r.t_max,
    ]
}

/// Encodes rays (rounded to `f32`) in the file format.
#[must_use]
pub fn encode<T: Real>(rays: &[Ray<T>]) -> Vec<u8> {
    let mut out = Vec::with_capacity(HEADER_BYTES + RAY_BYTES * rays.len());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(rays.len() as u64).to_le_bytes());
    for r in rays {
        for v in ray_values(r) {
            out.extend_from_slice(&(v.to_f64() as f32).to_le_bytes());
        }
    }
    out
}

/// Decodes and validates a ray file's bytes; `path` only names it in errors.
///
/// # Errors
/// [`RayFileError`] naming the first problem.
pub fn decode(path: &Path, bytes: &[u8]) -> Result<Vec<Ray<f32>>, RayFileError> {
    let path_buf = || path.to_owned();
    if bytes.len() < HEADER_BYTES {
        return Err(RayFileError::Short {
            path: path_buf(),
            len: bytes.len(),
        });
    }
    if bytes[..4] != MAGIC {
        return Err(RayFileError::Magic {
            path: path_buf(),
            found: String::from_utf8_lossy(&bytes[..4]).into_owned(),
        });
    }
    let word = |at: usize| [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
    let version = u32::from_le_bytes(word(4));
    if version != VERSION {
        return Err(RayFileError::Version {
            path: path_buf(),
            version,
        });
    }
    let mut count_bytes = [0u8; 8];
    count_bytes.copy_from_slice(&bytes[8..16]);
    let count = u64::from_le_bytes(count_bytes);
    let expected = count
        .checked_mul(RAY_BYTES as u64)
        .and_then(|b| b.checked_add(HEADER_BYTES as u64));
    if expected != Some(bytes.len() as u64) {
        return Err(RayFileError::CountMismatch {
            path: path_buf(),
            count,
            expected: expected.unwrap_or(u64::MAX),
            len: bytes.len(),
        });
    }
    bytes[HEADER_BYTES..]
        .chunks_exact(RAY_BYTES)
        .enumerate()
        .map(|(index, chunk)| {
            let f = |i: usize| f32::from_le_bytes(word_at(chunk, 4 * i));
            let ray = Ray {
                origin: Vec3::new(f(0), f(1), f(2)),
                direction: Vec3::new(f(3), f(4), f(5)),
                t_min: f(6),
                t_max: f(7),
            };
            ray.validate()
                .map(|()| ray)
                .map_err(|source| RayFileError::BadRay {
                    path: path_buf(),
                    index,
                    source,
                })
        })
        .collect()
}

fn word_at(chunk: &[u8], at: usize) -> [u8; 4] {
    [chunk[at], chunk[at + 1], chunk[at + 2], chunk[at + 3]]
}

/// Reads and validates a ray file.
///
/// # Errors
/// [`RayFileError`] naming the file and the first problem.
pub fn read(path: &Path) -> Result<Vec<Ray<f32>>, RayFileError> {
    let bytes = std::fs::read(path).map_err(|source| RayFileError::Io {
        path: path.to_owned(),
        source,
    })?;
    decode(path, &bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rays() -> Vec<Ray<f32>> {
        vec![
            Ray::new(Vec3::new(1.0, -2.0, 3.5), Vec3::new(0.0, -0.0, 1.0)).unwrap(),
            Ray::with_interval(
                Vec3::new(1e-20, 1e20, -7.25),
                Vec3::new(0.3, 0.4, -0.5),
                0.125,
                f32::INFINITY,
            )
            .unwrap(),
            // An empty interval is a valid ray that hits nothing.
            Ray::with_interval(Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), 2.0, 1.0).unwrap(),
        ]
    }

    fn bits(r: &Ray<f32>) -> [u32; 8] {
        ray_values(r).map(f32::to_bits)
    }

    #[test]
    fn rays_round_trip_bit_for_bit() {
        let original = rays();
        let bytes = encode(&original);
        assert_eq!(bytes.len(), 16 + 32 * 3);
        assert_eq!(&bytes[..4], b"RAYS");
        assert_eq!(bytes[4..8], 1u32.to_le_bytes());
        assert_eq!(bytes[8..16], 3u64.to_le_bytes());
        // The first ray's ox, little-endian.
        assert_eq!(bytes[16..20], 1.0f32.to_le_bytes());
        let back = decode(Path::new("x.rays"), &bytes).unwrap();
        assert_eq!(back.len(), 3);
        for (a, b) in original.iter().zip(&back) {
            assert_eq!(bits(a), bits(b));
        }
        let empty = decode(Path::new("e"), &encode::<f32>(&[])).unwrap();
        assert!(empty.is_empty());
    }

    #[test]
    fn bad_files_are_refused_with_their_reason() {
        let p = Path::new("bad.rays");
        let good = encode(&rays());
        let check = |bytes: &[u8], needle: &str| {
            let err = decode(p, bytes).unwrap_err().to_string();
            assert!(err.contains(needle) && err.contains("bad.rays"), "{err}");
        };
        check(&good[..10], "shorter than the 16-byte header");
        let mut magic = good.clone();
        magic[..4].copy_from_slice(b"RAYZ");
        check(&magic, "not \"RAYS\"");
        let mut version = good.clone();
        version[4..8].copy_from_slice(&2u32.to_le_bytes());
        check(&version, "version 2");
        check(&good[..good.len() - 1], "announces 3 rays");
        let mut more = good.clone();
        more[8..16].copy_from_slice(&4u64.to_le_bytes());
        check(&more, "announces 4 rays");
        let mut huge = good.clone();
        huge[8..16].copy_from_slice(&u64::MAX.to_le_bytes());
        check(&huge, "announces");
        let mut nan = good.clone();
        let at = 16 + 32 + 4 * 3; // ray 1, dx
        nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        check(&nan, "ray 1 is invalid: ray direction is not finite");
        let mut zero = good.clone();
        for i in 3..6 {
            let at = 16 + 4 * i;
            zero[at..at + 4].copy_from_slice(&0.0f32.to_le_bytes());
        }
        check(&zero, "ray 0 is invalid: ray direction is zero");
        let mut tmin = good;
        let at = 16 + 64 + 24;
        tmin[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        check(&tmin, "ray 2 is invalid");
    }

    #[test]
    fn a_missing_file_is_named() {
        let err = read(Path::new("/no/such/rays.bin"))
            .unwrap_err()
            .to_string();
        assert!(err.contains("/no/such/rays.bin"), "{err}");
    }
}
