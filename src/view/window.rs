//! The window and its event loop. The loop is pumped (winit's `pump_app_events`) rather than
//! handed control: the viewer's GPU context is made for the window, and the renderer borrows the
//! context, so the window must exist before them and outlive them; between pumps the viewer does
//! a frame's work.

use super::app::Viewer;
use anyhow::{anyhow, bail, Result};
use std::time::Duration;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::platform::pump_events::{EventLoopExtPumpEvents, PumpStatus};
use winit::window::{Window, WindowAttributes, WindowId};

/// Fails, naming what is missing, where no display server can be reached: on Linux and the BSDs a
/// window needs an X11 (`DISPLAY`) or Wayland (`WAYLAND_DISPLAY`) display.
pub fn require_display() -> Result<()> {
    #[cfg(all(unix, not(any(target_os = "macos", target_os = "ios", target_os = "android"))))]
    {
        let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
        if !set("DISPLAY") && !set("WAYLAND_DISPLAY") {
            bail!(
                "caustica view needs a display, but neither DISPLAY (X11) nor WAYLAND_DISPLAY (Wayland) is set: run it in a desktop session, or under Xvfb (e.g. xvfb-run caustica view ...); `caustica render` needs none"
            );
        }
    }
    Ok(())
}

/// Creates the window once the event loop says windows may be created.
struct Opener {
    attributes: WindowAttributes,
    window: Option<Result<Window>>,
}

impl ApplicationHandler for Opener {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none() {
            self.window = Some(
                event_loop.create_window(self.attributes.clone()).map_err(|e| anyhow!("creating the window: {e}")),
            );
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, _: WindowEvent) {}
}

/// An event loop and a window of `size` pixels (not scaled: one image pixel per screen pixel).
pub fn open(title: &str, size: [u32; 2]) -> Result<(EventLoop<()>, Window)> {
    let mut event_loop = EventLoop::new().map_err(|e| anyhow!("cannot open a window: {e}"))?;
    let attributes =
        Window::default_attributes().with_title(title).with_inner_size(PhysicalSize::new(size[0], size[1]));
    let mut opener = Opener { attributes, window: None };
    while opener.window.is_none() {
        if let PumpStatus::Exit(code) = event_loop.pump_app_events(Some(Duration::from_millis(100)), &mut opener) {
            bail!("the event loop ended (status {code}) before the window opened");
        }
    }
    let window = opener.window.take().expect("the loop ran until the window was made")?;
    Ok((event_loop, window))
}

/// Hands each window event to the viewer.
struct Pump<'v, 'a> {
    viewer: &'v mut Viewer<'a>,
}

impl ApplicationHandler for Pump<'_, '_> {
    fn resumed(&mut self, _: &ActiveEventLoop) {}

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        self.viewer.on_event(event);
    }
}

/// Alternates event handling and the viewer's frames until the viewer is done.
pub fn run(event_loop: &mut EventLoop<()>, viewer: &mut Viewer) -> Result<()> {
    loop {
        let wait = viewer.wait_time();
        if let PumpStatus::Exit(_) = event_loop.pump_app_events(Some(wait), &mut Pump { viewer }) {
            return Ok(());
        }
        if !viewer.frame()? {
            return Ok(());
        }
    }
}
