//! The TOML scene format: what it accepts and how it rejects mistakes (naming the key and line).

mod common;

use caustica::scene::{Environment, Filter, Sampler, Scene, Shape};
use common::temp_dir;
use std::path::Path;

const MINIMAL: &str = "[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\n";

fn parse_result(text: &str) -> anyhow::Result<Scene> {
    Scene::parse(text, "test.toml", Path::new("."))
}

fn error_of(text: &str) -> String {
    format!("{:#}", parse_result(text).expect_err("scene must be rejected"))
}

#[test]
fn every_scene_in_scenes_dir_loads() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).unwrap();
            if text.contains("$CAUSTICA_DATA") && !caustica::scene::data_dir().exists() {
                eprintln!(
                    "SKIPPED: {} needs the shared data folder ({} is missing)",
                    path.display(),
                    caustica::scene::data_dir().display()
                );
                continue;
            }
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
            assert!(!scene.shapes.is_empty() || !scene.instances.is_empty(), "{} has no geometry", path.display());
            count += 1;
        }
    }
    assert!(count >= 4, "expected at least the Cornell box, sky, probe and original Cornell box scenes");
}

#[test]
fn default_scene_is_the_cornell_box_with_a_light() {
    let scene = Scene::default_scene();
    assert_eq!(scene.light_count(), 1);
    let spheres = scene.shapes.iter().filter(|s| matches!(s, Shape::Sphere { .. })).count();
    assert_eq!(spheres, 2, "a mirror and a glass sphere");
}

#[test]
fn defaults_fill_in_film_integrator_and_a_black_environment() {
    let scene = parse_result(MINIMAL).unwrap();
    assert_eq!((scene.film.width, scene.film.height, scene.film.spp), (512, 512, 64));
    assert_eq!(scene.integrator.rr_start, 4);
    assert!(scene.integrator.nee && scene.integrator.absorption.is_none());
    assert!(matches!(scene.environment, Environment::Constant(c) if c == glam::Vec3::ZERO));
}

#[test]
fn unknown_key_is_named_with_its_line() {
    let e = error_of(&format!("{MINIMAL}[film]\nwidth = 10\nsamples = 4\n"));
    assert!(e.contains("samples") && e.contains("line 6"), "{e}");
    assert!(e.contains("test.toml"), "{e}");
}

/// A scene setting every fixed-length array the format has (`square.obj` must be in its folder).
const EVERY_ARRAY: &str = r#"[camera]
position = [0.0, 1.0, 3.0]
look_at = [0.0, 1.0, 0.0]
up = [0.0, 1.0, 0.0]
[materials.m]
albedo = [0.5, 0.5, 0.5]
emission = [0.0, 0.0, 0.0]
[materials.c]
eta = [0.2, 0.9, 1.1]
k = [3.9, 2.4, 2.1]
[materials.g]
transparency = 1.0
attenuation_color = [0.5, 0.6, 0.7]
attenuation_distance = 2.0
[[spheres]]
center = [0.0, 0.0, 0.0]
radius = 1.0
material = "m"
[[quads]]
origin = [0.0, 0.0, 0.0]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 1.0, 0.0]
material = "m"
[[triangles]]
vertices = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.5]]
material = "m"
[[meshes]]
file = "square.obj"
translate = [0.0, 0.0, -1.0]
rotate = [0.0, 0.0, 10.0]
scale = [1.0, 1.0, 1.0]
instances = [{ translate = [1.0, 0.0, 0.0], rotate = [0.0, 90.0, 0.0], scale = [1.0, 2.0, 1.0] }]
[environment]
color = [1.0, 1.0, 1.0]
"#;

#[test]
fn every_array_key_refuses_a_wrong_number_of_elements() {
    let dir = temp_dir("every-array");
    std::fs::write(dir.join("square.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\n").unwrap();
    Scene::parse(EVERY_ARRAY, "test.toml", &dir).expect("the unchanged scene is valid");
    // (text in EVERY_ARRAY, a wrong replacement, the key the error must name, the length it got)
    let mut cases: Vec<(&str, String, &str, usize)> = Vec::new();
    for (original, key) in [
        ("position = [0.0, 1.0, 3.0]", "camera.position"),
        ("look_at = [0.0, 1.0, 0.0]", "camera.look_at"),
        ("up = [0.0, 1.0, 0.0]", "camera.up"),
        ("albedo = [0.5, 0.5, 0.5]", "materials.m.albedo"),
        ("emission = [0.0, 0.0, 0.0]", "materials.m.emission"),
        ("eta = [0.2, 0.9, 1.1]", "materials.c.eta"),
        ("k = [3.9, 2.4, 2.1]", "materials.c.k"),
        ("attenuation_color = [0.5, 0.6, 0.7]", "materials.g.attenuation_color"),
        ("center = [0.0, 0.0, 0.0]", "spheres.center"),
        ("origin = [0.0, 0.0, 0.0]", "quads.origin"),
        ("edge_u = [1.0, 0.0, 0.0]", "quads.edge_u"),
        ("edge_v = [0.0, 1.0, 0.0]", "quads.edge_v"),
        ("translate = [0.0, 0.0, -1.0]", "meshes.translate"),
        ("rotate = [0.0, 0.0, 10.0]", "meshes.rotate"),
        ("scale = [1.0, 1.0, 1.0]", "meshes.scale"),
        ("translate = [1.0, 0.0, 0.0]", "translate"),
        ("rotate = [0.0, 90.0, 0.0]", "rotate"),
        ("scale = [1.0, 2.0, 1.0]", "scale"),
        ("color = [1.0, 1.0, 1.0]", "environment.color"),
    ] {
        cases.push((original, original.replace(']', ", 7.0]"), key, 4));
        cases.push((original, format!("{}]", &original[..original.rfind(", ").unwrap()]), key, 2));
    }
    cases.push(("[0.0, 1.0, 0.5]]", "[0.0, 1.0, 0.5, 7.0]]".to_owned(), "triangles.vertices", 4));
    cases.push(("[0.0, 1.0, 0.5]]", "[0.0, 1.0, 0.5], [1.0, 1.0, 1.0]]".to_owned(), "triangles.vertices", 4));
    cases.push((", [0.0, 1.0, 0.5]]", "]".to_owned(), "triangles.vertices", 2));
    for (original, wrong, key, length) in &cases {
        assert_eq!(EVERY_ARRAY.matches(original).count(), 1, "{original}");
        let text = EVERY_ARRAY.replace(original, wrong);
        let line = EVERY_ARRAY[..EVERY_ARRAY.find(original).unwrap()].matches('\n').count() + 1;
        let e = format!("{:#}", Scene::parse(&text, "test.toml", &dir).expect_err(wrong));
        for needle in [
            "test.toml: ",
            &format!("line {line}, "),
            &format!("invalid length {length}, expected an array of exactly 3 elements"),
            key,
        ] {
            assert!(e.contains(needle), "{wrong}: '{needle}' missing from: {e}");
        }
    }
}

#[test]
fn a_long_line_is_quoted_in_part_only() {
    let e = error_of(&format!("{MINIMAL}fov = \"{}\"\n", "x".repeat(1 << 20)));
    assert!(e.starts_with("test.toml: line 4, column 7: invalid type: string"), "{}", &e[..e.len().min(2000)]);
    assert!(e.len() < 1500, "{} bytes for one error", e.len());
}

#[test]
fn nesting_beyond_the_parser_limit_is_an_error_with_its_line() {
    let deep = 5000;
    let cases = [
        format!("{MINIMAL}\n[{}]\n", vec!["a"; deep].join(".")),
        format!("{MINIMAL}\nx = {}{}\n", "[".repeat(deep), "]".repeat(deep)),
        format!("{MINIMAL}\nx = {}1{}\n", "{ a = ".repeat(deep), " }".repeat(deep)),
    ];
    for text in cases {
        let e = error_of(&text);
        assert!(e.starts_with("test.toml: line 5, column "), "{}", &e[..e.len().min(2000)]);
        assert!(e.len() < 1500, "{} bytes for one error", e.len());
    }
}

/// Absorption inside a dielectric: both keys or neither, only with transparency, a colour in
/// (0, 1] per channel and a finite distance > 0; each error names its key.
#[test]
fn attenuation_keys_are_checked_naming_the_key() {
    let glass = |keys: &str| format!("{MINIMAL}[materials.g]\ntransparency = 1.0\n{keys}\n");
    let scene = parse_result(&glass("attenuation_color = [0.5, 0.25, 1.0]\nattenuation_distance = 2.0"))
        .expect("valid attenuation");
    let attenuation = scene.materials[0].attenuation.expect("parsed");
    let sigma_a = attenuation.sigma_a();
    assert!((sigma_a - glam::Vec3::new(2f32.ln() / 2.0, 4f32.ln() / 2.0, 0.0)).abs().max_element() < 1e-6, "{sigma_a}");
    for (keys, error) in [
        (
            "attenuation_color = [0.0, 0.5, 0.5]\nattenuation_distance = 1.0",
            "materials.g.attenuation_color must be in (0, 1] per channel",
        ),
        (
            "attenuation_color = [1.5, 0.5, 0.5]\nattenuation_distance = 1.0",
            "materials.g.attenuation_color must be in (0, 1] per channel",
        ),
        (
            "attenuation_color = [nan, 0.5, 0.5]\nattenuation_distance = 1.0",
            "materials.g.attenuation_color must be finite",
        ),
        (
            "attenuation_color = [0.5, 0.5, 0.5]\nattenuation_distance = 0.0",
            "materials.g.attenuation_distance must be > 0",
        ),
        (
            "attenuation_color = [0.5, 0.5, 0.5]\nattenuation_distance = inf",
            "materials.g.attenuation_distance must be finite",
        ),
        ("attenuation_color = [0.5, 0.5, 0.5]", "materials.g.attenuation_color needs materials.g.attenuation_distance"),
        ("attenuation_distance = 1.0", "materials.g.attenuation_distance needs materials.g.attenuation_color"),
    ] {
        let e = error_of(&glass(keys));
        assert!(e.contains(error), "{keys}: expected '{error}', got: {e}");
    }
    let e =
        error_of(&format!("{MINIMAL}[materials.g]\nattenuation_color = [0.5, 0.5, 0.5]\nattenuation_distance = 1.0\n"));
    assert!(e.contains("materials.g.attenuation_color needs materials.g.transparency > 0"), "{e}");
}

#[test]
fn unknown_material_is_named() {
    let e = error_of(&format!("{MINIMAL}[[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"gold\"\n"));
    assert!(e.contains("spheres[0].material") && e.contains("gold"), "{e}");
}

#[test]
fn out_of_range_values_are_errors_naming_the_key() {
    let cases = [
        (
            format!("{MINIMAL}[materials.m]\n[[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = -1.0\nmaterial = \"m\"\n"),
            "spheres[0].radius",
        ),
        (format!("{MINIMAL}[materials.m]\nreflectivity = 0.6\ntransparency = 0.6\n"), "R + T <= 1"),
        (format!("{MINIMAL}[materials.m]\nior = 0.0\n"), "materials.m.ior"),
        (format!("{MINIMAL}[materials.m]\nalbedo = [nan, 0.0, 0.0]\n"), "materials.m.albedo"),
        (format!("{MINIMAL}[materials.m]\nemission = [-1.0, 0.0, 0.0]\n"), "materials.m.emission"),
        ("[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\nfov = 180.0\n".to_string(), "camera.fov"),
        ("[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 3.0]\n".to_string(), "camera.look_at"),
        (format!("{MINIMAL}[film]\nwidth = 0\n"), "film.width"),
        (format!("{MINIMAL}[film]\nspp = 0\n"), "film.spp"),
        (format!("{MINIMAL}[integrator]\nabsorption = 1.5\n"), "integrator.absorption"),
        (format!("{MINIMAL}aperture = -0.1\n"), "camera.aperture"),
        (format!("{MINIMAL}aperture = inf\n"), "camera.aperture"),
        (format!("{MINIMAL}focus_distance = 0.0\n"), "camera.focus_distance"),
        (format!("{MINIMAL}focus_distance = nan\n"), "camera.focus_distance"),
        (format!("{MINIMAL}[integrator]\nclamp = 0.0\n"), "integrator.clamp"),
        (format!("{MINIMAL}[integrator]\nclamp = inf\n"), "integrator.clamp"),
        (format!("{MINIMAL}[environment]\ncolor = [1.0, 1.0, 1.0]\nprobe = \"p.pfm\"\n"), "only one of"),
        (format!("{MINIMAL}[environment]\nintensity = inf\n"), "environment.intensity"),
    ];
    for (text, key) in cases {
        let e = error_of(&text);
        assert!(e.contains(key), "expected an error naming '{key}', got: {e}");
    }
}

#[test]
fn lens_filter_and_clamp_default_to_a_pinhole_box_filter_and_no_clamp() {
    let scene = parse_result(MINIMAL).unwrap();
    assert_eq!((scene.camera.aperture, scene.camera.focus_distance), (0.0, 3.0), "focused on look_at");
    assert_eq!(scene.film.filter, Filter::Box);
    assert_eq!(scene.integrator.clamp, None);
    let scene = parse_result(&format!(
        "{MINIMAL}aperture = 0.05\nfocus_distance = 2.5\n[film]\nfilter = \"gaussian\"\n[integrator]\nclamp = 10.0\n"
    ))
    .unwrap();
    assert_eq!((scene.camera.aperture, scene.camera.focus_distance), (0.05, 2.5));
    assert_eq!((scene.film.filter, scene.integrator.clamp), (Filter::Gaussian, Some(10.0)));
}

#[test]
fn unknown_filter_is_named_with_the_choices() {
    let e = error_of(&format!("{MINIMAL}[film]\nfilter = \"lanczos\"\n"));
    assert!(e.contains("filter") && e.contains("lanczos") && e.contains("tent") && e.contains("line 5"), "{e}");
}

#[test]
fn sampler_defaults_to_sobol_and_unknown_samplers_are_named() {
    assert_eq!(parse_result(MINIMAL).unwrap().integrator.sampler, Sampler::Sobol);
    let scene = parse_result(&format!("{MINIMAL}[integrator]\nsampler = \"independent\"\n")).unwrap();
    assert_eq!(scene.integrator.sampler, Sampler::Independent);
    let e = error_of(&format!("{MINIMAL}[integrator]\nsampler = \"halton\"\n"));
    assert!(e.contains("sampler") && e.contains("halton") && e.contains("sobol") && e.contains("independent"), "{e}");
}

#[test]
fn missing_probe_file_is_named() {
    let e = error_of(&format!("{MINIMAL}[environment]\nprobe = \"no/such/probe.pfm\"\n"));
    assert!(e.contains("no/such/probe.pfm"), "{e}");
}

#[test]
fn obj_mesh_loads_with_transform() {
    let dir = temp_dir("obj");
    // A unit square in the xy plane as two triangles, plus one zero-area face that is dropped.
    std::fs::write(dir.join("square.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\nf 1 1 2\n").unwrap();
    let text = format!(
        "{MINIMAL}[materials.m]\n[[meshes]]\nfile = \"square.obj\"\nmaterial = \"m\"\nscale = 2.0\nrotate = [0.0, 90.0, 0.0]\ntranslate = [0.0, 0.0, -5.0]\n"
    );
    let scene = Scene::parse(&text, "mesh.toml", &dir).unwrap();
    assert_eq!(scene.meshes.len(), 1);
    assert_eq!(scene.meshes[0].triangles.len(), 2, "two triangles, the degenerate face dropped");
    assert_eq!(scene.meshes[0].triangle_materials, vec![0, 0], "the material override applies to every face");
    // (1, 0, 0) scaled by 2 -> (2, 0, 0), rotated 90 degrees about +y -> (0, 0, -2), translated -> (0, 0, -7).
    let p = scene.instances[0].transform.transform_point3(scene.meshes[0].positions[1]);
    assert!((p - glam::Vec3::new(0.0, 0.0, -7.0)).length() < 1e-5, "{p:?}");
}

/// Placing one file several times, by repeated entries or an `instances` list, stores it once.
#[test]
fn repeated_mesh_placements_share_one_mesh() {
    let dir = temp_dir("instances");
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let text = format!(
        "{MINIMAL}[materials.m]\n[materials.n]\n\
         [[meshes]]\nfile = \"tri.obj\"\nmaterial = \"m\"\nscale = 2.0\n\
         instances = [{{ translate = [1, 0, 0] }}, {{ translate = [0, 3, 0], rotate = [0, 0, 90] }}]\n\
         [[meshes]]\nfile = \"tri.obj\"\nmaterial = \"m\"\n\
         [[meshes]]\nfile = \"tri.obj\"\nmaterial = \"n\"\n"
    );
    let scene = Scene::parse(&text, "instances.toml", &dir).unwrap();
    assert_eq!(scene.meshes.len(), 2, "one mesh per (file, material); a new material needs its own copy");
    assert_eq!(scene.instances.len(), 4);
    assert_eq!(scene.instances.iter().map(|i| i.mesh).collect::<Vec<_>>(), vec![0, 0, 0, 1]);
    // The entry's scale applies first, then each instance's own placement: (1, 0, 0) -> (2, 0, 0)
    // -> rotated 90 degrees about z -> (0, 2, 0) -> translated -> (0, 5, 0).
    let p = scene.instances[1].transform.transform_point3(glam::Vec3::X);
    assert!((p - glam::Vec3::new(0.0, 5.0, 0.0)).length() < 1e-5, "{p:?}");
    let e = error_of(&format!(
        "{MINIMAL}[[meshes]]\nfile = \"tri.obj\"\ninstances = [{{ translate = [1, 0, 0], spin = 3 }}]\n"
    ));
    assert!(e.contains("spin"), "{e}");
    let e = format!(
        "{:#}",
        Scene::parse(
            &format!("{MINIMAL}[[meshes]]\nfile = \"tri.obj\"\ninstances = [{{ scale = [1, 0, 1] }}]\n"),
            "zero.toml",
            &dir
        )
        .unwrap_err()
    );
    assert!(e.contains("meshes[0].instances[0].scale"), "{e}");
}

/// An OBJ with its MTL brings its own materials, emitters among them.
#[test]
fn obj_materials_come_from_its_mtl() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/models/CornellBox-Original.obj");
    let scene = Scene::load(&path).unwrap();
    let light = scene.materials.iter().find(|m| m.name.ends_with(":light")).expect("the MTL's light material");
    assert_eq!(light.emission, glam::Vec3::new(17.0, 12.0, 4.0));
    let red = scene.materials.iter().find(|m| m.name.ends_with(":leftWall")).expect("leftWall");
    assert_eq!(red.albedo, glam::Vec3::new(0.63, 0.065, 0.05));
    assert_eq!(scene.light_count(), 2, "the light quad is two triangles");
}

#[test]
fn malformed_obj_is_rejected_with_the_file_name() {
    let dir = temp_dir("badobj");
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    std::fs::write(dir.join("nan.obj"), "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let ply_header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    std::fs::write(dir.join("bad.ply"), format!("{ply_header}0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n")).unwrap();
    std::fs::write(dir.join("huge.ply"), ply_header.replace("vertex 3", "vertex 1000000000")).unwrap();
    std::fs::write(dir.join("broken.gltf"), "{ \"asset\": { \"version\": \"2.0\" }, \"nodes\": [").unwrap();
    std::fs::write(
        dir.join("cyclic.gltf"),
        r#"{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"children": [1]}, {"children": [0]}]}"#,
    )
    .unwrap();
    std::fs::write(dir.join("shape.stl"), "solid x\nendsolid x\n").unwrap();
    for file in ["bad.obj", "nan.obj", "missing.obj", "bad.ply", "huge.ply", "broken.gltf", "cyclic.gltf", "shape.stl"]
    {
        let text = format!("{MINIMAL}[materials.m]\n[[meshes]]\nfile = \"{file}\"\nmaterial = \"m\"\n");
        let e = format!("{:#}", Scene::parse(&text, "mesh.toml", &dir).expect_err("bad mesh rejected"));
        assert!(e.contains(file), "{file}: {e}");
    }
}

/// A mesh placed with an anisotropic material (`roughness_v` differing from `roughness`) gets
/// MikkTSpace tangents, which orient its lobes, along growing u (+x here); with an isotropic
/// material it gets none. `roughness_v` outside [0, 1] is an error naming the key.
#[test]
fn anisotropic_mesh_materials_give_their_meshes_tangents_along_u() {
    let dir = temp_dir("anisotropic");
    std::fs::write(dir.join("square.obj"), "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n").unwrap();
    let text = format!(
        "{MINIMAL}[materials.brushed]\nreflectivity = 1.0\nroughness = 0.2\nroughness_v = 0.6\n[materials.even]\nreflectivity = 1.0\nroughness = 0.2\nroughness_v = 0.2\n\
         [[meshes]]\nfile = \"square.obj\"\nmaterial = \"brushed\"\n[[meshes]]\nfile = \"square.obj\"\nmaterial = \"even\"\n"
    );
    let scene = Scene::parse(&text, "anisotropic.toml", &dir).unwrap();
    let brushed = &scene.meshes[scene
        .meshes
        .iter()
        .position(|m| scene.materials[m.triangle_materials[0] as usize].name == "brushed")
        .unwrap()];
    let even = &scene.meshes
        [scene.meshes.iter().position(|m| scene.materials[m.triangle_materials[0] as usize].name == "even").unwrap()];
    assert_eq!(brushed.tangents.len(), brushed.positions.len(), "one tangent a vertex");
    assert!(brushed.tangents.iter().all(|t| (t.truncate() - glam::Vec3::X).length() < 1e-5), "{:?}", brushed.tangents);
    assert!(even.tangents.is_empty(), "an isotropic material needs no tangents");
    // A texture's to_uv (here swapping u and v) moves where the texture is read, not the lobes:
    // their frame is the mesh's own u, as Mitsuba's and pbrt's dp/du.
    let textured = format!(
        "{MINIMAL}[materials.brushed]\nreflectivity = 1.0\nroughness = 0.2\nroughness_v = 0.6\n\
         albedo_texture = {{ checkerboard = [[0.4, 0.4, 0.4], [0.2, 0.2, 0.2]], to_uv = [[0, 1, 0], [1, 0, 0]] }}\n\
         [[meshes]]\nfile = \"square.obj\"\nmaterial = \"brushed\"\n"
    );
    let scene = Scene::parse(&textured, "anisotropic-textured.toml", &dir).unwrap();
    assert!(
        scene.meshes[0].tangents.iter().all(|t| (t.truncate() - glam::Vec3::X).length() < 1e-5),
        "{:?}",
        scene.meshes[0].tangents
    );
    let e = error_of(&format!("{MINIMAL}[materials.m]\nroughness_v = 1.5\n"));
    assert!(e.contains("materials.m.roughness_v must be in [0, 1], got 1.5"), "{e}");
}
