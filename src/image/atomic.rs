//! Crash-safe file output: write a temporary file next to the target, sync
//! it, then rename it over the target. A reader (or a later run after a crash)
//! sees either the old file or the complete new one, never a torn one.
//!
//! The temporary files are named `.{target}.tmp-{pid}-{n}` (with `{target}` shortened, see
//! [`temp_stem`], where that would pass the 255 bytes a file name may have). A process that is
//! killed mid-write leaves one behind; [`remove_stale_temp_files`] clears those
//! of a target before the next run writes it, and [`remove_temp_files_in_flight`]
//! lets a process that quits on a signal remove its own first.

use std::ffi::OsString;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, SystemTime};

use super::{file_name, ImageError};

/// Writes `path` through `encode`, atomically. `encode` reports its own
/// format errors (naming `path`, not the temporary file); I/O failures
/// here are reported against `path` as well.
pub(crate) fn write_atomically(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<File>) -> Result<(), ImageError>,
) -> Result<(), ImageError> {
    let io_error = |source| io_error(path, source);
    let temp = TempFile::new(path).map_err(io_error)?;
    let file = File::create(&temp.path).map_err(io_error)?;
    finish(file, encode, path)?;
    std::fs::rename(&temp.path, path).map_err(io_error)
}

/// Checks that `path` can be written, without touching it: it is not a
/// directory, and a file can be created (and is then removed) beside it,
/// under the temporary name a real write would use. Run before the work
/// whose result goes there, so that a bad path fails at once.
pub fn check_writable(path: &Path) -> Result<(), ImageError> {
    let unwritable = |reason: String| ImageError::Unwritable { file: file_name(path), reason };
    if path.is_dir() {
        return Err(unwritable("it is a directory".to_owned()));
    }
    let temp = TempFile::new(path).map_err(|e| unwritable(e.to_string()))?;
    File::create(&temp.path).map_err(|e| {
        let dir = temp.path.parent().filter(|d| !d.as_os_str().is_empty());
        let dir = dir.unwrap_or(Path::new(".")).display();
        unwritable(format!("cannot create a file in {dir}: {e}"))
    })?;
    Ok(())
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
    ImageError::Io { file: file_name(path), cause: source }
}

/// The temporary files this process is writing now.
static IN_FLIGHT: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn in_flight() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // The list stays valid whatever a panicking holder was doing.
    IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner())
}

/// A temporary file for one write, listed in [`IN_FLIGHT`] from before it is
/// created until it is gone: dropping it removes the file unless it was
/// renamed over its target, so an error or a panic leaves nothing behind.
struct TempFile {
    path: PathBuf,
}

impl TempFile {
    fn new(target: &Path) -> std::io::Result<Self> {
        let path = temp_path(target)?;
        in_flight().push(path.clone());
        Ok(Self { path })
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        // After a successful rename there is nothing here to remove; after a
        // failure, the error being reported matters more than a leftover.
        let _ = std::fs::remove_file(&self.path);
        in_flight().retain(|p| p != &self.path);
    }
}

/// Removes the temporary files of the writes in flight. For a process that is
/// about to exit without finishing them (a second Ctrl-C): the targets keep
/// their previous contents, and no temporary file is left behind.
pub fn remove_temp_files_in_flight() {
    remove_temp_files_in_flight_where(|_| true);
}

/// Removes the temporary files in flight that `chosen` picks.
fn remove_temp_files_in_flight_where(chosen: impl Fn(&Path) -> bool) {
    for path in in_flight().iter().filter(|p| chosen(p)) {
        let _ = std::fs::remove_file(path);
    }
}

/// How long a temporary file must have gone unmodified before another process
/// may take it for abandoned: a write in progress touches its file
/// continually, so this protects a writer on another machine sharing the
/// directory, whose process id means nothing here.
const STALE_AFTER: Duration = Duration::from_secs(60);

/// Removes the temporary files that earlier writes of `target` left behind:
/// those of our naming pattern for exactly this target whose writer is gone (a
/// process id that no longer runs, or this process when the file is not one of
/// its writes in flight) and that were not modified in the last minute. Returns
/// the files removed. Other files are never touched.
pub fn remove_stale_temp_files(target: &Path) -> std::io::Result<Vec<PathBuf>> {
    let Some(name) = target.file_name() else {
        return Ok(vec![]);
    };
    let dir = target.parent().filter(|d| !d.as_os_str().is_empty());
    let dir = dir.unwrap_or(Path::new("."));
    let mut prefix = temp_stem(name);
    prefix.push(".tmp-");
    let prefix = prefix.to_string_lossy().into_owned();
    let mut removed = vec![];
    for entry in std::fs::read_dir(dir)? {
        let entry = entry?;
        let file_name = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = file_name.strip_prefix(&prefix).and_then(parse_pid_and_counter) else {
            continue;
        };
        let path = entry.path();
        let writer_gone = if pid == std::process::id() { !in_flight().contains(&path) } else { !process_runs(pid) };
        let untouched = entry
            .metadata()
            .and_then(|m| m.modified())
            .ok()
            .and_then(|modified| SystemTime::now().duration_since(modified).ok())
            .is_some_and(|age| age >= STALE_AFTER);
        if writer_gone && untouched && entry.file_type()?.is_file() {
            std::fs::remove_file(&path)?;
            removed.push(path);
        }
    }
    Ok(removed)
}

/// The process id in `{pid}-{n}`, the tail of a temporary file name.
fn parse_pid_and_counter(tail: &str) -> Option<u32> {
    let (pid, n) = tail.split_once('-')?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if !digits(pid) || !digits(n) {
        return None;
    }
    pid.parse().ok()
}

/// Whether process `pid` runs on this machine. Where that cannot be told (no
/// /proc), it is taken to run, so that its files are left alone.
fn process_runs(pid: u32) -> bool {
    let proc = Path::new("/proc");
    !proc.join("self").exists() || proc.join(pid.to_string()).exists()
}

/// `.{name}.tmp-{pid}-{n}` in the target's directory: the same directory so
/// that the rename stays on one file system (and is therefore atomic), hidden
/// so that directory listings do not show it, and unique per process and call
/// so that concurrent writers of one target do not share a temporary file.
fn temp_path(path: &Path) -> std::io::Result<PathBuf> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .ok_or_else(|| std::io::Error::new(std::io::ErrorKind::InvalidInput, "path does not name a file"))?;
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let mut temp = temp_stem(name);
    temp.push(format!(".tmp-{}-{n}", std::process::id()));
    Ok(path.with_file_name(temp))
}

/// The longest file name most file systems take (NAME_MAX), in bytes.
const NAME_MAX: usize = 255;
/// The longest `.tmp-{pid}-{n}`: a u32 and a u64 in decimal.
const TEMP_SUFFIX_MAX: usize = ".tmp-".len() + 10 + 1 + 20;

/// What a temporary file's name starts with for target file name `name`: `.{name}`, or, where that
/// and the suffix would pass [`NAME_MAX`] (a target of 220 bytes or more), the start of the name,
/// `~` and 16 hex digits of its BLAKE3 hash, which keeps the targets' temporary files apart.
fn temp_stem(name: &std::ffi::OsStr) -> OsString {
    let mut stem = OsString::from(".");
    if 1 + name.len() + TEMP_SUFFIX_MAX <= NAME_MAX {
        stem.push(name);
        return stem;
    }
    let hash = blake3::hash(name.as_encoded_bytes()).to_hex();
    let room = NAME_MAX - TEMP_SUFFIX_MAX - 1 - 1 - 16;
    let lossy = name.to_string_lossy();
    let cut = (0..=room.min(lossy.len())).rev().find(|&k| lossy.is_char_boundary(k)).unwrap_or(0);
    stem.push(&lossy[..cut]);
    stem.push(format!("~{}", &hash[..16]));
    stem
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
            Err(ImageError::Truncated { file: file_name(&path), expected: 1, found: 0 })
        })
        .unwrap_err();
        let contents = std::fs::read(&path).unwrap();
        let names = file_names(&dir);
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

    /// A file named as the `n`-th write of `target` by process `pid` would name its temporary
    /// file, last modified `age` ago.
    fn leftover(target: &Path, pid: u32, n: u32, age: Duration) -> PathBuf {
        let name = target.file_name().unwrap().to_string_lossy();
        let path = target.with_file_name(format!(".{name}.tmp-{pid}-{n}"));
        let file = File::create(&path).unwrap();
        file.set_modified(SystemTime::now() - age).unwrap();
        path
    }

    /// The id of a process that has exited.
    fn dead_pid() -> u32 {
        let mut child = std::process::Command::new("true").spawn().unwrap();
        let pid = child.id();
        child.wait().unwrap();
        pid
    }

    #[test]
    fn stale_temp_files_of_dead_writers_are_removed_and_nothing_else() {
        let dir = temp_dir("stale");
        let target = dir.join("out.png");
        let (old, dead) = (Duration::from_secs(600), dead_pid());
        let stale = leftover(&target, dead, 0, old);
        let stale_of_ours = leftover(&target, std::process::id(), 999_999, old);
        let live_writer = leftover(&target, 1, 0, old);
        let recent = leftover(&target, dead, 1, Duration::ZERO);
        let other_target = leftover(&dir.join("other.png"), dead, 0, old);
        let not_ours = dir.join(".out.png.tmp-x-0");
        std::fs::write(&not_ours, b"").unwrap();
        let mut removed = remove_stale_temp_files(&target).unwrap();
        removed.sort();
        let mut expected = vec![stale, stale_of_ours];
        expected.sort();
        let left: Vec<bool> = [&live_writer, &recent, &other_target, &not_ours].iter().map(|p| p.exists()).collect();
        assert_eq!(removed, expected);
        assert_eq!(left, [true; 4], "a running writer's, a recent, another target's and a foreign file stay");
    }

    #[test]
    fn a_quitting_process_removes_its_writes_in_flight() {
        let dir = temp_dir("in-flight");
        let path = dir.join("out.bin");
        std::fs::write(&path, b"old").unwrap();
        let mut during = vec![];
        let result = write_atomically(&path, |w| {
            w.write_all(b"partial").unwrap();
            during = file_names(&dir);
            // What the second Ctrl-C does before exiting, limited to this test's directory so
            // that tests writing at the same time keep their files.
            remove_temp_files_in_flight_where(|p| p.starts_with(&dir));
            Ok(())
        });
        let (after, contents) = (file_names(&dir), std::fs::read(&path).unwrap());
        assert_eq!(during.len(), 2, "the temporary file exists while writing: {during:?}");
        assert!(result.is_err(), "the write cannot complete once its file is gone");
        assert_eq!((after, contents), (vec!["out.bin".to_owned()], b"old".to_vec()));
    }

    #[test]
    fn check_writable_creates_nothing_and_refuses_directories_and_missing_ones() {
        let dir = temp_dir("writable");
        check_writable(&dir.join("out.exr")).unwrap();
        let names = file_names(&dir);
        let on_dir = check_writable(&dir).unwrap_err().to_string();
        let missing = check_writable(&dir.join("missing/out.exr")).unwrap_err().to_string();
        assert!(names.is_empty(), "{names:?}");
        assert!(on_dir.ends_with("cannot be written: it is a directory"), "{on_dir}");
        assert!(missing.contains("missing/out.exr: cannot be written: cannot create a file in"), "{missing}");
    }

    #[test]
    fn targets_of_up_to_255_bytes_are_written_and_their_leftovers_found() {
        let dir = temp_dir("atomic-long-name");
        for length in [200, 219, 220, 241, 255] {
            let name = format!("{}.png", "é".repeat((length - 4) / 2) + &"x".repeat((length - 4) % 2));
            assert_eq!(name.len(), length);
            let path = dir.join(&name);
            let temp = temp_path(&path).unwrap();
            assert!(temp.file_name().unwrap().len() <= NAME_MAX, "{length}: {}", temp.display());
            check_writable(&path).unwrap_or_else(|e| panic!("{length}: {e}"));
            write_atomically(&path, |out| out.write_all(b"data").map_err(|e| io_error(&path, e))).unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), b"data");
            // A leftover of a writer that is gone (no process has pid 0 ... u32::MAX here).
            let leftover = temp.with_file_name(
                temp.file_name()
                    .unwrap()
                    .to_string_lossy()
                    .replace(&format!("-{}-", std::process::id()), "-4294967295-"),
            );
            std::fs::write(&leftover, b"x").unwrap();
            let old = SystemTime::now() - 2 * STALE_AFTER;
            File::options().write(true).open(&leftover).unwrap().set_modified(old).unwrap();
            assert_eq!(remove_stale_temp_files(&path).unwrap(), vec![leftover], "{length}");
        }
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
