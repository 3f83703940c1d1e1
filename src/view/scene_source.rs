//! Where the viewer's scene comes from (a file, or the built-in Cornell box), loading it as
//! `render` does, and the files it read, which the viewer watches for changes.

use crate::input_file::InputFiles;
use crate::scene::{confinement, Scene};
use anyhow::Result;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug)]
pub struct SceneSource {
    /// `None`: the built-in Cornell box.
    pub path: Option<PathBuf>,
    /// Read only files inside the scene's folder and the shared data folder (`--confine`).
    pub confine: bool,
    /// `-D NAME=VALUE`: parameters of a Mitsuba XML scene.
    pub defines: Vec<(String, String)>,
}

/// A scene with every file it was read from: the scene file, meshes, textures, environment maps.
pub struct LoadedScene {
    pub scene: Scene,
    pub files: Vec<PathBuf>,
}

impl SceneSource {
    pub fn load(&self) -> Result<LoadedScene> {
        let Some(path) = &self.path else {
            anyhow::ensure!(
                self.defines.is_empty(),
                "-D sets parameters of a Mitsuba XML scene; the built-in scene has none"
            );
            return Ok(LoadedScene { scene: Scene::default_scene(), files: vec![] });
        };
        let files = if self.confine { confinement(path) } else { InputFiles::anywhere() }.recording();
        let scene = Scene::load_with(&files, path, &self.defines)?;
        Ok(LoadedScene { scene, files: files.opened() })
    }

    /// The scene's name for titles: its file name, or "Cornell box".
    pub fn title(&self) -> String {
        match &self.path {
            Some(p) => p.file_name().map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into_owned()),
            None => "Cornell box".to_owned(),
        }
    }

    /// A source for another file, with the same confinement and parameters.
    pub fn with_path(&self, path: &Path) -> Self {
        Self { path: Some(path.to_owned()), ..self.clone() }
    }
}
