//! `caustica view` in a real window: under the test's own Xvfb server when no display is set
//! (CI), driven with xdotool (synthesized input through the XTEST extension, as from a real
//! mouse and keyboard) and inspected with xwininfo and xprop. Minimizing needs a window manager:
//! that test runs openbox in its Xvfb. A file is dropped on the window by
//! tests/support/xdnd_drop.py (python3-xlib), as a file manager would. Without these tools
//! installed the window tests say SKIPPED loudly and pass; CI installs them (.ci/run).
//!
//! What the viewer shows and saves is checked against `caustica render`, pixel for pixel.

mod common;

use common::{caustica_command, temp_dir};
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// How long a viewer may take to open, compile its kernel and reach a state (lavapipe, 2 cores).
const PATIENCE: Duration = Duration::from_secs(90);

fn installed(program: &str) -> bool {
    Command::new("sh")
        .args(["-c", &format!("command -v {program}")])
        .stdout(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// An X display for one test: the session's own when DISPLAY is set, else an Xvfb server of this
/// test's, stopped when this is dropped. The window tests hold a lock: one viewer at a time (each
/// uses every core through lavapipe) and no two Xvfb servers racing for a display number.
struct XDisplay {
    name: String,
    xvfb: Option<Child>,
    window_manager: Option<Child>,
    _one_at_a_time: MutexGuard<'static, ()>,
}

impl Drop for XDisplay {
    fn drop(&mut self) {
        // The window manager first: it is a client of the server.
        for process in [self.window_manager.take(), self.xvfb.take()].into_iter().flatten() {
            stop(process);
        }
    }
}

/// Ends a process with SIGTERM, on which Xvfb removes its lock file and socket (SIGKILL would leave them).
fn stop(mut process: Child) {
    unsafe { libc::kill(process.id() as i32, libc::SIGTERM) };
    let _ = process.wait();
}

/// The display to test on, or `None` (having said SKIPPED) where the tools are missing. Without
/// a window manager, as most tests want: nothing moves, decorates or resizes the window.
fn x_display(test: &str) -> Option<XDisplay> {
    x_display_with(test, false)
}

/// The display to test on with a window manager running: openbox in the test's Xvfb, or the
/// session's own when DISPLAY is set (and one runs there).
fn x_display_with_window_manager(test: &str) -> Option<XDisplay> {
    x_display_with(test, true)
}

fn x_display_with(test: &str, window_manager: bool) -> Option<XDisplay> {
    static LOCK: Mutex<()> = Mutex::new(());
    let guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let session = std::env::var_os("DISPLAY").filter(|d| !d.is_empty()).map(|d| d.to_string_lossy().into_owned());
    let mut tools = vec!["xdotool", "xwininfo", "xprop"];
    if window_manager && session.is_none() {
        tools.push("openbox");
    }
    let missing: Vec<&str> = tools.into_iter().filter(|p| !installed(p)).collect();
    if !missing.is_empty() {
        eprintln!(
            "SKIPPED: {test}: {} not installed (apt-get install xdotool x11-utils openbox)",
            missing.join(" and ")
        );
        return None;
    }
    if let Some(name) = session {
        if window_manager && !has_window_manager(&name) {
            eprintln!(
                "SKIPPED: {test}: DISPLAY {name} has no window manager (none announces itself on the root window)"
            );
            return None;
        }
        return Some(XDisplay { name, xvfb: None, window_manager: None, _one_at_a_time: guard });
    }
    if !installed("Xvfb") {
        eprintln!("SKIPPED: {test}: no DISPLAY and Xvfb is not installed (apt-get install xvfb)");
        return None;
    }
    let (xvfb, number) = start_xvfb();
    let mut display =
        XDisplay { name: format!(":{number}"), xvfb: Some(xvfb), window_manager: None, _one_at_a_time: guard };
    if window_manager {
        display.window_manager = Some(start_openbox(&display.name));
    }
    Some(display)
}

/// Whether an EWMH window manager runs on the display (it names its window on the root window).
fn has_window_manager(display: &str) -> bool {
    let out = Command::new("xprop").args(["-root", "_NET_SUPPORTING_WM_CHECK"]).env("DISPLAY", display).output();
    out.is_ok_and(|o| String::from_utf8_lossy(&o.stdout).contains("window id"))
}

/// openbox on the display, once it manages windows.
fn start_openbox(display: &str) -> Child {
    let mut cmd = Command::new("openbox");
    cmd.env("DISPLAY", display).stdout(Stdio::null()).stderr(Stdio::null());
    stop_with_this_process(&mut cmd);
    let openbox = cmd.spawn().expect("start openbox");
    wait_until("openbox to manage the display", || has_window_manager(display).then_some(()));
    openbox
}

/// An Xvfb server on a display number it chooses, once it accepts connections: with -displayfd
/// it writes the number to a pipe when ready, so neither a taken number nor a socket that exists
/// before the server listens can make a test fail.
fn start_xvfb() -> (Child, u32) {
    use std::io::Read as _;
    use std::os::fd::FromRawFd as _;
    let mut fds = [0; 2];
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0, "a pipe for Xvfb's display number");
    let (read_end, write_end) = (fds[0], fds[1]);
    unsafe { libc::fcntl(read_end, libc::F_SETFD, libc::FD_CLOEXEC) };
    let mut cmd = Command::new("Xvfb");
    // -noreset: by default the server resets whenever its last client leaves (an xdotool call), and a
    // viewer connecting meanwhile is refused.
    cmd.args(["-displayfd", &write_end.to_string(), "-noreset", "-screen", "0", "800x600x24", "-nolisten", "tcp"])
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    stop_with_this_process(&mut cmd);
    let spawned = cmd.spawn();
    unsafe { libc::close(write_end) };
    let xvfb = spawned.expect("start Xvfb");
    let mut number = String::new();
    // Ends at the server's newline, or at end of file if it exited without one.
    let mut pipe = unsafe { std::fs::File::from_raw_fd(read_end) };
    let mut byte = [0u8; 1];
    while pipe.read(&mut byte).unwrap_or(0) == 1 && byte[0] != b'\n' {
        number.push(byte[0] as char);
    }
    match number.trim().parse() {
        Ok(n) => (xvfb, n),
        Err(_) => {
            stop(xvfb);
            panic!("Xvfb did not start (it gave no display number)");
        }
    }
}

/// Xvfb ends with the test process even when that is killed, rather than outliving it.
fn stop_with_this_process(cmd: &mut Command) {
    #[cfg(target_os = "linux")]
    unsafe {
        use std::os::unix::process::CommandExt as _;
        cmd.pre_exec(|| {
            libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGTERM);
            Ok(())
        });
    }
}

/// A running viewer with its output lines collected as they come.
struct Viewer {
    child: Child,
    stdout: Arc<Mutex<Vec<String>>>,
    stderr: Arc<Mutex<Vec<String>>>,
    display: String,
    window: String,
}

fn collect(stream: impl std::io::Read + Send + 'static) -> Arc<Mutex<Vec<String>>> {
    let lines = Arc::new(Mutex::new(vec![]));
    let sink = lines.clone();
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines().map_while(Result::ok) {
            sink.lock().unwrap().push(line);
        }
    });
    lines
}

fn wait_until<T>(what: &str, mut check: impl FnMut() -> Option<T>) -> T {
    let started = Instant::now();
    loop {
        if let Some(found) = check() {
            return found;
        }
        assert!(started.elapsed() < PATIENCE, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

impl Viewer {
    /// Starts `caustica view ARGS` in `dir` and waits until its window is up and its frame loop
    /// runs (the title shows the sample count).
    fn start(display: &XDisplay, dir: &Path, args: &[&str]) -> Viewer {
        let mut cmd = caustica_command(&[&["view", "--validation"], args].concat());
        cmd.current_dir(dir)
            .env("DISPLAY", &display.name)
            .env_remove("WAYLAND_DISPLAY")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        let mut child = cmd.spawn().expect("start caustica view");
        let (stdout, stderr) = (collect(child.stdout.take().unwrap()), collect(child.stderr.take().unwrap()));
        let mut viewer = Viewer { child, stdout, stderr, display: display.name.clone(), window: String::new() };
        viewer.window = wait_until("the viewer's window", || {
            viewer.check_alive();
            let found = viewer.xdotool(&["search", "--name", "caustica"]);
            found.lines().next().map(str::to_owned)
        });
        wait_until("the viewer's frame loop (spp in the title)", || {
            viewer.check_alive();
            viewer.title().contains("spp").then_some(())
        });
        // No window manager gives it the keyboard: the test does.
        viewer.xdotool(&["windowfocus", &viewer.window]);
        viewer
    }

    fn check_alive(&mut self) {
        if let Some(status) = self.child.try_wait().unwrap() {
            panic!("the viewer exited ({status}): {}", self.stderr.lock().unwrap().join("\n"));
        }
    }

    fn tool(&self, program: &str, args: &[&str]) -> String {
        let out = Command::new(program)
            .args(args)
            .env("DISPLAY", &self.display)
            .output()
            .unwrap_or_else(|e| panic!("{program}: {e}"));
        String::from_utf8_lossy(&out.stdout).into_owned()
    }

    fn xdotool(&self, args: &[&str]) -> String {
        self.tool("xdotool", args)
    }

    fn title(&self) -> String {
        self.xdotool(&["getwindowname", &self.window]).trim().to_owned()
    }

    /// The samples per pixel the title shows ("... - 12/100 spp - ...").
    fn samples_shown(&self) -> u32 {
        let title = self.title();
        let count = title
            .split(" - ")
            .find_map(|part| part.strip_suffix(" spp"))
            .and_then(|s| s.split('/').next()?.parse().ok());
        count.unwrap_or_else(|| panic!("no sample count in the title: {title}"))
    }

    /// Presses P and returns the camera block it printed (the `count`-th block).
    fn print_camera(&mut self) -> Camera {
        let before = self.stdout.lock().unwrap().iter().filter(|l| l.as_str() == "[camera]").count();
        self.xdotool(&["key", "p"]);
        wait_until("the camera printed by P", || {
            self.check_alive();
            let lines = self.stdout.lock().unwrap();
            let starts: Vec<usize> =
                lines.iter().enumerate().filter(|(_, l)| l.as_str() == "[camera]").map(|(i, _)| i).collect();
            let start = *starts.get(before)?;
            let block: Vec<&String> = lines[start..].iter().take_while(|l| !l.is_empty()).collect();
            (block.len() >= 7).then(|| Camera::parse(&block.iter().map(|l| l.as_str()).collect::<Vec<_>>().join("\n")))
        })
    }

    /// Presses S and returns the PNG and EXR it saved.
    fn save(&mut self, dir: &Path) -> (PathBuf, PathBuf) {
        let before = self.stderr.lock().unwrap().iter().filter(|l| l.contains("saved")).count();
        self.xdotool(&["key", "s"]);
        let line = wait_until("the files saved by S", || {
            self.check_alive();
            self.stderr.lock().unwrap().iter().filter(|l| l.contains("saved")).nth(before).cloned()
        });
        // "caustica view: saved X.png and X.exr (N spp)"
        let words: Vec<&str> = line.split_whitespace().collect();
        (dir.join(words[3]), dir.join(words[5]))
    }

    fn quit(mut self) {
        self.xdotool(&["key", "Escape"]);
        let status = wait_until("the viewer to quit on Esc", || self.child.try_wait().unwrap());
        assert!(status.success(), "Esc ends the viewer cleanly: {status}; {}", self.stderr.lock().unwrap().join("\n"));
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A `[camera]` block as printed by P.
#[derive(Clone, Debug)]
struct Camera {
    text: String,
    position: [f32; 3],
    look_at: [f32; 3],
}

impl Camera {
    fn parse(text: &str) -> Camera {
        let table: toml::Table = toml::from_str(text).unwrap_or_else(|e| panic!("P printed TOML: {e}\n{text}"));
        let camera = table["camera"].as_table().unwrap();
        let triple = |key: &str| -> [f32; 3] {
            let a = camera[key].as_array().unwrap();
            [0, 1, 2].map(|i| a[i].as_float().unwrap() as f32)
        };
        Camera { text: text.to_owned(), position: triple("position"), look_at: triple("look_at") }
    }

    fn offset(&self) -> glam::Vec3 {
        glam::Vec3::from(self.position) - glam::Vec3::from(self.look_at)
    }
}

/// A small, quick scene: the Cornell box of scenes/ at 48x36.
fn small_scene(dir: &Path, name: &str) -> PathBuf {
    let cornell = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell.toml")).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, cornell).unwrap();
    path
}

/// The scene text with its `[camera]` table replaced by `camera` (a block printed by P).
fn with_camera(scene: &str, camera: &str) -> String {
    let mut table: toml::Table = toml::from_str(scene).unwrap();
    let camera: toml::Table = toml::from_str(camera).unwrap();
    table.insert("camera".into(), camera["camera"].clone());
    toml::to_string(&table).unwrap()
}

fn png_pixels(path: &Path) -> (u32, u32, Vec<u8>) {
    let image = image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).to_rgb8();
    (image.width(), image.height(), image.into_raw())
}

fn render_png(dir: &Path, scene: &Path, extra: &[&str], output: &str) -> PathBuf {
    let out = caustica_command(&[&["render", scene.to_str().unwrap(), "-q", "-o", output], extra].concat())
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "render: {}", String::from_utf8_lossy(&out.stderr));
    dir.join(output)
}

fn assert_same_pixels(shown: &Path, rendered: &Path) {
    let (a, b) = (png_pixels(shown), png_pixels(rendered));
    assert_eq!((a.0, a.1), (b.0, b.1), "sizes of {} and {}", shown.display(), rendered.display());
    let differing = a.2.iter().zip(&b.2).filter(|(x, y)| x != y).count();
    assert_eq!(
        differing,
        0,
        "{} of {} samples of {} differ from {}",
        differing,
        a.2.len(),
        shown.display(),
        rendered.display()
    );
}

/// The EXR's sample count (caustica.samples).
fn samples_in(exr: &Path) -> u32 {
    caustica::farm::PartialRender::read(exr).unwrap().samples()
}

#[test]
fn screenshot_is_the_render_png_pixel_for_pixel() {
    let Some(display) = x_display("screenshot_is_the_render_png_pixel_for_pixel") else { return };
    let dir = temp_dir("view-screenshot");
    let scene = small_scene(&dir, "box.toml");
    // A fractional exposure and a curve: the GPU tonemap must not round one code differently.
    let settings =
        ["--spp", "3", "--width", "40", "--height", "30", "--seed", "7", "--exposure", "0.7", "--tonemap", "aces"];
    let out = caustica_command(
        &[&["view", "--validation", scene.to_str().unwrap(), "--screenshot", "shown.png"], &settings[..]].concat(),
    )
    .current_dir(&dir)
    .env("DISPLAY", &display.name)
    .env_remove("WAYLAND_DISPLAY")
    .output()
    .unwrap();
    assert!(out.status.success(), "view --screenshot: {}", String::from_utf8_lossy(&out.stderr));
    let rendered = render_png(&dir, &scene, &settings, "rendered.png");
    assert_same_pixels(&dir.join("shown.png"), &rendered);
    let (w, h, pixels) = png_pixels(&rendered);
    assert!(w == 40 && h == 30 && pixels.iter().any(|&v| v > 0), "a lit image");
}

#[test]
fn window_has_the_size_and_title_and_input_moves_the_camera_and_restarts_accumulation() {
    let Some(display) = x_display("window_has_the_size_and_title_and_input_moves_the_camera") else { return };
    let dir = temp_dir("view-input");
    let scene = small_scene(&dir, "box.toml");
    // Wide enough that the input lands beside the overlay (at most 250 points wide, top left).
    let mut viewer =
        Viewer::start(&display, &dir, &[scene.to_str().unwrap(), "--width", "400", "--height", "300", "--spp", "2"]);

    let info = viewer.tool("xwininfo", &["-id", &viewer.window]);
    assert!(info.contains("Width: 400") && info.contains("Height: 300"), "{info}");
    let title = viewer.title();
    assert!(title.contains("caustica") && title.contains("box.toml"), "{title}");

    let start = viewer.print_camera();
    let w = viewer.window.clone();
    // Left drag 40 pixels to the right: the camera orbits the pivot to the left, as far from it.
    viewer.xdotool(&[
        "mousemove",
        "--window",
        &w,
        "300",
        "150",
        "mousedown",
        "1",
        "mousemove",
        "--window",
        &w,
        "320",
        "150",
        "mousemove",
        "--window",
        &w,
        "340",
        "150",
        "mouseup",
        "1",
    ]);
    let orbited = viewer.print_camera();
    assert_eq!(orbited.look_at, start.look_at, "orbiting keeps the pivot");
    assert!(
        (orbited.offset().length() - start.offset().length()).abs() < 1e-3 * start.offset().length(),
        "and the distance to it"
    );
    let right = glam::Vec3::from(start.look_at) - glam::Vec3::from(start.position);
    let right = right.cross(glam::Vec3::Y).normalize();
    assert!(
        (glam::Vec3::from(orbited.position) - glam::Vec3::from(start.position)).dot(right) < -1e-3,
        "dragging right moves the camera left: {start:?} -> {orbited:?}"
    );

    // A click of the wheel's up button: dolly towards the pivot, 0.85 of the distance per step. A
    // real wheel's notch is one step; xdotool's click is a press and a release of button 4,
    // which winit's X11 backend reports as a step each.
    viewer.xdotool(&["mousemove", "--window", &w, "350", "150", "click", "4"]);
    let dollied = viewer.print_camera();
    let ratio = dollied.offset().length() / orbited.offset().length();
    assert!((ratio - 0.85 * 0.85).abs() < 1e-3, "two wheel steps dolly to 0.85^2 of the distance: {ratio}");
    assert!(dollied.offset().normalize().dot(orbited.offset().normalize()) > 0.9999, "along the view");

    // Right button held, W held: fly forward, carrying the pivot along.
    viewer.xdotool(&["mousedown", "3", "keydown", "w", "sleep", "0.3", "keyup", "w", "mouseup", "3"]);
    let flown = viewer.print_camera();
    let moved = glam::Vec3::from(flown.position) - glam::Vec3::from(dollied.position);
    assert!(moved.length() > 1e-3, "W moved the camera");
    assert!(moved.normalize().dot(-dollied.offset().normalize()) > 0.999, "forward: {moved:?}");
    assert!((flown.offset() - dollied.offset()).length() < 1e-3 * dollied.offset().length(), "the pivot moves along");

    // What S saves is a render from the moved camera alone: the accumulation restarted with each
    // move, so no sample of an earlier camera is in it.
    let (png, exr) = viewer.save(&dir);
    let samples = samples_in(&exr);
    assert!(samples >= 1);
    let moved_scene = dir.join("moved.toml");
    std::fs::write(&moved_scene, with_camera(&std::fs::read_to_string(&scene).unwrap(), &flown.text)).unwrap();
    let rendered = render_png(
        &dir,
        &moved_scene,
        &["--width", "400", "--height", "300", "--spp", &samples.to_string()],
        "moved.png",
    );
    assert_same_pixels(&png, &rendered);

    // A resized window gets an image of its new size (once the size has held for a moment).
    viewer.xdotool(&["windowsize", &w, "320", "240"]);
    wait_until("the image to follow the window's size", || {
        viewer.print_camera();
        viewer.stdout.lock().unwrap().iter().rev().find(|l| l.starts_with('#'))?.contains("(320x240)").then_some(())
    });
    viewer.quit();
}

/// The scene `text` with every albedo set to `albedo` and the camera's field of view to `fov`: a
/// picture told apart from the original at a glance.
fn recoloured_scene(text: &str, albedo: [f64; 3], fov: f64) -> String {
    let mut table: toml::Table = toml::from_str(text).unwrap();
    for (_, material) in table["materials"].as_table_mut().unwrap().iter_mut() {
        if let Some(value) = material.get_mut("albedo") {
            *value = toml::Value::try_from(albedo).unwrap();
        }
    }
    table["camera"].as_table_mut().unwrap().insert("fov".into(), toml::Value::Float(fov));
    toml::to_string(&table).unwrap()
}

#[test]
fn a_scene_rewritten_on_disk_is_reloaded_keeping_the_camera() {
    let Some(display) = x_display("a_scene_rewritten_on_disk_is_reloaded_keeping_the_camera") else { return };
    let dir = temp_dir("view-reload");
    let scene = small_scene(&dir, "box.toml");
    let original = std::fs::read_to_string(&scene).unwrap();
    let mut viewer =
        Viewer::start(&display, &dir, &[scene.to_str().unwrap(), "--width", "40", "--height", "30", "--spp", "2"]);
    let camera = viewer.print_camera();

    // The walls change colour and the file's camera moves: the viewer takes the walls, keeps its camera.
    let rewritten = recoloured_scene(&original, [0.2, 0.3, 0.9], 70.0);
    std::fs::write(&scene, &rewritten).unwrap();
    wait_until("the reload", || {
        viewer.check_alive();
        viewer.stderr.lock().unwrap().iter().any(|l| l.contains("reloaded box.toml")).then_some(())
    });
    let after = viewer.print_camera();
    assert_eq!((after.position, after.look_at), (camera.position, camera.look_at), "the camera is kept");

    let (png, exr) = viewer.save(&dir);
    let expected_scene = dir.join("expected.toml");
    std::fs::write(&expected_scene, with_camera(&rewritten, &camera.text)).unwrap();
    let rendered = render_png(
        &dir,
        &expected_scene,
        &["--width", "40", "--height", "30", "--spp", &samples_in(&exr).to_string()],
        "expected.png",
    );
    assert_same_pixels(&png, &rendered);
    viewer.quit();
}

#[test]
fn minimizing_pauses_accumulation_and_restoring_resumes_it() {
    let Some(display) = x_display_with_window_manager("minimizing_pauses_accumulation_and_restoring_resumes_it") else {
        return;
    };
    let dir = temp_dir("view-minimize");
    let scene = small_scene(&dir, "box.toml");
    // A limit the test does not reach: only the pause stops the samples.
    let viewer = Viewer::start(
        &display,
        &dir,
        &[scene.to_str().unwrap(), "--width", "40", "--height", "30", "--spp", "1000000"],
    );
    let w = viewer.window.clone();
    let first = viewer.samples_shown();
    wait_until("samples before minimizing", || (viewer.samples_shown() > first).then_some(()));

    viewer.xdotool(&["windowminimize", "--sync", &w]);
    // What winit asks (Window::is_minimized): the state the window manager gave the window. The
    // window manager sets it after the unmap `--sync` waits for (a clean-clone run once read it
    // empty), so wait for it.
    wait_until("the window manager to mark the window hidden (_NET_WM_STATE_HIDDEN)", || {
        viewer.tool("xprop", &["-id", &w, "_NET_WM_STATE"]).contains("_NET_WM_STATE_HIDDEN").then_some(())
    });
    // The dispatch in flight ends and the title (refreshed every 250 ms) catches up.
    std::thread::sleep(Duration::from_secs(1));
    let paused_at = viewer.samples_shown();
    std::thread::sleep(Duration::from_secs(2));
    let title = viewer.title();
    assert_eq!(viewer.samples_shown(), paused_at, "no samples are added while minimized: {title}");
    // The frame rate the title shows: an idle loop wakes about 30 times a second, a spinning one thousands.
    let fps: f64 = title
        .split(" - ")
        .find_map(|p| p.strip_suffix(" fps"))
        .and_then(|f| f.parse().ok())
        .unwrap_or_else(|| panic!("no fps in the title: {title}"));
    assert!(fps < 100.0, "the frame loop idles while minimized: {title}");

    viewer.xdotool(&["windowactivate", "--sync", &w]);
    wait_until("samples after restoring", || (viewer.samples_shown() > paused_at).then_some(()));
    viewer.quit();
}

#[test]
fn a_swapchain_made_out_of_date_by_quick_resizes_is_re_created() {
    let Some(display) = x_display("a_swapchain_made_out_of_date_by_quick_resizes_is_re_created") else { return };
    let dir = temp_dir("view-out-of-date");
    let scene = small_scene(&dir, "box.toml");
    let mut viewer = Viewer::start(
        &display,
        &dir,
        &[scene.to_str().unwrap(), "--width", "200", "--height", "150", "--spp", "1000000"],
    );
    let w = viewer.window.clone();
    // Sizes changing faster than frames: lavapipe's X11 surface then finds the swapchain out of
    // date at acquire or present before the viewer has seen the Resized event (17 times in 40
    // such resizes when counted), and the viewer must skip that frame and re-create the swapchain
    // rather than fail.
    let mut resizes = vec!["sleep".to_owned(), "0".to_owned()];
    for i in 0..30 {
        resizes.extend([
            "windowsize".into(),
            w.clone(),
            (150 + (i % 7) * 30).to_string(),
            (100 + (i % 5) * 25).to_string(),
            "sleep".into(),
            "0.03".into(),
        ]);
    }
    resizes.extend(["windowsize".into(), w.clone(), "160".into(), "120".into()]);
    viewer.xdotool(&resizes.iter().map(String::as_str).collect::<Vec<_>>());
    wait_until("the image to follow the final size", || {
        viewer.print_camera();
        viewer.stdout.lock().unwrap().iter().rev().find(|l| l.starts_with('#'))?.contains("(160x120)").then_some(())
    });
    let settled = viewer.samples_shown();
    wait_until("frames after the resizes", || {
        viewer.check_alive();
        (viewer.samples_shown() > settled).then_some(())
    });
    viewer.quit();
}

/// A Python 3 that has python3-xlib: the one on PATH, else Debian's (where PATH leads to another,
/// e.g. pyenv's, which does not see Debian's packages).
fn python_with_xlib() -> Option<&'static str> {
    ["python3", "/usr/bin/python3"].into_iter().find(|python| {
        Command::new(python).args(["-c", "import Xlib"]).stderr(Stdio::null()).status().is_ok_and(|s| s.success())
    })
}

#[test]
fn a_file_dropped_on_the_window_is_opened_with_its_own_camera() {
    let test = "a_file_dropped_on_the_window_is_opened_with_its_own_camera";
    let Some(python) = python_with_xlib() else {
        eprintln!("SKIPPED: {test}: python3-xlib is not installed (apt-get install python3-xlib)");
        return;
    };
    let Some(display) = x_display(test) else { return };
    let dir = temp_dir("view-drop");
    let scene = small_scene(&dir, "box.toml");
    // The dropped scene has other walls and another camera, so the picture tells the two apart.
    let dropped = dir.join("dropped.toml");
    std::fs::write(&dropped, recoloured_scene(&std::fs::read_to_string(&scene).unwrap(), [0.9, 0.6, 0.2], 65.0))
        .unwrap();
    let mut viewer =
        Viewer::start(&display, &dir, &[scene.to_str().unwrap(), "--width", "40", "--height", "30", "--spp", "2"]);

    let helper = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/support/xdnd_drop.py");
    let out = Command::new(python)
        .arg(&helper)
        .arg(&viewer.window)
        .arg(&dropped)
        .env("DISPLAY", &viewer.display)
        .output()
        .unwrap();
    assert!(out.status.success(), "the drop: {}", String::from_utf8_lossy(&out.stderr));
    wait_until("the dropped scene in the title", || {
        viewer.check_alive();
        viewer.title().contains("dropped.toml").then_some(())
    });

    // What is shown is the dropped scene, from its own camera, and S names the files after it.
    let (png, exr) = viewer.save(&dir);
    assert!(png.file_name().unwrap().to_string_lossy().starts_with("dropped-view-"), "{}", png.display());
    let rendered = render_png(
        &dir,
        &dropped,
        &["--width", "40", "--height", "30", "--spp", &samples_in(&exr).to_string()],
        "expected.png",
    );
    assert_same_pixels(&png, &rendered);
    viewer.quit();
}

#[test]
fn no_display_is_a_clear_error() {
    let out =
        caustica_command(&["view", "--spp", "1"]).env_remove("DISPLAY").env_remove("WAYLAND_DISPLAY").output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("DISPLAY") && err.contains("WAYLAND_DISPLAY") && err.contains("needs a display"), "{err}");
}

#[test]
fn bad_scenes_and_screenshot_names_fail_before_a_window_opens() {
    let dir = temp_dir("view-bad");
    // With a display name that leads nowhere: the errors must come first.
    let run = |args: &[&str]| caustica_command(args).current_dir(&dir).env("DISPLAY", ":0.nowhere").output().unwrap();
    let out = run(&["view", "missing.toml"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("missing.toml"), "{}", String::from_utf8_lossy(&out.stderr));
    let out = run(&["view", "--screenshot", "shot.exr"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains(".png"), "{}", String::from_utf8_lossy(&out.stderr));
}

/// The renderer calls the viewer is built on, on the device alone (no window).
mod viewer_renderer {
    use super::common::gpu;
    use caustica::render::Renderer;
    use caustica::scene::{Camera, Scene};
    use glam::Vec3;

    fn small_box() -> Scene {
        let mut scene = Scene::default_scene();
        scene.film.width = 24;
        scene.film.height = 20;
        scene
    }

    #[test]
    fn stepping_a_dispatch_at_a_time_gives_the_render_bit_for_bit() {
        let (_lock, ctx) = gpu();
        let scene = small_box();
        let mut whole = Renderer::new(&ctx, &scene, 3).unwrap();
        whole.render(3, |_| {}).unwrap();
        let mut stepped = Renderer::new(&ctx, &scene, 3).unwrap();
        // The viewer's dispatch size: passes cut into bands, one per step.
        stepped.set_dispatch_target(1e-6);
        let mut steps = 0;
        while stepped.samples_done < 3 || stepped.pass_target().is_some() {
            stepped.render_step(3).unwrap();
            steps += 1;
        }
        assert!(steps > 3, "a step is a band of a pass, not a pass: {steps} steps");
        assert_eq!(stepped.samples_done, 3);
        assert!(!stepped.render_step(3).unwrap(), "nothing is added past the limit");
        assert_eq!(stepped.accumulation().unwrap(), whole.accumulation().unwrap());
    }

    #[test]
    fn a_camera_change_starts_over_from_the_new_camera_and_rehashes() {
        let (_lock, ctx) = gpu();
        let scene = small_box();
        let moved = Camera::pinhole(Vec3::new(0.4, 1.2, 3.5), Vec3::new(0.0, 0.9, 0.0), Vec3::Y, 50.0);
        let mut moved_scene = scene.clone();
        moved_scene.camera = moved.clone();

        let mut viewer = Renderer::new(&ctx, &scene, 5).unwrap();
        let original_hash = viewer.scene_hash.clone();
        viewer.render(2, |_| {}).unwrap();
        viewer.set_camera(&moved).unwrap();
        assert_eq!(viewer.samples_done, 0);
        assert!(viewer.scene_hash.is_empty(), "no stale hash after a camera change");
        assert!(caustica::farm::snapshot(&viewer).unwrap().is_none(), "nothing rendered since");
        viewer.render(2, |_| {}).unwrap();
        assert!(caustica::farm::snapshot(&viewer).is_err(), "no snapshot with an unknown hash");
        viewer.refresh_scene_hash().unwrap();

        let mut fresh = Renderer::new(&ctx, &moved_scene, 5).unwrap();
        fresh.render(2, |_| {}).unwrap();
        assert_eq!(
            viewer.accumulation().unwrap(),
            fresh.accumulation().unwrap(),
            "no sample of the first camera is left"
        );
        assert_eq!(viewer.scene_hash, fresh.scene_hash, "the hash a render from that camera has");

        viewer.set_camera(&scene.camera).unwrap();
        viewer.refresh_scene_hash().unwrap();
        assert_eq!(viewer.scene_hash, original_hash);
    }
}
