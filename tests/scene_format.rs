//! The TOML scene format: what it accepts and how it rejects mistakes (naming the key and line).

mod common;

use caustica::scene::{Environment, Scene, Shape};
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
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{}: {e:#}", path.display()));
            assert!(!scene.shapes.is_empty(), "{} has no shapes", path.display());
            count += 1;
        }
    }
    assert!(count >= 3, "expected at least the Cornell box, sky and probe scenes");
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

#[test]
fn unknown_material_is_named() {
    let e = error_of(&format!("{MINIMAL}[[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"gold\"\n"));
    assert!(e.contains("spheres[0].material") && e.contains("gold"), "{e}");
}

#[test]
fn out_of_range_values_are_errors_naming_the_key() {
    let cases = [
        (format!("{MINIMAL}[materials.m]\n[[spheres]]\ncenter = [0.0, 0.0, 0.0]\nradius = -1.0\nmaterial = \"m\"\n"), "spheres[0].radius"),
        (format!("{MINIMAL}[materials.m]\nreflectivity = 0.6\ntransparency = 0.6\n"), "R + T <= 1"),
        (format!("{MINIMAL}[materials.m]\nior = 0.0\n"), "materials.m.ior"),
        (format!("{MINIMAL}[materials.m]\nalbedo = [nan, 0.0, 0.0]\n"), "materials.m.albedo"),
        (format!("{MINIMAL}[materials.m]\nemission = [-1.0, 0.0, 0.0]\n"), "materials.m.emission"),
        ("[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 0.0]\nfov = 180.0\n".to_string(), "camera.fov"),
        ("[camera]\nposition = [0.0, 1.0, 3.0]\nlook_at = [0.0, 1.0, 3.0]\n".to_string(), "camera.look_at"),
        (format!("{MINIMAL}[film]\nwidth = 0\n"), "film.width"),
        (format!("{MINIMAL}[film]\nspp = 0\n"), "film.spp"),
        (format!("{MINIMAL}[integrator]\nabsorption = 1.5\n"), "integrator.absorption"),
        (format!("{MINIMAL}[environment]\ncolor = [1.0, 1.0, 1.0]\nprobe = \"p.pfm\"\n"), "only one of"),
        (format!("{MINIMAL}[environment]\nintensity = inf\n"), "environment.intensity"),
    ];
    for (text, key) in cases {
        let e = error_of(&text);
        assert!(e.contains(key), "expected an error naming '{key}', got: {e}");
    }
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
    assert_eq!(scene.shapes.len(), 2, "two triangles, the degenerate face dropped");
    let Shape::Triangle { v, .. } = scene.shapes[0] else { panic!("expected a triangle") };
    // (1, 0, 0) scaled by 2 -> (2, 0, 0), rotated 90 degrees about +y -> (0, 0, -2), translated -> (0, 0, -7).
    assert!((v[1] - glam::Vec3::new(0.0, 0.0, -7.0)).length() < 1e-5, "{:?}", v[1]);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn malformed_obj_is_rejected_with_the_file_name() {
    let dir = temp_dir("badobj");
    std::fs::write(dir.join("bad.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 9\n").unwrap();
    std::fs::write(dir.join("nan.obj"), "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    for file in ["bad.obj", "nan.obj", "missing.obj"] {
        let text = format!("{MINIMAL}[materials.m]\n[[meshes]]\nfile = \"{file}\"\nmaterial = \"m\"\n");
        let e = format!("{:#}", Scene::parse(&text, "mesh.toml", &dir).expect_err("bad mesh rejected"));
        assert!(e.contains(file), "{file}: {e}");
    }
    std::fs::remove_dir_all(dir).ok();
}
