//! pbrt-v4 scenes: `tokens` splits the text, `parser` reads the directives with pbrt's graphics
//! state into a `Model`, `mapping` (with `materials` and `textures`, whose values are
//! `texture_value`'s) maps that onto caustica's scene file.
//!
//! The `pbrt4` crate was evaluated for the reading and not taken: its errors carry no position,
//! and every error here names the file and line.

mod mapping;
mod materials;
mod params;
mod parser;
mod texture_value;
mod textures;
mod tokens;

use super::Notes;
use crate::input_file::InputFiles;
use crate::scene::format::SceneFile;
use anyhow::Result;
use std::path::{Path, PathBuf};

/// The scene file of the pbrt-v4 scene at `path`, and the folder its relative paths are from.
pub fn import(files: &InputFiles, path: &Path, notes: &mut Notes) -> Result<(SceneFile, PathBuf)> {
    let model = parser::read(files, path)?;
    let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let file = mapping::map(&model, files, &base, path, notes)?;
    Ok((file, base))
}
