//! The `caustica` command line: a thin layer over the library.

use anyhow::{Context as _, Result};
use caustica::gpu::{list_devices, ContextOptions, GpuContext};
use caustica::image::{write_image_with, OutputOptions, PngDepth, Tonemap};
use caustica::render::{GeometryReport, Renderer};
use caustica::scene::{check_film, Scene};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::PathBuf;
use std::time::Instant;

#[derive(Parser)]
#[command(name = "caustica", version, about = "A physically based GPU path tracer (Vulkan compute)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(clap::Args, Clone)]
struct DeviceArgs {
    /// Vulkan device: index from `caustica devices` or part of its name. Default: a discrete GPU,
    /// else any GPU, CPU implementations (lavapipe) last.
    #[arg(long)]
    device: Option<String>,
    /// Enable the Khronos validation layer and fail on any message it reports.
    #[arg(long)]
    validation: bool,
}

impl DeviceArgs {
    fn context(&self) -> Result<GpuContext> {
        GpuContext::new(&ContextOptions { device: self.device.clone(), validation: self.validation })
    }
}

/// How the image is written: exposure, tone curve and depth apply to PNG only (PFM and EXR stay linear).
#[derive(clap::Args, Clone)]
struct OutputArgs {
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0)]
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
        #[command(flatten)]
        output_args: OutputArgs,
        /// No progress bar or summary.
        #[arg(short, long)]
        quiet: bool,
        #[command(flatten)]
        gpu: DeviceArgs,
    },
    /// List the Vulkan devices.
    Devices,
    /// Compare an image with a reference (PFM or EXR): relative MSE, mean absolute error and the
    /// ratio of their means.
    Compare {
        image: PathBuf,
        reference: PathBuf,
    },
    /// Render a scene (default: the Cornell box) and report geometry, BVH build, memory, and samples
    /// and rays per second.
    Bench {
        #[arg(long, default_value_t = 256)]
        width: u32,
        #[arg(long, default_value_t = 256)]
        height: u32,
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Scene to measure instead of the built-in Cornell box.
        scene: Option<PathBuf>,
        #[command(flatten)]
        gpu: DeviceArgs,
    },
}

fn load_scene(path: Option<&PathBuf>) -> Result<Scene> {
    match path {
        Some(p) => Scene::load(p),
        None => Ok(Scene::default_scene()),
    }
}

fn apply_overrides(scene: &mut Scene, width: Option<u32>, height: Option<u32>, spp: Option<u32>) -> Result<()> {
    scene.film.width = width.unwrap_or(scene.film.width);
    scene.film.height = height.unwrap_or(scene.film.height);
    scene.film.spp = spp.unwrap_or(scene.film.spp);
    check_film(&scene.film).context("command-line film settings")
}

fn progress_bar(total: u32, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(total as u64);
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} spp  {per_sec}  ETA {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar
}

fn render(scene: Scene, output: PathBuf, seed: u32, output_args: &OutputArgs, quiet: bool, gpu: &DeviceArgs) -> Result<()> {
    // Fail on a bad output path before spending minutes rendering.
    caustica::image::check_output_path(&output)?;
    let ctx = gpu.context()?;
    let started = Instant::now();
    let mut renderer = Renderer::new(&ctx, &scene, seed)?;
    let bar = progress_bar(scene.film.spp, quiet);
    renderer.render(scene.film.spp, |done| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    let image = renderer.image()?;
    write_image_with(&output, &image, &output_args.options())?;
    if !quiet {
        let pixel_samples = scene.film.width as f64 * scene.film.height as f64 * renderer.samples_done as f64;
        eprintln!(
            "wrote {} ({}x{}, {} spp) in {:.2} s on {}: {:.2} Msamples/s, {:.1} Mrays/s",
            output.display(),
            scene.film.width,
            scene.film.height,
            renderer.samples_done,
            started.elapsed().as_secs_f64(),
            ctx.info.name,
            pixel_samples / renderer.seconds / 1e6,
            renderer.rays_traced as f64 / renderer.seconds / 1e6,
        );
    }
    Ok(())
}

fn bench(mut scene: Scene, width: u32, height: u32, spp: u32, gpu: &DeviceArgs) -> Result<()> {
    apply_overrides(&mut scene, Some(width), Some(height), Some(spp))?;
    let ctx = gpu.context()?;
    let setup = Instant::now();
    let mut renderer = Renderer::new(&ctx, &scene, 1)?;
    let setup_s = setup.elapsed().as_secs_f64();
    // Warm-up pass: first-dispatch costs (pipeline caches, page faults) are not throughput.
    renderer.render(1, |_| {})?;
    let (rays0, secs0, spp0) = (renderer.rays_traced, renderer.seconds, renderer.samples_done);
    renderer.render(spp, |_| {})?;
    let seconds = renderer.seconds - secs0;
    let samples = (renderer.samples_done - spp0) as f64 * width as f64 * height as f64;
    let rays = (renderer.rays_traced - rays0) as f64;
    println!("scene:        {}", scene.name);
    println!("device:       {} ({})", ctx.info.name, ctx.info.kind.label());
    println!("image:        {width}x{height}, {spp} spp");
    print_geometry(&renderer.geometry);
    println!("setup:        {setup_s:.3} s (load excluded: BVH, upload, kernel compile)");
    println!("render:       {seconds:.3} s");
    println!("samples/s:    {:.3} M", samples / seconds / 1e6);
    println!("rays/s:       {:.3} M", rays / seconds / 1e6);
    println!("rays/sample:  {:.2}", rays / samples);
    Ok(())
}

fn print_geometry(g: &GeometryReport) {
    let a = &g.acceleration;
    let mib = |b: u64| b as f64 / 1048576.0;
    println!(
        "geometry:     {} primitives, {} mesh triangles stored, {} in the world, {} instances, {} lights",
        a.primitives, a.mesh_triangles, a.instanced_triangles, a.instances, g.lights
    );
    let rate = a.mesh_triangles as f64 / a.build_seconds.max(1e-9) / 1e6;
    println!("BVH build:    {:.3} s ({rate:.2} M triangles/s), {} nodes", a.build_seconds, a.nodes);
    if let Some(b) = &a.largest_mesh {
        println!("largest mesh: {} nodes, depth {}, SAH cost {:.2}", b.nodes, b.max_depth, b.sah_cost);
    }
    if let Some(t) = &a.top {
        println!("top level:    {} nodes, depth {}, SAH cost {:.2}", t.nodes, t.max_depth, t.sah_cost);
    }
    let per_triangle = if a.mesh_triangles > 0 { format!(", {:.1} B/triangle", a.bytes_per_triangle(g.geometry_bytes)) } else { String::new() };
    println!("GPU memory:   {:.1} MiB geometry + BVH{per_triangle}, {:.1} MiB textures, {:.1} MiB in all", mib(g.geometry_bytes), mib(g.texture_bytes), mib(g.gpu_bytes));
}

fn run() -> Result<()> {
    match Cli::parse().command {
        Command::Render { scene, output, spp, width, height, seed, output_args, quiet, gpu } => {
            let mut s = load_scene(scene.as_ref())?;
            apply_overrides(&mut s, width, height, spp)?;
            render(s, output, seed, &output_args, quiet, &gpu)
        }
        Command::Compare { image, reference } => {
            let (a, b) = (caustica::image::read_image(&image)?, caustica::image::read_image(&reference)?);
            let c = caustica::image::compare(&a, &b, (&image.display().to_string(), &reference.display().to_string()))?;
            println!("relative MSE:        {:.6e}", c.relative_mse);
            println!("mean absolute error: {:.6e}", c.mean_absolute_error);
            println!("ratio of means:      {:.6}", c.mean_ratio);
            Ok(())
        }
        Command::Devices => {
            let devices = list_devices()?;
            if devices.is_empty() {
                println!("no Vulkan devices found");
            }
            for d in devices {
                println!(
                    "{}: {} ({}, Vulkan {}, {:.0} MiB device-local, max storage buffer {:.0} MiB)",
                    d.index,
                    d.name,
                    d.kind.label(),
                    d.api_version,
                    d.device_local_bytes as f64 / 1048576.0,
                    d.max_storage_buffer_range as f64 / 1048576.0
                );
            }
            Ok(())
        }
        Command::Bench { width, height, spp, scene, gpu } => bench(load_scene(scene.as_ref())?, width, height, spp, &gpu),
    }
}

fn main() {
    if let Err(e) = run() {
        eprintln!("caustica: error: {e:#}");
        std::process::exit(1);
    }
}
