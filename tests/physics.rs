//! Analytic checks of the light transport on lavapipe. Each tolerance is a number of standard errors,
//! the standard error coming from the renders' own noise at the sample count used.

mod common;

use common::furnace::*;
use common::*;
use glam::Vec3;

fn furnace_check(material: &str, sphere_expected: f64, what: &str) {
    let (_lock, ctx) = gpu();
    let scene = furnace(material, 32, 64);
    let cover = coverage(&scene);
    let a = render(&ctx, &scene, 1);
    let b = render(&ctx, &scene, 2);
    assert_region_mean(&a, &b, &cover, Coverage::Sphere, sphere_expected, what);
    assert_region_mean(&a, &b, &cover, Coverage::Background, 1.0, what);
}

#[test]
fn furnace_albedo_one_is_one() {
    furnace_check("albedo = [1.0, 1.0, 1.0]", 1.0, "diffuse albedo 1 in a white furnace");
}

#[test]
fn furnace_albedo_half_is_half() {
    // A convex diffuse surface sees only the environment: one bounce, L = albedo * 1.
    furnace_check("albedo = [0.5, 0.5, 0.5]", 0.5, "diffuse albedo 0.5 in a white furnace");
}

#[test]
fn glass_sphere_invisible_in_furnace() {
    furnace_check("albedo = [0.0, 0.0, 0.0]\ntransparency = 1.0\nior = 1.5", 1.0, "glass sphere in a white furnace");
}

#[test]
fn mirror_sphere_invisible_in_furnace() {
    furnace_check("albedo = [0.0, 0.0, 0.0]\nreflectivity = 1.0", 1.0, "mirror sphere in a white furnace");
}

#[test]
fn mixed_rt_material_is_invisible_in_furnace() {
    // R = 0.3 mirror, T = 0.4 glass, 0.3 diffuse with albedo 1: every event preserves energy.
    furnace_check(
        "albedo = [1.0, 1.0, 1.0]\nreflectivity = 0.3\ntransparency = 0.4",
        1.0,
        "R/T material in a white furnace",
    );
}

#[test]
fn russian_roulette_start_does_not_change_the_mean() {
    let (_lock, ctx) = gpu();
    let mut early = cornell(32, 64);
    early.integrator.rr_start = 0;
    let mut late = cornell(32, 64);
    late.integrator.rr_start = 8;
    let a = render(&ctx, &early, 11);
    let b = render(&ctx, &late, 12);
    assert_same_mean(&a, &b, 5.0, "Cornell box, rr_start 0 against 8");
}

#[test]
fn fixed_absorption_roulette_does_not_change_the_mean() {
    let (_lock, ctx) = gpu();
    let mut fixed = cornell(32, 64);
    fixed.integrator.rr_start = 1;
    fixed.integrator.absorption = Some(0.5);
    let a = render(&ctx, &fixed, 21);
    let b = render(&ctx, &cornell(32, 64), 22);
    assert_same_mean(&a, &b, 5.0, "Cornell box, fixed absorption 0.5 against throughput roulette");
}

#[test]
fn nee_with_mis_agrees_with_bsdf_sampling() {
    let (_lock, ctx) = gpu();
    let nee = cornell(32, 64);
    let mut bsdf = cornell(32, 256);
    bsdf.integrator.nee = false;
    let a = render(&ctx, &nee, 31);
    let b = render(&ctx, &bsdf, 32);
    assert_same_mean(&a, &b, 5.0, "Cornell box, NEE + MIS against pure BSDF sampling");
}

#[test]
fn nee_lowers_the_noise_on_the_cornell_box() {
    // Same sample count: explicit light sampling must beat hitting a small light by chance.
    let (_lock, ctx) = gpu();
    let nee = cornell(24, 16);
    let mut bsdf = cornell(24, 16);
    bsdf.integrator.nee = false;
    let nee_var = pixel_noise_variance(&render(&ctx, &nee, 1), &render(&ctx, &nee, 2));
    let bsdf_var = pixel_noise_variance(&render(&ctx, &bsdf, 1), &render(&ctx, &bsdf, 2));
    assert!(nee_var * 2.0 < bsdf_var, "NEE variance {nee_var:.5} should be well below BSDF-only {bsdf_var:.5}");
}

#[test]
fn emissive_sphere_seen_directly_has_its_radiance() {
    // A camera ray that hits an emitter sees exactly its emission (plus nothing: black surroundings).
    let (_lock, ctx) = gpu();
    let mut scene = furnace("albedo = [0.0, 0.0, 0.0]\nemission = [2.0, 3.0, 4.0]", 16, 4);
    scene.environment = caustica::scene::Environment::Constant(Vec3::ZERO);
    let image = render(&ctx, &scene, 1);
    let cover = coverage(&scene);
    for (i, c) in cover.iter().enumerate() {
        let expected = match c {
            Coverage::Sphere => [2.0, 3.0, 4.0],
            Coverage::Background => [0.0; 3],
            Coverage::Edge => continue,
        };
        assert_eq!(image.pixels[i], expected, "pixel {i} ({c:?})");
    }
}

#[test]
fn glass_sphere_reflects_by_fresnel_at_normal_incidence() {
    // Looking along +z at the centre of a glass sphere (ior 1.5) with rays on its axis: every path
    // stays on the axis and leaves either back towards the camera (-z) or straight on (+z). The
    // environment is 1 in a cone around -z (the centre of an angular map) and 0 elsewhere, so the
    // pixel sees the total back-reflection F + (1-F)^2 F + (1-F)^2 F^3 + ... = 2F / (1 + F),
    // with F = ((ior - 1) / (ior + 1))^2 = 0.04.
    let (_lock, ctx) = gpu();
    let probe = angular_probe(64, |u, v| if u * u + v * v < 0.2 * 0.2 { [1.0; 3] } else { [0.0; 3] });
    let mut scene = furnace("albedo = [0.0, 0.0, 0.0]\ntransparency = 1.0\nior = 1.5", 16, 64);
    scene.camera.position = Vec3::new(0.0, 0.0, -3.5);
    scene.camera.fov_deg = 0.001;
    scene.environment = caustica::scene::Environment::Map(caustica::scene::EnvironmentMap {
        projection: caustica::scene::MapProjection::Angular,
        image: probe,
        intensity: 1.0,
        rotation_deg: 0.0,
    });
    let image = render(&ctx, &scene, 5);
    let f = 0.04f64;
    let expected = 2.0 * f / (1.0 + f);
    let n = (scene.film.width * scene.film.height * scene.film.spp) as f64;
    let mean = image.pixels.iter().map(|p| p[1] as f64).sum::<f64>() / image.pixels.len() as f64;
    // Each sample is (nearly) Bernoulli(expected); roulette past rr_start only adds a little variance.
    let stderr = (expected * (1.0 - expected) / n).sqrt();
    assert!(
        (mean - expected).abs() <= 5.0 * stderr,
        "back-reflection {mean:.5}, expected 2F/(1+F) = {expected:.5} within 5 standard errors ({:.5}) of {n} samples",
        5.0 * stderr
    );
}
