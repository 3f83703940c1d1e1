//! Participating media (scene/medium.rs, shaders/medium.glsl, medium_path.glsl, phase.glsl)
//! against closed forms, on lavapipe: transmittance through a slab per channel, a furnace of an
//! albedo-1 medium, single scattering under a directional light, next-event estimation against
//! phase sampling through null boundaries and media, and Henyey-Greenstein sampling by a chi-square
//! test on the real GLSL. Media are bounded by `type = "null"` materials, so every test also runs
//! the medium stack and the shadow rays' passage through null boundaries.

mod common;

use caustica::gpu::{compile_compute, Binding, Buffer, BufferKind, ComputeKernel};
use caustica::image::RgbImage;
use caustica::render::{assemble_with_kernel_files, SceneData, SceneFeatures, TEXTURE_BUDGET_BYTES};
use caustica::scene::grid_volume::vol_bytes;
use caustica::scene::Scene;
use common::chi_square::chi_square;
use common::*;
use std::f64::consts::PI;
use std::path::Path;

/// Per channel: the image's mean over the pixels in `region` (all where None) must be `expected`
/// within five standard errors (from the scatter of its independent pixels) plus 1e-3 relative,
/// and that tolerance must be below `resolution` x expected: the smallest relative error the
/// check is sure to see.
fn assert_channel_means(
    image: &RgbImage,
    region: Option<&dyn Fn(u32, u32) -> bool>,
    expected: [f64; 3],
    resolution: f64,
    what: &str,
) {
    for (c, &expected_c) in expected.iter().enumerate() {
        let mut values = vec![];
        for y in 0..image.height {
            for x in 0..image.width {
                if region.is_none_or(|inside| inside(x, y)) {
                    values.push(image.get(x, y)[c] as f64);
                }
            }
        }
        let (mean, stderr) = mean_and_stderr(&values);
        let tolerance = 5.0 * stderr + 1e-3 * expected_c;
        eprintln!("{what}: channel {c}: mean {mean:.5} +- {stderr:.5}, expected {:.5}", expected_c);
        assert!(
            tolerance < resolution * expected_c,
            "{what}: channel {c}: too noisy to resolve {resolution}: tolerance {tolerance:.2e}"
        );
        assert!(
            (mean - expected_c).abs() <= tolerance,
            "{what}: channel {c}: mean {mean:.5} +- {stderr:.5}, expected {:.5}",
            expected_c
        );
    }
}

/// Camera below the origin looking up +y through 2 degrees (every pixel within 1.4 degrees of
/// normal incidence: path lengths within 3e-4 of the axis's), `integrator` and `sky`; `rest` is
/// the scene's media, materials and shapes.
fn view_up(size: u32, spp: u32, integrator: &str, sky: [f32; 3], rest: &str) -> Scene {
    parse(&format!(
        r#"
        camera = {{ position = [0.0, -3.0, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = 2.0 }}
        film = {{ width = {size}, height = {size}, spp = {spp} }}
        integrator = {{ {integrator} }}
        environment = {{ color = {sky:?} }}
        {rest}
        "#
    ))
}

/// A slab between y = 0 and y = `d`, bounded by null quads facing out, filled with `medium` (its
/// type and coefficients).
fn slab(d: f32, medium: &str) -> String {
    format!(
        r#"
        [materials.boundary]
        type = "null"
        interior = "slab"
        [[media]]
        name = "slab"
        {medium}
        [[quads]]
        origin = [-2.0, 0.0, -2.0]
        edge_u = [4.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, 4.0]
        material = "boundary"
        [[quads]]
        origin = [-2.0, {d}, -2.0]
        edge_u = [0.0, 0.0, 4.0]
        edge_v = [4.0, 0.0, 0.0]
        material = "boundary"
        "#
    )
}

/// A white sky seen through a purely absorbing slab of depth 0.75 whose sigma_t differs 6-fold
/// between channels: each channel is exp(-sigma_t d), 0.741, 0.407 and 0.165, by free-flight
/// sampling in one channel a path with spectral MIS over all three (no closed form is evaluated by
/// the kernel: each path passes or is absorbed). Fails a 2.5 % error in any channel: a colour bias
/// of the channel choice, a transmittance of the wrong channel or length, a slab entered on the way
/// out (the stack's sides swapped).
#[test]
fn a_chromatic_slab_passes_exp_minus_sigma_t_d_in_each_channel() {
    let (_lock, ctx) = gpu();
    let d = 0.75;
    let sigma_t = [0.4, 1.2, 2.4];
    let scene = view_up(
        32,
        64,
        "",
        [1.0, 1.0, 1.0],
        &slab(d as f32, &format!("type = \"homogeneous\"\nsigma_a = {sigma_t:?}\nsigma_s = [0.0, 0.0, 0.0]")),
    );
    let image = render(&ctx, &scene, 1);
    let expected = sigma_t.map(|s: f64| (-s * d).exp());
    assert_channel_means(&image, None, expected, 0.025, "absorbing slab");
}

/// An albedo-1 medium inside a null sphere, under a uniform white sky, seen from outside: a
/// furnace, every pixel 1 in every channel whatever the medium (energy is conserved, the field
/// uniform). The medium is chromatic (optical radius 1, 3 and 6) and forward scattering (g 0.5),
/// so paths scatter many times with the channel of their distances fixed: this is where spectral
/// MIS must weigh a whole path's pdfs, not each event's. Fails a 2.5 % error in the mean of any
/// channel over the sphere's pixels (losing or gaining energy per scattering, a phase function
/// that is not normalised, per-event spectral weights).
#[test]
fn an_albedo_one_sphere_under_a_uniform_sky_is_the_sky_in_every_channel() {
    let (_lock, ctx) = gpu();
    let size = 32;
    let scene = parse(&format!(
        r#"
        camera = {{ position = [0.0, 0.0, 4.0], look_at = [0.0, 0.0, 0.0], fov = 20.0 }}
        film = {{ width = {size}, height = {size}, spp = 96 }}
        environment = {{ color = [1.0, 1.0, 1.0] }}
        [[media]]
        name = "cloud"
        type = "homogeneous"
        sigma_t = [1.0, 3.0, 6.0]
        albedo = [1.0, 1.0, 1.0]
        phase = "hg"
        g = 0.5
        [materials.boundary]
        type = "null"
        interior = "cloud"
        [[spheres]]
        center = [0.0, 0.0, 0.0]
        radius = 1.0
        material = "boundary"
        "#
    ));
    let image = render(&ctx, &scene, 1);
    // The pixels whose centres see the sphere (radius 1 at distance 4 through 20 degrees: tan of
    // the half angle 0.258 against the sphere's 0.2582 / image half width 0.1763).
    let inside = |x: u32, y: u32| {
        let (u, v) = ((x as f64 + 0.5) / size as f64 * 2.0 - 1.0, (y as f64 + 0.5) / size as f64 * 2.0 - 1.0);
        (u * u + v * v).sqrt() * (10f64.to_radians().tan()) < 0.9 * (1.0f64 / 15f64.sqrt())
    };
    assert_channel_means(&image, Some(&inside), [1.0; 3], 0.025, "albedo-1 furnace");
}

/// A 4 x 4 x 4 `.vol` grid of `value` everywhere (its own box the unit cube).
fn constant_grid(value: f32) -> Vec<u8> {
    vol_bytes([4, 4, 4], (glam::Vec3::ZERO, glam::Vec3::ONE), &[value; 64])
}

/// The chromatic slab of `a_chromatic_slab_...` as heterogeneous media: a constant grid (density
/// 0.5, coefficients doubled) must give exp(-sigma_t d) as the homogeneous slab does, and a grid
/// whose density ramps along the slab's depth (8 cells, 0.25 to 2) exp(-sigma_t tau), tau the
/// integral of its trilinear interpolation (linear between the cells' centres, constant beyond
/// the outermost). Fails a 2.5 % error in any channel: a tracking step at the wrong rate, a
/// density read from the wrong cell or axis (the ramp along x or z gives the grid's mean), a grid
/// placed off its bounds.
#[test]
fn density_grids_pass_the_transmittance_of_their_optical_depth() {
    let (_lock, ctx) = gpu();
    let d = 0.75;
    let sigma_t = [0.4, 1.2, 2.4];
    let medium = |file: &Path, sigma: [f64; 3]| {
        format!(
            "type = \"heterogeneous\"\ndensity = \"{}\"\nbounds = [[-2.0, 0.0, -2.0], [2.0, {d}, 2.0]]\nsigma_a = {sigma:?}\nsigma_s = [0.0, 0.0, 0.0]",
            file.display()
        )
    };
    let constant = write_file("media-grid", "constant.vol", constant_grid(0.5));
    let scene = view_up(32, 64, "", [1.0; 3], &slab(d as f32, &medium(&constant, sigma_t.map(|s| 2.0 * s))));
    let expected = sigma_t.map(|s: f64| (-s * d).exp());
    assert_channel_means(&render(&ctx, &scene, 1), None, expected, 0.025, "constant grid");
    // Density by cell along y: 0.25, 0.5, ..., 2 (the grid's y is the slab's depth).
    let ny = 8;
    let ramp: Vec<f32> = (0..2 * ny * 2).map(|i| 0.25 * ((i / 2) % ny + 1) as f32).collect();
    let ramp_file =
        write_file("media-grid", "ramp.vol", vol_bytes([2, ny as u32, 2], (glam::Vec3::ZERO, glam::Vec3::ONE), &ramp));
    // tau / d: the mean over the depth of the interpolated density: the outer half cells at
    // the end values, linear between the centres (trapezoids).
    let values: Vec<f64> = (0..ny).map(|j| 0.25 * (j + 1) as f64).collect();
    let inner: f64 = values.windows(2).map(|w| 0.5 * (w[0] + w[1])).sum();
    let mean_density = (0.5 * values[0] + inner + 0.5 * values[ny - 1]) / ny as f64;
    let scene = view_up(32, 128, "", [1.0; 3], &slab(d as f32, &medium(&ramp_file, sigma_t)));
    let expected = sigma_t.map(|s: f64| (-s * mean_density * d).exp());
    assert_channel_means(&render(&ctx, &scene, 1), None, expected, 0.025, "density ramp");
}

/// Single scattering in a slab of depth d = 0.2 (null boundaries, sigma_t 0.5, 1 and 2, albedo 0.8,
/// Henyey-Greenstein g = 0.5) under a directional light of irradiance 1 shining down at the camera
/// below, the sky black, paths of at most two segments: light scattered once towards the camera
/// anywhere in the slab has crossed it once in all, so each channel is
/// albedo sigma_t d exp(-sigma_t d) p(g, cos 0), p(0.5, 1) = 1.5 / pi. Next-event estimation from
/// points in the medium through a null boundary is the only way light arrives. Fails a 2.5 % error
/// in any channel: a phase function evaluated at the wrong angle (backward, 1/27 of it), a shadow
/// ray attenuated over the wrong length or not at all (1.1 to 1.5x), the scattering coefficient in
/// place of sigma_t.
#[test]
fn single_scattering_in_a_thin_slab_matches_its_integral() {
    let (_lock, ctx) = gpu();
    let (d, albedo, g): (f64, f64, f64) = (0.2, 0.8, 0.5);
    let sigma_t = [0.5, 1.0, 2.0];
    let lights = r#"
        [[lights]]
        type = "directional"
        direction = [0.0, -1.0, 0.0]
        irradiance = [1.0, 1.0, 1.0]
        "#;
    let coefficients = format!("albedo = [{albedo}, {albedo}, {albedo}]\nphase = \"hg\"\ng = {g}");
    let phase = (1.0 - g * g) / (4.0 * PI * (1.0 - g).powi(3));
    let expected = sigma_t.map(|s: f64| albedo * s * d * (-s * d).exp() * phase);
    let homogeneous = format!("type = \"homogeneous\"\nsigma_t = {sigma_t:?}\n{coefficients}");
    let scene = view_up(32, 64, "max_bounces = 2", [0.0; 3], &(slab(d as f32, &homogeneous) + lights));
    assert_channel_means(&render(&ctx, &scene, 1), None, expected, 0.025, "single scattering");
    // The same medium as a constant grid of density 0.5 at twice the coefficients: delta tracking
    // to the scattering point, ratio tracking of the shadow ray.
    let grid = write_file("media-grid", "constant.vol", constant_grid(0.5));
    let sigma_2 = sigma_t.map(|s| 2.0 * s);
    let heterogeneous = format!(
        "type = \"heterogeneous\"\ndensity = \"{}\"\nbounds = [[-2.0, 0.0, -2.0], [2.0, {d}, 2.0]]\nsigma_t = {sigma_2:?}\n{coefficients}",
        grid.display()
    );
    let scene = view_up(32, 192, "max_bounces = 2", [0.0; 3], &(slab(d as f32, &heterogeneous) + lights));
    assert_channel_means(&render(&ctx, &scene, 1), None, expected, 0.025, "single scattering in a constant grid");
}

/// A closed box whose six walls emit radiance 1 inwards and reflect nothing, filled with albedo-1
/// fog the camera is in, with a denser chromatic, back-scattering albedo-1 medium inside a null
/// sphere: a furnace lit by its walls, every pixel 1 in every channel. Light reaches the media's
/// points both by next-event estimation (MIS-weighted against phase sampling) and by phase
/// sampling hitting a wall, and the walls' light passes the sphere's null boundary both ways.
/// Fails a 2.5 % error in the mean of any channel: a light sample from a medium counted without its
/// MIS weight (twice what phase sampling also finds), a wall's pdf from the wrong distance after a
/// null boundary, a shadow ray out of the sphere attenuated by the wrong medium.
#[test]
fn an_albedo_one_fog_in_an_emitting_box_is_the_walls_radiance() {
    let (_lock, ctx) = gpu();
    // Six quads of the box [-1, 1]^3, each facing in (edge_u x edge_v along the inward normal).
    let walls = [
        ([-1.0, -1.0, -1.0], [0.0, 0.0, 2.0], [2.0, 0.0, 0.0]),
        ([-1.0, 1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 0.0, 2.0]),
        ([-1.0, -1.0, -1.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]),
        ([-1.0, -1.0, 1.0], [0.0, 2.0, 0.0], [2.0, 0.0, 0.0]),
        ([-1.0, -1.0, -1.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]),
        ([1.0, -1.0, -1.0], [0.0, 0.0, 2.0], [0.0, 2.0, 0.0]),
    ];
    let quads: String = walls
        .iter()
        .map(|(o, u, v)| format!("[[quads]]\norigin = {o:?}\nedge_u = {u:?}\nedge_v = {v:?}\nmaterial = \"wall\"\n"))
        .collect();
    let scene = parse(&format!(
        r#"
        camera = {{ position = [0.0, 0.0, 0.9], look_at = [0.0, 0.0, 0.0], fov = 60.0, medium = "fog" }}
        film = {{ width = 24, height = 24, spp = 64 }}
        [[media]]
        name = "fog"
        type = "homogeneous"
        sigma_t = [0.8, 1.0, 1.4]
        albedo = [1.0, 1.0, 1.0]
        phase = "hg"
        g = 0.5
        [[media]]
        name = "cloud"
        type = "homogeneous"
        sigma_t = [3.0, 5.0, 8.0]
        albedo = [1.0, 1.0, 1.0]
        phase = "hg"
        g = -0.4
        [materials.boundary]
        type = "null"
        interior = "cloud"
        [materials.wall]
        albedo = [0.0, 0.0, 0.0]
        emission = [1.0, 1.0, 1.0]
        [[spheres]]
        center = [0.0, 0.0, -0.2]
        radius = 0.4
        material = "boundary"
        {quads}
        "#
    ));
    for (what, scene) in [
        ("with NEE", scene.clone()),
        ("without NEE", {
            let mut s = scene;
            s.integrator.nee = false;
            s
        }),
    ] {
        let image = render(&ctx, &scene, 1);
        assert_channel_means(&image, None, [1.0; 3], 0.025, &format!("emitting box {what}"));
    }
}

/// Fog the camera is in, a denser medium inside a null sphere and a glass sphere filled with a
/// third, a diffuse floor and a spherical lamp: rendered with next-event estimation (light samples
/// from surfaces and from points in the media, through null boundaries, MIS-weighted against
/// BSDF and phase sampling) and without (phase and BSDF sampling alone, which hit the lamp through
/// the same boundaries). The two agree in the mean of the image and of each quadrant within four
/// standard errors of their differences; a light sample in a medium weighted 1 (counted twice
/// with the lamp hit by phase sampling) or a lamp's pdf taken from the wrong distance after a null
/// boundary makes them disagree.
#[test]
fn images_with_and_without_next_event_estimation_agree_through_media() {
    let (_lock, ctx) = gpu();
    let scene = |nee: bool| {
        parse(&format!(
            r#"
            camera = {{ position = [0.0, 1.0, 4.0], look_at = [0.0, 0.6, 0.0], fov = 45.0, medium = "fog" }}
            film = {{ width = 24, height = 24, spp = 256 }}
            integrator = {{ nee = {nee} }}
            [[media]]
            name = "fog"
            type = "homogeneous"
            sigma_a = [0.02, 0.03, 0.05]
            sigma_s = [0.2, 0.15, 0.1]
            phase = "hg"
            g = 0.4
            [[media]]
            name = "smoke"
            type = "homogeneous"
            sigma_t = [2.0, 3.0, 4.0]
            albedo = [0.9, 0.8, 0.7]
            phase = "hg"
            g = -0.3
            [[media]]
            name = "milk"
            type = "homogeneous"
            sigma_t = [5.0, 5.0, 5.0]
            albedo = [0.95, 0.95, 0.95]
            [materials.boundary]
            type = "null"
            interior = "smoke"
            [materials.glass]
            transparency = 1.0
            ior = 1.33
            interior = "milk"
            [materials.floor]
            albedo = [0.6, 0.6, 0.6]
            [materials.lamp]
            albedo = [0.0, 0.0, 0.0]
            emission = [6.0, 6.0, 6.0]
            [[spheres]]
            center = [-0.6, 0.5, 0.0]
            radius = 0.5
            material = "boundary"
            [[spheres]]
            center = [0.6, 0.4, 0.3]
            radius = 0.4
            material = "glass"
            [[spheres]]
            center = [0.0, 2.2, -0.5]
            radius = 0.4
            material = "lamp"
            [[quads]]
            origin = [-3.0, 0.0, 3.0]
            edge_u = [6.0, 0.0, 0.0]
            edge_v = [0.0, 0.0, -6.0]
            material = "floor"
            "#
        ))
    };
    let with = render(&ctx, &scene(true), 1);
    let without = render(&ctx, &scene(false), 2);
    assert_same_mean(&with, &without, 4.0, "NEE against phase and BSDF sampling");
}

/// A scene without media or null boundaries gets the surface-only kernel (SCENE_MEDIA 0); one with
/// either gets the medium code.
#[test]
fn only_scenes_with_media_compile_the_medium_code() {
    let features = |scene: &Scene| SceneFeatures::of(&SceneData::new(scene, TEXTURE_BUDGET_BYTES));
    assert!(!features(&Scene::default_scene()).media, "the Cornell box has no media");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let fog = Scene::load(&scenes.join("cornell_fog.toml")).expect("the fog box loads");
    assert!(features(&fog).media);
    let null_only = view_up(
        1,
        1,
        "",
        [0.0; 3],
        &slab(0.5, "type = \"homogeneous\"\nsigma_t = [0.0, 0.0, 0.0]\nalbedo = [0.0, 0.0, 0.0]"),
    );
    assert!(features(&null_only).media, "null boundaries need the medium code even in clear media");
}

/// Bad media and references to them are refused naming the key.
#[test]
fn bad_media_are_refused_naming_the_key() {
    let error = |rest: &str| {
        let text = format!("[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\n{rest}");
        format!("{:#}", Scene::parse(&text, "bad.toml", Path::new(".")).expect_err("refused"))
    };
    let fog =
        "[[media]]\nname = \"fog\"\ntype = \"homogeneous\"\nsigma_a = [0.1, 0.1, 0.1]\nsigma_s = [0.1, 0.1, 0.1]\n";
    for (rest, needle) in [
        (
            "[materials.m]\ntype = \"null\"\ninterior = \"smoke\"\n".to_owned() + fog,
            "materials.m.interior: unknown medium 'smoke' (defined: fog)",
        ),
        (
            "[materials.m]\ntransparency = 1.0\ninterior = \"smoke\"\n".to_owned(),
            "unknown medium 'smoke' (defined: none)",
        ),
        (
            fog.replace("sigma_a = [0.1, 0.1, 0.1]", "sigma_a = [0.1, -0.1, 0.1]"),
            "media[0].sigma_a must be finite and >= 0",
        ),
        (
            fog.replace("sigma_s = [0.1, 0.1, 0.1]", "sigma_s = [0.1, nan, 0.1]"),
            "media[0].sigma_s must be finite and >= 0",
        ),
        (fog.to_owned() + "phase = \"hg\"\ng = -1.0\n", "media[0].g must be in (-1, 1)"),
        (
            fog.to_owned() + "[materials.m]\ntype = \"null\"\ninterior = \"fog\"\nalbedo = [0.5, 0.5, 0.5]\n",
            "takes `interior` and no other key",
        ),
        (
            fog.to_owned() + "[materials.m]\ninterior = \"fog\"\n",
            "materials.m.interior needs materials.m.transparency > 0",
        ),
    ] {
        let message = error(&rest);
        assert!(message.contains(needle), "expected '{needle}' in: {message}");
    }
    let text = format!("[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\nmedium = \"smoke\"\n{fog}");
    let message = format!("{:#}", Scene::parse(&text, "bad.toml", Path::new(".")).expect_err("refused"));
    assert!(message.contains("camera.medium: unknown medium 'smoke'"), "{message}");
}

/// The test kernel of the Henyey-Greenstein chi-square: invocation i samples phase.glsl's
/// sample_phase_hg for `dir` with its own random stream and writes the direction and phase_hg's
/// density for it.
const PHASE_KERNEL: &str = r#"#version 460
#extension GL_EXT_samplerless_texture_functions : require
layout(local_size_x = 64) in;
#include "layout.glsl"
#include "rng.glsl"
#include "sampling.glsl"
#include "phase.glsl"
// dir.xyz = the ray's direction, dir.w = g; info = count, seed.
layout(std430, set = 0, binding = 30) readonly buffer Query { vec4 dir; uvec4 info; } query;
layout(std430, set = 0, binding = 32) writeonly buffer Results { vec4 results[]; };

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= query.info.x) return;
    Rng rng = rng_for_sample(query.info.y, id, 0u, SAMPLER_INDEPENDENT);
    float g = query.dir.w;
    vec3 wi = sample_phase_hg(g, query.dir.xyz, rng_next2(rng));
    results[id] = vec4(wi, phase_hg(g, dot(query.dir.xyz, wi)));
}
"#;

/// Henyey-Greenstein's density at cos_theta, in double precision.
fn hg(g: f64, cos_theta: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// Henyey-Greenstein sampling on the real GLSL for g from strongly backward to strongly forward:
/// 2^20 directions about a direction off every axis, binned over the sphere (40 x 80 bins in world
/// theta and phi, so the frame about the direction is tested too), against the bins' integrals of
/// the closed form (Gauss-Legendre, 3 x 3 nodes a bin), by Pearson's chi-square at a significance
/// of 1e-4 over the cases; and each sample's density from phase_hg against the closed form within
/// 1e-3 relative. A sampled cosine off by its sign, a density normalised to 2 pi instead of 4 pi
/// or evaluated at -cos fail.
#[test]
fn henyey_greenstein_samples_follow_its_density() {
    let (_lock, ctx) = gpu();
    const SAMPLES: u32 = 1 << 20;
    const THETA_BINS: usize = 40;
    const PHI_BINS: usize = 80;
    let cases = [-0.7, 0.0, 0.3, 0.9];
    let significance = 1e-4 / cases.len() as f64;
    let spirv = compile_compute(&assemble_with_kernel_files(PHASE_KERNEL).unwrap()).expect("test kernel compiles");
    let mut query = Buffer::with_data(&ctx, "query", BufferKind::HostStorage, &[0u8; 32]).unwrap();
    let results =
        Buffer::with_data(&ctx, "results", BufferKind::HostStorage, &vec![0u8; SAMPLES as usize * 16]).unwrap();
    let kernel =
        ComputeKernel::new(&ctx, &spirv, &[Binding::whole(30, &query), Binding::whole(32, &results)], 16).unwrap();
    let dir = glam::DVec3::new(0.3, -0.5, 0.8).normalize();
    let nodes = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
    let weights = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
    let (dt, dp) = (PI / THETA_BINS as f64, 2.0 * PI / PHI_BINS as f64);
    let mut failures = vec![];
    for g in cases {
        let mut q: Vec<u8> = bytemuck::cast_slice(&[dir.x as f32, dir.y as f32, dir.z as f32, g as f32]).to_vec();
        q.extend(bytemuck::cast_slice(&[SAMPLES, 777u32, 0, 0]));
        query.write(&q).unwrap();
        kernel.dispatch(&ctx, &[0u8; 16], [SAMPLES.div_ceil(64), 1, 1]).unwrap();
        ctx.check_validation().expect("no validation messages");
        let out: Vec<[f32; 4]> = bytemuck::cast_slice(&results.read().unwrap()[..SAMPLES as usize * 16]).to_vec();
        let mut observed = vec![0.0; THETA_BINS * PHI_BINS];
        let mut worst_density = 0.0f64;
        for r in &out {
            let w = glam::DVec3::new(r[0] as f64, r[1] as f64, r[2] as f64);
            let expected_density = hg(g, dir.dot(w.normalize()));
            worst_density = worst_density.max((r[3] as f64 - expected_density).abs() / expected_density);
            let theta = (w.z / w.length()).clamp(-1.0, 1.0).acos();
            let phi = w.y.atan2(w.x).rem_euclid(2.0 * PI);
            let i = ((theta / dt) as usize).min(THETA_BINS - 1);
            let j = ((phi / dp) as usize).min(PHI_BINS - 1);
            observed[i * PHI_BINS + j] += 1.0;
        }
        let mut expected = vec![0.0; THETA_BINS * PHI_BINS];
        for i in 0..THETA_BINS {
            for j in 0..PHI_BINS {
                let mut integral = 0.0;
                for (a, wa) in nodes.iter().zip(weights) {
                    let theta = (i as f64 + 0.5 + 0.5 * a) * dt;
                    for (b, wb) in nodes.iter().zip(weights) {
                        let phi = (j as f64 + 0.5 + 0.5 * b) * dp;
                        let w = glam::DVec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
                        integral += wa * wb * 0.25 * dt * dp * theta.sin() * hg(g, dir.dot(w));
                    }
                }
                expected[i * PHI_BINS + j] = integral * SAMPLES as f64;
            }
        }
        let (statistic, dof, p) = chi_square(&observed, &expected);
        eprintln!("g = {g}: chi-square {statistic:.1} on {dof} degrees of freedom, p = {p:.3e}; worst density error {worst_density:.2e}");
        if p < significance {
            failures.push(format!("g = {g}: p = {p:.3e}"));
        }
        if worst_density > 1e-3 {
            failures.push(format!("g = {g}: phase_hg off the closed form by {worst_density:.2e}"));
        }
    }
    kernel.destroy(&ctx);
    query.destroy(&ctx);
    results.destroy(&ctx);
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Mitsuba 3's media: a homogeneous fog the sensor is in (volpathmis), a null-bounded sphere of a
/// heterogeneous medium whose gridvolume is placed by its to_world, and a dielectric sphere with
/// a homogeneous interior; an exterior that is not the sensor's medium is refused.
#[test]
fn mitsuba_media_import_as_media_interiors_and_null_boundaries() {
    let dir = temp_dir("media-mitsuba");
    std::fs::write(dir.join("g.vol"), constant_grid(0.5)).unwrap();
    let xml = |exterior: &str| {
        format!(
            r#"<scene version="3.0.0">
  <integrator type="volpathmis"><integer name="max_depth" value="16"/></integrator>
  <medium type="homogeneous" id="fog">
    <rgb name="sigma_t" value="0.1, 0.2, 0.3"/>
    <float name="albedo" value="0.9"/>
    <phase type="hg"><float name="g" value="0.4"/></phase>
  </medium>
  <medium type="homogeneous" id="other"><float name="sigma_t" value="1"/></medium>
  <sensor type="perspective"><ref id="fog"/></sensor>
  <shape type="sphere">
    <bsdf type="null"/>
    <medium type="heterogeneous" name="interior">
      <volume type="gridvolume" name="sigma_t">
        <string name="filename" value="g.vol"/>
        <transform name="to_world"><scale value="2"/><translate x="-1" y="-1" z="-1"/></transform>
      </volume>
      <float name="scale" value="3"/>
    </medium>
    <ref name="exterior" id="{exterior}"/>
  </shape>
  <shape type="sphere">
    <point name="center" x="3" y="0" z="0"/>
    <bsdf type="dielectric"/>
    <medium type="homogeneous" name="interior"><float name="sigma_t" value="5"/></medium>
  </shape>
</scene>"#
        )
    };
    let load = |text: String| {
        let path = dir.join("scene.xml");
        std::fs::write(&path, text).unwrap();
        Scene::load_with(&caustica::input_file::InputFiles::anywhere(), &path, &[])
    };
    let scene = load(xml("fog")).expect("the scene imports");
    assert_eq!(scene.media.len(), 3, "{:?}", scene.media);
    let fog = scene.camera_medium.expect("the sensor's medium") as usize;
    assert!((scene.media[fog].sigma_t - glam::Vec3::new(0.1, 0.2, 0.3)).abs().max_element() < 1e-6);
    assert_eq!(scene.media[fog].phase, caustica::scene::Phase::HenyeyGreenstein { g: 0.4 });
    let null = scene.materials.iter().find(|m| m.null_surface).expect("the null boundary");
    let grid = &scene.media[null.interior.expect("its interior") as usize];
    assert_eq!(grid.sigma_t, glam::Vec3::splat(3.0), "scale times the unit sigma_t");
    assert_eq!(grid.albedo, glam::Vec3::splat(0.75), "Mitsuba's default albedo");
    let density = grid.density.as_ref().expect("a density grid");
    assert_eq!(density.bounds, (glam::Vec3::splat(-1.0), glam::Vec3::splat(1.0)), "the to_world's box");
    let glass = scene.materials.iter().find(|m| m.transparency > 0.0).expect("the dielectric");
    assert_eq!(scene.media[glass.interior.expect("its interior") as usize].sigma_t, glam::Vec3::splat(5.0));
    let message = format!("{:#}", load(xml("other")).expect_err("refused"));
    assert!(message.contains("exterior medium 'other' is not the sensor's"), "{message}");
}
