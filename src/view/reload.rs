//! Notices when a scene's files change on disk, by polling their modification times and sizes:
//! editors that save by writing a new file and renaming it over the old one (most do) are seen as
//! well as those that write in place, which file-system notifications on the old file would miss.

use std::path::PathBuf;
use std::time::{Duration, Instant, SystemTime};

/// How often the files are looked at.
const POLL_EVERY: Duration = Duration::from_millis(250);

/// What a file looked like: `None` while it is missing (mid-save, or deleted).
type Stamp = Option<(SystemTime, u64)>;

fn stamp(path: &PathBuf) -> Stamp {
    let metadata = std::fs::metadata(path).ok()?;
    Some((metadata.modified().ok()?, metadata.len()))
}

pub struct FileWatcher {
    files: Vec<(PathBuf, Stamp)>,
    last_poll: Instant,
    /// A change seen at the last poll, reported once the files have stopped changing for a poll
    /// (a save in several writes is reloaded once, whole).
    changed: bool,
}

impl FileWatcher {
    pub fn new(files: Vec<PathBuf>) -> Self {
        let files = files.into_iter().map(|f| {
            let s = stamp(&f);
            (f, s)
        });
        Self { files: files.collect(), last_poll: Instant::now(), changed: false }
    }

    /// Whether the files changed (and then settled) since the last time this said so.
    pub fn poll(&mut self) -> bool {
        if self.last_poll.elapsed() < POLL_EVERY {
            return false;
        }
        self.last_poll = Instant::now();
        let mut changing = false;
        for (path, seen) in &mut self.files {
            let now = stamp(path);
            if now != *seen {
                *seen = now;
                changing = true;
            }
        }
        let settled = self.changed && !changing;
        self.changed = changing || (self.changed && !settled);
        settled && self.files.iter().all(|(_, s)| s.is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rewritten_file_is_reported_once_it_settles() {
        let dir = crate::test_files::temp_dir("watch");
        let file = dir.join("scene.toml");
        std::fs::write(&file, "a").unwrap();
        let mut watcher = FileWatcher::new(vec![file.clone()]);
        let tick = |w: &mut FileWatcher| {
            w.last_poll = Instant::now() - POLL_EVERY;
            w.poll()
        };
        assert!(!tick(&mut watcher), "nothing changed");
        std::fs::write(&file, "bb").unwrap();
        assert!(!tick(&mut watcher), "changing: wait for it to settle");
        assert!(tick(&mut watcher), "settled: reload");
        assert!(!tick(&mut watcher), "reported once");
        std::fs::remove_file(&file).unwrap();
        assert!(!tick(&mut watcher));
        assert!(!tick(&mut watcher), "a missing file is not reloaded");
        std::fs::write(&file, "ccc").unwrap();
        assert!(!tick(&mut watcher));
        assert!(tick(&mut watcher), "back again: reload");
    }
}
