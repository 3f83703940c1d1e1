//! Scratch files for the library's unit tests.

use std::path::{Path, PathBuf};

/// A fresh, empty directory for one test, unique per tag and process.
pub fn temp_dir(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustica-unit-{tag}-{}", std::process::id()));
    // A leftover from an earlier run with the same pid is harmless to remove.
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("cannot create a temporary test directory");
    dir
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
