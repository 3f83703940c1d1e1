//! Crash-safe file output: write a temporary file next to the target, sync
//! it, then rename it over the target. A reader (or a later run after a crash)
//! sees either the old file or the complete new one, never a torn one.

use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::{file_name, ImageError};

/// Writes `path` through `encode`, atomically. `encode` reports its own
/// format errors (naming `path`, not the temporary file); I/O failures
/// here are reported against `path` as well.
pub(crate) fn write_atomically(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<File>) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let io_error = |source| io_error(path, source);
    let temp = temp_path(path).map_err(io_error)?;
    let file = File::create(&temp).map_err(io_error)?;
    let result =
        finish(file, encode, path).and_then(|()| std::fs::rename(&temp, path).map_err(io_error));
    if result.is_err() {
        // Best effort: the error being returned matters more than a leftover.
        let _ = std::fs::remove_file(&temp);
    }
    result
}

/// Encodes, flushes and syncs, so that the rename publishes complete data
/// even if the machine goes down right after it.
fn finish(
    file: File,
    encode: impl FnOnce(&mut BufWriter<File>) -> Result<(), ImageError>,
    path: &Path,
) -> Result<(), ImageError> {
    let io_error = |source| io_error(path, source);
    let mut writer = BufWriter::new(file);
    encode(&mut writer)?;
    // into_inner flushes the buffer, reporting a failed flush.
    let file = writer.into_inner().map_err(|e| io_error(e.into_error()))?;
    file.sync_all().map_err(io_error)
}

fn io_error(path: &Path, source: std::io::Error) -> ImageError {
    ImageError::Io {
        file: file_name(path),
        source,
    }
}

/// `.{name}.tmp-{pid}-{n}` in the target's directory: the same directory so
/// that the rename stays on one file system (and is therefore atomic), hidden
/// so that directory listings do not show it, and unique per process and call
/// so that concurrent writers of one target do not share a temporary file.
fn temp_path(path: &Path) -> std::io::Result<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "path does not name a file",
        )
    })?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut temp = std::ffi::OsString::from(".");
    temp.push(name);
    temp.push(format!(".tmp-{}-{n}", std::process::id()));
    Ok(path.with_file_name(temp))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::{file_names, temp_dir};
    use std::io::Write;

    #[test]
    fn replaces_target_and_leaves_no_temp_file() {
        let dir = temp_dir("replace");
        let path = dir.join("out.bin");
        std::fs::write(&path, b"old contents").unwrap();
        write_atomically(&path, |w| {
            w.write_all(b"new").unwrap();
            Ok(())
        })
        .unwrap();
        let contents = std::fs::read(&path).unwrap();
        let names = file_names(&dir);
        std::fs::remove_dir_all(&dir).unwrap();
        assert_eq!(contents, b"new");
        assert_eq!(names, ["out.bin"]);
    }

    #[test]
    fn failed_encode_keeps_old_file_and_removes_temp() {
        let dir = temp_dir("fail");
        let path = dir.join("out.bin");
        std::fs::write(&path, b"old").unwrap();
        let err = write_atomically(&path, |w| {
            w.write_all(b"partial").unwrap();
            Err(ImageError::Truncated {
                file: file_name(&path),
                expected: 1,
                found: 0,
            })
        })
        .unwrap_err();
        let contents = std::fs::read(&path).unwrap();
        let names = file_names(&dir);
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(matches!(err, ImageError::Truncated { .. }), "{err}");
        assert_eq!(contents, b"old");
        assert_eq!(names, ["out.bin"]);
    }

    #[test]
    fn missing_directory_error_names_the_target() {
        let path = Path::new("/nonexistent/caustica/out.bin");
        let err = write_atomically(path, |_| Ok(())).unwrap_err().to_string();
        assert!(err.starts_with("/nonexistent/caustica/out.bin: "), "{err}");
    }

    #[test]
    fn temp_file_is_hidden_sibling() {
        let temp = temp_path(Path::new("renders/out.exr")).unwrap();
        assert_eq!(temp.parent(), Some(Path::new("renders")));
        let name = temp.file_name().unwrap().to_string_lossy().into_owned();
        let prefix = format!(".out.exr.tmp-{}-", std::process::id());
        assert!(name.starts_with(&prefix), "{name}");
        assert!(temp_path(Path::new("/")).is_err());
    }
}
