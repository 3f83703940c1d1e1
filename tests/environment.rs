//! Environment lookups on the GPU: the kernel's direction-to-texel mapping for Debevec angular
//! probes and lat-long maps, checked by looking through a camera with a tiny field of view.

mod common;

use caustica::gpu::GpuContext;
use caustica::image::{self, RgbImage};
use caustica::scene::{
    angular_map_uv, Camera, Environment, EnvironmentMap, Film, Filter, Integrator, LightSelection, MapProjection,
    Sampler, Scene,
};
use common::*;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;
use std::path::PathBuf;

/// Radiance the kernel returns for a camera ray along `dir` in an otherwise empty scene.
fn radiance_along(ctx: &GpuContext, environment: &Environment, dir: Vec3) -> [f32; 3] {
    let up = if dir.normalize().y.abs() > 0.9 { Vec3::Z } else { Vec3::Y };
    let scene = Scene {
        name: "environment probe".into(),
        camera: Camera::pinhole(Vec3::ZERO, dir, up, 0.001),
        film: Film { width: 1, height: 1, spp: 1, filter: Filter::Box },
        integrator: Integrator {
            rr_start: 4,
            absorption: None,
            nee: true,
            max_bounces: 16,
            sample_environment: true,
            clamp: None,
            sampler: Sampler::Sobol,
            light_selection: LightSelection::Power,
        },
        materials: vec![],
        shapes: vec![],
        meshes: vec![],
        instances: vec![],
        textures: vec![],
        environment: environment.clone(),
        lights: vec![],
        media: vec![],
        camera_medium: None,
    };
    render(ctx, &scene, 1).pixels[0]
}

fn map(projection: MapProjection, image: RgbImage, rotation_deg: f32) -> Environment {
    Environment::Map(EnvironmentMap { projection, image, intensity: 1.0, rotation_deg })
}

/// An angular map whose texels hold their own (u, v) + 2, so the radiance seen names the texel.
/// Bilinear filtering of a linear ramp is exact, so the lookup returns the continuous (u, v).
fn coordinate_probe(size: u32) -> RgbImage {
    angular_probe(size, |u, v| [u + 2.0, v + 2.0, 1.0])
}

#[test]
fn angular_probe_maps_known_directions_to_debevec_coordinates() {
    let (_lock, ctx) = gpu();
    let env = map(MapProjection::Angular, coordinate_probe(256), 0.0);
    let cases = [
        (Vec3::new(0.0, 0.0, -1.0), Vec2::new(0.0, 0.0)), // forward: the centre
        (Vec3::new(1.0, 0.0, 0.0), Vec2::new(0.5, 0.0)),  // right: half way out, to the right
        (Vec3::new(-1.0, 0.0, 0.0), Vec2::new(-0.5, 0.0)),
        (Vec3::new(0.0, 1.0, 0.0), Vec2::new(0.0, 0.5)), // up: half way out, upwards
        (Vec3::new(0.0, -1.0, 0.0), Vec2::new(0.0, -0.5)),
        (Vec3::new(1.0, 0.0, 1.0), Vec2::new(0.75, 0.0)), // 135 degrees from forward
        (Vec3::new(0.0, 1.0, -1.0), Vec2::new(0.0, 0.25)), // 45 degrees up
    ];
    for (dir, expected) in cases {
        let seen = radiance_along(&ctx, &env, dir);
        let uv = Vec2::new(seen[0] - 2.0, seen[1] - 2.0);
        assert!(
            (uv - expected).length() < 2e-3,
            "direction {dir:?}: kernel looked up (u, v) = {uv:?}, expected {expected:?}"
        );
        let host = angular_map_uv(dir.normalize());
        assert!((host - expected).length() < 1e-5, "host mapping of {dir:?} is {host:?}");
    }
}

#[test]
fn angular_probe_never_uses_texels_outside_the_circle() {
    // Texels outside the disk are bright; inside 1. Directions near straight back read the rim.
    let (_lock, ctx) = gpu();
    let size = 64;
    let img = angular_probe(size, |u, v| if u * u + v * v > 1.0 { [1000.0; 3] } else { [1.0; 3] });
    assert!(img.pixels.iter().any(|p| p[0] == 1000.0), "the test probe has texels outside the circle");
    // Through the scene loader, which prepares probes for the kernel.
    let dir = temp_dir("rim");
    image::pfm::write(&dir.join("rim.pfm"), &img).unwrap();
    let scene_text =
        "[camera]\nposition = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\n[environment]\nprobe = \"rim.pfm\"\n";
    std::fs::write(dir.join("rim.toml"), scene_text).unwrap();
    let loaded = Scene::load(&dir.join("rim.toml")).expect("scene with probe loads");
    for k in 0..16 {
        let a = k as f32 / 16.0 * 2.0 * PI;
        // 2 degrees from straight back, all around.
        let back = Vec3::new(a.cos() * 0.035, a.sin() * 0.035, 1.0);
        let seen = radiance_along(&ctx, &loaded.environment, back);
        assert!(
            seen.iter().all(|&c| (c - 1.0).abs() < 1e-4),
            "direction {back:?} saw {seen:?}: a texel outside the circle was used"
        );
    }
}

/// A lat-long map whose texels hold (u, v) + 1 of their centres.
fn coordinate_latlong(w: u32, h: u32) -> RgbImage {
    let mut img = RgbImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            img.set(x, y, [(x as f32 + 0.5) / w as f32 + 1.0, (y as f32 + 0.5) / h as f32 + 1.0, 1.0]);
        }
    }
    img
}

#[test]
fn latlong_map_maps_known_directions() {
    let (_lock, ctx) = gpu();
    let env = map(MapProjection::LatLong, coordinate_latlong(512, 256), 0.0);
    let cases = [
        (Vec3::new(0.0, 0.0, -1.0), Vec2::new(0.5, 0.5)), // forward: centre of the image
        (Vec3::new(1.0, 0.0, 0.0), Vec2::new(0.75, 0.5)), // right
        (Vec3::new(-1.0, 0.0, 0.0), Vec2::new(0.25, 0.5)), // left
        (Vec3::new(0.0, 1.0, -1.0), Vec2::new(0.5, 0.25)), // 45 degrees up
        (Vec3::new(0.0, -1.0, -1.0), Vec2::new(0.5, 0.75)),
    ];
    for (dir, expected) in cases {
        let seen = radiance_along(&ctx, &env, dir);
        let uv = Vec2::new(seen[0] - 1.0, seen[1] - 1.0);
        assert!(
            (uv - expected).length() < 2e-3,
            "direction {dir:?}: kernel looked up (u, v) = {uv:?}, expected {expected:?}"
        );
    }
}

#[test]
fn rotation_turns_the_map_about_up_by_the_right_hand_rule() {
    // Rotating by +90 degrees about +y carries what was on the right (+x) to the front (-z).
    let (_lock, ctx) = gpu();
    let env = map(MapProjection::LatLong, coordinate_latlong(512, 256), 90.0);
    let seen = radiance_along(&ctx, &env, Vec3::new(0.0, 0.0, -1.0));
    assert!(
        (seen[0] - 1.75).abs() < 2e-3 && (seen[1] - 1.5).abs() < 2e-3,
        "front saw (u, v) = ({}, {})",
        seen[0] - 1.0,
        seen[1] - 1.0
    );
}

fn data_dir() -> Option<PathBuf> {
    let dir = PathBuf::from(std::env::var("CAUSTICA_DATA").unwrap_or_else(|_| "../shared/data".into()));
    if dir.join("probes/grace_probe_512.pfm").exists() {
        Some(dir)
    } else {
        eprintln!("SKIPPED: real light probe tests need CAUSTICA_DATA (default ../shared/data) with probes/grace_probe_512.pfm");
        None
    }
}

#[test]
fn grace_probe_texel_centres_are_seen_in_their_directions() {
    let Some(data) = data_dir() else { return };
    let (_lock, ctx) = gpu();
    let probe = image::read_image(&data.join("probes/grace_probe_512.pfm")).expect("grace probe reads");
    let n = probe.width;
    let env = map(MapProjection::Angular, probe.clone(), 0.0);
    // Texel centres on a grid inside the disk: the camera looking along each texel's direction
    // must see that texel's value (bilinear filtering at a texel centre returns the texel).
    let mut checked = 0;
    for y in (20..n - 20).step_by(61) {
        for x in (20..n - 20).step_by(53) {
            let (u, v) = texel_centre_uv(x, y, n);
            let r = (u * u + v * v).sqrt();
            if !(1e-3..=0.95).contains(&r) {
                continue;
            }
            let (phi, theta) = (PI * r, v.atan2(u));
            let dir = Vec3::new(phi.sin() * theta.cos(), phi.sin() * theta.sin(), -phi.cos());
            let seen = radiance_along(&ctx, &env, dir);
            let want = probe.get(x, y);
            for c in 0..3 {
                assert!(
                    (seen[c] - want[c]).abs() <= 2e-2 * want[c].abs() + 1e-3,
                    "texel ({x}, {y}) direction {dir:?}: saw {seen:?}, texel {want:?}"
                );
            }
            checked += 1;
        }
    }
    assert!(checked > 40, "only {checked} texels checked");
}

/// A Radiance `.hdr` (RGBE) lat-long map loads from a scene file like PFM and EXR ones, decoded
/// as (mantissa + 0.5) / 256 x 2^(exponent - 128), and the kernel sees its values.
#[test]
fn radiance_hdr_maps_load_from_scene_files() {
    let dir = temp_dir("env-hdr");
    let (width, height) = (8, 4);
    let mut file = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    for _ in 0..width * height {
        file.extend([64u8, 128, 192, 129]);
    }
    std::fs::write(dir.join("sky.hdr"), file).unwrap();
    let scene = Scene::parse(
        r#"
        camera = { position = [0.0, 0.0, 0.0], look_at = [1.0, 0.0, 0.0], up = [0.0, 1.0, 0.0] }
        environment = { latlong = "sky.hdr" }
        "#,
        "test scene",
        &dir,
    )
    .expect("a scene with an .hdr map loads");
    let expected = [64.5 / 128.0, 128.5 / 128.0, 192.5 / 128.0];
    let Environment::Map(ref map) = scene.environment else { panic!("the environment is a map") };
    assert_eq!((map.image.width, map.image.height), (width, height));
    assert!(map.image.pixels.iter().all(|&p| p == expected), "{:?}", map.image.pixels[0]);
    let (_lock, ctx) = gpu();
    let seen = radiance_along(&ctx, &scene.environment, Vec3::new(1.0, 0.3, -0.2));
    assert!(close(Vec3::from(seen), Vec3::from(expected)), "{seen:?}");
}
