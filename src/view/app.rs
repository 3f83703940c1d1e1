//! The viewer's state and its frame: input to camera moves and settings, a bounded slice of kernel
//! work, the picture and overlay presented, the scene reloaded when its files change.

use super::camera_control;
use super::display::{display_spirv, Display, DisplaySettings, View};
use super::overlay::{self, Status};
use super::reload::FileWatcher;
use super::scene_source::{LoadedScene, SceneSource};
use super::ViewOptions;
use crate::farm;
use crate::gpu::{Frame, GpuContext, OverlayDraw, Presented, Presenter};
use crate::image::{write_image_with, OutputOptions, PngDepth, Tonemap};
use crate::render::{AovSet, Renderer};
use crate::scene::{camera_toml, Camera, Scene};
use anyhow::{Context as _, Result};
use glam::Vec3;
use std::collections::{HashSet, VecDeque};
use std::io::Write as _;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use winit::dpi::PhysicalPosition;
use winit::event::{ElementState, KeyEvent, MouseButton, MouseScrollDelta, WindowEvent};
use winit::keyboard::{Key, KeyCode, NamedKey, PhysicalKey};
use winit::window::Window;

/// Wall time of one kernel dispatch in the viewer: short enough that, with the picture and the
/// overlay, a frame stays well under 1/30 s (`render` aims at 0.2 s, see renderer.rs).
const DISPATCH_TARGET_S: f64 = 1.0 / 60.0;
/// Exposure step of the + and - keys, in stops.
const EXPOSURE_STEP: f32 = 0.5;
/// Radians of orbit or look per pixel of drag, as a fraction of pi per window height.
const TURN_PER_HEIGHT: f32 = std::f32::consts::PI;
/// Flying speed: the scene's size per second; shift multiplies it.
const FLY_SCENES_PER_SECOND: f32 = 0.25;
const FLY_SHIFT_FACTOR: f32 = 4.0;
/// A key tap moves at least this long's worth, so a press and release seen in one frame count.
const FLY_TAP_S: f32 = 1.0 / 30.0;
/// The window's size must hold this long before the image is re-created at it.
const RESIZE_SETTLE: Duration = Duration::from_millis(200);
/// How often the title and, while idle, the overlay are refreshed.
const REFRESH_EVERY: Duration = Duration::from_millis(250);
/// Event wait while there is nothing to render.
const IDLE_WAIT: Duration = Duration::from_millis(33);

/// A renderer of the current scene, camera and image size, with the display bound to it.
struct Session<'a> {
    renderer: Renderer<'a>,
    display: Display,
}

/// Pixel samples added over the last few seconds, for samples per second.
#[derive(Default)]
struct Speed {
    /// (when, pixel samples added in all by then)
    history: VecDeque<(Instant, f64)>,
    total: f64,
}

/// Span the rate is measured over: several passes of a light scene at once.
const SPEED_WINDOW: Duration = Duration::from_secs(3);

impl Speed {
    fn add(&mut self, pixel_samples: f64) {
        let now = Instant::now();
        if self.history.is_empty() {
            self.history.push_back((now, self.total));
        }
        self.total += pixel_samples;
        self.history.push_back((now, self.total));
        // The oldest entry kept is the last one older than the window, so the span covers it.
        while self.history.len() > 2 && now - self.history[1].0 > SPEED_WINDOW {
            self.history.pop_front();
        }
    }

    /// Up to now, so that the rate falls to 0 once nothing is added (a heavy scene's pass in
    /// progress, or accumulation done).
    fn per_second(&self) -> f64 {
        match self.history.front() {
            Some(&(since, total)) if since.elapsed() > Duration::ZERO => {
                (self.total - total) / since.elapsed().as_secs_f64()
            }
            _ => 0.0,
        }
    }

    fn restart(&mut self) {
        self.history.clear();
    }
}

/// Mouse buttons held down for a drag that began on the picture (not on the overlay).
#[derive(Default)]
struct Drag {
    left: bool,
    middle: bool,
    right: bool,
    cursor: Option<PhysicalPosition<f64>>,
}

pub struct Viewer<'a> {
    ctx: &'a GpuContext,
    window: &'a Window,
    stop: &'static AtomicBool,
    presenter: Option<Presenter>,
    display_spirv: Vec<u32>,
    session: Option<Session<'a>>,
    source: SceneSource,
    scene: Scene,
    watcher: FileWatcher,
    /// The camera shown (the scene's, as moved since).
    camera: Camera,
    camera_moved: bool,
    seed: u32,
    /// `--spp`, which wins over each scene's film.spp.
    spp_override: Option<u32>,
    exposure: f32,
    tonemap: Tonemap,
    view: View,
    /// Whether renderers keep AOV sums (from the first switch to an AOV view on).
    aovs: bool,
    screenshot: Option<PathBuf>,
    egui: egui::Context,
    egui_input: egui_winit::State,
    drag: Drag,
    shift: bool,
    fly_keys: HashSet<KeyCode>,
    /// Keys pressed since the last frame, each moving at least a tap's worth.
    fly_taps: Vec<KeyCode>,
    /// When the window's size last changed, until the image follows it.
    resized_at: Option<Instant>,
    occluded: bool,
    pending_open: Option<PathBuf>,
    reload_requested: bool,
    quit: bool,
    redraw: bool,
    last_frame: Instant,
    frame_seconds: f64,
    last_refresh: Instant,
    speed: Speed,
    problem: Option<String>,
}

impl<'a> Viewer<'a> {
    pub fn new(ctx: &'a GpuContext, window: &'a Window, options: ViewOptions, loaded: LoadedScene) -> Result<Self> {
        let size = window.inner_size();
        let presenter = Presenter::new(ctx, [size.width, size.height])?;
        let egui = egui::Context::default();
        let egui_input = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            window,
            Some(window.scale_factor() as f32),
            None,
            None,
        );
        let mut viewer = Self {
            ctx,
            window,
            stop: options.stop,
            presenter: Some(presenter),
            display_spirv: display_spirv()?,
            session: None,
            camera: loaded.scene.camera.clone(),
            scene: loaded.scene,
            watcher: FileWatcher::new(loaded.files),
            source: options.source,
            camera_moved: false,
            seed: options.seed,
            spp_override: options.spp,
            exposure: options.exposure,
            tonemap: options.tonemap,
            view: View::Beauty,
            aovs: false,
            screenshot: options.screenshot,
            egui,
            egui_input,
            drag: Drag::default(),
            shift: false,
            fly_keys: HashSet::new(),
            fly_taps: vec![],
            resized_at: None,
            occluded: false,
            pending_open: None,
            reload_requested: false,
            quit: false,
            redraw: true,
            last_frame: Instant::now(),
            frame_seconds: 0.0,
            last_refresh: Instant::now(),
            speed: Speed::default(),
            problem: None,
        };
        viewer.start_session()?;
        Ok(viewer)
    }

    /// Samples per pixel at which accumulation stops.
    fn limit(&self) -> Option<u32> {
        Some(self.spp_override.unwrap_or(self.scene.film.spp))
    }

    fn done(&self) -> bool {
        let Some(session) = &self.session else { return true };
        let r = &session.renderer;
        r.pass_target().is_none() && (self.limit().is_some_and(|l| r.samples_done >= l) || r.samples_left() == 0)
    }

    fn paused(&self) -> bool {
        self.occluded || self.window.is_minimized() == Some(true)
    }

    /// How long the event loop may wait for events before the next frame.
    pub fn wait_time(&self) -> Duration {
        let work = self.redraw || self.camera_moved || !self.fly_keys.is_empty() || !self.done();
        // While paused nothing is rendered or drawn, so a redraw stays pending until the window is
        // back: waiting for it would spin the loop (thousands of empty frames a second, a core busy).
        if self.quit || (work && !self.paused()) {
            Duration::ZERO
        } else {
            IDLE_WAIT
        }
    }

    /// (Re)creates the renderer for the scene, camera and window size now: a reload, a resize, a
    /// switch to an AOV view. Accumulation starts over.
    fn start_session(&mut self) -> Result<()> {
        if let Some(old) = self.session.take() {
            self.ctx.wait_idle();
            old.display.destroy(self.ctx);
        }
        let size = self.window.inner_size();
        let mut scene = self.scene.clone();
        scene.camera = self.camera.clone();
        scene.film.width = size.width.clamp(1, 16384);
        scene.film.height = size.height.clamp(1, 16384);
        let aovs = if self.aovs {
            AovSet { albedo: true, normal: true, depth: true, samples: false }
        } else {
            AovSet::default()
        };
        let mut renderer = Renderer::with_aovs(self.ctx, &scene, self.seed, aovs)?;
        renderer.set_dispatch_target(DISPATCH_TARGET_S);
        let display = Display::new(self.ctx, &self.display_spirv, &renderer)?;
        self.session = Some(Session { renderer, display });
        self.speed.restart();
        self.camera_moved = false;
        self.redraw = true;
        Ok(())
    }

    pub fn on_event(&mut self, event: WindowEvent) {
        let consumed = self.egui_input.on_window_event(self.window, &event).consumed;
        self.redraw = true;
        match event {
            // Destroyed: by another client; the window can no longer be asked anything.
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.quit = true,
            WindowEvent::Resized(size) => {
                if let Some(p) = &mut self.presenter {
                    p.resize([size.width, size.height]);
                }
                self.resized_at = Some(Instant::now());
            }
            WindowEvent::Occluded(occluded) => self.occluded = occluded,
            WindowEvent::DroppedFile(path) => self.pending_open = Some(path),
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            WindowEvent::KeyboardInput { event, .. } if !consumed => self.on_key(&event),
            WindowEvent::MouseInput { state, button, .. } => {
                let pressed = state == ElementState::Pressed;
                // A drag begins only on the picture; it ends wherever the button is released.
                if pressed && consumed {
                    return;
                }
                match button {
                    MouseButton::Left => self.drag.left = pressed,
                    MouseButton::Middle => self.drag.middle = pressed,
                    MouseButton::Right => self.drag.right = pressed,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.on_cursor(position),
            WindowEvent::CursorLeft { .. } => self.drag.cursor = None,
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 50.0,
                };
                camera_control::dolly(&mut self.camera, steps);
                self.camera_moved = true;
            }
            _ => {}
        }
    }

    fn on_cursor(&mut self, position: PhysicalPosition<f64>) {
        let previous = self.drag.cursor.replace(position);
        let Some(previous) = previous else { return };
        let (dx, dy) = ((position.x - previous.x) as f32, (position.y - previous.y) as f32);
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        let height = self.window.inner_size().height.max(1) as f32;
        let turn = TURN_PER_HEIGHT / height;
        let d = &self.drag;
        if d.middle || (d.left && self.shift) {
            camera_control::pan(&mut self.camera, dx, dy, height);
        } else if d.left {
            // The scene follows the cursor: dragging right turns the camera left around the pivot,
            // dragging down raises it.
            camera_control::orbit(&mut self.camera, -dx * turn, dy * turn);
        } else if d.right {
            camera_control::look(&mut self.camera, -dx * turn, -dy * turn);
        } else {
            return;
        }
        self.camera_moved = true;
    }

    fn on_key(&mut self, event: &KeyEvent) {
        let pressed = event.state == ElementState::Pressed;
        if let PhysicalKey::Code(code) = event.physical_key {
            if is_fly_key(code) {
                if !pressed {
                    self.fly_keys.remove(&code);
                } else if self.drag.right {
                    if self.fly_keys.insert(code) {
                        self.fly_taps.push(code);
                    }
                    return;
                }
            }
        }
        if !pressed {
            return;
        }
        match &event.logical_key {
            Key::Named(NamedKey::Escape) => self.quit = true,
            Key::Character(c) => {
                let c = c.to_lowercase();
                if event.repeat && !matches!(c.as_str(), "+" | "=" | "-" | "_") {
                    return;
                }
                match c.as_str() {
                    "+" | "=" => self.exposure += EXPOSURE_STEP,
                    "-" | "_" => self.exposure -= EXPOSURE_STEP,
                    "t" => {
                        self.tonemap = match self.tonemap {
                            Tonemap::Clamp => Tonemap::Reinhard,
                            Tonemap::Reinhard => Tonemap::AcesFilmic,
                            Tonemap::AcesFilmic => Tonemap::Clamp,
                        }
                    }
                    "1" => self.set_view(View::Beauty),
                    "2" => self.set_view(View::Albedo),
                    "3" => self.set_view(View::Normal),
                    "4" => self.set_view(View::Depth),
                    "p" => {
                        // Fly keys tapped since the last frame move the camera first: the camera
                        // printed is where the input so far put it, however slow the frames are
                        // (held keys move with the next frame's time, as before).
                        self.fly(0.0);
                        self.print_camera();
                    }
                    "s" => {
                        if let Err(e) = self.save() {
                            self.report(format!("cannot save the image: {e:#}"));
                        }
                    }
                    "r" => self.reload_requested = true,
                    "f" => {
                        if let Some(bounds) = self.scene.bounds() {
                            let size = self.window.inner_size();
                            camera_control::frame_bounds(
                                &mut self.camera,
                                bounds,
                                size.width as f32 / size.height.max(1) as f32,
                            );
                            self.camera_moved = true;
                        }
                    }
                    _ => {}
                }
            }
            _ => {}
        }
    }

    fn set_view(&mut self, view: View) {
        self.view = view;
        if view.needs_aovs() && !self.aovs {
            // The kernel keeps AOV sums only when asked: a new renderer, accumulation from 0.
            self.aovs = true;
            if let Err(e) = self.start_session() {
                self.report(format!("cannot show the {}: {e:#}", view.name()));
                self.view = View::Beauty;
            }
        }
    }

    /// Says it on standard error and in the overlay.
    fn report(&mut self, problem: String) {
        log::warn!("caustica view: {problem}");
        self.problem = Some(problem);
    }

    /// Key P: the camera as a `[camera]` table of the scene format, on standard output.
    fn print_camera(&self) {
        let (samples, (w, h)) =
            self.session.as_ref().map_or((0, (0, 0)), |s| (s.renderer.samples_done, s.renderer.size()));
        let mut out = std::io::stdout().lock();
        let _ = write!(
            out,
            "# {} ({w}x{h}) at {samples} spp: paste into the scene file\n{}\n",
            self.source.title(),
            camera_toml(&self.camera)
        );
        let _ = out.flush();
    }

    /// Key S: the image as `render` writes it: a PNG with the current exposure and tonemapper,
    /// and an EXR with the accumulation (resumable with `render --resume`, mergeable).
    fn save(&mut self) -> Result<()> {
        let Some(session) = &mut self.session else { return Ok(()) };
        let renderer = &mut session.renderer;
        renderer.finish_pass()?;
        renderer.refresh_scene_hash()?;
        let Some(partial) = farm::snapshot(renderer)? else {
            log::info!("caustica view: nothing to save yet (no samples)");
            return Ok(());
        };
        let stem = self
            .source
            .path
            .as_ref()
            .and_then(|p| p.file_stem())
            .map_or_else(|| "cornell".to_owned(), |s| s.to_string_lossy().into_owned());
        let (png, exr) = (1..)
            .map(|n| (PathBuf::from(format!("{stem}-view-{n}.png")), PathBuf::from(format!("{stem}-view-{n}.exr"))))
            .find(|(png, exr)| !png.exists() && !exr.exists())
            .expect("some number is free");
        let options = OutputOptions { exposure: self.exposure, tonemap: self.tonemap, png_depth: PngDepth::Eight };
        write_image_with(&png, &partial.image(), &options)?;
        partial.write(&exr)?;
        log::info!("caustica view: saved {} and {} ({} spp)", png.display(), exr.display(), partial.samples());
        Ok(())
    }

    /// Reads the scene again, keeping the camera (R, or its files changed on disk).
    fn reload(&mut self, why: &str) {
        match self.source.load() {
            Ok(loaded) => {
                self.scene = loaded.scene;
                self.watcher = FileWatcher::new(loaded.files);
                match self.start_session() {
                    Ok(()) => {
                        self.problem = None;
                        log::info!("caustica view: reloaded {} ({why})", self.source.title());
                    }
                    Err(e) => self.report(format!("cannot render the reloaded scene: {e:#}")),
                }
            }
            Err(e) => self.report(format!("cannot reload: {e:#}")),
        }
    }

    /// A file dropped on the window: its scene, with its own camera.
    fn open(&mut self, path: PathBuf) {
        let source = self.source.with_path(&path);
        match source.load() {
            Ok(loaded) => {
                self.source = source;
                self.camera = loaded.scene.camera.clone();
                self.scene = loaded.scene;
                self.watcher = FileWatcher::new(loaded.files);
                match self.start_session() {
                    Ok(()) => {
                        self.problem = None;
                        log::info!("caustica view: opened {}", path.display());
                    }
                    Err(e) => self.report(format!("cannot render {}: {e:#}", path.display())),
                }
            }
            Err(e) => self.report(format!("cannot open {}: {e:#}", path.display())),
        }
    }

    /// Moves for the fly keys held (and tapped) since the last frame, `dt` seconds ago.
    fn fly(&mut self, dt: f32) {
        if self.fly_keys.is_empty() && self.fly_taps.is_empty() {
            return;
        }
        let size = self.scene.bounds().map_or(1.0, |(lo, hi)| (hi - lo).length().max(1e-3));
        let speed = size * FLY_SCENES_PER_SECOND * if self.shift { FLY_SHIFT_FACTOR } else { 1.0 };
        let mut along = Vec3::ZERO;
        let taps = std::mem::take(&mut self.fly_taps);
        let codes: HashSet<KeyCode> = self.fly_keys.iter().chain(&taps).copied().collect();
        for code in codes {
            // A key held since an earlier frame moves dt; one pressed since the last, at least a tap.
            let seconds = if taps.contains(&code) { dt.max(FLY_TAP_S) } else { dt };
            along += fly_direction(code) * seconds * speed;
        }
        if along != Vec3::ZERO {
            camera_control::fly(&mut self.camera, along);
            self.camera_moved = true;
        }
    }

    /// One frame: follow the window, apply camera changes, add a dispatch of samples, present.
    /// Returns false when the viewer is done.
    pub fn frame(&mut self) -> Result<bool> {
        if self.quit || self.stop.load(Ordering::SeqCst) {
            return Ok(false);
        }
        let now = Instant::now();
        let dt = (now - self.last_frame).as_secs_f32().min(0.1);
        self.frame_seconds = 0.9 * self.frame_seconds + 0.1 * (now - self.last_frame).as_secs_f64();
        self.last_frame = now;
        self.fly(dt);
        if let Some(path) = self.pending_open.take() {
            self.open(path);
        }
        if std::mem::take(&mut self.reload_requested) {
            self.reload("R pressed");
        } else if self.watcher.poll() {
            self.reload("its files changed on disk");
        }
        self.follow_window_size()?;
        let Some(session) = &mut self.session else { return Ok(!self.quit) };
        if std::mem::take(&mut self.camera_moved) {
            session.renderer.set_camera(&self.camera)?;
            self.speed.restart();
            self.redraw = true;
        }
        let paused = self.paused();
        if !paused && !self.done() {
            let limit = self.limit().unwrap_or(u32::MAX);
            let session = self.session.as_mut().expect("checked above");
            let before = session.renderer.samples_done as f64
                * session.renderer.size().0 as f64
                * session.renderer.size().1 as f64;
            session.renderer.render_step(limit)?;
            let r = &session.renderer;
            let (w, h) = r.size();
            // Samples of a completed pass; a band's share is counted when its pass completes.
            let after = r.samples_done as f64 * w as f64 * h as f64;
            self.speed.add((after - before).max(0.0));
            self.redraw = true;
        }
        let refresh = self.last_refresh.elapsed() >= REFRESH_EVERY;
        if refresh {
            self.last_refresh = Instant::now();
            self.update_title();
        }
        let screenshot_now = self.screenshot.is_some() && self.done();
        if !paused && (self.redraw || refresh || screenshot_now) {
            self.redraw = false;
            if let Some(screen) = self.draw(screenshot_now)? {
                let path = self.screenshot.take().expect("asked for a screenshot");
                let size = self.session.as_ref().map(|s| s.renderer.size()).expect("a session was drawn");
                anyhow::ensure!(
                    (screen.width, screen.height) == size,
                    "the window is {}x{} pixels, not the {}x{} asked for (a window manager resized it?): the screenshot would not be the image",
                    screen.width,
                    screen.height,
                    size.0,
                    size.1
                );
                crate::image::png::write_srgb8(&path, screen.width, screen.height, &screen.rgb)?;
                // With the speed the title shows, so that a run under a virtual display
                // (scripts/gpu-measure.sh) reads the viewer's frame rate and samples/s.
                log::info!(
                    "caustica view: wrote {} ({}x{}, {} spp; {:.2} Msamples/s, {:.1} fps)",
                    path.display(),
                    screen.width,
                    screen.height,
                    self.session.as_ref().map_or(0, |s| s.renderer.samples_done),
                    self.speed.per_second() / 1e6,
                    1.0 / self.frame_seconds.max(1e-6)
                );
                return Ok(false);
            }
        }
        Ok(!self.quit)
    }

    /// Re-creates the image at the window's size once a resize has settled.
    fn follow_window_size(&mut self) -> Result<()> {
        let size = self.window.inner_size();
        let Some(session) = &self.session else { return Ok(()) };
        if size.width == 0 || size.height == 0 || session.renderer.size() == (size.width, size.height) {
            return Ok(());
        }
        if self.resized_at.is_some_and(|t| t.elapsed() < RESIZE_SETTLE) {
            return Ok(());
        }
        self.resized_at = None;
        self.start_session()
    }

    fn update_title(&self) {
        let samples = self.session.as_ref().map_or(0, |s| s.renderer.samples_done);
        let limit = self.limit().map_or(String::new(), |l| format!("/{l}"));
        let fps = 1.0 / self.frame_seconds.max(1e-6);
        self.window.set_title(&format!(
            "caustica - {} - {samples}{limit} spp - {:.2} Msamples/s - {fps:.0} fps",
            self.source.title(),
            self.speed.per_second() / 1e6
        ));
    }

    fn settings(&self) -> DisplaySettings {
        // Depth shows black at the far side of the scene.
        let depth_far = self.scene.bounds().map_or(1.0, |(lo, hi)| {
            let corners = (0..8).map(|i| {
                Vec3::new(
                    if i & 1 == 0 { lo.x } else { hi.x },
                    if i & 2 == 0 { lo.y } else { hi.y },
                    if i & 4 == 0 { lo.z } else { hi.z },
                )
            });
            corners.map(|c| (c - self.camera.position).length()).fold(1e-3, f32::max)
        });
        DisplaySettings { exposure: self.exposure, tonemap: self.tonemap, view: self.view, depth_far }
    }

    /// Draws the picture, and the overlay unless taking a screenshot (which must be the image
    /// alone); with `read_back`, returns what was presented.
    fn draw(&mut self, read_back: bool) -> Result<Option<crate::gpu::Screen>> {
        let Some(order) = self.presenter.as_ref().and_then(Presenter::channel_order) else { return Ok(None) };
        let settings = self.settings();
        let overlay = if self.screenshot.is_none() {
            let raw = self.egui_input.take_egui_input(self.window);
            let session = self.session.as_ref().expect("drawn with a session");
            let (w, h) = session.renderer.size();
            let tonemap = self.tonemap.to_string();
            let status = Status {
                scene: &self.source.title(),
                device: &self.ctx.info.name,
                size: [w, h],
                samples: session.renderer.samples_done,
                limit: self.limit(),
                samples_per_second: self.speed.per_second(),
                frame_seconds: self.frame_seconds,
                exposure: self.exposure,
                tonemap: &tonemap,
                view: self.view.name(),
                seed: self.seed,
                problem: self.problem.as_deref(),
            };
            let output = self.egui.run_ui(raw, |ui| overlay::draw(ui.ctx(), &status));
            self.egui_input.handle_platform_output(self.window, output.platform_output);
            let primitives = self.egui.tessellate(output.shapes, output.pixels_per_point);
            Some((primitives, output.textures_delta, output.pixels_per_point))
        } else {
            None
        };
        let session = self.session.as_mut().expect("drawn with a session");
        let picture = session.display.picture(&session.renderer, &settings, order)?;
        let frame = Frame {
            picture: Some(picture),
            overlay: overlay.as_ref().map(|(primitives, textures, pixels_per_point)| OverlayDraw {
                primitives,
                textures,
                pixels_per_point: *pixels_per_point,
            }),
            read_back,
        };
        let presenter = self.presenter.as_mut().expect("the presenter lives until destroy");
        let presented = presenter.present(self.ctx, &frame).context("presenting a frame")?;
        self.ctx.check_validation()?;
        Ok(match presented {
            Presented::Shown(screen) => screen,
            Presented::NotShown => {
                self.redraw = true;
                None
            }
        })
    }

    /// Frees the GPU objects, before the context goes (also when unwinding from a panic, so that
    /// the validation layer reports no leak on top of it).
    fn destroy(&mut self) {
        self.ctx.wait_idle();
        if let Some(session) = self.session.take() {
            session.display.destroy(self.ctx);
        }
        if let Some(presenter) = self.presenter.take() {
            presenter.destroy(self.ctx);
        }
    }
}

impl Drop for Viewer<'_> {
    fn drop(&mut self) {
        self.destroy();
    }
}

fn is_fly_key(code: KeyCode) -> bool {
    matches!(code, KeyCode::KeyW | KeyCode::KeyA | KeyCode::KeyS | KeyCode::KeyD | KeyCode::KeyQ | KeyCode::KeyE)
}

/// A fly key's direction in the camera's frame (x right, y up, z forward).
fn fly_direction(code: KeyCode) -> Vec3 {
    match code {
        KeyCode::KeyW => Vec3::Z,
        KeyCode::KeyS => Vec3::NEG_Z,
        KeyCode::KeyA => Vec3::NEG_X,
        KeyCode::KeyD => Vec3::X,
        KeyCode::KeyQ => Vec3::NEG_Y,
        KeyCode::KeyE => Vec3::Y,
        _ => Vec3::ZERO,
    }
}
