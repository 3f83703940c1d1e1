//! Tests sized to catch small biases: the estimators of the light transport against exact values
//! in scenes built so that the answer is known in closed form and the noise is low, at sample
//! counts that resolve a bias of a few tenths of a percent. Each test states the smallest bias it
//! fails and checks at run time that its own noise still allows that claim (a test that lost its
//! power fails rather than passing quietly). The mutations of tests/mutations.toml, run by
//! scripts/mutate.py, show what each one catches (docs/testing.md).

mod common;

use caustica::image::RgbImage;
use caustica::scene::{Environment, EnvironmentMap, LightSelection, MapProjection, Scene};
use common::*;
use glam::Vec3;
use std::f64::consts::PI;
use std::path::Path;

/// The camera inside a closed, two-sided emissive diffuse sphere: every surface point sees only
/// the sphere's inside, whose radiance is therefore everywhere L = Le + albedo L, so
/// L = Le / (1 - albedo) exactly, at every pixel. With albedo 0.7 most of it arrives after
/// several bounces, through Russian roulette (from the first bounce), next-event estimation of a
/// sphere light from inside it (area sampling) and the MIS weights of emitters hit by BSDF
/// sampling: a bias in any of them shows in the mean.
fn inside_emissive_sphere(spp: u32) -> Scene {
    parse(&format!(
        r#"
        camera = {{ position = [0.1, -0.2, 0.15], look_at = [0.5, 0.3, -1.0], fov = 70 }}
        film = {{ width = 32, height = 32, spp = {spp} }}
        integrator = {{ rr_start = 1 }}
        [materials.shell]
        albedo = [0.7, 0.7, 0.7]
        emission = [0.3, 0.3, 0.3]
        two_sided = true
        [[spheres]]
        center = [0.0, 0.0, 0.0]
        radius = 1.0
        material = "shell"
        "#
    ))
}

/// Fails a 0.3 % bias in the mean (1 M paths; about 1.2 % relative noise per path).
#[test]
fn inside_an_emissive_sphere_radiance_is_emission_over_one_minus_albedo() {
    let (_lock, ctx) = gpu();
    let scene = inside_emissive_sphere(1024);
    let image = render(&ctx, &scene, 3);
    assert_mean_is(&image, 0.3 / (1.0 - 0.7), 0.0002, 0.003, "inside an emissive sphere, throughput roulette");
}

/// The same with roulette at a fixed absorption (survival 0.5 from the first bounce): the other
/// way q is chosen, dividing by it just the same. Fails a 1.5 % bias (its noise is higher).
#[test]
fn inside_an_emissive_sphere_with_fixed_absorption_roulette() {
    let (_lock, ctx) = gpu();
    let mut scene = inside_emissive_sphere(512);
    scene.integrator.absorption = Some(0.5);
    let image = render(&ctx, &scene, 4);
    assert_mean_is(&image, 0.3 / (1.0 - 0.7), 0.0002, 0.015, "inside an emissive sphere, fixed absorption 0.5");
}

/// Irradiance at the origin (normal +y) from a polygon of uniform radiance `radiance` facing it:
/// Lambert's formula, E = L / 2 sum_i angle(v_i, v_i+1) (n . unit(v_i x v_i+1)).
fn polygon_irradiance(vertices: &[Vec3], radiance: f64) -> f64 {
    let sum: f64 = (0..vertices.len())
        .map(|i| {
            let (a, b) = (vertices[i].as_dvec3(), vertices[(i + 1) % vertices.len()].as_dvec3());
            let angle = a.angle_between(b);
            angle * a.cross(b).normalize().y
        })
        .sum();
    radiance / 2.0 * sum.abs()
}

/// A sphere light (radius 0.5, centre 2 above the point), sampled by the cone it subtends:
/// E = pi L sin^2(half angle). Fails a 0.1 % bias.
#[test]
fn sphere_light_irradiance_is_exact() {
    let (_lock, ctx) = gpu();
    let scene =
        floor_point_scene("[[spheres]]\ncenter = [0.0, 2.0, 0.0]\nradius = 0.5\nmaterial = \"lamp\"", 256, true);
    let irradiance = PI * 4.0 * (0.5f64 / 2.0).powi(2);
    assert_mean_is(&render(&ctx, &scene, 1), 0.5 / PI * irradiance, 0.0002, 0.001, "floor under a sphere light");
}

/// A square light (1 x 1, 1.5 above the point, off centre), sampled by area. Fails a 0.2 % bias.
#[test]
fn quad_light_irradiance_is_exact() {
    let (_lock, ctx) = gpu();
    // The emitting side faces cross(edge_u, edge_v) = -y: down at the floor.
    let scene = floor_point_scene("[[quads]]\norigin = [-0.3, 1.5, -0.2]\nedge_u = [1.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]\nmaterial = \"lamp\"", 512, true);
    let corners =
        [Vec3::new(-0.3, 1.5, -0.2), Vec3::new(-0.3, 1.5, 0.8), Vec3::new(0.7, 1.5, 0.8), Vec3::new(0.7, 1.5, -0.2)];
    assert_mean_is(
        &render(&ctx, &scene, 2),
        0.5 / PI * polygon_irradiance(&corners, 4.0),
        0.0002,
        0.002,
        "floor under a quad light",
    );
}

/// A sphere light (as above, off axis) and a two-sided square light together: the irradiances add.
/// How a light is picked for next-event estimation must agree with the pdf the kernel divides
/// by, on the host (the alias table's powers) and in the kernel (the pick probability), whichever
/// way lights are picked. Fails a 0.5 % bias.
fn assert_two_lights_sum_exactly(selection: LightSelection, seed: u32) {
    let (_lock, ctx) = gpu();
    let lights = "[[spheres]]\ncenter = [1.5, 2.0, 0.0]\nradius = 0.5\nmaterial = \"lamp\"\n\
                  [materials.panel]\nalbedo = [0.0, 0.0, 0.0]\nemission = [1.0, 1.0, 1.0]\ntwo_sided = true\n\
                  [[quads]]\norigin = [-0.3, 1.5, -0.2]\nedge_u = [0.0, 0.0, 1.0]\nedge_v = [1.0, 0.0, 0.0]\nmaterial = \"panel\"";
    let mut scene = floor_point_scene(lights, 512, true);
    scene.integrator.light_selection = selection;
    // A sphere wholly above the horizon: E = pi L (r / d)^2 cos(theta) towards its centre.
    let centre = glam::DVec3::new(1.5, 2.0, 0.0);
    let sphere = PI * 4.0 * (0.5 / centre.length()).powi(2) * centre.normalize().y;
    let corners =
        [Vec3::new(-0.3, 1.5, -0.2), Vec3::new(-0.3, 1.5, 0.8), Vec3::new(0.7, 1.5, 0.8), Vec3::new(0.7, 1.5, -0.2)];
    let expected = 0.5 / PI * (sphere + polygon_irradiance(&corners, 1.0));
    assert_mean_is(
        &render(&ctx, &scene, seed),
        expected,
        0.0002,
        0.005,
        &format!("floor under a sphere and a two-sided quad, lights picked by {selection:?}"),
    );
}

#[test]
fn two_lights_picked_by_power_add_up_exactly() {
    assert_two_lights_sum_exactly(LightSelection::Power, 6);
}

#[test]
fn two_lights_picked_uniformly_add_up_exactly() {
    assert_two_lights_sum_exactly(LightSelection::Uniform, 7);
}

/// The same two lights picked by the light tree, where the pick probability depends on the point
/// and the hit emitter's pdf is walked up the tree from its leaf.
#[test]
fn two_lights_picked_by_the_light_tree_add_up_exactly() {
    assert_two_lights_sum_exactly(LightSelection::Bvh, 8);
}

/// A triangle light large and near enough to be sampled by solid angle (spherical triangle).
/// Fails a 0.1 % bias.
#[test]
fn triangle_light_sampled_by_solid_angle_is_exact() {
    let v = [Vec3::new(-0.8, 1.0, -0.5), Vec3::new(0.9, 1.2, -0.3), Vec3::new(0.1, 0.9, 1.0)];
    assert_floor_under_triangle_is_exact(v, 3, 0.001, "floor under a near triangle light");
}

/// A triangle light so small and far that it subtends less than 3e-4 sr: sampled by area.
/// Fails a 0.3 % bias.
#[test]
fn triangle_light_sampled_by_area_is_exact() {
    let v = [Vec3::new(-0.05, 4.0, -0.02), Vec3::new(0.04, 4.1, -0.03), Vec3::new(0.0, 3.95, 0.05)];
    assert_floor_under_triangle_is_exact(v, 4, 0.003, "floor under a small far triangle light");
}

/// The floor under a one-triangle mesh light with vertices `v`, 256 spp, against Lambert's formula.
fn assert_floor_under_triangle_is_exact(v: [Vec3; 3], seed: u32, bias: f64, what: &str) {
    let (_lock, ctx) = gpu();
    let dir = temp_dir("bias-triangle");
    let scene = floor_point_scene(&triangle_mesh_light(&dir, &v), 256, true);
    assert_mean_is(&render(&ctx, &scene, seed), 0.5 / PI * polygon_irradiance(&v, 4.0), 0.0002, bias, what);
}

/// A one-triangle OBJ with the lamp material, written into `dir`, as a scene fragment; wound so
/// that its front face looks down at the floor.
fn triangle_mesh_light(dir: &Path, v: &[Vec3; 3]) -> String {
    let normal = (v[1] - v[0]).cross(v[2] - v[0]);
    let order = if normal.y < 0.0 { [0, 1, 2] } else { [0, 2, 1] };
    let mut obj = String::new();
    for i in order {
        obj.push_str(&format!("v {} {} {}\n", v[i].x, v[i].y, v[i].z));
    }
    obj.push_str("f 1 2 3\n");
    let path = dir.join(format!("triangle-{}-{}.obj", v[0].x, v[0].y));
    std::fs::write(&path, obj).expect("write the triangle");
    format!("[[meshes]]\nfile = \"{}\"\nmaterial = \"lamp\"", path.display())
}

/// A lat-long sky whose rows vary (a bright band near the zenith over a dim sky) and whose last
/// column is three times as bright as the others (the edges of the sampling distribution's
/// tables), importance sampled: the floor's radiance is albedo / pi x the integral of the map's
/// radiance times the cosine over the upper hemisphere. The map is a product of a row and a column
/// factor, and so is its bilinear interpolation: the column factor, interpolated around the wrap,
/// integrates to its mean over the turn; the row factor is integrated here with the kernel's
/// interpolation between row centres. Fails a 0.2 % bias.
#[test]
fn floor_under_a_latlong_sky_is_its_cosine_weighted_integral() {
    let (_lock, ctx) = gpu();
    let (w, h) = (8u32, 16u32);
    let row_value = |j: u32| if j == 2 { 6.0 } else { 0.2 + 0.05 * j as f64 };
    let column_value = |i: u32| if i == w - 1 { 3.0 } else { 1.0 };
    let mut map = RgbImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            map.set(x, y, [(row_value(y) * column_value(x)) as f32; 3]);
        }
    }
    let column_mean = (0..w).map(column_value).sum::<f64>() / w as f64;
    let mut scene = floor_point_scene("", 512, true);
    scene.environment = Environment::Map(EnvironmentMap {
        projection: MapProjection::LatLong,
        image: map,
        intensity: 1.0,
        rotation_deg: 0.0,
    });
    // Radiance at polar angle theta: linear in the texel coordinate between row centres, held
    // beyond the first and last (the kernel's bilinear lookup, constant along a row).
    let radiance = |theta: f64| {
        let t = (theta / PI * h as f64 - 0.5).clamp(0.0, (h - 1) as f64);
        let j = (t.floor() as u32).min(h - 2);
        let f = t - j as f64;
        row_value(j) * (1.0 - f) + row_value(j + 1) * f
    };
    // Irradiance: 2 pi int_0^{pi/2} L(theta) cos sin dtheta, by the midpoint rule (exact to 1e-9 here).
    let steps = 200_000;
    let dtheta = PI / 2.0 / steps as f64;
    let irradiance: f64 = column_mean
        * 2.0
        * PI
        * (0..steps).map(|k| (k as f64 + 0.5) * dtheta).map(|t| radiance(t) * t.cos() * t.sin() * dtheta).sum::<f64>();
    assert_mean_is(&render(&ctx, &scene, 5), 0.5 / PI * irradiance, 0.0002, 0.002, "floor under a lat-long sky");
}

/// An importance-sampled lat-long sky (uniform, 0.5) and a sphere light together: next-event
/// estimation picks between the map and the area lights, and the MIS weights of both sides must
/// carry that choice. The sphere hides its own solid angle of the sky:
/// E = pi L_sky + (L_lamp - L_sky) pi sin^2(half angle) cos(theta). Fails a 0.5 % bias.
#[test]
fn sky_and_sphere_light_add_up_exactly() {
    let (_lock, ctx) = gpu();
    let mut scene =
        floor_point_scene("[[spheres]]\ncenter = [1.5, 2.0, 0.0]\nradius = 0.5\nmaterial = \"lamp\"", 512, true);
    let mut map = RgbImage::new(16, 8);
    map.pixels.fill([0.5; 3]);
    scene.environment = Environment::Map(EnvironmentMap {
        projection: MapProjection::LatLong,
        image: map,
        intensity: 1.0,
        rotation_deg: 0.0,
    });
    let centre = glam::DVec3::new(1.5, 2.0, 0.0);
    let sphere_cosine_solid_angle = PI * (0.5 / centre.length()).powi(2) * centre.normalize().y;
    let irradiance = PI * 0.5 + (4.0 - 0.5) * sphere_cosine_solid_angle;
    assert_mean_is(
        &render(&ctx, &scene, 8),
        0.5 / PI * irradiance,
        0.0002,
        0.005,
        "floor under a lat-long sky and a sphere light",
    );
}
