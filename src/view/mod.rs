//! `caustica view`: an interactive, progressive viewer. A window (winit) shows the image as the
//! kernel accumulates it, tonemapped on the GPU exactly as PNG output is, with camera moves,
//! display settings, an overlay, and reloads when the scene's files change.
//!
//! - [`window`]: the window and its event loop;
//! - [`app`]: the viewer's state, input handling and frames;
//! - [`camera_control`]: orbit, pan, dolly, fly and framing on the scene's camera;
//! - [`display`]: the GPU picture (shaders/display.comp) of a renderer's accumulation;
//! - [`overlay`]: the egui overlay and the key list;
//! - [`scene_source`], [`reload`]: where the scene comes from and noticing it changed.
//!
//! The Vulkan side (swapchain, frames, the overlay's render pass) is in `crate::gpu`.

mod app;
mod camera_control;
mod display;
mod overlay;
mod reload;
mod scene_source;
mod window;

pub use overlay::KEYS;
pub use scene_source::SceneSource;
pub use window::require_display;

use crate::gpu::{ContextOptions, GpuContext};
use crate::image::Tonemap;
use crate::scene::check_film;
use anyhow::{Context as _, Result};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

pub struct ViewOptions {
    pub source: SceneSource,
    /// Samples per pixel to stop at (default: the scene's film.spp).
    pub spp: Option<u32>,
    /// Window size in pixels (default: the scene's film size).
    pub width: Option<u32>,
    pub height: Option<u32>,
    pub seed: u32,
    pub exposure: f32,
    pub tonemap: Tonemap,
    /// Render to the sample limit, save what the window shows there, and quit.
    pub screenshot: Option<PathBuf>,
    pub context: ContextOptions,
    /// Set by Ctrl-C (SIGINT) or SIGTERM: the viewer ends cleanly.
    pub stop: &'static AtomicBool,
}

/// Opens the window and runs the viewer until it is closed (or the screenshot is written).
pub fn run(options: ViewOptions) -> Result<()> {
    // Bad input is refused before a window opens.
    let mut loaded = options.source.load()?;
    let film = &mut loaded.scene.film;
    film.width = options.width.unwrap_or(film.width);
    film.height = options.height.unwrap_or(film.height);
    film.spp = options.spp.unwrap_or(film.spp);
    check_film(film).context("command-line film settings")?;
    if let Some(path) = &options.screenshot {
        let png = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("png"));
        anyhow::ensure!(
            png,
            "--screenshot {}: a screenshot is what the window shows, 8-bit sRGB: give it a .png name",
            path.display()
        );
        crate::image::check_output_path(path)?;
    }
    require_display()?;
    let (mut event_loop, window) =
        window::open(&format!("caustica - {}", options.source.title()), [film.width, film.height])?;
    let ctx = GpuContext::for_window(&options.context, &window)?;
    let mut viewer = app::Viewer::new(&ctx, &window, options, loaded)?;
    window::run(&mut event_loop, &mut viewer)
}
