//! Rough materials on lavapipe: GGX conductors and dielectrics and the plastic coat in the white
//! furnace, their limit at roughness 0, next-event estimation against plain BSDF sampling, the
//! scene-format keys and the glTF mapping. Tolerances are standard errors from the renders' noise.

mod common;

use caustica::scene::{Conductor, Scene};
use common::furnace::*;
use common::*;
use glam::Vec3;
use std::path::Path;

/// Sphere mean in the furnace (two renders of 32 x 32 at `spp`), with its standard error.
fn furnace_sphere(material: &str, spp: u32) -> (f64, f64) {
    let (_lock, ctx) = gpu();
    let scene = furnace(material, 32, spp);
    let cover = coverage(&scene);
    let (a, b) = (render(&ctx, &scene, 1), render(&ctx, &scene, 2));
    let (background, _) = region_mean(&a, &b, &cover, Coverage::Background);
    assert!((background - 1.0).abs() < 1e-5, "{material}: background {background}, expected 1");
    region_mean(&a, &b, &cover, Coverage::Sphere)
}

/// Asserts the furnace sphere reflects at most the incoming radiance (within 5 standard errors)
/// and at least `floor`; returns the mean.
fn assert_furnace_within(material: &str, spp: u32, floor: f64, what: &str) -> f64 {
    let (mean, stderr) = furnace_sphere(material, spp);
    eprintln!("{what}: furnace sphere mean {mean:.4} (standard error {stderr:.4})");
    assert!(
        mean <= 1.0 + 5.0 * stderr,
        "{what}: mean {mean:.5} creates energy (5 standard errors = {:.5})",
        5.0 * stderr
    );
    assert!(
        mean >= floor - 5.0 * stderr,
        "{what}: mean {mean:.5} below {floor} (5 standard errors = {:.5})",
        5.0 * stderr
    );
    mean
}

#[test]
fn rough_perfect_reflector_in_furnace_loses_only_multiple_scattering() {
    // F = 1: what GGX loses is the light its single-scattering model drops (masked after the
    // first microfacet bounce), which grows with roughness. Floors sit below the measured values
    // (0.999, 0.974, 0.842 at roughness 0.1, 0.5, 1) by a few standard errors.
    let mut means = vec![];
    for (roughness, floor) in [(0.1, 0.995), (0.5, 0.875), (1.0, 0.35)] {
        let material = format!("albedo = [0.0, 0.0, 0.0]\nreflectivity = 1.0\nroughness = {roughness}");
        means.push(assert_furnace_within(&material, 64, floor, &format!("F = 1 conductor, roughness {roughness}")));
    }
    assert!(means[0] > means[1] && means[1] > means[2], "energy loss must grow with roughness: {means:?}");
}

#[test]
fn rough_glass_in_furnace_stays_at_most_one() {
    for (roughness, floor) in [(0.3, 0.955), (1.0, 0.33)] {
        let material = format!("albedo = [0.0, 0.0, 0.0]\ntransparency = 1.0\nior = 1.5\nroughness = {roughness}");
        assert_furnace_within(&material, 64, floor, &format!("rough glass, roughness {roughness}"));
    }
}

#[test]
fn white_plastic_under_a_smooth_coat_is_invisible_in_furnace() {
    // The coat reflects F(wo) and the normalised base returns exactly the remaining 1 - F(wo).
    let (_lock, ctx) = gpu();
    let scene = furnace("albedo = [1.0, 1.0, 1.0]\ncoat = true\nior = 1.5", 32, 64);
    let cover = coverage(&scene);
    let (a, b) = (render(&ctx, &scene, 3), render(&ctx, &scene, 4));
    assert_region_mean(&a, &b, &cover, Coverage::Sphere, 1.0, "white plastic, smooth coat");
}

#[test]
fn white_plastic_under_a_rough_coat_stays_at_most_one() {
    assert_furnace_within(
        "albedo = [1.0, 1.0, 1.0]\ncoat = true\nroughness = 0.5",
        64,
        0.9,
        "white plastic, coat roughness 0.5",
    );
}

/// A camera looking along -z at the centre of a unit sphere with a field of view so narrow that
/// every ray meets it head-on, under a white sky: the pixel is the sphere's normal-incidence
/// reflectance (one delta bounce, no noise).
fn normal_incidence_reflectance(material: &str) -> [f32; 3] {
    let (_lock, ctx) = gpu();
    let mut scene = furnace(material, 4, 1);
    scene.camera.fov_deg = 0.001;
    render(&ctx, &scene, 1).pixels[5]
}

#[test]
fn smooth_metals_reflect_their_complex_fresnel_at_normal_incidence() {
    // ((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2) per channel.
    for (name, eta, k) in caustica::scene::METALS {
        let got = normal_incidence_reflectance(&format!("metal = \"{name}\""));
        for c in 0..3 {
            let expected = ((eta[c] - 1.0).powi(2) + k[c] * k[c]) / ((eta[c] + 1.0).powi(2) + k[c] * k[c]);
            assert!((got[c] - expected).abs() < 1e-4, "{name} channel {c}: {} against {expected}", got[c]);
        }
    }
    let got = normal_incidence_reflectance("metal = \"albedo\"\nalbedo = [0.9, 0.5, 0.2]");
    for (c, f0) in [0.9, 0.5, 0.2].into_iter().enumerate() {
        assert!((got[c] - f0).abs() < 1e-4, "Schlick metal channel {c}: {} against F0 {f0}", got[c]);
    }
}

/// The Cornell box (common's) with its mirror and glass spheres of `roughness`.
fn cornell(size: u32, spp: u32, roughness: f32) -> Scene {
    let mut scene = common::cornell(size, spp);
    for m in scene.materials.iter_mut().filter(|m| m.reflectivity > 0.0 || m.transparency > 0.0) {
        m.roughness = roughness;
    }
    scene
}

#[test]
fn nearly_smooth_ggx_matches_the_mirror_and_glass() {
    // Roughness 0.05 (alpha 0.0025) goes through the GGX lobes, with NEE and MIS at the spheres;
    // roughness 0 through the delta lobes.
    let (_lock, ctx) = gpu();
    let scene = cornell(32, 64, 0.0);
    assert!(scene.materials.iter().filter(|m| m.reflectivity > 0.0 || m.transparency > 0.0).count() == 2);
    let smooth = render(&ctx, &scene, 41);
    let rough = render(&ctx, &cornell(32, 64, 0.05), 42);
    assert_same_mean(&smooth, &rough, 5.0, "Cornell box, roughness 0 against 0.05");
}

/// A floor of rough plastic under a large area light, with a rough copper, a rough glass and a
/// smooth-coated plastic sphere.
const ROUGH_SCENE: &str = r#"
[camera]
position = [0.0, 1.2, 3.5]
look_at = [0.0, 0.4, 0.0]
fov = 45.0
[film]
width = 32
height = 32
[materials.floor]
albedo = [0.6, 0.6, 0.6]
coat = true
roughness = 0.4
[materials.copper]
metal = "copper"
roughness = 0.3
[materials.glass]
albedo = [0.0, 0.0, 0.0]
transparency = 1.0
roughness = 0.3
[materials.plastic]
albedo = [0.1, 0.3, 0.8]
coat = true
[materials.light]
emission = [4.0, 4.0, 4.0]
[[quads]]
origin = [-3.0, 0.0, 3.0]
edge_u = [6.0, 0.0, 0.0]
edge_v = [0.0, 0.0, -6.0]
material = "floor"
[[quads]]
origin = [-1.0, 2.5, -1.0]
edge_u = [2.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 2.0]
material = "light"
[[spheres]]
center = [-0.9, 0.4, 0.0]
radius = 0.4
material = "copper"
[[spheres]]
center = [0.0, 0.4, 0.3]
radius = 0.4
material = "glass"
[[spheres]]
center = [0.9, 0.4, 0.0]
radius = 0.4
material = "plastic"
"#;

/// Renders `toml` with NEE + MIS at 64 spp and with BSDF sampling alone at 256 and asserts the
/// two agree in the mean.
fn assert_nee_agrees(toml: &str, what: &str) {
    let (_lock, ctx) = gpu();
    let mut nee = parse(toml);
    nee.film.spp = 64;
    let mut bsdf = parse(toml);
    bsdf.film.spp = 256;
    bsdf.integrator.nee = false;
    let a = render(&ctx, &nee, 51);
    let b = render(&ctx, &bsdf, 52);
    assert_same_mean(&a, &b, 5.0, &format!("{what}: NEE + MIS against pure BSDF sampling"));
}

/// A floor of `floor` under a 2 x 2 area light, seen at a slant so that it mirrors the light.
fn lit_floor(floor: &str, extra: &str) -> String {
    format!(
        r#"
        [camera]
        position = [0.0, 1.0, 3.0]
        look_at = [0.0, 0.0, 0.0]
        [film]
        width = 32
        height = 32
        [materials.floor]
        {floor}
        [materials.light]
        emission = [4.0, 4.0, 4.0]
        [[quads]]
        origin = [-3.0, 0.0, 3.0]
        edge_u = [6.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -6.0]
        material = "floor"
        [[quads]]
        origin = [-1.0, 1.5, -1.0]
        edge_u = [2.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, 2.0]
        material = "light"
        {extra}
        "#
    )
}

#[test]
fn nee_lights_a_diffuse_floor_beyond_the_lights_footprint() {
    // Regression: shadow rays measured from the surface point rather than from their offset
    // origin hit the light's own plane at grazing angles, darkening NEE there by up to 100%.
    let scene =
        lit_floor("albedo = [0.5, 0.5, 0.5]", "").replace("position = [0.0, 1.0, 3.0]", "position = [0.0, 0.3, 3.0]");
    assert_nee_agrees(&scene, "diffuse floor seen low");
}

#[test]
fn nee_on_a_rough_conductor_agrees_with_bsdf_sampling() {
    assert_nee_agrees(&lit_floor("metal = \"copper\"\nroughness = 0.6", ""), "rough copper floor");
}

#[test]
fn nee_on_a_rough_plastic_agrees_with_bsdf_sampling() {
    assert_nee_agrees(&lit_floor("albedo = [0.5, 0.5, 0.5]\ncoat = true\nroughness = 0.6", ""), "rough plastic floor");
}

#[test]
fn nee_through_rough_glass_agrees_with_bsdf_sampling() {
    let sphere = "[materials.glass]\nalbedo = [0.0, 0.0, 0.0]\ntransparency = 1.0\nroughness = 0.4\n\
        [[spheres]]\ncenter = [0.0, 0.5, 0.5]\nradius = 0.5\nmaterial = \"glass\"";
    assert_nee_agrees(&lit_floor("albedo = [0.5, 0.5, 0.5]", sphere), "rough glass sphere on a diffuse floor");
}

#[test]
fn nee_through_a_rough_interface_agrees_with_bsdf_sampling() {
    // A single rough glass sheet above an area light: what the camera sees is mostly light
    // refracted once, which NEE evaluates through the refraction lobe.
    let scene = r#"
        [camera]
        position = [0.0, 1.2, 2.5]
        look_at = [0.0, 0.0, 0.0]
        [film]
        width = 32
        height = 32
        [materials.glass]
        albedo = [0.0, 0.0, 0.0]
        transparency = 1.0
        roughness = 1.0
        [materials.light]
        emission = [4.0, 4.0, 4.0]
        [[quads]]
        origin = [-3.0, 0.0, 3.0]
        edge_u = [6.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -6.0]
        material = "glass"
        [[quads]]
        origin = [-1.0, -1.0, 1.0]
        edge_u = [2.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -2.0]
        material = "light"
    "#;
    assert_nee_agrees(scene, "light under a rough glass sheet");
}

#[test]
fn nee_on_mixed_rough_materials_agrees_with_bsdf_sampling() {
    assert_nee_agrees(ROUGH_SCENE, "rough copper, glass and plastics");
}

fn error_of(material: &str) -> String {
    let text = format!("[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\n[materials.m]\n{material}\n");
    format!("{:#}", Scene::parse(&text, "test.toml", Path::new(".")).expect_err("material must be rejected"))
}

#[test]
fn bad_material_keys_are_errors_naming_the_key() {
    for (material, needle) in [
        ("roughness = 1.5", "materials.m.roughness"),
        ("roughness = -0.1", "materials.m.roughness"),
        ("roughness = nan", "materials.m.roughness"),
        ("metal = \"brass\"", "materials.m.metal"),
        ("metal = \"gold\"\neta = [1.0, 1.0, 1.0]\nk = [1.0, 1.0, 1.0]", "materials.m.metal"),
        ("eta = [1.0, 1.0, 1.0]", "materials.m.k"),
        ("k = [1.0, 1.0, 1.0]", "materials.m.eta"),
        ("eta = [0.0, 1.0, 1.0]\nk = [1.0, 1.0, 1.0]", "materials.m.eta"),
        ("eta = [1.0, 1.0, 1.0]\nk = [-1.0, 1.0, 1.0]", "materials.m.k"),
        ("eta = [inf, 1.0, 1.0]\nk = [1.0, 1.0, 1.0]", "materials.m.eta"),
        ("coat = 1", "coat"),
        ("distribution = \"phong\"", "distribution"),
        ("thin = 1", "thin"),
        ("metal = \"gold\"\nreflectivity = 0.5\ntransparency = 0.6", "R + T <= 1"),
    ] {
        let e = error_of(material);
        assert!(e.contains(needle), "{material:?}: error does not name {needle}: {e}");
    }
}

#[test]
fn metal_keys_make_a_conductor_and_keep_the_rt_defaults() {
    let text = "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\n\
        [materials.gold]\nmetal = \"gold\"\nroughness = 0.3\n\
        [materials.half]\nmetal = \"silver\"\nreflectivity = 0.5\n\
        [materials.custom]\neta = [0.2, 0.3, 0.4]\nk = [3.0, 2.0, 1.0]\n\
        [materials.plain]\nreflectivity = 0.25\n";
    let scene = Scene::parse(text, "test.toml", Path::new(".")).unwrap();
    let get = |name: &str| scene.materials.iter().find(|m| m.name == name).unwrap();
    let (eta, k) = caustica::scene::metal("gold").unwrap();
    assert_eq!(get("gold").conductor, Conductor::Complex { eta, k });
    assert_eq!((get("gold").reflectivity, get("gold").roughness), (1.0, 0.3), "a metal defaults to R = 1");
    assert_eq!(get("half").reflectivity, 0.5);
    assert_eq!(
        get("custom").conductor,
        Conductor::Complex { eta: Vec3::new(0.2, 0.3, 0.4), k: Vec3::new(3.0, 2.0, 1.0) }
    );
    assert_eq!(
        (get("plain").conductor, get("plain").reflectivity, get("plain").roughness),
        (Conductor::Mirror, 0.25, 0.0)
    );
    assert!(!get("plain").coat);
}

/// One triangle drawn three times, with a metal, a plastic and a transmissive material.
const GLTF: &str = r#"{
  "asset": {"version": "2.0"},
  "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
  "bufferViews": [{"buffer": 0, "byteLength": 36}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}],
  "extensionsUsed": ["KHR_materials_transmission", "KHR_materials_ior"],
  "materials": [
    {"name": "metal", "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.2, 1], "metallicFactor": 1, "roughnessFactor": 0.4}},
    {"name": "plastic", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.3, 0.4, 1], "metallicFactor": 0, "roughnessFactor": 0.6}},
    {"name": "glass", "pbrMetallicRoughness": {"metallicFactor": 0, "roughnessFactor": 0.2},
     "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}, "KHR_materials_ior": {"ior": 1.4}}}
  ],
  "meshes": [{"primitives": [
    {"attributes": {"POSITION": 0}, "material": 0},
    {"attributes": {"POSITION": 0}, "material": 1},
    {"attributes": {"POSITION": 0}, "material": 2}
  ]}],
  "nodes": [{"mesh": 0}],
  "scenes": [{"nodes": [0]}]
}"#;

#[test]
fn gltf_metallic_roughness_maps_onto_rough_conductors_plastics_and_glass() {
    let dir = temp_dir("materials-gltf");
    let path = dir.join("materials.gltf");
    std::fs::write(&path, GLTF).unwrap();
    let scene = Scene::load(&path).unwrap();
    let get = |name: &str| {
        scene.materials.iter().find(|m| m.name.ends_with(name)).unwrap_or_else(|| panic!("no material {name}"))
    };
    let metal = get(":metal");
    assert_eq!(
        (metal.reflectivity, metal.transparency, metal.roughness, metal.conductor),
        (1.0, 0.0, 0.4, Conductor::Albedo)
    );
    assert_eq!(metal.albedo, Vec3::new(0.9, 0.6, 0.2), "the base colour is the metal's F0");
    let plastic = get(":plastic");
    assert_eq!((plastic.reflectivity, plastic.transparency, plastic.roughness, plastic.coat), (0.0, 0.0, 0.6, true));
    let glass = get(":glass");
    assert_eq!((glass.reflectivity, glass.transparency, glass.roughness, glass.ior), (0.0, 1.0, 0.2, 1.4));
}

/// A diffuse square (albedo 0.5, front side +z) filling the view under a white sky, seen from
/// `z` on the axis (in front when positive, behind when negative).
fn square_in_the_furnace(material: &str, z: f32) -> caustica::image::RgbImage {
    let (_lock, ctx) = gpu();
    let scene = parse(&format!(
        r#"
        camera = {{ position = [0.0, 0.0, {z}], look_at = [0.0, 0.0, 0.0], fov = 60.0 }}
        film = {{ width = 16, height = 16, spp = 16 }}
        environment = {{ color = [1.0, 1.0, 1.0] }}
        [materials.m]
        albedo = [0.5, 0.5, 0.5]
        {material}
        [[quads]]
        origin = [-2.0, -2.0, 0.0]
        edge_u = [4.0, 0.0, 0.0]
        edge_v = [0.0, 4.0, 0.0]
        material = "m"
        "#
    ));
    render(&ctx, &scene, 5)
}

/// A one-sided surface (Mitsuba's BSDFs without `twosided`) is black from behind, exactly, and
/// from the front the same as a two-sided one: albedo x sky = 0.5 to five standard errors of the
/// pixel mean (about 1 % here); a kernel that ignored the flag shows 0.5 from behind, one that
/// applied it to the front side shows 0.
#[test]
fn a_one_sided_surface_is_black_from_behind() {
    let behind = square_in_the_furnace("one_sided = true", -1.0);
    assert!(behind.pixels.iter().all(|p| *p == [0.0; 3]), "a one-sided square seen from behind is not black");
    for (material, z, what) in [
        ("one_sided = true", 1.0, "one-sided, in front"),
        ("", -1.0, "two-sided, behind"),
        ("", 1.0, "two-sided, in front"),
    ] {
        let image = square_in_the_furnace(material, z);
        let values: Vec<f64> = image.pixels.iter().map(|&p| luminance(p)).collect();
        let (mean, stderr) = mean_and_stderr(&values);
        assert!(
            (mean - 0.5).abs() <= 5.0 * stderr + 1e-6,
            "{what}: the square shows {mean:.4}, expected 0.5 (five standard errors {:.4})",
            5.0 * stderr
        );
    }
    assert!(error_of("one_sided = true\ntransparency = 0.5").contains("materials.m.one_sided"));
}
