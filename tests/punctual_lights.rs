//! Point, spot and directional lights (`[[lights]]`) against their closed forms, on lavapipe.
//!
//! The plane tests look straight down at a diffuse floor (albedo 0.5) under one light and a black
//! sky. Nothing else is in the scene, so every pixel is the light's direct illumination alone,
//! albedo / pi x the irradiance at the floor point it sees; for a delta light that is one number
//! per point (next-event estimation is exact), so the only spread within a pixel is the floor
//! point moving across its footprint. Each pixel is compared with the closed form averaged over
//! its footprint (the box filter), and the image's mean residual with zero: a per-pixel error in
//! the shape (a missing cosine, a wrong power of the distance, a falloff in the wrong place)
//! fails the first, a bias of 0.1 % in the level fails the second.

mod common;

use caustica::image::RgbImage;
use caustica::scene::{LightSelection, Scene};
use common::*;
use glam::DVec3;
use std::f64::consts::PI;

const ALBEDO: f64 = 0.5;
/// Height of the camera above the floor; it looks straight down, image rows along -z.
const CAMERA_HEIGHT: f64 = 2.0;
const FOV_DEG: f64 = 60.0;
const SIZE: u32 = 24;
const SPP: u32 = 16;

/// The floor (6 x 6, twice what the camera sees: the scene's size sets a directional light's
/// power) seen from above under `lights` (TOML `[[lights]]` entries) and a black sky.
fn floor_scene(lights: &str, spp: u32) -> Scene {
    parse(&format!(
        r#"
        camera = {{ position = [0.0, {CAMERA_HEIGHT}, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = {FOV_DEG} }}
        film = {{ width = {SIZE}, height = {SIZE}, spp = {spp} }}
        [materials.floor]
        albedo = [{ALBEDO}, {ALBEDO}, {ALBEDO}]
        [[quads]]
        origin = [-3.0, 0.0, 3.0]
        edge_u = [6.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -6.0]
        material = "floor"
        {lights}
        "#
    ))
}

/// The floor point seen at film position (fx, fy) in [0, 1]^2 (the kernel's pinhole camera:
/// right = +x, up the image = -z).
fn floor_point(fx: f64, fy: f64) -> DVec3 {
    let tan_half = (0.5 * FOV_DEG).to_radians().tan();
    let (x, y) = ((2.0 * fx - 1.0) * tan_half, (1.0 - 2.0 * fy) * tan_half);
    DVec3::new(CAMERA_HEIGHT * x, 0.0, -CAMERA_HEIGHT * y)
}

/// Per pixel: the mean of `radiance` over the pixel's footprint (an 8 x 8 midpoint grid) and its
/// spread (largest minus smallest value on the grid).
fn expected_image(radiance: &dyn Fn(DVec3) -> f64) -> Vec<(f64, f64)> {
    const GRID: u32 = 8;
    let mut out = Vec::new();
    for py in 0..SIZE {
        for px in 0..SIZE {
            let values: Vec<f64> = (0..GRID * GRID)
                .map(|k| {
                    let fx = (px as f64 + ((k % GRID) as f64 + 0.5) / GRID as f64) / SIZE as f64;
                    let fy = (py as f64 + ((k / GRID) as f64 + 0.5) / GRID as f64) / SIZE as f64;
                    radiance(floor_point(fx, fy))
                })
                .collect();
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            let spread =
                values.iter().cloned().fold(f64::MIN, f64::max) - values.iter().cloned().fold(f64::MAX, f64::min);
            out.push((mean, spread));
        }
    }
    out
}

/// Each pixel within 5 x its footprint's spread / (2 sqrt(spp)) (the error of averaging `spp`
/// points of a function confined to that spread) plus 0.02 % (f32 sums, ray offsets) of the
/// image's mean; and the mean residual within 5 standard errors (from the residuals' own scatter)
/// plus 0.02 %, which must be below 0.1 % of the mean: the smallest bias the test claims to fail.
fn assert_image_is(image: &RgbImage, expected: &[(f64, f64)], what: &str) {
    let mean_expected = expected.iter().map(|e| e.0).sum::<f64>() / expected.len() as f64;
    let floor = 2e-4 * mean_expected;
    let mut residuals = Vec::new();
    for (i, (&p, &(value, spread))) in image.pixels.iter().zip(expected).enumerate() {
        let measured = luminance(p);
        let tolerance = 5.0 * spread / (2.0 * (SPP as f64).sqrt()) + floor;
        let (x, y) = (i as u32 % SIZE, i as u32 / SIZE);
        assert!(
            (measured - value).abs() <= tolerance,
            "{what}: pixel ({x}, {y}) is {measured:.6}, expected {value:.6} (tolerance {tolerance:.6})"
        );
        residuals.push(measured - value);
    }
    let n = residuals.len() as f64;
    let mean = residuals.iter().sum::<f64>() / n;
    let stderr = (residuals.iter().map(|r| r * r).sum::<f64>() / n / n).sqrt();
    let tolerance = 5.0 * stderr + floor;
    eprintln!(
        "{what}: mean residual {:+.4} % of the mean {mean_expected:.5}, tolerance {:.4} %",
        mean / mean_expected * 100.0,
        tolerance / mean_expected * 100.0
    );
    assert!(
        tolerance <= 1e-3 * mean_expected,
        "{what}: the tolerance {:.3} % no longer resolves a 0.1 % bias",
        tolerance / mean_expected * 100.0
    );
    assert!(
        mean.abs() <= tolerance,
        "{what}: the image is {:+.3} % off its closed form (tolerance {:.3} %)",
        mean / mean_expected * 100.0,
        tolerance / mean_expected * 100.0
    );
}

/// albedo / pi x I cos(theta) / d^2 at a floor point lit by a point of intensity I at `light`.
fn point_lit(light: DVec3, intensity: f64, p: DVec3) -> f64 {
    let to_light = light - p;
    let d2 = to_light.length_squared();
    ALBEDO / PI * intensity * (to_light.y / d2.sqrt()) / d2
}

/// A point light over a diffuse plane gives (albedo / pi) I cos(theta) / d^2 at every point.
#[test]
fn point_light_over_a_diffuse_plane_is_intensity_cosine_over_distance_squared() {
    let (_lock, ctx) = gpu();
    let light = DVec3::new(0.3, 1.0, -0.2);
    let scene =
        floor_scene("[[lights]]\ntype = \"point\"\nposition = [0.3, 1.0, -0.2]\nintensity = [2.0, 2.0, 2.0]", SPP);
    let image = render(&ctx, &scene, 1);
    assert_image_is(&image, &expected_image(&|p| point_lit(light, 2.0, p)), "point light over a plane");
}

/// A directional light gives (albedo / pi) E cos(theta) everywhere.
#[test]
fn directional_light_is_irradiance_times_cosine() {
    let (_lock, ctx) = gpu();
    let travel = DVec3::new(0.4, -1.0, 0.3).normalize();
    let scene = floor_scene(
        "[[lights]]\ntype = \"directional\"\ndirection = [0.4, -1.0, 0.3]\nirradiance = [3.0, 3.0, 3.0]",
        SPP,
    );
    let image = render(&ctx, &scene, 2);
    assert_image_is(&image, &expected_image(&|_| ALBEDO / PI * 3.0 * -travel.y), "directional light over a plane");
}

/// A spot pointing straight down from 1 above the floor, cone_angle 40, falloff_start 20: the point
/// light inside 20 degrees, zero outside 40, linear in the angle between. The view holds all three
/// zones, each with pixels wholly inside it.
#[test]
fn spot_light_is_the_point_light_inside_its_falloff_zero_outside_and_linear_between() {
    let (_lock, ctx) = gpu();
    let light = DVec3::new(0.0, 1.0, 0.0);
    let (cone, falloff) = (40f64.to_radians(), 20f64.to_radians());
    let lights = "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nintensity = [2.0, 2.0, 2.0]\ncone_angle = 40.0\nfalloff_start = 20.0";
    let image = render(&ctx, &floor_scene(lights, SPP), 3);
    let angle = |p: DVec3| (light - p).angle_between(DVec3::Y);
    let factor = |t: f64| {
        if t <= falloff {
            1.0
        } else if t >= cone {
            0.0
        } else {
            (cone - t) / (cone - falloff)
        }
    };
    let expected = expected_image(&|p| point_lit(light, 2.0, p) * factor(angle(p)));
    assert_image_is(&image, &expected, "spot light over a plane");
    // The zones, by pixels whose footprint lies wholly in one (the spread is 0 only outside).
    let point = expected_image(&|p| point_lit(light, 2.0, p));
    let inside = expected.iter().zip(&point).filter(|(s, p)| s.0 == p.0).count();
    let outside = expected.iter().filter(|e| e.0 == 0.0).count();
    let between = expected.len() - inside - outside;
    eprintln!("spot: {inside} pixels inside falloff_start, {between} in the falloff or on its edges, {outside} outside cone_angle");
    assert!(inside >= 20 && between >= 100 && outside >= 100, "the view no longer holds all three zones");
    for (i, _) in expected.iter().enumerate().filter(|(_, e)| e.0 == 0.0) {
        assert_eq!(luminance(image.pixels[i]), 0.0, "pixel {i} lies outside the cone but is lit");
    }
}

/// A point, spot and directional light at once, picked by power or uniformly, beside an emissive
/// sphere out of view: the pixels are the sum of the four closed forms whichever way lights are
/// picked (the pick probabilities of area and punctual lights share one total, and the sphere's
/// MIS weight divides by it). Fails a 2 % bias (the noise of picking by power; 0.3 % uniformly).
fn assert_four_lights_add_up(selection: LightSelection, seed: u32) {
    let (_lock, ctx) = gpu();
    let lights = "[[lights]]\ntype = \"point\"\nposition = [0.3, 1.0, -0.2]\nintensity = [2.0, 2.0, 2.0]\n\
                  [[lights]]\ntype = \"spot\"\nposition = [-0.5, 1.5, 0.0]\nlook_at = [-0.5, 0.0, 0.0]\nintensity = [20.0, 20.0, 20.0]\ncone_angle = 30.0\nfalloff_start = 10.0\n\
                  [[lights]]\ntype = \"directional\"\ndirection = [0.4, -1.0, 0.3]\nirradiance = [0.5, 0.5, 0.5]\n\
                  [materials.lamp]\nalbedo = [0.0, 0.0, 0.0]\nemission = [4.0, 4.0, 4.0]\n\
                  [[spheres]]\ncenter = [0.9, 1.2, 0.5]\nradius = 0.15\nmaterial = \"lamp\"";
    let mut scene = floor_scene(lights, 1024);
    scene.integrator.light_selection = selection;
    let image = render(&ctx, &scene, seed);
    let spot = DVec3::new(-0.5, 1.5, 0.0);
    let (cone, falloff) = (30f64.to_radians(), 10f64.to_radians());
    let spot_factor = |p: DVec3| {
        let t = (spot - p).angle_between(DVec3::Y);
        if t <= falloff {
            1.0
        } else if t >= cone {
            0.0
        } else {
            (cone - t) / (cone - falloff)
        }
    };
    let travel = DVec3::new(0.4, -1.0, 0.3).normalize();
    // A sphere wholly above the horizon: E = pi L (r / d)^2 cos(theta) towards its centre.
    let sphere = |p: DVec3| {
        let to_centre = DVec3::new(0.9, 1.2, 0.5) - p;
        PI * 4.0 * (0.15 / to_centre.length()).powi(2) * to_centre.normalize().y
    };
    let expected = expected_image(&|p| {
        point_lit(DVec3::new(0.3, 1.0, -0.2), 2.0, p)
            + point_lit(spot, 20.0, p) * spot_factor(p)
            + ALBEDO / PI * (0.5 * -travel.y + sphere(p))
    });
    // Picking one of four lights per sample adds noise (by power, most: the second number of the
    // alias table's pick is not stratified with the first): compare the mean, with its own scatter.
    let (mean, stderr) =
        mean_and_stderr(&image.pixels.iter().zip(&expected).map(|(p, e)| luminance(*p) - e.0).collect::<Vec<_>>());
    let level = expected.iter().map(|e| e.0).sum::<f64>() / expected.len() as f64;
    let tolerance = 5.0 * stderr + 2e-4 * level;
    eprintln!(
        "four lights picked by {selection:?}: mean residual {:+.4} %, tolerance {:.4} %",
        mean / level * 100.0,
        tolerance / level * 100.0
    );
    assert!(
        tolerance <= 0.02 * level,
        "the tolerance {:.3} % no longer resolves a 2 % bias",
        tolerance / level * 100.0
    );
    assert!(
        mean.abs() <= tolerance,
        "four lights picked by {selection:?}: {:+.3} % off the sum of their closed forms",
        mean / level * 100.0
    );
}

#[test]
fn point_spot_and_directional_lights_picked_by_power_add_up() {
    assert_four_lights_add_up(LightSelection::Power, 4);
}

#[test]
fn point_spot_and_directional_lights_picked_uniformly_add_up() {
    assert_four_lights_add_up(LightSelection::Uniform, 5);
}

/// A sun disk (20 degrees across, tilted 25 degrees from the zenith) gives `irradiance` on a
/// surface facing it, so irradiance x cos(tilt) on the floor: a uniform disk wholly above the
/// horizon has a cosine-weighted solid angle of pi sin^2(radius) cos(tilt), and its radiance is
/// irradiance / (pi sin^2(radius)). Sampled by next-event estimation and BSDF sampling, MIS
/// weighted. Fails a 0.2 % bias.
#[test]
fn sun_disk_gives_its_irradiance() {
    let (_lock, ctx) = gpu();
    let tilt = 25f64.to_radians();
    let lights = format!("[[lights]]\ntype = \"directional\"\ndirection = [{}, {}, 0.0]\nirradiance = [2.0, 2.0, 2.0]\nangular_diameter = 20.0", tilt.sin(), -tilt.cos());
    let image = render(&ctx, &floor_point_scene(&lights, 256, true), 6);
    assert_mean_is(&image, 0.5 / PI * 2.0 * tilt.cos(), 2e-4, 0.002, "floor under a sun disk");
}

/// The same disk, 60 degrees across, found by BSDF sampling alone (no next-event estimation):
/// the radiance of the disk seen by escaping rays. Fails a 3 % bias.
#[test]
fn sun_disk_found_by_bsdf_sampling_alone_gives_its_irradiance() {
    let (_lock, ctx) = gpu();
    let tilt = 25f64.to_radians();
    let lights = format!("[[lights]]\ntype = \"directional\"\ndirection = [{}, {}, 0.0]\nirradiance = [2.0, 2.0, 2.0]\nangular_diameter = 60.0", tilt.sin(), -tilt.cos());
    let image = render(&ctx, &floor_point_scene(&lights, 256, false), 7);
    assert_mean_is(&image, 0.5 / PI * 2.0 * tilt.cos(), 2e-4, 0.03, "floor under a sun disk, BSDF sampling only");
}

/// Penumbra of a sun disk (8 degrees across, straight overhead) behind the straight edge of a black
/// half-plane 1 above the floor, covering x < 0. A floor point at x sees the part of the disk whose
/// rays pass x + h w.x / w.y >= 0; its irradiance is that part's cosine-weighted integral (a polar
/// midpoint rule over the cone here), rising from 0 to E across x in [-h tan r, h tan r], r the
/// disk's angular radius. The camera, under the half-plane, sees a strip across the edge, 64
/// columns of 32 rows; each column's mean is compared with the closed form within 6 standard
/// errors of its rows, and the width of the penumbra (from 10 % to 90 %) with the closed form's
/// within one column (6.25 mm of 140 mm: a disk 5 % too wide or narrow fails).
#[test]
fn sun_disk_casts_a_penumbra_of_the_right_width() {
    let (_lock, ctx) = gpu();
    let (width, height) = (64u32, 32u32);
    let (height_above, diameter_deg, irradiance, camera_y) = (1.0f64, 8.0f64, 2.0f64, 0.5f64);
    let half_view = 0.2f64;
    let tan_half = half_view / camera_y / (width as f64 / height as f64);
    let fov = 2.0 * tan_half.atan().to_degrees();
    let scene = parse(&format!(
        r#"
        camera = {{ position = [0.0, {camera_y}, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = {fov} }}
        film = {{ width = {width}, height = {height}, spp = 64 }}
        [materials.floor]
        albedo = [0.5, 0.5, 0.5]
        [materials.black]
        albedo = [0.0, 0.0, 0.0]
        [[quads]]
        origin = [-50.0, 0.0, 50.0]
        edge_u = [100.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -100.0]
        material = "floor"
        [[quads]]
        origin = [-50.0, {height_above}, -50.0]
        edge_u = [50.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, 100.0]
        material = "black"
        [[lights]]
        type = "directional"
        direction = [0.0, -1.0, 0.0]
        irradiance = [{irradiance}, {irradiance}, {irradiance}]
        angular_diameter = {diameter_deg}
        "#
    ));
    let image = render(&ctx, &scene, 8);
    let radius = (0.5 * diameter_deg).to_radians();
    let radiance = irradiance / (PI * radius.sin().powi(2));
    // Irradiance at floor x: the visible part of the disk, cosine weighted.
    let floor_irradiance = |x: f64| {
        let (steps_t, steps_p) = (200, 400);
        let (dt, dp) = (radius / steps_t as f64, 2.0 * PI / steps_p as f64);
        let mut sum = 0.0;
        for i in 0..steps_t {
            let t = (i as f64 + 0.5) * dt;
            let (st, ct) = t.sin_cos();
            for j in 0..steps_p {
                let p = (j as f64 + 0.5) * dp;
                if x + height_above * st * p.cos() / ct >= 0.0 {
                    sum += ct * st * dt * dp;
                }
            }
        }
        radiance * sum
    };
    let column_x = |c: f64| (2.0 * c / width as f64 - 1.0) * half_view;
    let mut measured = Vec::new();
    let mut expected = Vec::new();
    for c in 0..width {
        let values: Vec<f64> = (0..height).map(|r| luminance(image.get(c, r))).collect();
        let (mean, stderr) = mean_and_stderr(&values);
        // The column's footprint, 4 points across.
        let e =
            (0..4).map(|k| floor_irradiance(column_x(c as f64 + (k as f64 + 0.5) / 4.0))).sum::<f64>() / 4.0 * 0.5 / PI;
        assert!(
            (mean - e).abs() <= 6.0 * stderr + 1e-3 * e.max(0.1),
            "column {c} (x = {:.4}): {mean:.5}, expected {e:.5} (standard error {stderr:.5})",
            column_x(c as f64 + 0.5)
        );
        measured.push(mean);
        expected.push(e);
    }
    // Where a column profile crosses `level` of the full value, in columns (linear between centres).
    let crossing = |profile: &[f64], level: f64| {
        let target = level * 0.5 / PI * irradiance;
        let c =
            profile.windows(2).position(|w| w[0] < target && w[1] >= target).expect("the profile crosses the level");
        c as f64 + (target - profile[c]) / (profile[c + 1] - profile[c])
    };
    let measured_width = crossing(&measured, 0.9) - crossing(&measured, 0.1);
    let expected_width = crossing(&expected, 0.9) - crossing(&expected, 0.1);
    eprintln!("penumbra from 10 % to 90 %: {measured_width:.2} columns, expected {expected_width:.2}");
    assert!(expected_width > 12.0, "the penumbra no longer spans enough columns to measure");
    assert!(
        (measured_width - expected_width).abs() <= 1.0,
        "penumbra {measured_width:.2} columns wide, expected {expected_width:.2}"
    );
}
