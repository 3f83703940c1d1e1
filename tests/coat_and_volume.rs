//! glTF's clear coat (KHR_materials_clearcoat) and Beer-Lambert absorption inside dielectrics
//! (KHR_materials_volume, and the scene format's `attenuation_color` / `attenuation_distance`)
//! against closed forms, on lavapipe. Every view here looks straight at a plane through a 2-degree
//! field of view under a constant sky, so each pixel's answer is the normal-incidence one (the
//! corners are 1.4 degrees off it: below 1e-3 of any answer here).

mod common;

use caustica::render::{AovSet, KernelChoice, Renderer};
use caustica::scene::{fresnel_dielectric, Clearcoat, Scene};
use common::gltf_square::{png_uri, write_gltf_square};
use common::{gpu, mean_and_stderr, parse, render, temp_dir};
use std::path::Path;

/// Fresnel reflectance of a dielectric of index 1.5 at normal incidence, ((n - 1) / (n + 1))^2.
const F0: f64 = 0.04;

/// Camera below the origin looking up +y through 2 degrees, and a constant sky of `sky`; `rest`
/// is the scene's materials and shapes.
fn view_up(sky: [f32; 3], size: u32, spp: u32, rest: &str) -> String {
    format!(
        r#"
        camera = {{ position = [0.0, -3.0, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = 2.0 }}
        film = {{ width = {size}, height = {size}, spp = {spp} }}
        environment = {{ color = {sky:?} }}
        {rest}
        "#
    )
}

/// Per channel: the image's mean must be `expected` within five standard errors (from the scatter
/// of its independent pixels), and those must be below `resolution` x expected, the smallest
/// relative error the check is sure to see.
fn assert_channel_means(image: &caustica::image::RgbImage, expected: [f64; 3], resolution: f64, what: &str) {
    for c in 0..3 {
        let values: Vec<f64> = image.pixels.iter().map(|p| p[c] as f64).collect();
        let (mean, stderr) = mean_and_stderr(&values);
        eprintln!("{what}: channel {c}: mean {mean:.5} +- {stderr:.5}, expected {:.5}", expected[c]);
        assert!(
            5.0 * stderr < resolution * expected[c],
            "{what}: channel {c}: too noisy to resolve {resolution}: stderr {stderr:.2e}"
        );
        assert!(
            (mean - expected[c]).abs() <= 5.0 * stderr + 1e-3 * expected[c],
            "{what}: channel {c}: mean {mean:.5} +- {stderr:.5}, expected {:.5}",
            expected[c]
        );
    }
}

/// A slab of glass of index 1 (no refraction, no reflection) between y = 0 and y = 0.75, its faces
/// outwards, absorbing with `attenuation_color` [0.8, 0.5, 0.2] per `attenuation_distance` 0.5:
/// every path crosses it straight, so each pixel is the sky times 0.8, 0.5, 0.2 to the power 1.5,
/// exactly (no noise; the corners' longer paths change it by under 1e-3). Without absorption the
/// pixel is the sky (a factor 1.4 to 11 off); absorbing on the way in instead of out (over the 3
/// units from the camera) gives the sixth powers, and sigma_a not multiplied by the length the
/// cubes; any error in sigma_a or the path length above 0.2 % fails.
#[test]
fn a_slab_of_absorbing_glass_passes_the_attenuation_color_per_distance() {
    let sky = [2.0f32, 1.0, 0.5];
    let scene = parse(&view_up(
        sky,
        16,
        4,
        r#"
        [materials.glass]
        transparency = 1.0
        ior = 1.0
        attenuation_color = [0.8, 0.5, 0.2]
        attenuation_distance = 0.5
        [[quads]]
        origin = [-2.0, 0.0, -2.0]
        edge_u = [4.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, 4.0]
        material = "glass"
        [[quads]]
        origin = [-2.0, 0.75, -2.0]
        edge_u = [0.0, 0.0, 4.0]
        edge_v = [4.0, 0.0, 0.0]
        material = "glass"
        "#,
    ));
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &scene, 3);
    let expected = [0.8f32, 0.5, 0.2].map(|c| c.powf(1.5));
    for (i, p) in image.pixels.iter().enumerate() {
        for c in 0..3 {
            let want = sky[c] * expected[c];
            assert!((p[c] - want).abs() <= 2e-3 * want, "pixel {i} channel {c}: {} where the slab passes {want}", p[c]);
        }
    }
}

/// The same slab from a glTF file (two placements of one square, the second turned to face up), of
/// index 1.5 and KHR_materials_volume attenuationColor [0.8, 0.5, 0.2] per attenuationDistance 1
/// (its thicknessFactor, 0.1, is ignored): light crossing the slab once keeps a = colour^0.75, each
/// face reflects F = 0.04, and the pixel is the sky times all that the slab returns and passes:
/// R + T = F + (1 - F)^2 F a^2 / (1 - F^2 a^2) + (1 - F)^2 a / (1 - F^2 a^2). Resolves 2 %.
#[test]
fn a_gltf_slab_with_khr_materials_volume_absorbs_between_its_faces() {
    let dir = temp_dir("gltf-volume-slab");
    let material = r#"{"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0},
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1},
                       "KHR_materials_volume": {"thicknessFactor": 0.1, "attenuationColor": [0.8, 0.5, 0.2], "attenuationDistance": 1}}}"#;
    write_gltf_square(&dir, "slab.gltf", 0.0, 2.0, material, "");
    let scene = Scene::parse(
        &view_up(
            [1.0; 3],
            32,
            16,
            r#"
            [[meshes]]
            file = "slab.gltf"
            [[meshes]]
            file = "slab.gltf"
            rotate = [180.0, 0.0, 0.0]
            translate = [0.0, 0.75, 0.0]
            "#,
        ),
        "gltf slab",
        &dir,
    )
    .expect("valid test scene");
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &scene, 5);
    let expected = [0.8, 0.5, 0.2].map(|color: f64| {
        let a = color.powf(0.75);
        let bounce = 1.0 - F0 * F0 * a * a;
        F0 + (1.0 - F0).powi(2) * F0 * a * a / bounce + (1.0 - F0).powi(2) * a / bounce
    });
    assert_channel_means(&image, expected, 0.02, "glTF slab, index 1.5");
}

/// A quad at y = 0 facing the camera, of material `m`.
const FACING_QUAD: &str = r#"
    [[quads]]
    origin = [-2.0, 0.0, -2.0]
    edge_u = [4.0, 0.0, 0.0]
    edge_v = [0.0, 0.0, 4.0]
    material = "m"
"#;

/// A diffuse quad of `albedo` under a white sky, with `coat` on its material.
fn coated_quad(albedo: f32, coat: Option<Clearcoat>, size: u32, spp: u32) -> Scene {
    let mut scene = parse(&view_up(
        [1.0; 3],
        size,
        spp,
        &format!("[materials.m]\nalbedo = [{albedo}, {albedo}, {albedo}]\n{FACING_QUAD}"),
    ));
    scene.materials[0].clearcoat = coat;
    scene
}

/// [`coated_quad`] seen at 60 degrees from its normal (cos 0.5) through half a degree.
fn coated_quad_at_60_degrees(albedo: f32, coat: Option<Clearcoat>, size: u32, spp: u32) -> Scene {
    let mut scene = coated_quad(albedo, coat, size, spp);
    scene.camera.position = glam::Vec3::new(0.0, -1.5, 3.0 * 0.75f32.sqrt());
    scene.camera.up = glam::Vec3::Y;
    scene.camera.fov_deg = 0.5;
    scene
}

fn smooth_coat(factor: f32) -> Option<Clearcoat> {
    Some(Clearcoat { factor, roughness: 0.0, texture: None, roughness_texture: None })
}

/// A smooth clear coat of factor 0.6 over a black diffuse base under a white sky reflects the sky
/// times factor x F(view) (glTF's `fresnel_coat` weight): 0.6 x 0.04 = 0.024 at normal incidence,
/// 0.6 x 0.0918 at 60 degrees; the base reflects nothing. Resolves 5 %: a Fresnel of the wrong
/// index (1.33 gives 0.02 head-on), the factor left out (0.04), the coat weighted by its factor
/// alone (0.6), or F taken from inside the coat (total reflection at 60 degrees: 0.6) fail.
#[test]
fn a_smooth_clear_coat_over_black_reflects_factor_times_fresnel() {
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &coated_quad(0.0, smooth_coat(0.6), 48, 64), 7);
    assert_channel_means(&image, [0.6 * F0; 3], 0.05, "clear coat 0.6 over black, head-on");
    let image = render(&ctx, &coated_quad_at_60_degrees(0.0, smooth_coat(0.6), 48, 64), 7);
    assert_channel_means(
        &image,
        [0.6 * fresnel_dielectric(0.5, 1.5); 3],
        0.05,
        "clear coat 0.6 over black, at 60 degrees",
    );
}

/// The scene file's `clearcoat` and `clearcoat_roughness` keys give the material glTF's clear coat
/// gives (the same `Clearcoat`), and the kernel renders it: the black base under a key-made coat of
/// 0.6 gives the closed form of the test above, bit for bit the image of the coat set directly.
#[test]
fn the_clearcoat_keys_are_the_gltf_clear_coat() {
    let keyed = parse(&view_up(
        [1.0; 3],
        48,
        64,
        &format!("[materials.m]\nalbedo = [0.0, 0.0, 0.0]\nclearcoat = 0.6\n{FACING_QUAD}"),
    ));
    assert_eq!(keyed.materials[0].clearcoat, smooth_coat(0.6));
    let rough = parse(&view_up(
        [1.0; 3],
        8,
        1,
        &format!("[materials.m]\nclearcoat = 0.25\nclearcoat_roughness = 0.5\n{FACING_QUAD}"),
    ));
    assert_eq!(
        rough.materials[0].clearcoat,
        Some(Clearcoat { factor: 0.25, roughness: 0.5, texture: None, roughness_texture: None })
    );
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &keyed, 7);
    assert_channel_means(&image, [0.6 * F0; 3], 0.05, "clear coat 0.6 from the scene file's key over black, head-on");
    assert!(
        image.pixels == render(&ctx, &coated_quad(0.0, smooth_coat(0.6), 48, 64), 7).pixels,
        "the key and the coat set directly render alike"
    );
    for (keys, needle) in [
        ("clearcoat = 1.5", "materials.m.clearcoat must be in [0, 1], got 1.5"),
        ("clearcoat = 0.5\nclearcoat_roughness = -0.1", "materials.m.clearcoat_roughness must be in [0, 1], got -0.1"),
        ("clearcoat_roughness = 0.5", "materials.m.clearcoat_roughness needs materials.m.clearcoat"),
    ] {
        let text = view_up([1.0; 3], 8, 1, &format!("[materials.m]\n{keys}\n{FACING_QUAD}"));
        let e = format!("{:#}", Scene::parse(&text, "coat.toml", Path::new(".")).expect_err("refused"));
        assert!(e.contains(needle), "{keys}: {e}");
    }
}

/// Over a white diffuse base the same coat conserves energy exactly: every path returns the white
/// sky, whether the coat (weight factor x F) or the base (the rest, 1 - factor x F) takes it, so
/// every pixel is 1. A base weighted 1 instead (a coat that only adds) gives 1.024; a base whose
/// scale divides by its probability twice gives 1 / 0.976.
#[test]
fn a_clear_coat_over_white_conserves_energy_in_a_white_furnace() {
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &coated_quad(1.0, smooth_coat(0.6), 16, 16), 7);
    for (i, p) in image.pixels.iter().enumerate() {
        for (c, value) in p.iter().enumerate() {
            assert!((value - 1.0).abs() <= 1e-4, "pixel {i} channel {c}: {value} under a white sky, not 1");
        }
    }
}

/// The accumulated sums of `scene` rendered by the general kernel (which has the clear coat's code),
/// as bits.
fn general_sums(ctx: &caustica::gpu::GpuContext, scene: &Scene) -> Vec<[u32; 4]> {
    let mut renderer =
        Renderer::with_kernel(ctx, scene, 3, AovSet::default(), KernelChoice::General).expect("scene uploads");
    renderer.render(scene.film.spp, |_| {}).expect("render succeeds without validation messages");
    renderer.accumulation().expect("readback").iter().map(|p| p.map(f32::to_bits)).collect()
}

/// A clear coat of factor 0 is no coat, bit for bit: it draws no random number and changes no
/// weight, even in the general kernel (where the coat's code is compiled in), over a plastic (a
/// rough grey coated base, which draws numbers of its own after the coat's place).
#[test]
fn a_clear_coat_of_factor_zero_renders_exactly_as_none() {
    let mut uncoated = coated_quad(0.5, None, 24, 8);
    uncoated.materials[0].coat = true;
    uncoated.materials[0].roughness = 0.4;
    let mut zero = uncoated.clone();
    zero.materials[0].clearcoat =
        Some(Clearcoat { factor: 0.0, roughness: 0.3, texture: None, roughness_texture: None });
    let (_lock, ctx) = gpu();
    let (a, b) = (general_sums(&ctx, &uncoated), general_sums(&ctx, &zero));
    let differing = a.iter().zip(&b).filter(|(p, q)| p != q).count();
    assert_eq!(differing, 0, "{differing} of {} pixels differ between no clear coat and one of factor 0", a.len());
}

/// A 1 x 1 linear RGBA PNG.
fn png_texel(texel: [u8; 4]) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 1, 1);
    encoder.set_color(png::ColorType::Rgba);
    encoder.write_header().unwrap().write_image_data(&texel).unwrap();
    bytes
}

/// glTF end to end: a black, smooth glTF dielectric (a plastic whose own coat reflects F = 0.04)
/// under KHR_materials_clearcoat factor 1 with clearcoatTexture R = 128 (so c = 128 / 255) and
/// clearcoatRoughnessFactor 1 with clearcoatRoughnessTexture G = 0 (a smooth coat: both read from
/// one texel (128, 0, 255, 255)). Under a white sky at normal incidence the pixel is c F + (1 - c F) F
/// = 0.0593. Resolves 5 %: without the coat it is 0.04, with the texture's R ignored 0.0784, with
/// the texture channels swapped 0.04 (G = 0 for the factor); with the roughness texture ignored
/// the coat has roughness 1 and the pixel is 0.0453 (measured: single-scattering GGX at alpha 1
/// keeps about a quarter of the coat's share). A roughness read from R (alpha 0.25) would lose
/// too little to see here.
#[test]
fn a_gltf_clear_coat_reads_its_factor_and_roughness_textures() {
    let dir = temp_dir("gltf-clearcoat");
    let material = r#"{"pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 0},
        "extensions": {"KHR_materials_clearcoat": {"clearcoatFactor": 1, "clearcoatTexture": {"index": 0},
                                                    "clearcoatRoughnessFactor": 1, "clearcoatRoughnessTexture": {"index": 0}}}}"#;
    let resources = format!(
        r#""textures": [{{"source": 0}}], "images": [{{"uri": "{}"}}],"#,
        png_uri(&png_texel([128, 0, 255, 255]))
    );
    write_gltf_square(&dir, "coated.gltf", 0.0, 2.0, material, &resources);
    let scene =
        Scene::parse(&view_up([1.0; 3], 48, 64, "[[meshes]]\nfile = \"coated.gltf\"\n"), "gltf clear coat", &dir)
            .expect("valid test scene");
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &scene, 11);
    let c = 128.0 / 255.0;
    assert_channel_means(&image, [c * F0 + (1.0 - c * F0) * F0; 3], 0.05, "glTF clear coat with textures");
}

/// A smooth plastic (index 1.5) over albedo (0.8, 0.5, 0.2), head-on under a white sky, whose coat
/// reflects light back down onto the base (`coat_internal_reflections`): F0 + (1 - F0) rho', where
/// rho' = rho (1 - Fin) / (1 - rho Fin) and 1 - Fin = (1 - Fout) / 1.5^2 (Fout the coat's cosine-
/// weighted average Fresnel from outside; Mitsuba's nonlinear plastic). Resolves 2 %: without the
/// internal reflections the channels are 0.81, 0.52, 0.23 (1.1-2.3x); with Fin taken as Fout
/// (0.09, 0.8 x 0.908 / 0.927 = 0.78) the red channel is 4 % off.
#[test]
fn a_plastic_with_internal_reflections_darkens_and_saturates_its_base() {
    let text = view_up([1.0; 3], 48, 64, &format!("[materials.m]\nalbedo = [0.8, 0.5, 0.2]\ncoat = true\nior = 1.5\ncoat_internal_reflections = true\n{FACING_QUAD}"));
    let scene = parse(&text);
    let leaves = (1.0 - caustica::scene::average_fresnel(1.5) as f64) / 2.25;
    let expected = [0.8, 0.5, 0.2].map(|rho: f64| F0 + (1.0 - F0) * rho * leaves / (1.0 - rho * (1.0 - leaves)));
    let (_lock, ctx) = gpu();
    assert_channel_means(&render(&ctx, &scene, 7), expected, 0.02, "plastic with internal reflections, head-on");
    let refused = Scene::parse(&text.replace("coat = true\n", ""), "t.toml", std::path::Path::new("."))
        .expect_err("refused without a coat");
    assert!(format!("{refused:#}").contains("materials.m.coat_internal_reflections"), "{refused:#}");
}
