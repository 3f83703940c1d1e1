//! Shared by the GPU tests: a lavapipe context with validation, scene construction and the
//! statistics that turn sample counts into tolerances.
#![allow(dead_code)]

pub mod chi_square;
pub mod furnace;
pub mod gltf_square;
pub mod two_meshes;
// The library's unit tests' scratch directories, one definition for both.
#[path = "../../src/test_files.rs"]
mod test_files;
#[allow(unused_imports)]
pub use test_files::{file_names, temp_dir, write_file, write_files, ScratchDir, WrittenFiles};

use caustica::gpu::{ContextOptions, GpuContext};
use caustica::image::RgbImage;
use caustica::render::Renderer;
use caustica::scene::Scene;
use std::path::Path;
use std::sync::{Mutex, MutexGuard, Once};

pub const LAVAPIPE_ICD: &str = "/usr/share/vulkan/icd.d/lvp_icd.x86_64.json";

/// Whether the suite runs on the machine's own Vulkan devices (`CAUSTICA_LAVAPIPE=none`, see
/// scripts/test.sh) rather than on lavapipe.
pub fn own_devices() -> bool {
    std::env::var_os("CAUSTICA_LAVAPIPE").is_some_and(|v| v == "none")
}

/// Lavapipe's ICD when the caller has not chosen a driver already (VK_DRIVER_FILES unset) nor
/// asked for the machine's own devices, and Mesa's lavapipe is installed.
pub fn lavapipe_override() -> Option<&'static str> {
    (std::env::var_os("VK_DRIVER_FILES").is_none() && !own_devices() && Path::new(LAVAPIPE_ICD).exists())
        .then_some(LAVAPIPE_ICD)
}

/// The caustica binary of this build, on lavapipe unless the caller chose a driver.
pub fn caustica_command(args: &[&str]) -> std::process::Command {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_caustica"));
    if let Some(icd) = lavapipe_override() {
        cmd.env("VK_DRIVER_FILES", icd);
    }
    cmd.args(args);
    cmd
}

/// Runs the caustica binary to its end.
pub fn caustica(args: &[&str]) -> std::process::Output {
    caustica_command(args).output().expect("run caustica")
}

/// Whether `ctx` ends shader loops early (Debian 12's Mesa 22.3), where the kernel's forms that
/// need every loop run to its end (the walk queue, the wavefront) are not compiled: the caller's
/// test says SKIPPED, naming `what` it lacks, and returns.
pub fn loops_end_early(ctx: &GpuContext, what: &str) -> bool {
    let early = ctx.loop_limit().expect("probe").is_some();
    if early {
        eprintln!("SKIPPED: {} ends loops early, so it has no {what}", ctx.info.driver_info);
    }
    early
}

/// Names the environment variable that makes the GPU tests' contexts trace with this traversal
/// (`compute`, `ray-query` or `auto`, as `--traversal`): scripts/test.sh runs the tests that
/// trace rays (geometry, alpha, instancing, furnaces, images) once with each. Unset: `auto`.
pub const TRAVERSAL_VAR: &str = "CAUSTICA_TRAVERSAL";

/// What [`TRAVERSAL_VAR`] asks for.
pub fn traversal_request() -> caustica::gpu::TraversalRequest {
    match std::env::var(TRAVERSAL_VAR) {
        Ok(name) => caustica::gpu::TraversalRequest::parse(&name).unwrap_or_else(|e| panic!("{TRAVERSAL_VAR}: {e}")),
        Err(_) => caustica::gpu::TraversalRequest::Auto,
    }
}

/// A lavapipe context as [`gpu`] makes, tracing with `traversal`; `None` (the caller's test says
/// SKIPPED) where the device cannot.
pub fn gpu_with_traversal(traversal: caustica::gpu::TraversalRequest) -> Option<(MutexGuard<'static, ()>, GpuContext)> {
    let guard = gpu_lock();
    let options = ContextOptions { device: None, validation: true, storage_binding_limit: None, traversal };
    match GpuContext::new(&options) {
        Ok(ctx) => Some((guard, ctx)),
        Err(e) => {
            eprintln!("SKIPPED: {e:#}");
            None
        }
    }
}

/// The GPU tests run on lavapipe everywhere (the same checks on a machine with a GPU), one at a time:
/// lavapipe already uses every core for one dispatch. With `CAUSTICA_LAVAPIPE=none` they run on the
/// device the CLI takes by default.
pub fn gpu() -> (MutexGuard<'static, ()>, GpuContext) {
    gpu_with_storage_limit(None)
}

/// The GPU tests' turn at the device (one at a time), lavapipe chosen where the caller chose no driver.
fn gpu_lock() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    static FORCE: Once = Once::new();
    let guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    FORCE.call_once(|| {
        if let Some(icd) = lavapipe_override() {
            std::env::set_var("VK_DRIVER_FILES", icd);
        }
    });
    guard
}

/// As [`gpu`], with the device's storage-binding range lowered to `limit` bytes when given.
pub fn gpu_with_storage_limit(limit: Option<u64>) -> (MutexGuard<'static, ()>, GpuContext) {
    let guard = gpu_lock();
    let ctx = GpuContext::new(&ContextOptions {
        device: None,
        validation: true,
        storage_binding_limit: limit,
        traversal: traversal_request(),
    })
    .expect("a Vulkan device (install mesa-vulkan-drivers)");
    if std::env::var_os("CI").is_some() {
        assert!(ctx.validating(), "CI must run with the Khronos validation layer (vulkan-validationlayers)");
    }
    (guard, ctx)
}

/// Imports the one-file scene `name` (Mitsuba XML or pbrt-v4, by its extension) with the text
/// `text`, written into a fresh scratch folder tagged `tag`.
pub fn import_text(tag: &str, name: &str, text: &str) -> anyhow::Result<caustica::scene::import::Imported> {
    caustica::scene::import::import(
        &caustica::input_file::InputFiles::anywhere(),
        &write_files(tag, &[(name, text)]),
        &[],
    )
}

/// As [`import_text`], then made a scene, the folder kept until then.
pub fn import_text_scene(tag: &str, name: &str, text: &str) -> anyhow::Result<Scene> {
    let files = write_files(tag, &[(name, text)]);
    let anywhere = caustica::input_file::InputFiles::anywhere();
    caustica::scene::import::import(&anywhere, &files, &[])?.into_scene(&anywhere)
}

/// The message of the scene `import_text_scene` must refuse.
pub fn import_text_error(tag: &str, name: &str, text: &str) -> String {
    match import_text_scene(tag, name, text) {
        Ok(_) => panic!("the scene must be refused:\n{text}"),
        Err(e) => format!("{e:#}"),
    }
}

/// Two points or vectors within 1e-5 in every coordinate.
pub fn close(a: glam::Vec3, b: glam::Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

/// A square angular-map probe whose texel at map coordinates (u, v) in [-1, 1]^2 (u right, v up,
/// at the texel centre) has the value `texel(u, v)`.
pub fn angular_probe(size: u32, texel: impl Fn(f32, f32) -> [f32; 3]) -> RgbImage {
    let mut img = RgbImage::new(size, size);
    for y in 0..size {
        for x in 0..size {
            let (u, v) = texel_centre_uv(x, y, size);
            img.set(x, y, texel(u, v));
        }
    }
    img
}

/// Angular-map coordinates of the centre of texel (x, y) of a size x size probe.
pub fn texel_centre_uv(x: u32, y: u32, size: u32) -> (f32, f32) {
    ((x as f32 + 0.5) / size as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / size as f32 * 2.0)
}

pub fn render(ctx: &GpuContext, scene: &Scene, seed: u32) -> RgbImage {
    image_of(Renderer::new(ctx, scene, seed).expect("scene uploads"), scene.film.spp)
}

/// Renders `spp` samples with a renderer already made, and reads the image back.
pub fn image_of(mut renderer: Renderer, spp: u32) -> RgbImage {
    renderer.render(spp, |_| {}).expect("render succeeds without validation messages");
    renderer.image().expect("readback")
}

pub fn parse(toml: &str) -> Scene {
    Scene::parse(toml, "test scene", Path::new(".")).expect("valid test scene")
}

/// A diffuse floor (albedo 0.5, y = 0) under `lights` and a black sky, seen at the origin through
/// a 0.01 degree field of view, so that every pixel sees the same point and the answer is one
/// number. Nothing but the floor can receive light, and the material `lamp` it offers (emission
/// 4, albedo 0) reflects none: the pixel is the direct light alone (next-event estimation, if
/// `nee`, plus emitters hit by BSDF sampling, MIS weighted), albedo / pi x the irradiance.
pub fn floor_point_scene(lights: &str, spp: u32, nee: bool) -> Scene {
    parse(&format!(
        r#"
        camera = {{ position = [0.0, 1.0, 3.0], look_at = [0.0, 0.0, 0.0], fov = 0.01 }}
        film = {{ width = 32, height = 32, spp = {spp} }}
        integrator = {{ nee = {nee} }}
        [materials.floor]
        albedo = [0.5, 0.5, 0.5]
        [materials.lamp]
        albedo = [0.0, 0.0, 0.0]
        emission = [4.0, 4.0, 4.0]
        [[quads]]
        origin = [-50.0, 0.0, 50.0]
        edge_u = [100.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -100.0]
        material = "floor"
        {lights}
        "#
    ))
}

/// The built-in Cornell box (scenes/cornell.toml) at `size` x `size` pixels and `spp` samples.
pub fn cornell(size: u32, spp: u32) -> Scene {
    let mut scene = Scene::default_scene();
    (scene.film.width, scene.film.height, scene.film.spp) = (size, size, spp);
    scene
}

/// Asserts that `image`'s mean luminance is `expected` within 5 standard errors plus `floor`
/// (relative: the rounding of f32 sums and ray offsets), and that this tolerance is below `bias`
/// (relative), the smallest bias the test claims to fail. The standard error comes from the
/// scatter of the pixels: each is an independent estimate (its random numbers are scrambled by
/// pixel).
pub fn assert_mean_is(image: &RgbImage, expected: f64, floor: f64, bias: f64, what: &str) {
    let (mean, stderr) = mean_and_stderr(&image.pixels.iter().map(|&p| luminance(p)).collect::<Vec<_>>());
    let tolerance = 5.0 * stderr + floor * expected;
    eprintln!(
        "{what}: mean {mean:.6}, expected {expected:.6}, difference {:+.4} %, tolerance {:.4} %",
        (mean / expected - 1.0) * 100.0,
        tolerance / expected * 100.0
    );
    assert!(
        tolerance <= bias * expected,
        "{what}: the tolerance {:.3} % no longer resolves a {:.2} % bias: raise the sample count",
        tolerance / expected * 100.0,
        bias * 100.0
    );
    assert!(
        (mean - expected).abs() <= tolerance,
        "{what}: mean {mean:.6}, expected {expected:.6} ({:+.3} %, tolerance {:.3} %)",
        (mean / expected - 1.0) * 100.0,
        tolerance / expected * 100.0
    );
}

/// Asserts that the caustica run `o` failed (exit status 1, as for any bad input or usage error)
/// saying `needle` on stderr.
pub fn fails_with(o: &std::process::Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "exit status {:?}, stderr {stderr}", o.status);
    assert!(stderr.contains(needle), "stderr does not say '{needle}': {stderr}");
}

/// The Rust files below `dir`, at any depth (the source checks: tests/layers.rs,
/// tests/safety_notes.rs).
pub fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

pub fn luminance(p: [f32; 3]) -> f64 {
    (0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]) as f64
}

/// Mean and standard error of `values` about `center` when every value is an independent
/// estimate of `center` (the error of the mean, from the scatter of the values themselves).
pub fn mean_and_stderr(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Per-pixel noise variance of an image rendered with `spp` samples, from two renders with
/// different seeds: Var(a - b) = 2 sigma^2, so the estimate needs no knowledge of the true image.
pub fn pixel_noise_variance(a: &RgbImage, b: &RgbImage) -> f64 {
    let n = a.pixels.len() as f64;
    a.pixels.iter().zip(&b.pixels).map(|(p, q)| (luminance(*p) - luminance(*q)).powi(2)).sum::<f64>() / (2.0 * n)
}

/// Asserts that two independent renders of what should be the same expected image agree: the
/// mean of the per-pixel difference, over the whole image and each quadrant, is within `k`
/// standard errors of zero, the standard error coming from the differences themselves.
pub fn assert_same_mean(a: &RgbImage, b: &RgbImage, k: f64, what: &str) {
    let (w, h) = (a.width, a.height);
    let regions =
        [(0, 0, w, h), (0, 0, w / 2, h / 2), (w / 2, 0, w, h / 2), (0, h / 2, w / 2, h), (w / 2, h / 2, w, h)];
    for (x0, y0, x1, y1) in regions {
        let mut diffs = vec![];
        let mut mean_a = 0.0;
        for y in y0..y1 {
            for x in x0..x1 {
                let (pa, pb) = (luminance(a.get(x, y)), luminance(b.get(x, y)));
                diffs.push(pa - pb);
                mean_a += pa;
            }
        }
        let n = diffs.len() as f64;
        let mean = diffs.iter().sum::<f64>() / n;
        // Under the hypothesis each difference has mean zero, so its second moment is its variance.
        let stderr = (diffs.iter().map(|d| d * d).sum::<f64>() / n / n).sqrt();
        assert!(
            mean.abs() <= k * stderr,
            "{what}: region ({x0},{y0})-({x1},{y1}): mean difference {mean:.5} exceeds {k} standard errors ({stderr:.5}); mean of the first image {:.4}",
            mean_a / n
        );
    }
}

/// An 8-bit sRGB-encoded value as linear, the reference for what textures.glsl decodes.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// The suite's checked-in scenes (`caustica bench --suite`'s list: the built-in Cornell box and
/// scenes/*.toml), each loaded, by name; those that need the missing shared data folder are said
/// SKIPPED and left out.
pub fn checked_in_scenes() -> Vec<(String, Scene)> {
    use caustica::bench::{suite_entries, SuiteEntry};
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut loaded = Vec::new();
    for entry in suite_entries(Some(&scenes), &caustica::scene::data_dir()).expect("the scenes folder lists") {
        match entry {
            SuiteEntry::Skip { name, reason } => eprintln!("SKIPPED {name}: {reason}"),
            SuiteEntry::Run { name, path, .. } => {
                let scene = match path {
                    Some(path) => Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e:#}")),
                    None => Scene::default_scene(),
                };
                loaded.push((name, scene));
            }
        }
    }
    loaded
}
