//! A scene of two placed meshes in a room, and its sums read back bit for bit: what the tests of
//! the kernel's alternative forms (tests/walk_queue.rs, tests/wavefront.rs) compare with the plain
//! kernel's.

use super::parse;
use caustica::gpu::GpuContext;
use caustica::render::{AovSet, AovSums, KernelChoice, Renderer, WalkQueue};
use caustica::scene::{Instance, Mesh, Scene};
use glam::{Mat4, Vec3};

/// A bumpy `n` x `n` patch over [-1, 1]^2 in the xz plane, facing up: 2 n^2 triangles, enough
/// for a BVH of several levels.
pub fn bumpy_patch(n: u32, material: u32) -> Mesh {
    let at = |i: u32, j: u32| {
        let (x, z) = (2.0 * i as f32 / n as f32 - 1.0, 2.0 * j as f32 / n as f32 - 1.0);
        Vec3::new(x, 0.15 * (5.0 * x).sin() * (4.0 * z).cos(), z)
    };
    let positions = (0..=n).flat_map(|j| (0..=n).map(move |i| at(i, j))).collect();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    let triangles: Vec<[u32; 3]> = (0..n)
        .flat_map(|j| {
            (0..n).flat_map(move |i| [[v(i, j), v(i, j + 1), v(i + 1, j)], [v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)]])
        })
        .collect();
    Mesh {
        name: "patch".into(),
        positions,
        triangle_materials: vec![material; triangles.len()],
        triangles,
        ..Default::default()
    }
}

/// Two placed meshes (one diffuse, one glass, so that paths end at very different depths) over
/// a floor and under a sphere lamp, both shapes tested before the walk: a top level of its root
/// alone, the scene class the queue is compiled for.
pub fn two_meshes_in_a_room() -> Scene {
    let mut scene = parse(
        r#"
        camera = { position = [0, 1.2, 3.2], look_at = [0, 0.2, 0], fov = 45 }
        film = { width = 40, height = 32, spp = 7 }
        environment = { color = [0.05, 0.05, 0.08] }
        [materials.clay]
        albedo = [0.7, 0.6, 0.5]
        [materials.glass]
        transparency = 1.0
        ior = 1.5
        [materials.floor]
        albedo = [0.5, 0.5, 0.5]
        [materials.lamp]
        emission = [8.0, 8.0, 7.0]
        [[quads]]
        origin = [-3.0, -0.5, 3.0]
        edge_u = [6.0, 0.0, 0.0]
        edge_v = [0.0, 0.0, -6.0]
        material = "floor"
        [[spheres]]
        center = [0.0, 2.0, 0.5]
        radius = 0.3
        material = "lamp"
        "#,
    );
    let material = |name: &str| scene.materials.iter().position(|m| m.name == name).unwrap() as u32;
    scene.meshes = vec![bumpy_patch(12, material("clay")), bumpy_patch(10, material("glass"))];
    scene.instances = vec![
        Instance {
            mesh: 0,
            transform: Mat4::from_translation(Vec3::new(-0.6, 0.0, 0.0))
                * Mat4::from_rotation_x(0.6)
                * Mat4::from_scale(Vec3::splat(0.6)),
        },
        Instance {
            mesh: 1,
            transform: Mat4::from_translation(Vec3::new(0.6, 0.3, 0.2))
                * Mat4::from_rotation_z(-0.8)
                * Mat4::from_scale(Vec3::splat(0.5)),
        },
    ];
    scene
}

/// The sums of `scene` (seed 11, AOVs on), as bits, rendered in passes adding `steps` samples;
/// the queue its kernel walked from, if any; and whether it ran the wavefront.
pub fn sums(
    ctx: &GpuContext,
    scene: &Scene,
    choice: KernelChoice,
    steps: &[u32],
) -> (Vec<[u32; 4]>, AovSums, Option<WalkQueue>, bool) {
    let mut renderer = Renderer::with_kernel(ctx, scene, 11, AovSet::ALL, choice).expect("scene uploads");
    let (bits, aovs) = rendered_sums(&mut renderer, steps);
    (bits, aovs, renderer.walk_queue, renderer.runs_wavefront())
}

/// The sums `renderer` (made with AOVs) holds once it has rendered in passes adding `steps`
/// samples, as bits.
pub fn rendered_sums(renderer: &mut Renderer, steps: &[u32]) -> (Vec<[u32; 4]>, AovSums) {
    for &spp in steps {
        renderer.render(spp, |_| {}).expect("render succeeds without validation messages");
    }
    let bits = renderer.accumulation().expect("readback").iter().map(|p| p.map(f32::to_bits)).collect();
    (bits, renderer.aov_sums().expect("readback").expect("AOVs were asked for"))
}
