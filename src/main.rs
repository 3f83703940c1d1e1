//! The `caustica` command line: a thin layer over the library.

use anyhow::{Context as _, Result};
use caustica::bench::{self, FilmOverrides, KernelSetup};
use caustica::denoise::{DeviceChoice, Quality};
use caustica::farm::{self, format_ranges, is_exr, parse_duration, per_second, Outcome, PartialRender, RenderJob};
use caustica::gpu::{list_devices, ContextOptions, GpuContext, TraversalRequest};
use caustica::image::{write_image_with, OutputOptions, PngDepth, Tonemap};
use caustica::input_file::InputFiles;
use caustica::render::{AovSet, GroupOrder, KernelChoice, KernelOptions, Renderer};
use caustica::scene::{check_film, Film, Filter, Scene};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::time::{Duration, Instant};

#[derive(Parser)]
#[command(name = "caustica", version, about = "A physically based GPU path tracer (Vulkan compute)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args, Clone)]
struct DeviceArgs {
    /// Vulkan device: index or UUID from `caustica devices`, or part of its name. Default: a
    /// discrete GPU, else any GPU, CPU implementations (lavapipe) last.
    #[arg(long)]
    device: Option<String>,
    /// Enable the Khronos validation layer and fail on any message it reports.
    #[arg(long)]
    validation: bool,
    /// How rays find what they hit: caustica's compute walk of its BVH, or the device's ray
    /// queries (VK_KHR_ray_query); auto picks ray queries on GPUs that have them and the compute
    /// walk on CPU devices (lavapipe), where it measured faster (docs/benchmarks.md).
    #[arg(long, default_value = "auto", value_parser = traversal)]
    traversal: TraversalRequest,
}

fn traversal(text: &str) -> Result<TraversalRequest, String> {
    TraversalRequest::parse(text).map_err(|e| e.to_string())
}

impl DeviceArgs {
    fn context(&self) -> Result<GpuContext> {
        GpuContext::new(&ContextOptions {
            device: self.device.clone(),
            validation: self.validation,
            storage_binding_limit: None,
            traversal: self.traversal,
        })
    }
}

/// How the image is written: exposure, tone curve and depth apply to PNG only (PFM and EXR stay linear).
#[derive(clap::Args, Clone)]
struct OutputArgs {
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, value_parser = exposure, allow_hyphen_values = true)]
    exposure: f32,
    /// Tone curve for PNG output, applied after exposure and before sRGB encoding.
    #[arg(long, value_enum, default_value_t = Tonemap::Clamp)]
    tonemap: Tonemap,
    /// Bits per channel of PNG output.
    #[arg(long, value_enum, default_value_t = PngDepth::Eight)]
    png_depth: PngDepth,
}

impl OutputArgs {
    fn options(&self) -> OutputOptions {
        OutputOptions { exposure: self.exposure, tonemap: self.tonemap, png_depth: self.png_depth }
    }
}

/// Stopping, checkpoints and sample ranges (docs/farm.md).
#[derive(clap::Args, Clone)]
struct FarmArgs {
    /// Render until this much time is spent (whole passes), e.g. 90s, 10m, 1h30m, 2.5h. Without
    /// --spp the scene's sample count is no limit; with it, whichever comes first.
    #[arg(long, value_parser = duration)]
    time: Option<Duration>,
    /// Write a checkpoint (the accumulation, resumable) whenever this much time has passed.
    #[arg(long, value_parser = duration)]
    checkpoint_every: Option<Duration>,
    /// Checkpoint file (EXR). Default: the output path with the extension .checkpoint.exr.
    #[arg(long)]
    checkpoint: Option<PathBuf>,
    /// Continue from the checkpoint; --spp is then the total the image should hold.
    #[arg(long)]
    resume: bool,
    /// Index of the first sample: renders with disjoint ranges (offset, offset + spp) of one scene and
    /// seed merge into one image with `caustica merge`.
    #[arg(long, default_value_t = 0, conflicts_with = "resume")]
    sample_offset: u32,
}

impl FarmArgs {
    fn checkpoint_path(&self, output: &Path) -> PathBuf {
        self.checkpoint.clone().unwrap_or_else(|| output.with_extension("checkpoint.exr"))
    }

    /// Checkpoints are written (periodically if asked, and at the end) once any checkpoint option is given.
    fn checkpointing(&self) -> bool {
        self.checkpoint_every.is_some() || self.checkpoint.is_some() || self.resume
    }
}

fn duration(text: &str) -> Result<Duration, String> {
    parse_duration(text).map_err(|e| e.to_string())
}

/// Stops of exposure: a finite number whose scale 2^EV is a finite, non-zero f32 (NaN or infinity
/// would turn every pixel black or white).
fn exposure(text: &str) -> Result<f32, String> {
    const RANGE: std::ops::RangeInclusive<f32> = -126.0..=127.0;
    match text.trim().parse::<f32>() {
        Ok(ev) if RANGE.contains(&ev) => Ok(ev),
        Ok(ev) if ev.is_finite() => Err(format!(
            "{ev} stops is out of range: 2^EV must be a float, so from {} to {}",
            RANGE.start(),
            RANGE.end()
        )),
        Ok(_) => Err(format!("'{text}' is not a finite number of stops (e.g. -1, 0, 2.5)")),
        Err(_) => Err(format!("'{text}' is not a number of stops (e.g. -1, 0, 2.5)")),
    }
}

fn aov_set(text: &str) -> Result<AovSet, String> {
    AovSet::parse(text).map_err(|e| e.to_string())
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (the built-in Cornell box when no scene is given).
    Render {
        /// Scene file (TOML), or a mesh file (.gltf, .glb, .obj, .ply) to render on its own under a
        /// white sky. Omit for the built-in Cornell box.
        scene: Option<PathBuf>,
        /// Output image: .pfm, .exr (linear) or .png (exposure, tone curve, then sRGB).
        #[arg(short, long, default_value = "render.png")]
        output: PathBuf,
        /// Samples per pixel (overrides the scene's film.spp).
        #[arg(long)]
        spp: Option<u32>,
        /// Image width in pixels (overrides film.width).
        #[arg(long)]
        width: Option<u32>,
        /// Image height in pixels (overrides film.height).
        #[arg(long)]
        height: Option<u32>,
        /// Random seed: the same seed gives the same image.
        #[arg(long, default_value_t = 1)]
        seed: u32,
        /// Extra EXR layers, comma-separated: albedo, normal (the features denoisers such as Open
        /// Image Denoise take), depth, samples; or all. Needs .exr output.
        #[arg(long, value_parser = aov_set)]
        aov: Option<AovSet>,
        /// Denoise the image with Intel Open Image Denoise 2 (scripts/install-oidn.sh installs it),
        /// guided by the albedo and normal of the first non-mirror, non-glass surface, at this
        /// quality (default high). An .exr output keeps the noisy image (layer "noisy") and the
        /// guides (layers "albedo", "normal") beside the denoised one.
        #[arg(long, value_enum, num_args = 0..=1, default_missing_value = "high", value_name = "QUALITY")]
        denoise: Option<Quality>,
        #[command(flatten)]
        framing: FramingArgs,
        #[command(flatten)]
        output_args: OutputArgs,
        #[command(flatten)]
        farm: FarmArgs,
        /// No progress bar or summary, and of the messages only warnings and errors.
        #[arg(short, long, conflicts_with = "verbose")]
        quiet: bool,
        /// Detail messages too (the log's debug level).
        #[arg(short, long)]
        verbose: bool,
        /// Print a summary as JSON on standard output at the end.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        scene_files: SceneFileArgs,
        #[command(flatten)]
        kernel: KernelOptionArgs,
        #[command(flatten)]
        gpu: DeviceArgs,
    },
    /// Open a window that shows the image as samples accumulate, with a camera to move (see the
    /// keys in the window's overlay or docs/cli.md "Viewer"). Needs a display (X11 or Wayland).
    View {
        /// Scene file (TOML) or mesh file, as `render` takes. Omit for the built-in Cornell box.
        scene: Option<PathBuf>,
        /// Samples per pixel to stop at (default: the scene's film.spp).
        #[arg(long)]
        spp: Option<u32>,
        /// Window width in pixels (default: film.width); the image follows the window's size.
        #[arg(long)]
        width: Option<u32>,
        /// Window height in pixels (default: film.height).
        #[arg(long)]
        height: Option<u32>,
        /// Random seed: the same seed gives the same image as `render --seed`.
        #[arg(long, default_value_t = 1)]
        seed: u32,
        /// Exposure in stops (keys + and -), as `render --exposure` for PNG output.
        #[arg(long, default_value_t = 0.0, value_parser = exposure, allow_hyphen_values = true)]
        exposure: f32,
        /// Tone curve (key T), as `render --tonemap` for PNG output.
        #[arg(long, value_enum, default_value_t = Tonemap::Clamp)]
        tonemap: Tonemap,
        /// Render to --spp, save what the window shows as this PNG and quit: the same pixels as
        /// `render SCENE --spp N -o FILE.png` with the same size, seed, exposure and tonemap.
        #[arg(long)]
        screenshot: Option<PathBuf>,
        #[command(flatten)]
        scene_files: SceneFileArgs,
        #[command(flatten)]
        gpu: DeviceArgs,
    },
    /// Add up partial renders (EXR files from `render --sample-offset`, checkpoints, earlier merges)
    /// of one scene and seed with disjoint sample ranges.
    Merge {
        /// Partial renders.
        #[arg(required_unless_present = "watch", conflicts_with = "watch")]
        inputs: Vec<PathBuf>,
        /// Preview a farm while it runs: merge the parts and checkpoints that appear in DIR into
        /// the output as they come (of files sharing samples, the one holding more), saying how
        /// many of the --spp planned samples per pixel are in; end when all are, or on SIGINT or
        /// SIGTERM, with what is in written.
        #[arg(long, value_name = "DIR", requires = "spp")]
        watch: Option<PathBuf>,
        /// With --watch: the samples per pixel the farm renders in all (tasks x samples each).
        #[arg(long, requires = "watch")]
        spp: Option<u32>,
        /// Merged image: .exr keeps the accumulation (mergeable and resumable again); .pfm, .png.
        #[arg(short, long)]
        output: PathBuf,
        /// Denoise the merged image (as `render --denoise`), with the partials' albedo and normal
        /// guides where they have them.
        #[arg(long, value_enum, num_args = 0..=1, default_missing_value = "high", value_name = "QUALITY", conflicts_with = "watch")]
        denoise: Option<Quality>,
        #[command(flatten)]
        output_args: OutputArgs,
        /// No summary, and of the messages only warnings and errors.
        #[arg(short, long, conflicts_with = "verbose")]
        quiet: bool,
        /// Detail messages too (the log's debug level).
        #[arg(short, long)]
        verbose: bool,
    },
    /// Denoise a render (an EXR checkpoint, partial render or merge caustica wrote) with Intel
    /// Open Image Denoise 2, with its albedo and normal layers as guides where it has them.
    Denoise {
        /// The render: an .exr file caustica wrote.
        input: PathBuf,
        /// The denoised image: .exr (keeps the accumulation, the noisy image and the AOVs, as
        /// `render --denoise`), .pfm or .png.
        #[arg(short, long)]
        output: PathBuf,
        /// fast, balanced or high.
        #[arg(long, value_enum, default_value_t = Quality::High)]
        quality: Quality,
        #[command(flatten)]
        output_args: OutputArgs,
        /// Only warnings and errors.
        #[arg(short, long)]
        quiet: bool,
    },
    /// List the Vulkan devices.
    Devices {
        /// One JSON array on standard output: each device's index, UUID, name, kind, Vulkan and
        /// driver versions and memory (how a farm task picks its GPU: docs/farm.md).
        #[arg(long)]
        json: bool,
    },
    /// Write a Mitsuba 3 XML or pbrt-v4 scene as the equivalent caustica TOML scene (meshes referenced by path).
    Convert {
        /// The scene to convert (.xml or .pbrt).
        input: PathBuf,
        /// The TOML scene to write.
        #[arg(short, long)]
        output: PathBuf,
        /// Set a `<default>` parameter, e.g. -D spp=64 (repeatable).
        #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = define)]
        define: Vec<(String, String)>,
    },
    /// Compare an image with a reference (PFM, EXR or Radiance .hdr): relative MSE, mean absolute error and the
    /// ratio of their means.
    Compare { image: PathBuf, reference: PathBuf },
    /// Render a scene (default: the Cornell box) and report geometry, BVH build, memory, and samples
    /// and rays per second; with --suite, every checked-in scene in one table.
    Bench {
        /// Image width (default 256; with --suite, each scene's own, see src/bench/suite.rs).
        #[arg(long)]
        width: Option<u32>,
        /// Image height (default 256; with --suite, each scene's own).
        #[arg(long)]
        height: Option<u32>,
        /// Samples per pixel timed, after 0.3 s of warm-up samples (default 64; with --suite, each
        /// scene's own).
        #[arg(long)]
        spp: Option<u32>,
        /// Scene to measure instead of the built-in Cornell box.
        #[arg(conflicts_with = "suite")]
        scene: Option<PathBuf>,
        /// Measure the built-in Cornell box and every scene file of the scenes folder, one row
        /// each; scenes that need the shared data folder ($CAUSTICA_DATA) are skipped, saying so,
        /// when it is missing.
        #[arg(long)]
        suite: bool,
        /// The suite's scenes folder (default: scenes, from the working directory).
        #[arg(long, requires = "suite")]
        scenes: Option<PathBuf>,
        /// Accumulate these AOVs too (as `render --aov`), to measure what they cost.
        #[arg(long, value_parser = aov_set)]
        aov: Option<AovSet>,
        /// Also time denoising an image of this size with Open Image Denoise at this quality
        /// (default high), on the device `render --denoise` would use.
        #[arg(long, value_enum, num_args = 0..=1, default_missing_value = "high", value_name = "QUALITY", conflicts_with = "suite")]
        denoise: Option<Quality>,
        /// Print the results as JSON (with --suite, one document: the device and a row per scene).
        #[arg(long)]
        json: bool,
        /// Measure the general kernel, compiled with every scene feature, instead of the kernel
        /// compiled for the scene: what specialization gains (the image is the same).
        #[arg(long)]
        general_kernel: bool,
        /// The order in which a dispatch's workgroups take the image's rows (the image is the
        /// same): in-order top to bottom, or interleaved across the band so that each of a CPU
        /// device's threads gets rows from the whole image. Default: interleaved on CPU devices
        /// (lavapipe), in order on GPUs.
        #[arg(long, value_enum)]
        group_order: Option<GroupOrder>,
        #[command(flatten)]
        scene_files: SceneFileArgs,
        #[command(flatten)]
        kernel: KernelOptionArgs,
        #[command(flatten)]
        gpu: DeviceArgs,
    },
}

/// Cameras that frame the scene's bounding box in place of its own (render; src/scene/framing.rs).
#[derive(clap::Args, Clone)]
struct FramingArgs {
    /// Look at the scene's bounding box from these angles in degrees, fitted to it: azimuth about
    /// +y (0 from +z, 90 from +x) and elevation (90 from straight above), e.g. 30,20. Replaces the
    /// scene's camera with a 40 degree one.
    #[arg(long, value_name = "AZ,EL", value_parser = orbit_angles, allow_hyphen_values = true)]
    camera_orbit: Option<(f32, f32)>,
    /// Move the scene's camera along its viewing axis, aimed at the bounding box's centre, to the
    /// nearest place from which the whole box is in view (its direction and field of view kept).
    #[arg(long, conflicts_with = "camera_orbit")]
    camera_fit: bool,
}

impl FramingArgs {
    /// The scene's camera replaced or moved as asked, for its film as it will be rendered.
    fn apply(&self, scene: &mut Scene) -> Result<()> {
        if self.camera_orbit.is_none() && !self.camera_fit {
            return Ok(());
        }
        let Some(bounds) = caustica::scene::framing::scene_bounds(scene) else {
            anyhow::bail!("--camera-orbit and --camera-fit need a scene with shapes or meshes to frame");
        };
        let aspect = scene.film.width as f32 / scene.film.height as f32;
        scene.camera = match self.camera_orbit {
            Some((azimuth, elevation)) => caustica::scene::framing::orbit_camera(bounds, azimuth, elevation, aspect),
            None => caustica::scene::framing::fit_camera(&scene.camera, bounds, aspect),
        };
        Ok(())
    }
}

/// `--camera-orbit`'s AZ,EL: finite degrees, the elevation within [-90, 90].
fn orbit_angles(text: &str) -> Result<(f32, f32), String> {
    let parse = |t: &str| t.trim().parse::<f32>().ok().filter(|v| v.is_finite());
    match text.split_once(',').map(|(a, e)| (parse(a), parse(e))) {
        Some((Some(azimuth), Some(elevation))) if (-90.0..=90.0).contains(&elevation) => Ok((azimuth, elevation)),
        Some((Some(_), Some(elevation))) => Err(format!("elevation {elevation} is outside -90..90 degrees")),
        _ => Err(format!("'{text}' is not AZ,EL in degrees (e.g. 30,20)")),
    }
}

/// Which files a scene may read (render and bench).
#[derive(clap::Args, Clone)]
struct SceneFileArgs {
    /// Read only files inside the scene's folder and the shared data folder ($CAUSTICA_DATA), after
    /// resolving `..` and symbolic links: for scenes someone else wrote (docs/farm.md).
    #[arg(long)]
    confine: bool,
    /// Set a Mitsuba XML scene's `<default>` parameter, e.g. -D spp=64 (repeatable).
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = define)]
    define: Vec<(String, String)>,
}

/// How the kernel runs (render and bench).
#[derive(clap::Args, Clone)]
struct KernelOptionArgs {
    /// Override one of the kernel's run-time choices for an A/B of one binary, e.g. walk-queue=0
    /// (repeatable; the image is the same, only the speed differs). `--kernel-option help` lists
    /// the keys, their values, and each device class's defaults. The CAUSTICA_* variables of
    /// docs/development.md set the same options; this flag wins.
    #[arg(long = "kernel-option", value_name = "KEY=VALUE")]
    kernel_option: Vec<String>,
}

impl KernelOptionArgs {
    /// The options asked for, over the environment's; `None` after printing the help that
    /// `help` asks for.
    fn options(&self) -> Result<Option<KernelOptions>> {
        if self.kernel_option.iter().any(|o| o == "help") {
            print!("{}", caustica::render::kernel_options_help());
            return Ok(None);
        }
        KernelOptions::from_env_and(&self.kernel_option).map(Some)
    }
}

/// `name=value` of `-D`.
fn define(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((name, value)) if !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') => {
            Ok((name.to_owned(), value.to_owned()))
        }
        _ => Err(format!("'{text}' is not NAME=VALUE (a parameter name of letters, digits and _)")),
    }
}

impl SceneFileArgs {
    /// The scene at `path` (the built-in Cornell box without one).
    fn load_scene(&self, path: Option<&PathBuf>) -> Result<Scene> {
        match path {
            Some(p) if self.confine => Scene::load_with(&caustica::scene::confinement(p), p, &self.define),
            Some(p) => Scene::load_with(&InputFiles::anywhere(), p, &self.define),
            None if !self.define.is_empty() => {
                anyhow::bail!("-D sets parameters of a Mitsuba XML scene; the built-in scene has none")
            }
            None => Ok(Scene::default_scene()),
        }
    }
}

fn apply_overrides(scene: &mut Scene, width: Option<u32>, height: Option<u32>, spp: Option<u32>) -> Result<()> {
    scene.film.width = width.unwrap_or(scene.film.width);
    scene.film.height = height.unwrap_or(scene.film.height);
    scene.film.spp = spp.unwrap_or(scene.film.spp);
    check_film(&scene.film).context("command-line film settings")
}

/// A bar towards `total` samples, or a counter when only time limits the render.
fn progress_bar(total: Option<u32>, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let Some(total) = total else {
        let counter = ProgressBar::new_spinner();
        counter.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed_precise}] {pos} spp  {per_sec}").expect("valid template"),
        );
        return counter;
    };
    let bar = ProgressBar::new(total as u64);
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} spp  {per_sec}  ETA {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar
}

/// Set by SIGINT or SIGTERM: the render stops after the pass in flight.
static STOP: AtomicBool = AtomicBool::new(false);

/// SIGINTs received.
static INTERRUPTS: AtomicU32 = AtomicU32::new(0);

/// On SIGINT, SIGTERM or SIGHUP: when `graceful`, the first sets [`STOP`] (the pass in flight is
/// finished and the image written) and only a second SIGINT quits: GNU `timeout`, Slurm and
/// Kubernetes send SIGTERM more than once (`timeout` to the process and its group), and a repeat
/// must not throw the render away during its final write. Without `graceful` the first signal
/// quits. Quitting removes the temporary files of writes in flight, so that an image being written
/// keeps its previous contents and leaves nothing else behind.
fn handle_signals(graceful: bool) -> Result<()> {
    signals::install(move |signal| {
        let interrupted_before = signal == signals::INTERRUPT && INTERRUPTS.fetch_add(1, Ordering::SeqCst) > 0;
        let stopping = STOP.swap(true, Ordering::SeqCst);
        if !graceful || interrupted_before {
            caustica::image::remove_temp_files_in_flight();
            std::process::exit(130);
        }
        if !stopping {
            eprintln!("caustica: finishing the pass in flight (interrupt again to quit at once)");
        }
    })
    .context("installing the SIGINT/SIGTERM handler")
}

/// Signal handling: `install(on)` calls `on` on a thread of its own, where anything may be done
/// (unlike in a signal handler), with each SIGINT, SIGTERM and SIGHUP the process receives.
#[cfg(unix)]
mod signals {
    use std::io::{Error, ErrorKind};
    use std::sync::atomic::{AtomicI32, Ordering};

    pub const INTERRUPT: i32 = libc::SIGINT;

    /// The write end of the pipe that carries signal numbers from the handler to the thread.
    static PIPE: AtomicI32 = AtomicI32::new(-1);

    extern "C" fn on_signal(signal: libc::c_int) {
        let byte = signal as u8;
        // SAFETY: write(2) is async-signal-safe and given one byte that lives across the call; the
        // pipe stays open for the life of the process (a full pipe only loses a repeated signal).
        let _ = unsafe { libc::write(PIPE.load(Ordering::SeqCst), (&byte as *const u8).cast(), 1) };
    }

    pub fn install(on: impl Fn(i32) + Send + 'static) -> std::io::Result<()> {
        let mut ends = [-1; 2];
        // SAFETY: pipe(2) writes two descriptors into the two-element array it is given.
        if unsafe { libc::pipe(ends.as_mut_ptr()) } != 0 {
            return Err(Error::last_os_error());
        }
        let [read_end, write_end] = ends;
        PIPE.store(write_end, Ordering::SeqCst);
        std::thread::spawn(move || loop {
            let mut byte = 0u8;
            // SAFETY: read(2) into one byte that lives across the call, from the pipe's read end,
            // which stays open for the life of the process.
            match unsafe { libc::read(read_end, (&mut byte as *mut u8).cast(), 1) } {
                1 => on(i32::from(byte)),
                _ if Error::last_os_error().kind() == ErrorKind::Interrupted => continue,
                _ => return,
            }
        });
        let handler = on_signal as extern "C" fn(libc::c_int);
        for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
            // SAFETY: a zeroed sigaction is valid; it is given the handler, an empty mask and
            // SA_RESTART, and on_signal does only async-signal-safe work.
            let installed = unsafe {
                let mut action: libc::sigaction = std::mem::zeroed();
                action.sa_sigaction = handler as libc::sighandler_t;
                action.sa_flags = libc::SA_RESTART;
                libc::sigemptyset(&mut action.sa_mask);
                libc::sigaction(signal, &action, std::ptr::null_mut())
            };
            if installed != 0 {
                return Err(Error::last_os_error());
            }
        }
        Ok(())
    }
}

/// Signal handling: Ctrl-C and the like call `on`, all as [`INTERRUPT`](signals::INTERRUPT).
#[cfg(not(unix))]
mod signals {
    pub const INTERRUPT: i32 = 2;

    pub fn install(on: impl Fn(i32) + Send + 'static) -> Result<(), ctrlc::Error> {
        ctrlc::set_handler(move || on(INTERRUPT))
    }
}

/// Clears what killed earlier writes of `targets` left behind, saying so unless `quiet`.
fn remove_leftovers(targets: &[&Path], quiet: bool) {
    for path in farm::remove_leftovers(targets) {
        if !quiet {
            eprintln!("caustica: note: removed {}, left by an interrupted write", path.display());
        }
    }
}

struct RenderRequest {
    output: PathBuf,
    seed: u32,
    /// `--aov`; absent, none, or when resuming the checkpoint's.
    aovs: Option<AovSet>,
    /// `--denoise`.
    denoise: Option<Quality>,
    /// Sample limit; `None` renders until the time budget or a stop.
    spp: Option<u32>,
    quiet: bool,
    json: bool,
    kernel: KernelOptions,
}

fn render(
    scene: Scene,
    request: RenderRequest,
    output_args: &OutputArgs,
    farm_args: &FarmArgs,
    gpu: &DeviceArgs,
) -> Result<()> {
    let output = &request.output;
    let checkpoint = farm_args.checkpoint_path(output);
    // Fail on a bad output or checkpoint path before spending minutes rendering; the checkpoint's
    // only where one is written (the default's name is longer than the output's, maybe too long).
    if farm_args.checkpointing() {
        farm::check_render_files(output, &checkpoint)?;
    } else {
        caustica::image::check_output_path(output)?;
    }
    let resume_from = if farm_args.resume { Some(PartialRender::read(&checkpoint)?) } else { None };
    // A resumed render goes on with the checkpoint's AOVs, which need not be named again (an --aov
    // naming others is refused by farm::resume).
    let mut aovs = request.aovs.or(resume_from.as_ref().map(|p| p.aovs)).unwrap_or_default();
    if !aovs.is_empty() && !is_exr(output) {
        let named = match request.aovs {
            Some(_) => format!("--aov {aovs}"),
            None => format!("{}: the checkpoint's AOVs ({aovs})", checkpoint.display()),
        };
        anyhow::bail!("{named}: AOVs are layers of an EXR file, so the output must be .exr, not {}", output.display());
    }
    if let Some(spp) = request.spp {
        match &resume_from {
            Some(partial) => farm::check_sample_range(farm::resumable_range(partial, &checkpoint)?.start, spp)
                .with_context(|| format!("{}: cannot resume to --spp {spp}", checkpoint.display()))?,
            None => farm::check_sample_range(farm_args.sample_offset, spp)
                .with_context(|| format!("--sample-offset {} --spp {spp}", farm_args.sample_offset))?,
        }
    }
    // Denoising renders its guides in the same pass (a resumed render keeps its checkpoint's AOVs:
    // without them the image is denoised on its colour alone). OIDN is loaded now, so that a
    // missing or wrong library fails before any rendering.
    let oidn = match request.denoise {
        Some(_) => {
            if resume_from.is_none() {
                aovs.albedo = true;
                aovs.normal = true;
            }
            Some(caustica::denoise::Library::load()?)
        }
        None => None,
    };
    remove_leftovers(&[output, &checkpoint], request.quiet);
    handle_signals(true)?;
    let ctx = gpu.context()?;
    let denoiser = match &oidn {
        Some(library) => {
            let denoiser = library.denoiser(DeviceChoice::SameAs(ctx.info.uuid))?;
            log::info!("caustica: denoising with {} ({})", denoiser.describe(), library.origin);
            Some(denoiser)
        }
        None => None,
    };
    let started = Instant::now();
    let mut renderer =
        Renderer::with_options(&ctx, &scene, request.seed, aovs, KernelChoice::ForScene, &request.kernel)?;
    renderer.set_sample_offset(farm_args.sample_offset);
    if let Some(partial) = &resume_from {
        farm::resume(&mut renderer, partial, &checkpoint)?;
    }
    let resumed = resume_from.map_or(0, |p| p.samples());
    let bar = progress_bar(request.spp, request.quiet);
    bar.set_position(resumed as u64);
    let job = RenderJob {
        spp: request.spp,
        time: farm_args.time,
        checkpoint: checkpoint.clone(),
        checkpoint_every: farm_args.checkpoint_every,
        stop: &STOP,
    };
    let outcome =
        farm::run(&mut renderer, &job, |done| bar.set_position(done as u64)).with_context(|| scene.name.clone())?;
    bar.finish_and_clear();
    let partial = farm::snapshot(&renderer)?.context("no samples were rendered")?;
    let denoised = match (&denoiser, request.denoise) {
        (Some(denoiser), Some(quality)) => Some(farm::denoise(denoiser, &partial, quality)?),
        _ => None,
    };
    if let Err(e) = write_render(output, &partial, output_args, denoised.as_ref()) {
        // The samples are worth more than the image: keep them where --resume finds them.
        return Err(match partial.write(&checkpoint) {
            Ok(()) => anyhow::anyhow!(
                "{e:#}; the {} samples per pixel are saved in {}: rerun with --resume --checkpoint {} to write the image from them",
                partial.samples(),
                checkpoint.display(),
                checkpoint.display()
            ),
            Err(_) => e,
        });
    }
    // An EXR output that is its own checkpoint was written just now.
    if farm_args.checkpointing() && !farm::same_file(output, &checkpoint) {
        partial.write(&checkpoint)?;
    }
    let rendered = renderer.samples_done - resumed;
    let pixel_samples = scene.film.width as f64 * scene.film.height as f64 * rendered as f64;
    let (samples_per_s, rays_per_s) =
        (per_second(pixel_samples, renderer.seconds), per_second(renderer.rays_traced as f64, renderer.seconds));
    if !request.quiet {
        let why = match outcome {
            Outcome::Done => String::new(),
            Outcome::TimeUp => " (time budget spent)".to_owned(),
            Outcome::Interrupted => " (interrupted)".to_owned(),
        };
        // Dropped samples mean a kernel bug or a degenerate scene: say so, but only then.
        let dropped = match renderer.nonfinite_samples {
            0 => String::new(),
            n => format!(", {n} non-finite samples dropped"),
        };
        let speed = match (rendered, samples_per_s, rays_per_s) {
            (0, ..) => format!("no samples added ({} already held {resumed} spp)", checkpoint.display()),
            (_, Some(samples), Some(rays)) => format!("{:.2} Msamples/s, {:.1} Mrays/s", samples / 1e6, rays / 1e6),
            _ => "too quick to time".to_owned(),
        };
        let denoised_note = match &denoised {
            Some(d) => format!(", denoised in {:.2} s", d.seconds),
            None => String::new(),
        };
        eprintln!(
            "wrote {} ({}x{}, {} spp{why}{denoised_note}) in {:.2} s on {}: {speed}{dropped}",
            output.display(),
            scene.film.width,
            scene.film.height,
            renderer.samples_done,
            started.elapsed().as_secs_f64(),
            ctx.info.name,
        );
    }
    if request.json {
        let summary = json!({
            "scene": scene.name,
            "scene_hash": renderer.scene_hash,
            "device": ctx.info.name,
            "traversal": renderer.traversal.name(),
            "width": scene.film.width,
            "height": scene.film.height,
            "seed": request.seed,
            "samples": renderer.samples_done,
            "sample_ranges": format_ranges(&partial.ranges),
            "aovs": aovs.to_string(),
            "samples_this_run": rendered,
            "seconds": started.elapsed().as_secs_f64(),
            "render_seconds": renderer.seconds,
            "samples_per_second": samples_per_s,
            "rays_per_second": rays_per_s,
            "nonfinite_samples": renderer.nonfinite_samples,
            "loop_limit": renderer.loop_limit(),
            "repeated_dispatches": renderer.repeated_dispatches,
            "outcome": outcome,
            "denoised": denoised.as_ref().map(|d| json!({ "how": d.how, "seconds": d.seconds })),
            "output": output,
            "checkpoint": farm_args.checkpointing().then_some(&checkpoint),
        });
        println!("{summary}");
    }
    Ok(())
}

/// EXR output is a partial render (mean, accumulation and attributes: mergeable and resumable);
/// other formats get the mean. A denoised render's image is the denoised one (an EXR keeps the
/// mean as its "noisy" layer).
fn write_render(
    output: &Path,
    partial: &PartialRender,
    output_args: &OutputArgs,
    denoised: Option<&farm::Denoised>,
) -> Result<()> {
    if let Some(denoised) = denoised {
        farm::write_denoised(output, partial, denoised, &output_args.options())
    } else if is_exr(output) {
        partial.write(output)
    } else {
        Ok(write_image_with(output, &partial.image(), &output_args.options())?)
    }
}

/// One device as `devices --json` prints it.
fn device_json(d: &caustica::gpu::DeviceInfo) -> serde_json::Value {
    serde_json::json!({
        "index": d.index,
        "uuid": d.uuid_text(),
        "name": d.name,
        "kind": d.kind.label(),
        "vulkan": d.api_version,
        "driver_name": d.driver_name,
        "driver_info": d.driver_info,
        "device_local_bytes": d.device_local_bytes,
    })
}

fn merge(
    inputs: &[PathBuf],
    output: &Path,
    output_args: &OutputArgs,
    quiet: bool,
    denoise: Option<Quality>,
) -> Result<()> {
    caustica::image::check_output_path(output)?;
    // OIDN before the inputs are read: a missing library fails first.
    let denoiser = denoise.map(|_| caustica::denoise::Denoiser::new(DeviceChoice::AnyGpu)).transpose()?;
    remove_leftovers(&[output], quiet);
    handle_signals(false)?;
    let merged = farm::merge_files(inputs)?;
    let denoised = match (&denoiser, denoise) {
        (Some(denoiser), Some(quality)) => Some(farm::denoise(denoiser, &merged, quality)?),
        _ => None,
    };
    write_render(output, &merged, output_args, denoised.as_ref())?;
    if let (Some(d), false) = (&denoised, quiet) {
        eprintln!("caustica: denoised in {:.2} s with {}", d.seconds, d.how);
    }
    if !quiet && !merged.aovs.is_empty() && !is_exr(output) {
        eprintln!("caustica: note: the AOV layers ({}) are kept only by .exr output", merged.aovs);
    }
    if !quiet {
        eprintln!(
            "wrote {} ({} partial renders, {} spp: samples {})",
            output.display(),
            inputs.len(),
            merged.samples(),
            format_ranges(&merged.ranges)
        );
    }
    Ok(())
}

/// `denoise IN.exr -o OUT`: a render caustica wrote, denoised with the guides it has.
fn denoise(input: &Path, output: &Path, quality: Quality, output_args: &OutputArgs, quiet: bool) -> Result<()> {
    caustica::image::check_output_path(output)?;
    let denoiser = caustica::denoise::Denoiser::new(DeviceChoice::AnyGpu)?;
    let partial = PartialRender::read(input)?;
    remove_leftovers(&[output], quiet);
    let denoised = farm::denoise(&denoiser, &partial, quality)?;
    if !denoised.guided {
        eprintln!(
            "caustica: warning: {} has no albedo and normal layers (render with --aov albedo,normal or --denoise): denoised on its colour alone",
            input.display()
        );
    }
    farm::write_denoised(output, &partial, &denoised, &output_args.options())?;
    if !quiet {
        eprintln!(
            "wrote {} ({}x{}, {} spp, denoised in {:.2} s with {})",
            output.display(),
            partial.width,
            partial.height,
            partial.samples(),
            denoised.seconds,
            denoised.how
        );
    }
    Ok(())
}

/// `merge --watch DIR --spp N -o OUT`: folds in the parts and checkpoints appearing in DIR (see
/// farm::pick_watched), rewriting OUT whenever more samples are in, until N samples per pixel are
/// or a SIGINT/SIGTERM comes; then OUT holds what is in. Polls twice a second: farms write their
/// files over network file systems, where change notification is not to be relied on.
fn merge_watch(dir: &Path, spp: u32, output: &Path, output_args: &OutputArgs, quiet: bool) -> Result<()> {
    anyhow::ensure!(dir.is_dir(), "{}: --watch takes a folder (the farm's parts)", dir.display());
    anyhow::ensure!(spp > 0, "--spp: the farm plans no samples");
    caustica::image::check_output_path(output)?;
    remove_leftovers(&[output], quiet);
    signals::install(|signal| {
        if signal == signals::INTERRUPT && INTERRUPTS.fetch_add(1, Ordering::SeqCst) > 0 {
            caustica::image::remove_temp_files_in_flight();
            std::process::exit(130);
        }
        if !STOP.swap(true, Ordering::SeqCst) {
            eprintln!("caustica: writing what is in (interrupt again to quit at once)");
        }
    })
    .context("installing the SIGINT/SIGTERM handler")?;
    let mut said_skipped = std::collections::HashSet::new();
    let mut written = 0;
    loop {
        // Read STOP before looking, so that the files there when the signal came are all in.
        let stopping = STOP.load(Ordering::SeqCst);
        let farm::Picked { chosen, skipped } =
            farm::pick_watched(dir, output).with_context(|| format!("reading {}", dir.display()))?;
        for s in skipped {
            if said_skipped.insert((s.path.clone(), s.reason.clone())) {
                eprintln!("caustica: warning: {}: left out of the preview: {}", s.path.display(), s.reason);
            }
        }
        let samples: u32 = chosen.iter().map(|(_, p)| p.samples()).sum();
        if samples != written && !chosen.is_empty() {
            let files = chosen.len();
            let merged = farm::merge(chosen.iter().map(|(path, p)| (path.as_path(), p.clone())).collect())?;
            write_render(output, &merged, output_args, None)?;
            written = samples;
            if !quiet {
                eprintln!(
                    "{}: {samples} of {spp} planned spp in ({:.0} %), from {files} file{}: samples {}",
                    output.display(),
                    100.0 * f64::from(samples) / f64::from(spp),
                    if files == 1 { "" } else { "s" },
                    format_ranges(&merged.ranges)
                );
            }
        }
        if samples >= spp || stopping {
            if !quiet {
                match (samples >= spp, written) {
                    (true, _) => eprintln!("{}: all {spp} planned spp are in", output.display()),
                    (false, 0) => eprintln!("{}: stopped with no parts in; nothing written", output.display()),
                    (false, _) => eprintln!("{}: stopped with {samples} of {spp} planned spp", output.display()),
                }
            }
            return Ok(());
        }
        for _ in 0..10 {
            if STOP.load(Ordering::SeqCst) {
                break;
            }
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

/// `convert IN -o OUT.toml`: the imported scene as TOML, checked to load before it is written.
fn convert(input: &Path, output: &Path, defines: &[(String, String)]) -> Result<()> {
    use caustica::scene::import;
    if !import::is_foreign_scene(input) {
        anyhow::bail!("{}: convert reads Mitsuba 3 XML (.xml) and pbrt-v4 (.pbrt) scenes", input.display());
    }
    if output.extension().and_then(|e| e.to_str()) != Some("toml") {
        anyhow::bail!("{}: convert writes a caustica scene, so the output must be .toml", output.display());
    }
    let imported = import::import(&InputFiles::anywhere(), input, defines)?;
    for warning in &imported.warnings {
        eprintln!("caustica: warning: {warning}");
    }
    let folder = output.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let text = imported.to_toml(folder)?;
    // The TOML must stand on its own before it replaces anything; what stops it is most often a
    // file the scene names (a mesh, a map) that is missing or unreadable, which the error names.
    Scene::parse(&text, &output.display().to_string(), folder)
        .with_context(|| format!("{}: the converted scene does not load", input.display()))?;
    std::fs::write(output, text).with_context(|| format!("writing {}", output.display()))?;
    eprintln!("wrote {}", output.display());
    Ok(())
}

/// `bench SCENE`: one scene, by default at 256x256 and 64 spp (not the scene's own film, so that
/// figures of different scenes compare).
#[allow(clippy::too_many_arguments)]
fn bench(
    mut scene: Scene,
    film: FilmOverrides,
    aovs: AovSet,
    denoise: Option<Quality>,
    kernel: &KernelSetup,
    json: bool,
    gpu: &DeviceArgs,
) -> Result<()> {
    apply_overrides(
        &mut scene,
        Some(film.width.unwrap_or(256)),
        Some(film.height.unwrap_or(256)),
        Some(film.spp.unwrap_or(64)),
    )?;
    // OIDN first: a missing library fails before the measurement.
    let oidn = denoise.map(|_| caustica::denoise::Library::load()).transpose()?;
    let ctx = gpu.context()?;
    let measured = bench::measure(&ctx, &scene, aovs, kernel)?;
    let denoised = match (&oidn, denoise) {
        (Some(library), Some(quality)) => {
            let denoiser = library.denoiser(DeviceChoice::SameAs(ctx.info.uuid))?;
            Some(bench::time_denoise(&denoiser, scene.film.width, scene.film.height, quality)?)
        }
        _ => None,
    };
    if json {
        let mut summary = measured.json_with_device(&ctx.info);
        if let (Some(timing), serde_json::Value::Object(fields)) = (&denoised, &mut summary) {
            fields.insert("denoise".to_owned(), timing.json());
        }
        println!("{summary}");
    } else {
        bench::print_measurement(&measured, &ctx.info);
        if let Some(timing) = &denoised {
            println!("{}", timing.line());
        }
    }
    Ok(())
}

/// `bench --suite`: every scene of the suite on one device; fails (after the table) when a scene
/// that should have run did not.
fn bench_suite(
    scenes: Option<&Path>,
    overrides: FilmOverrides,
    aovs: AovSet,
    kernel: &KernelSetup,
    json: bool,
    scene_files: &SceneFileArgs,
    gpu: &DeviceArgs,
) -> Result<()> {
    // A bad override is refused once, before any work, rather than by every scene in turn.
    let (w, h, spp) = (overrides.width.unwrap_or(1), overrides.height.unwrap_or(1), overrides.spp.unwrap_or(1));
    check_film(&Film { width: w, height: h, spp, filter: Filter::Box }).context("command-line film settings")?;
    let entries = bench::suite_entries(scenes, &caustica::scene::data_dir())?;
    let ctx = gpu.context()?;
    let outcome = bench::run_suite(&ctx, &entries, overrides, aovs, kernel, |path| {
        scene_files.load_scene(Some(&path.to_path_buf()))
    });
    if json {
        println!("{}", bench::suite_json(&outcome, &ctx.info));
        bench::print_left_out(&outcome);
    } else {
        bench::print_suite(&outcome, &ctx.info);
    }
    if !outcome.failed.is_empty() {
        let names: Vec<&str> = outcome.failed.iter().map(|(name, _)| name.as_str()).collect();
        anyhow::bail!("{} of the suite's scenes failed: {}", names.len(), names.join(", "));
    }
    Ok(())
}

/// The command line, or exit: 0 after --help or --version, and 1, as for any bad input, after a
/// usage error (clap's own default would be 2).
fn parse_command_line() -> Cli {
    Cli::try_parse().unwrap_or_else(|e| {
        let _ = e.print();
        std::process::exit(if e.use_stderr() { 1 } else { 0 });
    })
}

/// The library's messages (the `log` facade) on standard error, each as its bare text: they carry
/// their own "caustica: " or "caustica view: " prefix. Only caustica's own: the log records of its
/// dependencies (winit, gpu-allocator, ...) stay unprinted, as before the library logged.
struct StderrLog;

impl log::Log for StderrLog {
    fn enabled(&self, metadata: &log::Metadata) -> bool {
        metadata.level() <= log::max_level() && metadata.target().split("::").next() == Some("caustica")
    }

    fn log(&self, record: &log::Record) {
        if self.enabled(record.metadata()) {
            eprintln!("{}", record.args());
        }
    }

    fn flush(&self) {}
}

/// Installs [`StderrLog`]: warnings and errors always; progress and choices (info) unless `-q`;
/// detail (debug) with `-v`.
fn install_log(quiet: bool, verbose: bool) {
    static LOG: StderrLog = StderrLog;
    // set_logger fails only when a logger is installed already, and this runs once.
    let _ = log::set_logger(&LOG);
    log::set_max_level(match (quiet, verbose) {
        (true, _) => log::LevelFilter::Warn,
        (false, true) => log::LevelFilter::Debug,
        (false, false) => log::LevelFilter::Info,
    });
}

fn run() -> Result<()> {
    let command = parse_command_line().command;
    match &command {
        Command::Render { quiet, verbose, .. } | Command::Merge { quiet, verbose, .. } => install_log(*quiet, *verbose),
        _ => install_log(false, false),
    }
    match command {
        Command::Render {
            scene,
            output,
            spp,
            width,
            height,
            seed,
            aov,
            denoise,
            framing,
            output_args,
            farm,
            quiet,
            verbose: _,
            json,
            scene_files,
            kernel,
            gpu,
        } => {
            let Some(kernel) = kernel.options()? else { return Ok(()) };
            let mut s = scene_files.load_scene(scene.as_ref())?;
            apply_overrides(&mut s, width, height, spp)?;
            framing.apply(&mut s)?;
            // A time budget alone lifts the scene's sample count.
            let spp = if farm.time.is_some() { spp } else { Some(s.film.spp) };
            render(
                s,
                RenderRequest { output, seed, aovs: aov, denoise, spp, quiet, json, kernel },
                &output_args,
                &farm,
                &gpu,
            )
        }
        Command::View { scene, spp, width, height, seed, exposure, tonemap, screenshot, scene_files, gpu } => {
            handle_signals(true)?;
            caustica::view::run(caustica::view::ViewOptions {
                source: caustica::view::SceneSource {
                    path: scene,
                    confine: scene_files.confine,
                    defines: scene_files.define,
                },
                spp,
                width,
                height,
                seed,
                exposure,
                tonemap,
                screenshot,
                context: ContextOptions {
                    device: gpu.device,
                    validation: gpu.validation,
                    storage_binding_limit: None,
                    traversal: gpu.traversal,
                },
                stop: &STOP,
            })
        }
        Command::Merge { watch: Some(dir), spp: Some(spp), output, output_args, quiet, .. } => {
            merge_watch(&dir, spp, &output, &output_args, quiet)
        }
        Command::Merge { inputs, output, output_args, quiet, denoise, .. } => {
            merge(&inputs, &output, &output_args, quiet, denoise)
        }
        Command::Denoise { input, output, quality, output_args, quiet } => {
            denoise(&input, &output, quality, &output_args, quiet)
        }
        Command::Compare { image, reference } => {
            let (a, b) = (caustica::image::read_image(&image)?, caustica::image::read_image(&reference)?);
            let c = caustica::image::compare(&a, &b, (&image.display().to_string(), &reference.display().to_string()))?;
            println!("relative MSE:        {:.6e}", c.relative_mse);
            println!("mean absolute error: {:.6e}", c.mean_absolute_error);
            match c.mean_ratio {
                Some(ratio) => println!("ratio of means:      {ratio:.6}"),
                None => println!("ratio of means:      none (the reference is black)"),
            }
            Ok(())
        }
        Command::Convert { input, output, define } => convert(&input, &output, &define),
        Command::Devices { json } => {
            let devices = list_devices()?;
            if json {
                println!("{}", serde_json::to_string(&devices.iter().map(device_json).collect::<Vec<_>>())?);
                return Ok(());
            }
            if devices.is_empty() {
                println!("no Vulkan devices found");
            }
            for d in devices {
                println!(
                    "{}: {} ({}, Vulkan {}, {:.0} MiB device-local, max storage buffer {:.0} MiB){}",
                    d.index,
                    d.name,
                    d.kind.label(),
                    d.api_version,
                    d.device_local_bytes as f64 / 1048576.0,
                    d.max_storage_buffer_range as f64 / 1048576.0,
                    d.uuid_text().map(|u| format!(", UUID {u}")).unwrap_or_default()
                );
            }
            Ok(())
        }
        Command::Bench {
            width,
            height,
            spp,
            scene,
            suite,
            scenes,
            aov,
            denoise,
            json,
            general_kernel,
            group_order,
            scene_files,
            kernel,
            gpu,
        } => {
            let Some(options) = kernel.options()? else { return Ok(()) };
            let (aovs, film) = (aov.unwrap_or_default(), FilmOverrides { width, height, spp });
            let choice = if general_kernel { KernelChoice::General } else { KernelChoice::ForScene };
            let kernel = KernelSetup { choice, group_order, options };
            if suite {
                return bench_suite(scenes.as_deref(), film, aovs, &kernel, json, &scene_files, &gpu);
            }
            bench(scene_files.load_scene(scene.as_ref())?, film, aovs, denoise, &kernel, json, &gpu)
        }
    }
}

/// The error and its causes, outermost first, each said once: a cause whose text a message already
/// includes (errors that print their source and also return it, as I/O wrappers often do) is left
/// out.
fn error_report(error: &anyhow::Error) -> String {
    let mut report = String::new();
    for cause in error.chain() {
        let text = cause.to_string();
        if report.contains(&text) {
            continue;
        }
        if !report.is_empty() {
            report.push_str(": ");
        }
        report.push_str(&text);
    }
    printable(&report)
}

/// The most characters of an error report: messages quote tokens cut short, and this bounds any
/// that does not.
const REPORT_CHARS: usize = 8192;

/// `text` for a terminal: control characters other than line breaks and tabs escaped (a hostile
/// file's bytes must not reach the terminal raw), cut to [`REPORT_CHARS`].
fn printable(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars().take(REPORT_CHARS) {
        match c {
            '\n' | '\t' => out.push(c),
            c if c.is_control() => out.extend(c.escape_default()),
            c => out.push(c),
        }
    }
    let length = text.chars().count();
    if length > REPORT_CHARS {
        out.push_str(&format!("… ({} more characters)", length - REPORT_CHARS));
    }
    out
}

fn main() {
    if let Err(e) = run() {
        eprintln!("caustica: error: {}", error_report(&e));
        std::process::exit(1);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_report_says_each_cause_once() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "No such file or directory (os error 2)");
        let repeating = anyhow::Error::new(io)
            .context("out.exr: No such file or directory (os error 2)")
            .context("writing the image");
        assert_eq!(error_report(&repeating), "writing the image: out.exr: No such file or directory (os error 2)");
        let plain = anyhow::anyhow!("disk full").context("out.png");
        assert_eq!(error_report(&plain), "out.png: disk full");
    }

    #[test]
    fn error_reports_escape_control_characters_and_are_bounded() {
        let hostile = anyhow::anyhow!("'\u{1b}[2J\u{7}'\nline two");
        assert_eq!(error_report(&hostile), "'\\u{1b}[2J\\u{7}'\nline two");
        let long = anyhow::anyhow!("{}", "x".repeat(REPORT_CHARS + 5));
        assert!(error_report(&long).ends_with("x… (5 more characters)"));
    }

    #[test]
    fn exposure_must_be_finite_stops() {
        assert_eq!(exposure("-1.5"), Ok(-1.5));
        for bad in ["NaN", "nan", "inf", "-inf", "infinity", "1e9", "200", "x"] {
            let err = exposure(bad).unwrap_err();
            assert!(err.contains("stops"), "{bad}: {err}");
        }
    }
}
