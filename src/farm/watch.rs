//! `caustica merge --watch DIR`: which of the partial renders in a folder a preview adds up while a
//! farm fills it. A task leaves a checkpoint while it runs and a part when it ends (both holding
//! its range from the same first sample, the one with more samples the newer), a preempted task a
//! part and a checkpoint that a later run overtakes; the preview takes, of the files that overlap,
//! those with the most samples, so it never counts a sample twice.

use super::partial::PartialRender;
use std::path::{Path, PathBuf};

/// A file of the folder that the preview leaves out, and why (said once per file and version).
#[derive(Clone, Debug, PartialEq)]
pub struct Skipped {
    pub path: PathBuf,
    pub reason: String,
}

/// What [`pick`] found in the folder.
#[derive(Debug, Default)]
pub struct Picked {
    /// The files to merge, with what they hold: no two share a sample.
    pub chosen: Vec<(PathBuf, PartialRender)>,
    pub skipped: Vec<Skipped>,
}

/// Reads the `.exr` files directly in `dir` (not `leave_out`, the preview itself, nor the
/// temporary files of writes in flight), and picks those to merge: of files that share samples,
/// the one holding more; files of another render than the largest one (scene, seed, size, AOVs)
/// and files that do not read are skipped, with the reason.
pub fn pick(dir: &Path, leave_out: &Path) -> std::io::Result<Picked> {
    let mut skipped = vec![];
    let mut found = vec![];
    let mut names: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) && p.is_file())
        .filter(|p| !super::outputs::same_file(p, leave_out))
        .collect();
    names.sort();
    for path in names {
        match PartialRender::read(&path) {
            Ok(partial) => found.push((path, partial)),
            Err(e) => skipped.push(Skipped { path, reason: format!("{e:#}") }),
        }
    }
    // Largest first, so that of overlapping files the one with more samples is taken, and the
    // render that the others must match is the one most of the samples belong to.
    found.sort_by(|(pa, a), (pb, b)| b.samples().cmp(&a.samples()).then(pa.cmp(pb)));
    let mut chosen: Vec<(PathBuf, PartialRender)> = vec![];
    for (path, partial) in found {
        if let Some((first_path, first)) = chosen.first() {
            if let Err(e) = first.check_same_render(&partial) {
                let reason = format!("{e:#}, unlike {}", first_path.display());
                skipped.push(Skipped { path, reason });
                continue;
            }
        }
        let overlaps = chosen.iter().any(|(_, c)| overlap(&c.ranges, &partial.ranges));
        if !overlaps {
            chosen.push((path, partial));
        }
    }
    Ok(Picked { chosen, skipped })
}

/// Whether two sorted lists of half-open ranges share an index.
fn overlap(a: &[std::ops::Range<u32>], b: &[std::ops::Range<u32>]) -> bool {
    a.iter().any(|x| b.iter().any(|y| x.start < y.end && y.start < x.end))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_overlap_when_they_share_an_index() {
        assert!(overlap(&[0..4], &[3..5]));
        assert!(!overlap(&[0..4], &[4..8]));
        assert!(overlap(&[0..2, 6..8], &[7..9]));
        assert!(!overlap(&[0..2, 6..8], &[2..6]));
    }
}
