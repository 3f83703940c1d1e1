//! Scratch files for tests: the library's unit tests, and the integration tests through
//! tests/common (which includes this file), so both leave nothing behind.

use std::ops::Deref;
use std::path::{Path, PathBuf};

/// A fresh, empty directory for one test, removed with everything in it when the value is dropped:
/// at the end of the test, passing or failing (a panic unwinds through the drop). Its name starts
/// `caustica-{tag}-`, so a kept one is easy to find. It reads as a `Path` (`dir.join(...)`,
/// `&dir`).
pub struct ScratchDir(tempfile::TempDir);

impl Deref for ScratchDir {
    type Target = Path;
    fn deref(&self) -> &Path {
        self.0.path()
    }
}

impl AsRef<Path> for ScratchDir {
    fn as_ref(&self) -> &Path {
        self.0.path()
    }
}

/// A scratch directory for one test (see [`ScratchDir`]); unique, so tests running at once never
/// share one. With `CAUSTICA_KEEP_TEST_FILES` set, it is left in place for a look afterwards.
pub fn temp_dir(tag: &str) -> ScratchDir {
    let dir = tempfile::Builder::new()
        .prefix(&format!("caustica-{tag}-"))
        .disable_cleanup(std::env::var_os("CAUSTICA_KEEP_TEST_FILES").is_some())
        .tempdir()
        .expect("cannot create a temporary test directory");
    ScratchDir(dir)
}

/// Files written into a scratch directory of their own: reads as the path of the first, and keeps
/// the directory until it is dropped.
pub struct WrittenFiles {
    _dir: ScratchDir,
    first: PathBuf,
}

impl Deref for WrittenFiles {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.first
    }
}

/// Writes `files` (name, text) into a fresh scratch directory tagged `tag`.
pub fn write_files(tag: &str, files: &[(&str, &str)]) -> WrittenFiles {
    let dir = temp_dir(tag);
    for (name, text) in files {
        std::fs::write(dir.join(name), text).expect("cannot write a test file");
    }
    let first = dir.join(files[0].0);
    WrittenFiles { _dir: dir, first }
}

/// Writes one file `name` into a fresh scratch directory tagged `tag`.
pub fn write_file(tag: &str, name: &str, bytes: impl AsRef<[u8]>) -> WrittenFiles {
    let dir = temp_dir(tag);
    let first = dir.join(name);
    std::fs::write(&first, bytes).expect("cannot write a test file");
    WrittenFiles { _dir: dir, first }
}

/// The names in a directory, sorted: what a writer left behind.
pub fn file_names(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("readable test directory")
        .map(|e| e.expect("directory entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}
