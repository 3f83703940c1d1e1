//! `bench --suite`: which scenes run, at what size, and which are skipped and why.
//!
//! The suite is the built-in Cornell box and every `*.toml` in the scenes folder, so a scene added
//! there joins it without a code change. Scenes that read the shared data folder
//! (`$CAUSTICA_DATA/...` paths) run only when that folder exists; otherwise they are skipped with
//! the reason, so a clone without the data still gets a table of what it can run.

use super::KernelSetup;
use super::{measure, Measurement};
use crate::gpu::GpuContext;
use crate::input_file::{InputFiles, InputKind};
use crate::render::AovSet;
use crate::scene::{check_film, Scene, DEFAULT_SCENE_TOML};
use anyhow::{bail, Context as _, Result};
use std::path::{Path, PathBuf};

/// Image size and samples per pixel of one suite scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SuiteSize {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
}

/// Sizes given on the command line (`--width`, `--height`, `--spp`), each replacing its own
/// dimension of every scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FilmOverrides {
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub spp: Option<u32>,
}

impl FilmOverrides {
    pub fn applied_to(self, size: SuiteSize) -> SuiteSize {
        SuiteSize {
            width: self.width.unwrap_or(size.width),
            height: self.height.unwrap_or(size.height),
            spp: self.spp.unwrap_or(size.spp),
        }
    }
}

/// Per-scene sizes chosen so that the whole suite (shared data included) takes about two minutes
/// on the 2-core machine with Debian 12's lavapipe (Mesa 22.3), the slowest device it runs on,
/// and each scene renders for about 10 s there and 2 s on Mesa 25: long enough that dispatch
/// overheads and the machine's noise do not dominate. Timings are in docs/benchmarks/history.md (issue 11).
const SIZES: &[(&str, SuiteSize)] = &[
    ("cornell.toml", SuiteSize { width: 160, height: 120, spp: 64 }),
    ("cornell_original.toml", SuiteSize { width: 128, height: 128, spp: 32 }),
    ("sky.toml", SuiteSize { width: 160, height: 120, spp: 192 }),
    ("probe.toml", SuiteSize { width: 160, height: 120, spp: 128 }),
    ("materials.toml", SuiteSize { width: 160, height: 90, spp: 128 }),
    ("bunny_cornell.toml", SuiteSize { width: 128, height: 128, spp: 16 }),
    ("bunny_sky.toml", SuiteSize { width: 128, height: 128, spp: 64 }),
    ("meshes_probe.toml", SuiteSize { width: 128, height: 96, spp: 64 }),
    ("bunny_field.toml", SuiteSize { width: 128, height: 96, spp: 32 }),
    ("helmet.toml", SuiteSize { width: 128, height: 128, spp: 48 }),
    ("smallpt.toml", SuiteSize { width: 128, height: 96, spp: 16 }),
];

/// A scene the table above does not know yet: small, so an unexpectedly slow scene cannot hold the
/// suite up for long.
const UNLISTED: SuiteSize = SuiteSize { width: 96, height: 96, spp: 8 };

/// The suite's scenes folder when `--scenes` is not given, relative to the working directory.
pub const DEFAULT_SCENES: &str = "scenes";

/// The name the built-in scene is listed under (it is `scenes/cornell.toml`, compiled in).
const BUILT_IN: &str = "cornell.toml (built-in)";

pub fn default_size(file_name: &str) -> SuiteSize {
    SIZES.iter().find(|(name, _)| *name == file_name).map_or(UNLISTED, |(_, size)| *size)
}

/// One scene of the suite, or why it does not run.
#[derive(Clone, Debug, PartialEq)]
pub enum SuiteEntry {
    /// `path` is None for the built-in Cornell box.
    Run {
        name: String,
        path: Option<PathBuf>,
        size: SuiteSize,
    },
    Skip {
        name: String,
        reason: String,
    },
}

/// The suite's scenes in the order they run: the built-in Cornell box, then `scenes_dir/*.toml` by
/// name (`cornell.toml` only if it differs from the built-in copy). Scenes naming
/// `$CAUSTICA_DATA/` files are skipped when `data_dir` is not a folder. `scenes_dir` None is the
/// default, `scenes` in the working directory, whose absence is a skip (a run outside the
/// repository); a folder given (`--scenes`) that is not one is an error.
pub fn suite_entries(scenes_dir: Option<&Path>, data_dir: &Path) -> Result<Vec<SuiteEntry>> {
    if let Some(given) = scenes_dir.filter(|dir| !dir.is_dir()) {
        bail!("--scenes {}: not a folder of scene files", given.display());
    }
    entries_of(scenes_dir.unwrap_or(Path::new(DEFAULT_SCENES)), data_dir)
}

/// [`suite_entries`] of `scenes_dir`, skipped when it is not a folder.
fn entries_of(scenes_dir: &Path, data_dir: &Path) -> Result<Vec<SuiteEntry>> {
    let mut entries =
        vec![SuiteEntry::Run { name: BUILT_IN.to_owned(), path: None, size: default_size("cornell.toml") }];
    if !scenes_dir.is_dir() {
        let reason = format!(
            "the scenes folder {} does not exist (run from the repository, or give --scenes DIR)",
            scenes_dir.display()
        );
        entries.push(SuiteEntry::Skip { name: format!("{}/*.toml", scenes_dir.display()), reason });
        return Ok(entries);
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(scenes_dir)
        .with_context(|| format!("reading the scenes folder {}", scenes_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    let data_missing = !data_dir.is_dir();
    for path in files {
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        // Read as any scene file is: regular files only, within the scene size cap.
        let text = InputFiles::anywhere().read_to_string(&path, InputKind::Scene)?;
        if text == DEFAULT_SCENE_TOML {
            continue;
        }
        // The test of the command line decides the same way (tests/cli.rs): the shared data is
        // named only through this prefix.
        if data_missing && text.contains("$CAUSTICA_DATA/") {
            let reason =
                format!("needs the shared data folder, and {} is not one (set CAUSTICA_DATA)", data_dir.display());
            entries.push(SuiteEntry::Skip { name, reason });
            continue;
        }
        entries.push(SuiteEntry::Run { size: default_size(&name), name, path: Some(path) });
    }
    Ok(entries)
}

/// Everything a suite run produced: a row per scene measured, and the scenes that did not run.
#[derive(Default)]
pub struct SuiteOutcome {
    pub rows: Vec<Measurement>,
    /// Scenes left out by design (no shared data), with the reason.
    pub skipped: Vec<(String, String)>,
    /// Scenes that should have run but failed to load or render, with the error.
    pub failed: Vec<(String, String)>,
}

/// Measures every `Run` entry on `ctx`, each at its size unless `overrides` replaces a dimension.
/// `load` reads a scene file (`--confine` decides how). Skips and failures are said on stderr as
/// they happen, so a long suite shows at once what it leaves out; a failure does not stop the
/// others.
pub fn run_suite(
    ctx: &GpuContext,
    entries: &[SuiteEntry],
    overrides: FilmOverrides,
    aovs: AovSet,
    kernel: &KernelSetup,
    load: impl Fn(&Path) -> Result<Scene>,
) -> SuiteOutcome {
    let mut outcome = SuiteOutcome::default();
    for entry in entries {
        let (name, path, size) = match entry {
            SuiteEntry::Skip { name, reason } => {
                log::warn!("caustica: SKIPPED {name}: {reason}");
                outcome.skipped.push((name.clone(), reason.clone()));
                continue;
            }
            SuiteEntry::Run { name, path, size } => (name, path, size),
        };
        let film = overrides.applied_to(*size);
        log::info!("caustica: bench {name} ({}x{}, {} spp)", film.width, film.height, film.spp);
        let measured = (|| {
            let mut scene = match path {
                Some(p) => load(p)?,
                None => Scene::default_scene(),
            };
            scene.name = name.clone();
            (scene.film.width, scene.film.height, scene.film.spp) = (film.width, film.height, film.spp);
            check_film(&scene.film).context("command-line film settings")?;
            measure(ctx, &scene, aovs, kernel)
        })();
        match measured {
            Ok(row) => outcome.rows.push(row),
            Err(e) => {
                let error = format!("{e:#}");
                log::warn!("caustica: FAILED {name}: {error}");
                outcome.failed.push((name.clone(), error));
            }
        }
    }
    outcome
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(entries: &[SuiteEntry]) -> Vec<(&str, bool)> {
        entries
            .iter()
            .map(|e| match e {
                SuiteEntry::Run { name, .. } => (name.as_str(), true),
                SuiteEntry::Skip { name, .. } => (name.as_str(), false),
            })
            .collect()
    }

    #[test]
    fn shared_data_scenes_are_skipped_without_the_data_and_run_with_it() {
        let dir = crate::test_files::temp_dir("suite");
        let (scenes, data) = (dir.join("scenes"), dir.join("data"));
        std::fs::create_dir_all(&scenes).unwrap();
        std::fs::write(scenes.join("cornell.toml"), DEFAULT_SCENE_TOML).unwrap();
        std::fs::write(scenes.join("b_local.toml"), "# no shared data\n").unwrap();
        std::fs::write(scenes.join("a_shared.toml"), "file = \"$CAUSTICA_DATA/meshes/x.ply\"\n").unwrap();
        std::fs::write(scenes.join("notes.txt"), "not a scene").unwrap();

        let without = suite_entries(Some(&scenes), &data).unwrap();
        assert_eq!(
            names(&without),
            [(BUILT_IN, true), ("a_shared.toml", false), ("b_local.toml", true)],
            "the built-in box once, files by name"
        );
        let SuiteEntry::Skip { reason, .. } = &without[1] else { unreachable!() };
        assert!(reason.contains("shared data") && reason.contains(&data.display().to_string()), "{reason}");

        std::fs::create_dir_all(&data).unwrap();
        let with = suite_entries(Some(&scenes), &data).unwrap();
        assert_eq!(names(&with), [(BUILT_IN, true), ("a_shared.toml", true), ("b_local.toml", true)]);
    }

    #[test]
    fn a_missing_default_scenes_folder_leaves_the_built_in_box_and_says_why() {
        let entries = entries_of(Path::new("/nonexistent/scenes"), Path::new("/nonexistent/data")).unwrap();
        assert_eq!(names(&entries), [(BUILT_IN, true), ("/nonexistent/scenes/*.toml", false)]);
    }

    #[test]
    fn a_scenes_folder_given_that_is_not_one_is_an_error() {
        let error = suite_entries(Some(Path::new("/nonexistent/scenes")), Path::new("/nonexistent/data")).unwrap_err();
        assert_eq!(error.to_string(), "--scenes /nonexistent/scenes: not a folder of scene files");
    }

    #[test]
    fn each_override_replaces_only_its_own_dimension() {
        let size = SuiteSize { width: 160, height: 120, spp: 32 };
        assert_eq!(FilmOverrides::default().applied_to(size), size);
        let wider = FilmOverrides { width: Some(8), ..Default::default() };
        assert_eq!(wider.applied_to(size), SuiteSize { width: 8, height: 120, spp: 32 });
    }

    #[test]
    fn unlisted_scenes_get_the_small_default() {
        assert_eq!(default_size("cornell.toml"), SIZES[0].1);
        assert_eq!(default_size("new_scene.toml"), UNLISTED);
    }
}
