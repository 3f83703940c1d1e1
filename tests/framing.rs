//! Cameras that frame a scene (issue 51): a mesh file without a camera of its own, and
//! `render --camera-orbit AZ,EL` / `--camera-fit`.
//!
//! The model is a flat dark square in the xz plane, two-sided, under the white sky a mesh file is
//! rendered under: a camera that sees it has a dark centre, one that looks along its plane (as the
//! framing from +z did) sees only sky.

mod common;

use caustica::image::read_image;
use caustica::scene::Scene;
use common::gltf_square::write_gltf_square;
use common::*;
use std::path::Path;

const DARK_SQUARE: &str = r#"{"doubleSided": true, "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.1, 0.1, 1], "metallicFactor": 0, "roughnessFactor": 1}}"#;

/// Luminance of the centre pixel and the image's mean.
fn centre_and_mean(image: &caustica::image::RgbImage) -> (f64, f64) {
    let centre = luminance(image.get(image.width / 2, image.height / 2));
    let mean = image.pixels.iter().map(|&p| luminance(p)).sum::<f64>() / image.pixels.len() as f64;
    (centre, mean)
}

/// A flat model with no camera is seen from above: its centre is the dark square, and the square
/// covers a good part of the view (a fitted frame), yet not all of it (the whole square is in view).
#[test]
fn a_flat_model_without_a_camera_is_seen_from_above() {
    let dir = temp_dir("framing-flat");
    write_gltf_square(&dir, "square.gltf", 0.0, 1.0, DARK_SQUARE, "");
    let mut scene = Scene::load(&dir.join("square.gltf")).expect("the square loads as a scene");
    assert!(scene.camera.position.y > 0.5 * (scene.camera.position - scene.camera.look_at).length());
    scene.film.width = 16;
    scene.film.height = 16;
    scene.film.spp = 4;
    let (_lock, ctx) = gpu();
    let image = render(&ctx, &scene, 1);
    let (centre, mean) = centre_and_mean(&image);
    assert!(centre < 0.5, "the centre sees the dark square: {centre}");
    assert!(mean < 0.8 && mean > 0.2, "the square fills part of the view, the sky the rest: mean {mean}");
}

fn render_cli(dir: &Path, extra: &[&str]) -> std::process::Output {
    let (model, out) = (dir.join("square.gltf"), dir.join("out.pfm"));
    let mut args = vec!["render", model.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend(["--width", "16", "--height", "12", "--spp", "2", "-q"]);
    args.extend(extra);
    caustica(&args)
}

/// `--camera-orbit 0,0` looks along the square's plane and sees sky; `--camera-orbit 30,90`
/// looks straight down on it; `--camera-fit` keeps a camera's direction; a bad angle is an error.
#[test]
fn camera_orbit_and_fit_on_the_command_line() {
    let dir = temp_dir("framing-cli");
    write_gltf_square(&dir, "square.gltf", 0.0, 1.0, DARK_SQUARE, "");
    let read = || read_image(&dir.join("out.pfm")).expect("the render wrote its image");

    let level = render_cli(&dir, &["--camera-orbit", "0,0"]);
    assert!(level.status.success(), "{}", String::from_utf8_lossy(&level.stderr));
    let (_, mean) = centre_and_mean(&read());
    assert!(mean > 0.9, "edge on, the square is almost invisible: mean {mean}");

    let above = render_cli(&dir, &["--camera-orbit", "30,90"]);
    assert!(above.status.success(), "{}", String::from_utf8_lossy(&above.stderr));
    let (centre, mean) = centre_and_mean(&read());
    assert!(centre < 0.5 && mean < 0.6, "from above the square fills the view: centre {centre}, mean {mean}");

    let fit = render_cli(&dir, &["--camera-fit"]);
    assert!(fit.status.success(), "{}", String::from_utf8_lossy(&fit.stderr));
    let (centre, _) = centre_and_mean(&read());
    assert!(centre < 0.5, "the fitted default camera still sees the square: {centre}");

    fails_with(&render_cli(&dir, &["--camera-orbit", "10,100"]), "elevation 100 is outside");
    fails_with(&render_cli(&dir, &["--camera-orbit", "ten"]), "AZ,EL");
}
