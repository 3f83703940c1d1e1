//! Scenes written for other renderers: Mitsuba 3 XML (`mitsuba_xml` reads the document,
//! `mitsuba` maps it) and pbrt-v4 (`pbrt`), onto caustica's own scene file model, so that a rendered import and the
//! TOML `caustica convert` writes from it are the same scene by construction (`convert`).
//!
//! Faithful where caustica's model allows and loud where it does not: an element or parameter
//! caustica cannot render is an error naming the file, line and element; a documented
//! approximation is a warning, said once per kind.

mod convert;
mod mitsuba;
mod mitsuba_media;
mod mitsuba_xml;
mod pbrt;
mod scene_parts;
mod spectrum;
mod transform;

use super::format::SceneFile;
use super::{build, Scene};
use crate::input_file::InputFiles;
use anyhow::{bail, Context as _, Result};
use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};
use std::rc::Rc;

/// The most shapes an imported scene may get (spheres, quads, triangles, mesh placements, each
/// instance's copies counted): a small file that instances a large group many times over could
/// otherwise ask for any amount of memory.
const MAX_SHAPES: usize = 4_000_000;

/// The most characters of a token a message quotes.
const SHOWN_CHARS: usize = 80;

/// `text` (a token of the file) as a message quotes it: at most [`SHOWN_CHARS`] characters, then
/// `…` and how many more there were, with control characters escaped, so that a hostile token
/// can neither flood the terminal nor write to it.
pub(super) fn shown(text: &str) -> String {
    let escaped = |c: char| -> String {
        match c.is_control() {
            true => c.escape_default().collect(),
            false => c.to_string(),
        }
    };
    let length = text.chars().count();
    let kept: String = text.chars().take(SHOWN_CHARS).map(escaped).collect();
    match length > SHOWN_CHARS {
        true => format!("{kept}… ({} more characters)", length - SHOWN_CHARS),
        false => kept,
    }
}

/// Where something was written: file and line (1-based).
#[derive(Clone, Debug)]
pub struct Location {
    pub file: Rc<str>,
    pub line: u32,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}:{}", self.file, self.line)
    }
}

/// Is `path` a scene of another renderer that [`import`] reads?
pub fn is_foreign_scene(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("xml") || e.eq_ignore_ascii_case("pbrt"))
}

/// A foreign scene in caustica's model, with the approximations made on the way.
pub struct Imported {
    file: SceneFile,
    /// Relative paths in `file` (meshes, maps) are relative to this folder.
    base: PathBuf,
    name: String,
    /// One line per kind of approximation made.
    pub warnings: Vec<String>,
}

impl Imported {
    /// The validated scene, reading its meshes and maps through `files`.
    pub fn into_scene(self, files: &InputFiles) -> Result<Scene> {
        build(self.file, &self.name, &self.base, files).with_context(|| self.name.clone())
    }

    /// The equivalent caustica TOML, to be written into `output_folder`: paths are kept relative
    /// when that is the scene's own folder and made absolute otherwise; meshes written in the
    /// scene are written into `output_folder` as PLY files, which the TOML lists.
    pub fn to_toml(&self, output_folder: &Path) -> Result<String> {
        convert::to_toml(&self.file, &self.base, output_folder, &self.name)
    }
}

/// Reads a foreign scene (see [`is_foreign_scene`]); `defines` are `-D name=value` parameters
/// (Mitsuba's `<default>`s; pbrt has none).
pub fn import(files: &InputFiles, path: &Path, defines: &[(String, String)]) -> Result<Imported> {
    let mut notes = Notes::default();
    let pbrt = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("pbrt"));
    let (file, base) = match (pbrt, defines.first()) {
        (true, Some((name, _))) => {
            bail!("-D {name}=...: parameters are for Mitsuba XML scenes, not {}", path.display())
        }
        (true, None) => pbrt::import(files, path, &mut notes)?,
        (false, _) => mitsuba::import(files, path, defines, &mut notes)?,
    };
    Ok(Imported { file, base, name: path.display().to_string(), warnings: notes.warnings })
}

/// Warnings, each kind said once.
#[derive(Default)]
pub struct Notes {
    kinds: BTreeSet<&'static str>,
    warnings: Vec<String>,
}

impl Notes {
    /// Records `message` unless a warning of the same `kind` was recorded already.
    pub fn warn_once(&mut self, kind: &'static str, message: impl FnOnce() -> String) {
        if self.kinds.insert(kind) {
            self.warnings.push(message());
        }
    }
}
