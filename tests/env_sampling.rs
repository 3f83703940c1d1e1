//! Importance sampling of environment maps, on the GPU: unbiased (it agrees in the mean with plain
//! BSDF sampling, and a white map keeps the furnace at exactly 1) and worth it (lower variance).

mod common;

use caustica::image::RgbImage;
use caustica::scene::{Environment, EnvironmentMap, MapProjection, Scene};
use common::*;
use glam::Vec3;
use std::f32::consts::PI;

/// World direction of the map position (x, y) in [0, 1]^2 (y down the image), as the kernel maps it.
fn map_direction(projection: MapProjection, x: f32, y: f32) -> Option<Vec3> {
    match projection {
        MapProjection::LatLong => {
            let (phi, theta) = ((x - 0.5) * 2.0 * PI, y * PI);
            Some(Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos()))
        }
        MapProjection::Angular => {
            let (a, b) = (2.0 * x - 1.0, 1.0 - 2.0 * y);
            let r = (a * a + b * b).sqrt();
            (r <= 1.0).then(|| {
                let s = if r > 0.0 { (PI * r).sin() / r } else { 0.0 };
                Vec3::new(a * s, b * s, -(PI * r).cos())
            })
        }
    }
}

/// A map whose texel centres hold `radiance(direction)` (black outside an angular map's disk).
fn environment(projection: MapProjection, width: u32, height: u32, radiance: impl Fn(Vec3) -> f32) -> Environment {
    let mut image = RgbImage::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let d = map_direction(projection, (x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / height as f32);
            image.set(x, y, [d.map_or(0.0, &radiance); 3]);
        }
    }
    Environment::Map(EnvironmentMap { projection, image, intensity: 1.0, rotation_deg: 30.0 })
}

/// A dim sky with a bright disc of 20 degrees radius up and to the side, the kind of light that
/// BSDF sampling finds only by chance.
fn sky_with_sun(d: Vec3) -> f32 {
    let sun = Vec3::new(0.6, 0.7, 0.3).normalize();
    0.1 + 0.2 * d.y.max(0.0) + if d.dot(sun) > 20f32.to_radians().cos() { 10.0 } else { 0.0 }
}

/// A diffuse sphere on a floor, lit only by the environment.
fn sphere_on_floor(spp: u32, nee: bool, environment: Environment) -> Scene {
    let mut scene = parse(&format!(
        r#"
        camera = {{ position = [0, 1.5, 4], look_at = [0, 0.5, 0], fov = 40 }}
        film = {{ width = 32, height = 32, spp = {spp} }}
        integrator = {{ nee = {nee} }}
        [materials.white]
        albedo = [0.8, 0.8, 0.8]
        [[spheres]]
        center = [0, 1, 0]
        radius = 1
        material = "white"
        [[quads]]
        origin = [-3, 0, 3]
        edge_u = [6, 0, 0]
        edge_v = [0, 0, -6]
        material = "white"
        "#
    ));
    scene.environment = environment;
    scene
}

#[test]
fn importance_sampled_maps_agree_with_bsdf_sampling() {
    let (_lock, ctx) = gpu();
    for projection in [MapProjection::LatLong, MapProjection::Angular] {
        let (w, h) = if projection == MapProjection::LatLong { (64, 32) } else { (64, 64) };
        let env = environment(projection, w, h, sky_with_sun);
        let sampled = render(&ctx, &sphere_on_floor(64, true, env.clone()), 11);
        let bsdf = render(&ctx, &sphere_on_floor(256, false, env), 12);
        assert_same_mean(
            &sampled,
            &bsdf,
            5.0,
            &format!("{projection:?} map: importance sampling + MIS against BSDF sampling"),
        );
    }
}

#[test]
fn importance_sampling_lowers_the_variance_under_a_sun() {
    let (_lock, ctx) = gpu();
    let env = environment(MapProjection::LatLong, 64, 32, sky_with_sun);
    let variance = |nee: bool| {
        let a = render(&ctx, &sphere_on_floor(16, nee, env.clone()), 21);
        let b = render(&ctx, &sphere_on_floor(16, nee, env.clone()), 22);
        pixel_noise_variance(&a, &b)
    };
    let (sampled, bsdf) = (variance(true), variance(false));
    assert!(sampled < 0.25 * bsdf, "per-pixel variance with map sampling {sampled:.5}, BSDF sampling only {bsdf:.5}");
}

/// A sphere of albedo 1 under a white map reflects exactly 1 everywhere: any error in the map's
/// sampling density (its Jacobian, the rotation, the cell lookup) shows as a mean other than 1.
#[test]
fn white_maps_keep_the_furnace_at_one() {
    let (_lock, ctx) = gpu();
    for projection in [MapProjection::LatLong, MapProjection::Angular] {
        let mut scene = parse(
            r#"
            camera = { position = [0, 0, 2.2], look_at = [0, 0, 0], fov = 40 }
            film = { width = 16, height = 16, spp = 64 }
            [materials.white]
            albedo = [1, 1, 1]
            [[spheres]]
            center = [0, 0, 0]
            radius = 1
            material = "white"
            "#,
        );
        scene.environment = environment(projection, 32, 32, |_| 1.0);
        let image = render(&ctx, &scene, 5);
        // The camera sits close enough that the sphere fills the whole view.
        let values: Vec<f64> = image.pixels.iter().map(|p| luminance(*p)).collect();
        let (mean, stderr) = mean_and_stderr(&values);
        assert!((mean - 1.0).abs() <= 5.0 * stderr.max(1e-4), "{projection:?}: furnace mean {mean:.5} +- {stderr:.5}");
    }
}
