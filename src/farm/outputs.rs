//! The files a render writes, the image and its checkpoint, checked before the first sample: a bad
//! path found after the render would lose it. Also clears what killed earlier writes of them left.

use crate::image::{check_output_path, remove_stale_temp_files};
use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// Checks `output` (`-o`) and `checkpoint` (`--checkpoint` or its default) before any work: each can
/// be written (see [`check_output_path`]), the checkpoint is an `.exr` file, and it is not the
/// output unless the output is an `.exr` too (the same partial render, written once).
pub fn check_render_files(output: &Path, checkpoint: &Path) -> Result<()> {
    check_output_path(output)?;
    if same_file(output, checkpoint) && !is_exr(output) {
        bail!(
            "-o {} and --checkpoint {} are the same file: the checkpoint (EXR data) would overwrite the image; give the checkpoint another name",
            output.display(),
            checkpoint.display()
        );
    }
    if !is_exr(checkpoint) {
        bail!(
            "--checkpoint {}: a checkpoint is an OpenEXR file (the raw accumulation and its sample ranges), so its name must end in .exr",
            checkpoint.display()
        );
    }
    check_output_path(checkpoint)?;
    Ok(())
}

/// Whether `a` and `b` name one file: compared with their directories resolved (symbolic links,
/// `.` and `..`, relative paths), and the files too where they exist (a link to the other).
pub fn same_file(a: &Path, b: &Path) -> bool {
    matches!((resolved(a), resolved(b)), (Some(a), Some(b)) if a == b)
}

/// The absolute path of `path` without symbolic links, for a file that need not exist yet in a
/// directory that does; `None` when the directory does not exist either.
fn resolved(path: &Path) -> Option<PathBuf> {
    if let Ok(file) = path.canonicalize() {
        return Some(file);
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    Some(dir.canonicalize().ok()?.join(path.file_name()?))
}

/// Removes the temporary files that killed writes of `targets` left behind (see
/// [`remove_stale_temp_files`]) and returns them. Best effort: a directory that cannot be listed
/// keeps its leftovers, which harm nothing but space.
pub fn remove_leftovers(targets: &[&Path]) -> Vec<PathBuf> {
    targets.iter().flat_map(|t| remove_stale_temp_files(t).unwrap_or_default()).collect()
}

pub fn is_exr(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_files::temp_dir;

    #[test]
    fn same_file_sees_through_relative_and_dotted_paths() {
        let dir = temp_dir("same-file");
        std::fs::create_dir(dir.join("sub")).unwrap();
        assert!(same_file(&dir.join("out.png"), &dir.join("sub/../out.png")));
        assert!(same_file(&dir.join("out.png"), &dir.join("./out.png")));
        assert!(!same_file(&dir.join("out.png"), &dir.join("sub/out.png")));
        assert!(
            !same_file(&dir.join("missing/out.png"), &dir.join("missing/out.png")),
            "no directory: nothing to compare"
        );
        #[cfg(unix)]
        {
            std::fs::write(dir.join("real.exr"), b"x").unwrap();
            std::os::unix::fs::symlink(dir.join("real.exr"), dir.join("link.exr")).unwrap();
            assert!(same_file(&dir.join("real.exr"), &dir.join("link.exr")));
        }
    }

    #[test]
    fn checkpoint_must_be_exr_and_not_the_image() {
        let dir = temp_dir("render-files");
        let (png, exr) = (dir.join("out.png"), dir.join("out.exr"));
        std::fs::create_dir(dir.join("sub")).unwrap();
        let err = check_render_files(&png, &dir.join("sub/../out.png")).unwrap_err().to_string();
        assert!(err.contains("are the same file"), "{err}");
        let err = check_render_files(&png, &dir.join("ck.png")).unwrap_err().to_string();
        assert!(err.contains("--checkpoint") && err.contains("ck.png") && err.contains("must end in .exr"), "{err}");
        check_render_files(&exr, &exr).expect("an EXR output is the checkpoint's own format");
        check_render_files(&png, &dir.join("out.checkpoint.exr")).unwrap();
        let err = check_render_files(&png, &dir.join("missing/ck.exr")).unwrap_err().to_string();
        assert!(err.contains("missing/ck.exr") && err.contains("does not exist"), "{err}");
    }
}
