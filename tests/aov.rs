//! AOVs on lavapipe: in scenes built here, the albedo, normal and depth layers hold the known
//! material albedo, plane normal and ray distance (a mirror shows what it reflects), the sample
//! layer the sample count; the EXR carries them under the documented channel names; the beauty is
//! unchanged by them; resuming and merging keep them bit for bit; bad combinations are refused.

mod common;

use caustica::farm::{snapshot, PartialRender};
use caustica::render::{AovSet, Renderer};
use caustica::scene::{Instance, Mesh, Scene, Texture};
use common::*;
use glam::{Mat4, Vec2, Vec3};
use std::path::Path;

/// A 8x8 render of the built-in scene with `args` added; panics unless it succeeds.
fn render_cli(out: &Path, args: &[&str]) {
    let mut all = vec!["render", "-o", out.to_str().unwrap(), "--width", "8", "--height", "8", "-q", "--validation"];
    all.extend_from_slice(args);
    let o = caustica(&all);
    assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
}

/// Renders `scene` with every AOV, as the partial render an EXR output would hold.
fn render_aovs(scene: &Scene) -> PartialRender {
    let (_lock, ctx) = gpu();
    let mut renderer = Renderer::with_aovs(&ctx, scene, 3, AovSet::ALL).expect("scene uploads");
    renderer.render(scene.film.spp, |_| {}).expect("render succeeds without validation messages");
    snapshot(&renderer).unwrap().unwrap()
}

/// The per-pixel means of a render: albedo, normal, depth and sample count.
struct Layers {
    width: u32,
    albedo: Vec<[f32; 3]>,
    normal: Vec<[f32; 3]>,
    depth: Vec<f32>,
    samples: Vec<f32>,
}

fn layers(p: &PartialRender) -> Layers {
    let samples: Vec<f32> = p.accumulation.iter().map(|a| a[3]).collect();
    let sums = p.aov_sums.as_ref().expect("kernel AOVs were requested");
    Layers {
        width: p.width,
        albedo: sums.albedo(&samples),
        normal: sums.normal(&samples),
        depth: sums.depth(),
        samples,
    }
}

fn close(a: [f32; 3], b: [f32; 3], tolerance: f32) -> bool {
    (0..3).all(|c| (a[c] - b[c]).abs() <= tolerance)
}

/// Direction (not normalised) of the pinhole ray through film point `film` (pixels, y down) of a
/// camera at the origin looking down -z with up +y.
fn ray(scene: &Scene, film: Vec2) -> Vec3 {
    let (w, h) = (scene.film.width as f32, scene.film.height as f32);
    let tan_half = (scene.camera.fov_deg.to_radians() * 0.5).tan();
    Vec3::new((2.0 * film.x / w - 1.0) * tan_half * w / h, (1.0 - 2.0 * film.y / h) * tan_half, -1.0)
}

/// Smallest and largest `f` over a grid on pixel (x, y), corners included: the range a box-filtered
/// mean of a smooth `f` falls in.
fn footprint_range(x: u32, y: u32, f: impl Fn(Vec2) -> f32) -> (f32, f32) {
    let n = 8;
    let values: Vec<f32> = (0..=n * n + 2 * n)
        .map(|i| f(Vec2::new(x as f32 + (i % (n + 1)) as f32 / n as f32, y as f32 + (i / (n + 1)) as f32 / n as f32)))
        .collect();
    (values.iter().copied().fold(f32::INFINITY, f32::min), values.iter().copied().fold(f32::NEG_INFINITY, f32::max))
}

/// Checks every pixel's depth against `distance(film point)` over the pixel's footprint.
fn assert_depth(scene: &Scene, l: &Layers, distance: impl Fn(Vec2) -> f32) {
    for (i, &z) in l.depth.iter().enumerate() {
        let (x, y) = (i as u32 % l.width, i as u32 / l.width);
        let (lo, hi) = footprint_range(x, y, &distance);
        let slack = 1e-5 * hi;
        assert!(
            z >= lo - slack && z <= hi + slack,
            "pixel ({x}, {y}) of {}: depth {z} outside [{lo}, {hi}]",
            scene.name
        );
    }
}

#[test]
fn flat_diffuse_wall_gives_its_albedo_normal_and_distance() {
    // The wall faces away from the camera (front side -z): the normal layer shows the side seen.
    let scene = parse(
        r#"
        camera = { position = [0, 0, 0], look_at = [0, 0, -1], fov = 40 }
        film = { width = 8, height = 8, spp = 4, filter = "box" }
        environment = { color = [1, 1, 1] }
        [materials.wall]
        albedo = [0.2, 0.4, 0.6]
        [[quads]]
        origin = [-5, -5, -2]
        edge_u = [0, 10, 0]
        edge_v = [10, 0, 0]
        material = "wall"
        "#,
    );
    let l = layers(&render_aovs(&scene));
    for (i, (&albedo, &normal)) in l.albedo.iter().zip(&l.normal).enumerate() {
        assert!(close(albedo, [0.2, 0.4, 0.6], 1e-6), "pixel {i}: albedo {albedo:?}");
        assert!(close(normal, [0.0, 0.0, 1.0], 1e-6), "pixel {i}: normal {normal:?}, expected the camera-facing +z");
    }
    assert!(l.samples.iter().all(|&n| n == 4.0), "{:?}", l.samples);
    // The plane z = -2 is 2 |d| away along the ray d with d.z = -1.
    assert_depth(&scene, &l, |film| 2.0 * ray(&scene, film).length());
}

#[test]
fn mirror_shows_the_albedo_and_normal_of_the_wall_it_reflects() {
    // A black mirror in the plane x + z = -2 fills the view and sends the camera's rays towards +x,
    // onto a wall at x = 3 facing them; the depth stays that of the mirror, the first hit.
    let scene = parse(
        r#"
        camera = { position = [0, 0, 0], look_at = [0, 0, -1], fov = 20 }
        film = { width = 8, height = 8, spp = 4, filter = "box" }
        environment = { color = [1, 1, 1] }
        [materials.mirror]
        albedo = [0, 0, 0]
        reflectivity = 1.0
        [materials.wall]
        albedo = [0.7, 0.1, 0.3]
        [[quads]]
        origin = [-1, -1, -1]
        edge_u = [2, 0, -2]
        edge_v = [0, 2, 0]
        material = "mirror"
        [[quads]]
        origin = [3, -10, -12]
        edge_u = [0, 20, 0]
        edge_v = [0, 0, 20]
        material = "wall"
        "#,
    );
    let l = layers(&render_aovs(&scene));
    for (i, (&albedo, &normal)) in l.albedo.iter().zip(&l.normal).enumerate() {
        assert!(close(albedo, [0.7, 0.1, 0.3], 1e-6), "pixel {i}: albedo {albedo:?}, expected the reflected wall's");
        assert!(close(normal, [-1.0, 0.0, 0.0], 1e-6), "pixel {i}: normal {normal:?}, expected the reflected wall's");
    }
    // s (X, Y, -1) meets x + z = -2 at s = 2 / (1 - X).
    assert_depth(&scene, &l, |film| {
        let d = ray(&scene, film);
        2.0 / (1.0 - d.x) * d.length()
    });
}

#[test]
fn escaping_rays_give_the_clamped_sky_no_normal_and_infinite_depth() {
    let scene = parse(
        r#"
        camera = { position = [0, 0, 0], look_at = [0, 0, -1] }
        film = { width = 4, height = 4, spp = 2 }
        environment = { color = [0.5, 2.0, 0.25] }
        "#,
    );
    let l = layers(&render_aovs(&scene));
    assert!(l.albedo.iter().all(|&a| a == [0.5, 1.0, 0.25]), "{:?}", l.albedo);
    assert!(l.normal.iter().all(|&n| n == [0.0; 3]), "{:?}", l.normal);
    assert!(l.depth.iter().all(|&z| z == f32::INFINITY), "{:?}", l.depth);
}

#[test]
fn textured_mesh_gives_material_albedo_times_texture() {
    let mut scene = parse(
        r#"
        camera = { position = [0, 0, 3], look_at = [0, 0, 0], fov = 20 }
        film = { width = 4, height = 4, spp = 2 }
        environment = { color = [1, 1, 1] }
        [materials.textured]
        albedo = [0.5, 1, 0.8]
        "#,
    );
    let texel = [200u8, 100, 50, 255];
    scene.textures = vec![Texture {
        name: "flat".into(),
        width: 1,
        height: 1,
        texels: vec![texel],
        srgb: true,
        wrap: Default::default(),
    }];
    scene.materials[0].albedo_texture = Some(0);
    let corners =
        [Vec3::new(-1.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(-1.0, -1.0, 0.0)];
    scene.meshes = vec![Mesh {
        name: "square".into(),
        positions: corners.to_vec(),
        normals: vec![Vec3::Z; 4],
        uvs: corners.iter().map(|p| Vec2::new(p.x + 0.5, 0.5 - p.y)).collect(),
        triangles: vec![[0, 3, 2], [0, 2, 1]],
        triangle_materials: vec![0, 0],
        tangents: Vec::new(),
        colors: Vec::new(),
    }];
    scene.instances = vec![Instance { mesh: 0, transform: Mat4::IDENTITY }];
    let expected = [0.5 * srgb_to_linear(texel[0]), srgb_to_linear(texel[1]), 0.8 * srgb_to_linear(texel[2])];
    let l = layers(&render_aovs(&scene));
    for (i, (&albedo, &normal)) in l.albedo.iter().zip(&l.normal).enumerate() {
        assert!(close(albedo, expected, 2e-3), "pixel {i}: albedo {albedo:?}, expected {expected:?}");
        assert!(close(normal, [0.0, 0.0, 1.0], 1e-4), "pixel {i}: normal {normal:?}");
    }
}

#[test]
fn aovs_leave_the_beauty_unchanged_bit_for_bit() {
    let (_lock, ctx) = gpu();
    let mut scene = Scene::default_scene();
    scene.film.width = 16;
    scene.film.height = 16;
    let beauty = |aovs| {
        let mut r = Renderer::with_aovs(&ctx, &scene, 4, aovs).unwrap();
        r.render(3, |_| {}).unwrap();
        assert_eq!(r.aov_sums().unwrap().is_some(), aovs.needs_kernel());
        r.accumulation().unwrap()
    };
    assert!(beauty(AovSet::default()) == beauty(AovSet::ALL), "the AOV kernel changed the beauty");
}

/// With storage bindings of 4 KiB, a 32x32 image's AOV sums span several bindings each, like the
/// accumulation, and come out the same bit for bit.
#[test]
fn aov_sums_split_across_bindings_are_the_same() {
    let mut scene = Scene::default_scene();
    scene.film.width = 32;
    scene.film.height = 32;
    let render = |limit| {
        let (_lock, ctx) = gpu_with_storage_limit(limit);
        let mut r = Renderer::with_aovs(&ctx, &scene, 2, AovSet::ALL).unwrap();
        r.render(2, |_| {}).unwrap();
        let split: Vec<_> = r
            .geometry
            .split_arrays
            .iter()
            .filter(|(name, _)| name.ends_with("sums"))
            .map(|&(_, windows)| windows)
            .collect();
        (split, r.accumulation().unwrap(), r.aov_sums().unwrap().unwrap())
    };
    let (whole, split) = (render(None), render(Some(4096)));
    assert!(
        whole.0.is_empty() && split.0.len() == 2 && split.0.iter().all(|&w| w > 1),
        "windows: {:?} and {:?}",
        whole.0,
        split.0
    );
    assert!(whole.1 == split.1 && whole.2 == split.2, "the split render differs");
}

#[test]
fn exr_output_carries_the_documented_layers() {
    let dir = temp_dir("aov-layers");
    let (all, albedo) = (dir.join("all.exr"), dir.join("albedo.exr"));
    render_cli(&all, &["--spp", "2", "--aov", "all"]);
    render_cli(&albedo, &["--spp", "2", "--aov", "albedo"]);
    let read = |path: &Path| {
        let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
        let layer = &image.layer_data[0];
        let channels: Vec<(String, Vec<f32>)> = layer
            .channel_data
            .list
            .iter()
            .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
            .collect();
        (channels, layer.attributes.other.get(&exr::prelude::Text::from("caustica.aovs")).cloned())
    };
    let names = |channels: &[(String, Vec<f32>)]| {
        channels.iter().map(|(n, _)| n.clone()).filter(|n| !n.starts_with("accumulation")).collect::<Vec<_>>()
    };
    let (channels, attribute) = read(&all);
    // EXR stores channels sorted by name.
    let expected =
        ["B", "G", "R", "Z", "albedo.B", "albedo.G", "albedo.R", "normal.X", "normal.Y", "normal.Z", "samples.Y"];
    assert_eq!(names(&channels), expected);
    assert_eq!(attribute, Some(exr::prelude::AttributeValue::Text("albedo,normal,depth,samples".into())));
    let samples = &channels.iter().find(|(n, _)| n == "samples.Y").unwrap().1;
    assert!(samples.len() == 64 && samples.iter().all(|&n| n == 2.0), "{samples:?}");
    // The middle of the image looks into the Cornell box; at the rim some rays pass it by.
    let depth = &channels.iter().find(|(n, _)| n == "Z").unwrap().1;
    assert!(
        depth.iter().all(|&z| z > 0.0) && (2..6).all(|y| (2..6).all(|x| depth[y * 8 + x].is_finite())),
        "{depth:?}"
    );
    assert_eq!(
        caustica::image::read_image(&all).unwrap(),
        PartialRender::read(&all).unwrap().image(),
        "viewers still get the beauty"
    );
    assert_eq!(names(&read(&albedo).0), ["B", "G", "R", "albedo.B", "albedo.G", "albedo.R"]);
}

#[test]
fn resumed_and_merged_renders_keep_the_aovs_bit_for_bit() {
    let dir = temp_dir("aov-farm");
    let path = |name: &str| dir.join(name);
    let (full, part, resumed, checkpoint) = (path("full.exr"), path("part.exr"), path("resumed.exr"), path("ck.exr"));
    let ck = checkpoint.to_str().unwrap();
    render_cli(&full, &["--spp", "5", "--seed", "5", "--aov", "all"]);
    render_cli(&part, &["--spp", "2", "--seed", "5", "--aov", "all", "--checkpoint", ck]);
    // No --aov: the checkpoint says which AOVs it holds.
    render_cli(&resumed, &["--spp", "5", "--seed", "5", "--resume", "--checkpoint", ck]);
    let (a, b) = (PartialRender::read(&full).unwrap(), PartialRender::read(&resumed).unwrap());
    assert!(a.aov_sums.is_some());
    assert!(a == b, "2 spp resumed to 5 differs from 5 in one go");

    // Partials of one sample each add up in the kernel's own order.
    let ones: Vec<_> = (0..3).map(|k| path(&format!("one{k}.exr"))).collect();
    for (k, one) in ones.iter().enumerate() {
        render_cli(one, &["--spp", "1", "--sample-offset", &k.to_string(), "--aov", "all"]);
    }
    let (whole, merged) = (path("whole.exr"), path("merged.exr"));
    render_cli(&whole, &["--spp", "3", "--aov", "all"]);
    let o = caustica(&[
        "merge",
        "-q",
        "-o",
        merged.to_str().unwrap(),
        ones[1].to_str().unwrap(),
        ones[0].to_str().unwrap(),
        ones[2].to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        PartialRender::read(&whole).unwrap() == PartialRender::read(&merged).unwrap(),
        "3 x 1 spp merged differs from 3 spp"
    );
}

#[test]
fn bad_aov_combinations_fail_with_a_message() {
    let dir = temp_dir("aov-bad");
    let path = |name: &str| dir.join(name).to_str().unwrap().to_owned();
    fails_with(&caustica(&["render", "-o", &path("x.png"), "--aov", "albedo"]), "the output must be .exr, not");
    fails_with(&caustica(&["render", "-o", &path("x.exr"), "--aov", "albedo,variance"]), "unknown AOV 'variance'");
    let (with, without, ck) = (path("with.exr"), path("without.exr"), path("ck.exr"));
    render_cli(Path::new(&with), &["--spp", "1", "--aov", "all", "--checkpoint", &ck]);
    render_cli(Path::new(&without), &["--spp", "1", "--sample-offset", "1"]);
    let merged = path("merged.exr");
    fails_with(
        &caustica(&["merge", "-o", &merged, &with, &without]),
        "different AOVs (none, not albedo,normal,depth,samples)",
    );
    assert!(!Path::new(&merged).exists(), "a refused merge wrote its output");
    let resume = [
        "render",
        "-o",
        &path("more.exr"),
        "--width",
        "8",
        "--height",
        "8",
        "--spp",
        "2",
        "--resume",
        "--checkpoint",
        &ck,
        "--aov",
        "albedo",
    ];
    fails_with(&caustica(&resume), "cannot resume: different AOVs (albedo,normal,depth,samples, not albedo)");
    let png = path("more.png");
    let to_png = ["render", "-o", &png, "--width", "8", "--height", "8", "--spp", "2", "--resume", "--checkpoint", &ck];
    fails_with(
        &caustica(&to_png),
        "the checkpoint's AOVs (albedo,normal,depth,samples): AOVs are layers of an EXR file, so the output must be .exr",
    );
}
