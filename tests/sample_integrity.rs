//! Every sample dispatched is a sample accumulated, on every device. Debian 12's lavapipe (Mesa
//! 22.3) ends a shader invocation's loops after 65,535 iterations in total, silently; before the
//! renderer knew, a tiny image at thousands of samples per pixel lost up to a quarter of them and two
//! identical runs differed. These tests render with many samples per invocation and compare, bit
//! for bit, with the same render split into one-sample dispatches (which no device cuts short), and
//! check that every pixel holds exactly the samples asked for.

mod common;

use caustica::gpu::GpuContext;
use caustica::render::{Renderer, FEW_PRIMITIVES};
use caustica::scene::{Scene, Shape};
use common::gpu;
use glam::Vec3;
use std::path::Path;

/// The accumulation of `spp` samples of `scene`, after `configure` had its say on the renderer.
fn accumulate(
    ctx: &GpuContext,
    scene: &Scene,
    spp: u32,
    configure: impl FnOnce(&mut Renderer),
) -> (Vec<[f32; 4]>, u32) {
    let mut renderer = Renderer::new(ctx, scene, 5).expect("scene uploads");
    configure(&mut renderer);
    renderer.render(spp, |_| {}).expect("render succeeds without validation messages");
    assert_eq!(renderer.samples_done, spp);
    (renderer.accumulation().expect("readback"), renderer.repeated_dispatches)
}

fn assert_every_pixel_holds(accumulation: &[[f32; 4]], spp: u32, what: &str) {
    let short: Vec<usize> = (0..accumulation.len()).filter(|&i| accumulation[i][3] != spp as f32).collect();
    assert!(
        short.is_empty(),
        "{what}: {} of {} pixels do not hold {spp} samples (first: pixel {} with {})",
        short.len(),
        accumulation.len(),
        short[0],
        accumulation[short[0]][3]
    );
}

/// A render with many samples per dispatch against the same render in one-sample dispatches; and,
/// on a device with a loop limit, dispatches sized as if it had none, so that the limit cuts them
/// short and the renderer must notice and repeat them.
fn check_against_one_sample_dispatches(scene: &Scene, spp: u32) {
    let (_lock, ctx) = gpu();
    let (reference, _) = accumulate(&ctx, scene, spp, |r| r.fix_samples_per_dispatch(1));
    assert_every_pixel_holds(&reference, spp, "one-sample dispatches");
    let (planned, repeated) = accumulate(&ctx, scene, spp, |r| r.fix_samples_per_dispatch(spp));
    assert_every_pixel_holds(&planned, spp, "dispatches planned within the loop limit");
    assert!(
        planned == reference,
        "{}: the render planned within the loop limit differs from the one-sample dispatches",
        scene.name
    );
    assert_eq!(repeated, 0, "{}: a dispatch planned within the loop limit was cut short", scene.name);
    let (timed, _) = accumulate(&ctx, scene, spp, |_| {});
    assert!(
        timed == reference,
        "{}: the render in dispatches sized by time differs from the one-sample dispatches",
        scene.name
    );
    let limit = ctx.loop_limit().expect("loop limit probe");
    let (unplanned, repeated) = accumulate(&ctx, scene, spp, |r| {
        r.fix_samples_per_dispatch(spp);
        r.ignore_loop_limit_in_planning();
    });
    assert_every_pixel_holds(&unplanned, spp, "dispatches sized without regard to the loop limit");
    assert!(
        unplanned == reference,
        "{}: dispatches repeated after the loop limit differ from one-sample dispatches",
        scene.name
    );
    match limit {
        // Proves the test reaches the limit it guards against: without the checks, these samples were lost.
        Some(limit) => assert!(
            repeated > 0,
            "{}: no dispatch reached the device's loop limit of {limit}, so the repeat went untested",
            scene.name
        ),
        None => {
            eprintln!("{}: this device has no loop limit; the repeat after one is not exercised here", ctx.info.name)
        }
    }
}

#[test]
fn tiny_image_at_thousands_of_samples_loses_none() {
    let mut scene = Scene::default_scene();
    scene.film.width = 16;
    scene.film.height = 12;
    // The Cornell box's own 8 shapes are tested as straight-line code, with no loop to count: its
    // 2000 samples stay within Mesa 22.3's loop limit. With more shapes than that takes, the kernel
    // walks the BVH, whose loops reach the limit, and the repeat is exercised. The spheres sit
    // behind the camera.
    let behind_the_camera = Shape::Sphere { center: Vec3::new(0.0, 0.0, 10.0), radius: 0.01, material: 0 };
    scene.shapes.resize(FEW_PRIMITIVES + 1, behind_the_camera);
    check_against_one_sample_dispatches(&scene, 2000);
}

#[test]
fn mesh_scene_loses_no_samples() {
    let mut scene = Scene::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_original.toml"))
        .expect("cornell_original loads");
    scene.film.width = 12;
    scene.film.height = 12;
    check_against_one_sample_dispatches(&scene, 384);
}

/// Debian 12's lavapipe (Mesa 22.3) is the device these tests were written for: its limit must be
/// found. Mesa 25's has none.
#[test]
fn loop_limit_probe_finds_the_limit_of_mesa_22_lavapipe() {
    let (_lock, ctx) = gpu();
    let limit = ctx.loop_limit().expect("loop limit probe");
    eprintln!("{} (driver version {}): loop limit {limit:?}", ctx.info.name, ctx.info.driver);
    if let Some(limit) = limit {
        assert!(limit >= 1000, "{}: a loop limit of {limit} iterations is implausibly low", ctx.info.name);
    }
    // Mesa encodes its version as Vulkan's VK_MAKE_VERSION: the major version is the top 10 bits.
    let driver_version =
        u32::from_str_radix(ctx.info.driver.trim_start_matches("0x"), 16).expect("driver version in hex");
    if ctx.info.name.starts_with("llvmpipe") && driver_version >> 22 == 22 {
        assert_eq!(limit, Some(65535), "Mesa 22's lavapipe ends loops after 65,535 iterations");
    }
}

/// An emitter near the top of the float range: one sample is finite, but the sum of a few
/// overflows. The kernel must drop and count the sample that would make the sum infinite, never
/// write an infinite pixel while reporting no non-finite samples.
#[test]
fn sums_that_would_overflow_drop_the_sample_and_count_it() {
    let (_lock, ctx) = gpu();
    let scene = common::parse(
        r#"
        [camera]
        position = [0.0, 0.0, 3.0]
        look_at = [0.0, 0.0, 0.0]
        fov = 30.0
        [film]
        width = 4
        height = 4
        spp = 8
        [materials.hot]
        albedo = [0.0, 0.0, 0.0]
        emission = [1e38, 1e38, 1e38]
        [[quads]]
        origin = [-2.0, -2.0, 0.0]
        edge_u = [4.0, 0.0, 0.0]
        edge_v = [0.0, 4.0, 0.0]
        material = "hot"
        "#,
    );
    let mut renderer = Renderer::new(&ctx, &scene, 1).expect("scene uploads");
    renderer.render(8, |_| {}).expect("render succeeds");
    let accumulation = renderer.accumulation().expect("readback");
    assert!(
        accumulation.iter().all(|a| a.iter().all(|v| v.is_finite())),
        "a pixel's sum overflowed: {:?}",
        accumulation[0]
    );
    assert_every_pixel_holds(&accumulation, 8, "overflowing emitter");
    // 1e38 fits three times below f32::MAX (3.4e38): the fourth sample of every pixel overflows.
    assert_eq!(renderer.nonfinite_samples, 16 * 5, "samples dropped for overflowing the sum");
}
