//! Picking area lights by power (an alias table) on the GPU: a scene with thousands of emissive
//! triangles renders, agrees in the mean with uniform selection and with BSDF sampling alone, and
//! has a lower error than uniform selection at equal samples.

mod common;

use caustica::image::compare;
use caustica::render::{frame_params, Renderer, SceneData};
use caustica::scene::{Instance, LightSelection, Mesh, Scene};
use common::*;
use glam::{Mat4, Vec3};

/// Cells of the emissive ceiling grid, two triangles each.
const GRID: (u32, u32) = (64, 32);

/// A diffuse floor under a ceiling of 4096 dim emissive triangles (a mesh placed by a scale and a
/// translation, emitting downwards), one small bright sphere that emits half the power
/// and a two-sided panel standing on the floor: uniform selection spends all but two shadow rays
/// in 4098 on the dim grid.
fn many_lights(spp: u32, nee: bool, selection: LightSelection) -> Scene {
    let mut scene = parse(&format!(
        r#"
        camera = {{ position = [0, 0.6, 3], look_at = [0, 0.2, 0], fov = 45 }}
        film = {{ width = 24, height = 24, spp = {spp} }}
        integrator = {{ nee = {nee} }}
        [materials.floor]
        albedo = [0.7, 0.7, 0.7]
        [materials.grid]
        albedo = [0.5, 0.5, 0.5]
        emission = [0.1, 0.1, 0.1]
        [materials.lamp]
        albedo = [0, 0, 0]
        emission = [60, 50, 40]
        [materials.panel]
        albedo = [0, 0, 0]
        emission = [6, 6, 8]
        two_sided = true
        [[quads]]
        origin = [-2, 0, 2]
        edge_u = [4, 0, 0]
        edge_v = [0, 0, -4]
        material = "floor"
        [[spheres]]
        center = [0.4, 0.45, 0]
        radius = 0.1
        material = "lamp"
        [[quads]]
        origin = [-1.2, 0.1, -0.4]
        edge_u = [0, 0, 0.8]
        edge_v = [0, 0.5, 0]
        material = "panel"
        "#
    ));
    scene.integrator.light_selection = selection;
    let grid_material = scene.materials.iter().position(|m| m.name == "grid").expect("grid material") as u32;
    // The unit square in xz at y = 0; triangles wound so that their front faces -y.
    let (nx, nz) = GRID;
    let positions = (0..=nz)
        .flat_map(|j| (0..=nx).map(move |i| Vec3::new(i as f32 / nx as f32, 0.0, j as f32 / nz as f32)))
        .collect();
    let vertex = |i: u32, j: u32| j * (nx + 1) + i;
    let triangles: Vec<[u32; 3]> = (0..nz)
        .flat_map(|j| {
            (0..nx).flat_map(move |i| {
                [
                    [vertex(i, j), vertex(i + 1, j), vertex(i, j + 1)],
                    [vertex(i + 1, j), vertex(i + 1, j + 1), vertex(i, j + 1)],
                ]
            })
        })
        .collect();
    scene.meshes = vec![Mesh {
        name: "emissive grid".into(),
        positions,
        triangle_materials: vec![grid_material; triangles.len()],
        triangles,
        ..Default::default()
    }];
    scene.instances = vec![Instance {
        mesh: 0,
        transform: Mat4::from_translation(Vec3::new(-2.0, 1.0, -2.0)) * Mat4::from_scale(Vec3::splat(4.0)),
    }];
    scene
}

#[test]
fn thousands_of_emissive_triangles_are_lights() {
    let (_lock, ctx) = gpu();
    let scene = many_lights(1, true, LightSelection::Power);
    let renderer = Renderer::new(&ctx, &scene, 1).expect("scene uploads");
    assert_eq!(renderer.geometry.lights, (2 * GRID.0 * GRID.1 + 2) as usize);
    assert_eq!(scene.light_count(), renderer.geometry.lights);
}

/// Power and uniform selection are two choices of the same unbiased estimator, and with either the
/// MIS weights of NEE and of emitters hit by BSDF sampling must sum to 1: a pick probability
/// missing or different on one side shows as a difference in the mean.
#[test]
fn power_uniform_and_bsdf_only_agree_in_the_mean() {
    let (_lock, ctx) = gpu();
    let power = render(&ctx, &many_lights(64, true, LightSelection::Power), 11);
    let uniform = render(&ctx, &many_lights(64, true, LightSelection::Uniform), 12);
    let bsdf = render(&ctx, &many_lights(256, false, LightSelection::Power), 13);
    assert_same_mean(&power, &uniform, 5.0, "many lights: power against uniform selection");
    assert_same_mean(&power, &bsdf, 5.0, "many lights: power selection against BSDF sampling only");
}

#[test]
fn power_selection_lowers_the_error_among_many_lights() {
    let (_lock, ctx) = gpu();
    let reference = render(&ctx, &many_lights(512, true, LightSelection::Power), 99);
    let error = |selection: LightSelection| {
        let image = render(&ctx, &many_lights(16, true, selection), 5);
        compare(&image, &reference, ("render", "reference")).expect("same size").relative_mse
    };
    let (power, uniform) = (error(LightSelection::Power), error(LightSelection::Uniform));
    eprintln!("relative MSE at 16 spp: power {power:.5}, uniform {uniform:.5}, ratio {:.2}", uniform / power);
    assert!(power < 0.5 * uniform, "relative MSE with power selection {power:.5}, uniform {uniform:.5}");
}

/// Asserts that the floor (y = 0, albedo 0.7, filling rows 14 and below) shows `radiance(ray)`,
/// averaged over 8 x 8 rays per pixel, within 5 standard errors of the render's mean (its noise
/// from two seeds' difference) plus 0.5 % for that quadrature. `radiance` gets the eye and a ray
/// direction.
fn assert_floor_is_analytic(scene: &Scene, radiance: impl Fn(Vec3, Vec3) -> f64, what: &str) {
    let (_lock, ctx) = gpu();
    let params = frame_params(scene, &SceneData::new(scene, 0), 0);
    let v = Vec3::from_array;
    let (eye, forward, right, up, tan_half) =
        (v(params.cam_origin), v(params.cam_forward), v(params.cam_right), v(params.cam_up), params.tan_half_fov);
    let size = scene.film.width as f32;
    let expected = |x: u32, y: u32| {
        let f = |p: u32, s: u32| (p as f32 + (s as f32 + 0.5) / 8.0) / size * 2.0 - 1.0;
        (0..64)
            .map(|k| {
                radiance(eye, (forward + f(x, k % 8) * tan_half * right - f(y, k / 8) * tan_half * up).normalize())
            })
            .sum::<f64>()
            / 64.0
    };
    let (a, b) = (render(&ctx, scene, 1), render(&ctx, scene, 2));
    let pixels: Vec<(u32, u32)> = (14..24).flat_map(|y| (0..24).map(move |x| (x, y))).collect();
    let n = pixels.len() as f64;
    let variance =
        pixels.iter().map(|&(x, y)| (luminance(a.get(x, y)) - luminance(b.get(x, y))).powi(2)).sum::<f64>() / (2.0 * n);
    let stderr = (variance / 2.0 / n).sqrt();
    let got = pixels.iter().map(|&(x, y)| 0.5 * (luminance(a.get(x, y)) + luminance(b.get(x, y)))).sum::<f64>() / n;
    let want = pixels.iter().map(|&(x, y)| expected(x, y)).sum::<f64>() / n;
    eprintln!("{what}: mean {got:.5}, analytic {want:.5} (standard error {stderr:.5})");
    assert!(
        (got - want).abs() <= 5.0 * stderr + 0.005 * want,
        "{what}: mean {got:.5}, analytic {want:.5} (standard error {stderr:.5})"
    );
}

/// Where a ray from `eye` meets the floor.
fn floor_point(eye: Vec3, d: Vec3) -> Vec3 {
    eye - eye.y / d.y * d
}

/// Direct light from the bright sphere alone on the floor (the grid dark, no mesh): radiance
/// 0.7 L (r / d)^2 cos(theta) at a floor point a distance d from its centre. Shadow rays used to
/// graze the sphere and count it as its own blocker, which took 12 % of this light away far from
/// the sphere and more near it.
#[test]
fn sphere_light_gives_the_analytic_direct_light() {
    let mut scene = many_lights(256, true, LightSelection::Power);
    scene.materials.iter_mut().filter(|m| m.name == "grid" || m.name == "panel").for_each(|m| m.emission = Vec3::ZERO);
    scene.meshes.clear();
    scene.instances.clear();
    let (center, radius) = (Vec3::new(0.4, 0.45, 0.0), 0.1f64);
    let emitted = luminance([60.0, 50.0, 40.0]);
    let radiance = |eye: Vec3, d: Vec3| {
        let to_center = (center - floor_point(eye, d)).as_dvec3();
        0.7 * emitted * radius * radius / to_center.length_squared() * to_center.y / to_center.length()
    };
    assert_floor_is_analytic(&scene, radiance, "floor under a sphere light");
}

/// A large triangle light just above the floor, where it subtends up to a hemisphere and is
/// sampled by solid angle: the floor's radiance is 0.7 / pi times Lambert's polygon irradiance,
/// L / 2 |sum over edges of the angle they subtend times n . (unit normal of their plane)|.
/// Rays that meet the triangle's dark back first see black.
#[test]
fn large_triangle_light_gives_the_analytic_direct_light() {
    let scene = parse(
        r#"
        camera = { position = [0, 0.6, 3], look_at = [0, 0.2, 0], fov = 45 }
        film = { width = 24, height = 24, spp = 64 }
        [materials.floor]
        albedo = [0.7, 0.7, 0.7]
        [materials.light]
        albedo = [0, 0, 0]
        emission = [4, 3, 2]
        [[quads]]
        origin = [-2, 0, 2]
        edge_u = [4, 0, 0]
        edge_v = [0, 0, -4]
        material = "floor"
        [[triangles]]
        vertices = [[-1.5, 0.3, -1], [1.5, 0.3, -1], [0, 0.3, 1]]
        material = "light"
        "#,
    );
    let v = [Vec3::new(-1.5, 0.3, -1.0), Vec3::new(1.5, 0.3, -1.0), Vec3::new(0.0, 0.3, 1.0)].map(|p| p.as_dvec3());
    let emitted = luminance([4.0, 3.0, 2.0]);
    let inside = |p: glam::DVec3| (0..3).all(|i| (v[(i + 1) % 3] - v[i]).cross(p - v[i]).y <= 0.0);
    let radiance = |eye: Vec3, d: Vec3| {
        let (eye, d) = (eye.as_dvec3(), d.as_dvec3());
        if inside(eye + (0.3 - eye.y) / d.y * d) {
            return 0.0;
        }
        let p = floor_point(eye.as_vec3(), d.as_vec3()).as_dvec3();
        let q = v.map(|c| (c - p).normalize());
        let sum: f64 =
            (0..3).map(|i| q[i].angle_between(q[(i + 1) % 3]) * q[i].cross(q[(i + 1) % 3]).normalize().y).sum();
        0.7 / std::f64::consts::PI * emitted / 2.0 * sum.abs()
    };
    assert_floor_is_analytic(&scene, radiance, "floor under a large triangle light");
}

#[test]
fn light_selection_defaults_to_the_light_tree_and_rejects_unknown_choices() {
    let camera = "camera = { position = [0, 0, 3], look_at = [0, 0, 0] }\n";
    assert_eq!(parse(camera).integrator.light_selection, LightSelection::Bvh);
    assert_eq!(
        parse(&format!("{camera}[integrator]\nlight_selection = \"power\"\n")).integrator.light_selection,
        LightSelection::Power
    );
    assert_eq!(
        parse(&format!("{camera}[integrator]\nlight_selection = \"uniform\"\n")).integrator.light_selection,
        LightSelection::Uniform
    );
    let e = format!(
        "{:#}",
        Scene::parse(
            &format!("{camera}[integrator]\nlight_selection = \"random\"\n"),
            "s.toml",
            std::path::Path::new(".")
        )
        .expect_err("rejected")
    );
    assert!(
        e.contains("light_selection")
            && e.contains("random")
            && e.contains("bvh")
            && e.contains("power")
            && e.contains("uniform"),
        "{e}"
    );
}
