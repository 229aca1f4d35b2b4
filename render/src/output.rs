//! Output files written whole or not at all.
//!
//! A [`PendingFile`] is a destination checked up front ([`PendingFile::create`]
//! proves its directory writable, so an unwritable path fails before any work
//! is done) and written only once the output is ready: each `write_*` method
//! creates a temporary file in the destination's directory, fills it and
//! renames it over the destination; on any error the temporary file is
//! deleted. A reader never sees a partial file, and a run interrupted while
//! it works (Ctrl-C, SIGTERM: no destructor runs) leaves no hidden
//! `.NAME.XXXXXX.tmp` behind, since none exists until the writing starts
//! (see: issue 32, item 4).

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Why an output file could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The destination is a directory.
    #[error("cannot write {path}: it is a directory")]
    IsDirectory {
        /// The destination.
        path: PathBuf,
    },
    /// The destination's directory does not exist.
    #[error("cannot write {path}: {dir} is not an existing directory")]
    NoDirectory {
        /// The destination.
        path: PathBuf,
        /// Its directory.
        dir: PathBuf,
    },
    /// The destination's directory is not writable, or writing failed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The destination.
        path: PathBuf,
        /// What the system said.
        source: std::io::Error,
    },
    /// The image encoder failed.
    #[error("cannot write {path}: {message}")]
    Encode {
        /// The destination.
        path: PathBuf,
        /// What the encoder said.
        message: String,
    },
}

/// A destination checked for writing; written, whole, by one of the
/// `write_*` methods.
#[derive(Debug)]
pub struct PendingFile {
    dest: PathBuf,
    dir: PathBuf,
    name: String,
}

impl PendingFile {
    /// Checks that `dest` can be written: not a directory, in an existing
    /// directory where a file can be created (proved by creating a
    /// temporary file there and deleting it at once). Nothing stays behind.
    ///
    /// # Errors
    /// [`OutputError`] if `dest` is a directory or its directory is missing or
    /// not writable.
    pub fn create(dest: &Path) -> Result<Self, OutputError> {
        if dest.is_dir() {
            return Err(OutputError::IsDirectory {
                path: dest.to_owned(),
            });
        }
        let dir = match dest.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        let name = dest
            .file_name()
            .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
        if !dir.is_dir() {
            // Missing, or a file.
            return Err(OutputError::NoDirectory {
                path: dest.to_owned(),
                dir: dir.to_owned(),
            });
        }
        let pending = Self {
            dest: dest.to_owned(),
            dir: dir.to_owned(),
            name,
        };
        // Dropped at once: the probe is deleted.
        drop(pending.temporary()?);
        Ok(pending)
    }

    /// A new temporary file beside the destination, named after it.
    fn temporary(&self) -> Result<tempfile::NamedTempFile, OutputError> {
        let prefix = format!(".{}.", self.name);
        let mut builder = tempfile::Builder::new();
        builder.prefix(&prefix).suffix(".tmp");
        // A temporary file is private (0600); the result should be an ordinary
        // file, readable as the umask allows, like one `File::create` makes.
        #[cfg(unix)]
        builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
        builder.tempfile_in(&self.dir).map_err(|e| OutputError::Io {
            path: self.dest.clone(),
            // tempfile's error names its random file name; the kind is what matters.
            source: std::io::Error::from(e.kind()),
        })
    }

    /// The destination path.
    #[must_use]
    pub fn dest(&self) -> &Path {
        &self.dest
    }

    fn io_error(&self, source: std::io::Error) -> OutputError {
        OutputError::Io {
            path: self.dest.clone(),
            source,
        }
    }

    /// Writes `bytes` and commits.
    ///
    /// # Errors
    /// [`OutputError::Io`] if creating, writing or renaming fails (the
    /// temporary file is removed).
    pub fn write_all(self, bytes: &[u8]) -> Result<(), OutputError> {
        let mut tmp = self.temporary()?;
        if let Err(e) = tmp.as_file_mut().write_all(bytes) {
            return Err(self.io_error(e));
        }
        self.commit(tmp)
    }

    /// Encodes an 8-bit RGB image as PNG and commits.
    ///
    /// # Errors
    /// [`OutputError`] if encoding, creating, writing or renaming fails.
    pub fn write_png(self, width: u32, height: u32, rgb: &[u8]) -> Result<(), OutputError> {
        use image::ImageEncoder;
        let mut tmp = self.temporary()?;
        let result = {
            let mut w = BufWriter::new(tmp.as_file_mut());
            let r = image::codecs::png::PngEncoder::new(&mut w).write_image(
                rgb,
                width,
                height,
                image::ExtendedColorType::Rgb8,
            );
            r.map_err(|e| e.to_string())
                .and_then(|()| w.flush().map_err(|e| e.to_string()))
        };
        if let Err(message) = result {
            return Err(OutputError::Encode {
                path: self.dest.clone(),
                message,
            });
        }
        self.commit(tmp)
    }

    /// Gives a new temporary file to `f` (buffered), then commits.
    ///
    /// # Errors
    /// [`OutputError::Io`] if creating, `f`, flushing or renaming fails.
    pub fn write_with(
        self,
        f: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
    ) -> Result<(), OutputError> {
        let mut tmp = self.temporary()?;
        let result = {
            let mut w = BufWriter::new(tmp.as_file_mut());
            f(&mut w).and_then(|()| w.flush())
        };
        match result {
            Ok(()) => self.commit(tmp),
            Err(e) => Err(self.io_error(e)),
        }
    }

    /// Flushes `tmp` to disk and renames it over the destination.
    fn commit(self, tmp: tempfile::NamedTempFile) -> Result<(), OutputError> {
        let file: &File = tmp.as_file();
        if let Err(e) = file.sync_all() {
            return Err(self.io_error(e));
        }
        let dest = self.dest;
        tmp.persist(&dest).map(drop).map_err(|e| OutputError::Io {
            path: dest,
            source: e.error,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn entries(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// See: issue 32, item 4. A checked destination holds no temporary file
    /// while the work runs (an interrupted run, whose destructors never run,
    /// leaves nothing), and neither a failed nor a finished write leaves one.
    #[test]
    fn no_temporary_file_exists_before_or_after_writing() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("a.bin");
        let pending = PendingFile::create(&dest).unwrap();
        assert!(!dest.exists());
        assert!(entries(dir.path()).is_empty(), "nothing while working");
        drop(pending);
        assert!(entries(dir.path()).is_empty());
        let failed = PendingFile::create(&dest)
            .unwrap()
            .write_with(|_| Err(std::io::Error::other("the encoder gave up")));
        assert!(failed.unwrap_err().to_string().contains("gave up"));
        assert!(entries(dir.path()).is_empty(), "nothing after a failure");
        PendingFile::create(&dest)
            .unwrap()
            .write_all(b"whole")
            .unwrap();
        assert_eq!(std::fs::read(&dest).unwrap(), b"whole");
        assert_eq!(entries(dir.path()), vec!["a.bin".to_owned()]);
    }

    #[cfg(unix)]
    #[test]
    fn results_are_ordinary_files_not_private_temporaries() {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("p.bin");
        PendingFile::create(&dest).unwrap().write_all(b"x").unwrap();
        let reference = dir.path().join("reference.bin");
        std::fs::write(&reference, b"x").unwrap();
        let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
        assert_eq!(mode(&dest), mode(&reference));
    }

    #[test]
    fn bad_destinations_are_named() {
        let dir = tempfile::tempdir().unwrap();
        let err = PendingFile::create(dir.path()).unwrap_err();
        assert!(err.to_string().contains("is a directory"), "{err}");
        let missing = dir.path().join("no/such/dir/x.png");
        let err = PendingFile::create(&missing).unwrap_err();
        assert!(err.to_string().contains("no/such/dir/x.png"), "{err}");
    }

    #[test]
    fn png_round_trips() {
        let dir = tempfile::tempdir().unwrap();
        let dest = dir.path().join("x.png");
        let rgb: Vec<u8> = (0..2 * 3 * 3).map(|i| (i * 13) as u8).collect();
        PendingFile::create(&dest)
            .unwrap()
            .write_png(2, 3, &rgb)
            .unwrap();
        let img = image::open(&dest).unwrap().to_rgb8();
        assert_eq!((img.width(), img.height()), (2, 3));
        assert_eq!(img.into_raw(), rgb);
    }
}
