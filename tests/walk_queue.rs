//! The walk queue (src/render/walk_queue.rs, shaders/walk_queue.glsl and queued_paths.glsl)
//! renders the plain kernel's sums bit for bit: every vertex, shadow ray and sample the same, and
//! the samples added in sample order, whatever order a lane's two paths end in and however the
//! render is split into passes. The general kernel (no queue: its top level is a tree) is the
//! reference. A hit taken from another walk's slot, a shadow ray's light added after its vertex's
//! or the samples added as they end would each change the sums (the mutations `queue-*` of
//! tests/mutations.toml).

mod common;

use caustica::render::{AovSet, AovSums, KernelChoice, Renderer, WalkQueue, WALK_QUEUE_VAR, WORKGROUP_VAR};
use caustica::scene::{Instance, Mesh, Scene};
use common::{gpu, parse};
use glam::{Mat4, Vec3};

/// A bumpy `n` x `n` patch over [-1, 1]^2 in the xz plane, facing up: 2 n^2 triangles, enough
/// for a BVH of several levels.
fn bumpy_patch(n: u32, material: u32) -> Mesh {
    let at = |i: u32, j: u32| {
        let (x, z) = (2.0 * i as f32 / n as f32 - 1.0, 2.0 * j as f32 / n as f32 - 1.0);
        Vec3::new(x, 0.15 * (5.0 * x).sin() * (4.0 * z).cos(), z)
    };
    let positions = (0..=n).flat_map(|j| (0..=n).map(move |i| at(i, j))).collect();
    let v = |i: u32, j: u32| j * (n + 1) + i;
    let triangles: Vec<[u32; 3]> = (0..n).flat_map(|j| (0..n).flat_map(move |i| [[v(i, j), v(i, j + 1), v(i + 1, j)], [v(i + 1, j), v(i, j + 1), v(i + 1, j + 1)]])).collect();
    Mesh { name: "patch".into(), positions, triangle_materials: vec![material; triangles.len()], triangles, ..Default::default() }
}

/// Two placed meshes (one diffuse, one glass, so that paths end at very different depths) over
/// a floor and under a sphere lamp, both shapes tested before the walk: a top level of its root
/// alone, the scene class the queue is compiled for.
fn two_meshes_in_a_room() -> Scene {
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
        Instance { mesh: 0, transform: Mat4::from_translation(Vec3::new(-0.6, 0.0, 0.0)) * Mat4::from_rotation_x(0.6) * Mat4::from_scale(Vec3::splat(0.6)) },
        Instance { mesh: 1, transform: Mat4::from_translation(Vec3::new(0.6, 0.3, 0.2)) * Mat4::from_rotation_z(-0.8) * Mat4::from_scale(Vec3::splat(0.5)) },
    ];
    scene
}

/// The sums of `scene` (seed 11, AOVs on), as bits, rendered in passes adding `steps` samples, and
/// the queue its kernel walked from, if any.
fn sums(ctx: &caustica::gpu::GpuContext, scene: &Scene, choice: KernelChoice, steps: &[u32]) -> (Vec<[u32; 4]>, AovSums, Option<WalkQueue>) {
    let mut renderer = Renderer::with_kernel(ctx, scene, 11, AovSet::ALL, choice).expect("scene uploads");
    for &spp in steps {
        renderer.render(spp, |_| {}).expect("render succeeds without validation messages");
    }
    let bits = renderer.accumulation().expect("readback").iter().map(|p| p.map(f32::to_bits)).collect();
    (bits, renderer.aov_sums().expect("readback").expect("AOVs were asked for"), renderer.walk_queue)
}

#[test]
fn the_walk_queue_renders_the_plain_kernels_sums_bit_for_bit() {
    let (_lock, ctx) = gpu();
    let scene = two_meshes_in_a_room();
    let spp = scene.film.spp;
    let (queued, queued_aovs, queue) = sums(&ctx, &scene, KernelChoice::ForScene, &[spp]);
    if queue.is_none() {
        // The queue is compiled for lavapipe whose loops run to their end (Mesa 24 and newer).
        assert!(ctx.loop_limit().expect("probe").is_some(), "{}: the scene's kernel did not walk from the queue", ctx.info.driver_info);
        eprintln!("SKIPPED: {} ends loops early, so it has no walk queue", ctx.info.driver_info);
        return;
    }
    let (plain, plain_aovs, general_queue) = sums(&ctx, &scene, KernelChoice::General, &[spp]);
    assert!(general_queue.is_none(), "the general kernel walks each lane's rays itself");
    let differing = queued.iter().zip(&plain).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} of {} pixels differ between the queue's kernel and the plain one", plain.len());
    assert!(queued_aovs == plain_aovs, "the AOV sums differ between the queue's kernel and the plain one");
    // Passes of 2, then 3, then 2 samples: the pixels resume with either path.
    let (split, split_aovs, _) = sums(&ctx, &scene, KernelChoice::ForScene, &[2, 3, spp - 5]);
    assert!(split == queued && split_aovs == queued_aovs, "the queue's sums depend on how the render is split into passes");
}

/// The queue's kernel with the subgroup barriers a GPU's lanes need (walk_queue.glsl's
/// queue_barrier) compiles, passes validation and renders the plain kernel's sums bit for bit,
/// in passes of 2 and 5 samples: on lavapipe, whose subgroup barrier is a workgroup barrier, in
/// workgroups of one subgroup. What it cannot show is that the barriers stand where a device whose
/// lanes do not run in step needs them: lavapipe's lanes run in step with or without them (a
/// barrier moved into the walk loop's divergent branch passes here too). That is the GPU's run to
/// show: scripts/gpu-measure.sh compares the GPU's images with lavapipe's.
#[test]
fn the_walk_queue_with_subgroup_barriers_renders_the_same_sums() {
    let (_lock, ctx) = gpu();
    if ctx.loop_limit().expect("probe").is_some() {
        eprintln!("SKIPPED: {} ends loops early, so it has no walk queue", ctx.info.driver_info);
        return;
    }
    let scene = two_meshes_in_a_room();
    let spp = scene.film.spp;
    // The overrides are read when a renderer is made; the lock keeps this binary's other test
    // from making one meanwhile.
    std::env::set_var(WALK_QUEUE_VAR, "barriers");
    std::env::set_var(WORKGROUP_VAR, format!("{}x1", ctx.info.subgroup_size));
    let (with_barriers, aovs_with_barriers, queue) = sums(&ctx, &scene, KernelChoice::ForScene, &[2, spp - 2]);
    std::env::remove_var(WALK_QUEUE_VAR);
    std::env::remove_var(WORKGROUP_VAR);
    assert!(queue.is_some_and(|q| q.subgroup_barriers), "the scene's kernel walked from the queue, with barriers: {queue:?}");
    let (plain, plain_aovs, _) = sums(&ctx, &scene, KernelChoice::General, &[spp]);
    let differing = with_barriers.iter().zip(&plain).filter(|(a, b)| a != b).count();
    assert_eq!(differing, 0, "{differing} of {} pixels differ between the queue's kernel with barriers and the plain one", plain.len());
    assert!(aovs_with_barriers == plain_aovs, "the AOV sums differ between the queue's kernel with barriers and the plain one");
}
