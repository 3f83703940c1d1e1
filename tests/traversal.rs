//! The two traversals (src/gpu/traversal.rs) render the same images in expectation: caustica's
//! compute walk of its BVH and the device's ray queries over Vulkan acceleration structures
//! (shaders/ray_query.glsl), on every checked-in scene. Their hits differ in the last bits (the
//! device's triangle test is not Moller-Trumbore, and alpha's coin is tossed with the object-space
//! ray the device computes), so the images are compared statistically, not bit for bit. And a
//! device without ray queries refuses `--traversal ray-query`, naming itself.
//! The rest of the tests that trace rays run with each traversal too: scripts/test.sh runs them
//! again under CAUSTICA_TRAVERSAL=ray-query (tests/common/mod.rs).

mod common;

use caustica::gpu::{GpuContext, Traversal, TraversalRequest};
use caustica::render::{AovSet, KernelChoice, Renderer};
use caustica::scene::Scene;
use common::{checked_in_scenes, gpu_with_traversal, LAVAPIPE_ICD};
use std::path::Path;

/// Side of the square blocks of pixels whose means are compared.
const BLOCK: u32 = 8;
/// Samples per pixel of each of the two independent halves a traversal renders.
const HALF_SPP: u32 = 16;
/// Most squared block differences, as a share of the blocks' variance (see assert_traversals_agree).
const MAX_RATIO: f64 = 0.25;

/// Per block of BLOCK x BLOCK pixels, per channel: the mean over the block's pixels of two
/// independent renders of `samples` samples each (disjoint sample streams) of `scene` with `ctx`'s
/// traversal, and which traversal ran.
fn block_halves(ctx: &GpuContext, scene: &Scene, samples: u32) -> ([Vec<f64>; 2], Traversal) {
    let mut halves = [Vec::new(), Vec::new()];
    let mut traversal = Traversal::Compute;
    for (h, half) in halves.iter_mut().enumerate() {
        let mut renderer =
            Renderer::with_kernel(ctx, scene, 5, AovSet::default(), KernelChoice::ForScene).expect("scene uploads");
        renderer.set_sample_offset(h as u32 * samples);
        renderer.render(samples, |_| {}).expect("render succeeds without validation messages");
        traversal = renderer.traversal;
        let image = renderer.image().expect("readback");
        let (bw, bh) = (image.width / BLOCK, image.height / BLOCK);
        for by in 0..bh {
            for bx in 0..bw {
                let mut sum = [0.0f64; 3];
                for y in by * BLOCK..(by + 1) * BLOCK {
                    for x in bx * BLOCK..(bx + 1) * BLOCK {
                        let p = image.get(x, y);
                        for c in 0..3 {
                            sum[c] += p[c] as f64;
                        }
                    }
                }
                half.extend(sum.map(|s| s / (BLOCK * BLOCK) as f64));
            }
        }
    }
    (halves, traversal)
}

/// Compares the block means of both traversals' renders of `scene`. Each block's difference D of
/// means has at most the variance of two independent means, which each traversal's two
/// independent halves estimate ((h1 - h2)^2 / 4 for their mean). The renders share their seed, so
/// that a path is the same in both wherever the traversals find the same hits: D^2 summed over the
/// blocks is then about the share of paths that diverged times the sum of those variances (a few
/// in ten thousand on lavapipe). Above MAX_RATIO of it, a quarter of the paths, fails. Returns the
/// smallest uniform relative bias the test catches on this scene: the one whose squared sum over
/// the blocks alone reaches MAX_RATIO. `None` where the scene has no walk for ray queries to
/// replace (a few shapes tested in turn: both kernels are the compute walk's).
fn assert_traversals_agree(compute: &GpuContext, ray_query: &GpuContext, scene: &Scene) -> Option<f64> {
    let name = &scene.name;
    let (r, tr) = block_halves(ray_query, scene, HALF_SPP);
    if tr != Traversal::RayQuery {
        eprintln!("{name}: no walk to replace (a few shapes tested in turn), so no ray queries to compare");
        return None;
    }
    let (c, tc) = block_halves(compute, scene, HALF_SPP);
    assert_eq!(tc, Traversal::Compute, "{name}");
    let (mut squared_differences, mut variances, mut squared_means) = (0.0, 0.0, 0.0);
    for i in 0..c[0].len() {
        let (mean_c, mean_r) = ((c[0][i] + c[1][i]) / 2.0, (r[0][i] + r[1][i]) / 2.0);
        squared_differences += (mean_c - mean_r).powi(2);
        variances += ((c[0][i] - c[1][i]).powi(2) + (r[0][i] - r[1][i]).powi(2)) / 4.0;
        squared_means += mean_c.powi(2);
    }
    // A scene with no noise at all (nothing but sky, say) must agree exactly, up to rounding.
    let variances = variances.max(1e-12 * squared_means).max(1e-20);
    let ratio = squared_differences / variances;
    let catches = (MAX_RATIO * variances / squared_means.max(1e-30)).sqrt();
    eprintln!(
        "{name}: traversals {} and {}: block differences {ratio:.4}x their variance (at most {MAX_RATIO}); catches a bias of {:.2} %",
        tc.name(),
        tr.name(),
        catches * 100.0
    );
    assert!(
        ratio <= MAX_RATIO,
        "{name}: the block means of the compute walk and of ray queries differ by {ratio:.2}x their estimated variance"
    );
    Some(catches)
}

#[test]
fn every_checked_in_scene_renders_alike_with_either_traversal() {
    let Some((_lock, ray_query)) = gpu_with_traversal(TraversalRequest::RayQuery) else { return };
    let compute = compute_context();
    let (mut compared, mut meshes) = (0, 0);
    for (name, mut scene) in checked_in_scenes() {
        (scene.film.width, scene.film.height) = (8 * BLOCK, 6 * BLOCK);
        let Some(catches) = assert_traversals_agree(&compute, &ray_query, &scene) else { continue };
        assert!(catches < 0.04, "{name}: the comparison catches only biases above {:.1} %", catches * 100.0);
        compared += 1;
        meshes += usize::from(!scene.meshes.is_empty());
    }
    // The scenes without a shared data folder: the mesh scenes of scenes/models among them.
    assert!(compared >= 3 && meshes >= 2, "{compared} scenes compared, {meshes} with meshes");
}

#[test]
fn ray_query_is_refused_by_a_device_without_it() {
    // Debian 12's Mesa 22.3 lavapipe, which has no ray queries.
    if !Path::new(LAVAPIPE_ICD).exists() {
        eprintln!("SKIPPED: no system lavapipe at {LAVAPIPE_ICD}");
        return;
    }
    let run = |traversal: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_caustica"))
            .args(["bench", "--spp", "1", "--width", "8", "--height", "8", "--traversal", traversal])
            .env("VK_DRIVER_FILES", LAVAPIPE_ICD)
            // The system's driver with the system's libraries, not those of a newer Mesa beside it.
            .env_remove("LD_LIBRARY_PATH")
            .output()
            .expect("run caustica")
    };
    let refused = run("ray-query");
    let stderr = String::from_utf8_lossy(&refused.stderr);
    if refused.status.success() {
        eprintln!("SKIPPED: the system's lavapipe has ray queries (Mesa 24.1 or newer), so nothing refuses them");
        return;
    }
    assert_eq!(refused.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("llvmpipe") && stderr.contains("does not support ray queries"),
        "the error names the device and what it lacks: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{stderr}");
    // auto falls back to the compute walk there, without a word on standard error about it.
    let auto = run("auto");
    let stderr = String::from_utf8_lossy(&auto.stderr);
    assert!(auto.status.success(), "{stderr}");
    assert!(!stderr.to_lowercase().contains("ray"), "auto says nothing of ray queries: {stderr}");
    let stdout = String::from_utf8_lossy(&auto.stdout);
    assert!(stdout.contains("traversal compute"), "{stdout}");
}

/// A context of the compute walk, for comparison with a ray-query one.
fn compute_context() -> GpuContext {
    GpuContext::new(&caustica::gpu::ContextOptions {
        device: None,
        validation: true,
        storage_binding_limit: None,
        traversal: TraversalRequest::Compute,
    })
    .expect("a Vulkan device")
}

/// A placed mesh of BLEND alpha (opacity 0.4) beside an opaque glass one: the first's triangles are
/// candidates that ray_query.glsl confirms by alpha's coin, the second's are flagged opaque. The
/// coin is tossed with the object-space ray, which the device computes for ray queries and the
/// kernel for its walk, so the two traversals' paths through the cut-out may differ in their last
/// bits and part ways: the comparison allows for it (MAX_RATIO).
#[test]
fn alpha_cut_outs_render_alike_with_either_traversal() {
    let Some((_lock, ray_query)) = gpu_with_traversal(TraversalRequest::RayQuery) else { return };
    let compute = compute_context();
    let mut scene = common::two_meshes::two_meshes_in_a_room();
    let clay = scene.meshes[0].triangle_materials[0] as usize;
    scene.materials[clay].maps.alpha =
        Some(caustica::scene::Alpha { factor: 0.4, texture: None, mode: caustica::scene::AlphaMode::Blend });
    (scene.film.width, scene.film.height) = (8 * BLOCK, 6 * BLOCK);
    let catches = assert_traversals_agree(&compute, &ray_query, &scene).expect("a walk for ray queries to replace");
    assert!(catches < 0.04, "the comparison catches only biases above {:.1} %", catches * 100.0);
}

/// More shapes than a scene tests in turn (FEW_PRIMITIVES), so that rays meet them through the
/// acceleration structure as boxes whose candidates the kernel intersects exactly, beside two
/// placed meshes, one of glass: the walked shapes' path of ray_query.glsl.
#[test]
fn walked_shapes_and_placed_meshes_render_alike_with_either_traversal() {
    let Some((_lock, ray_query)) = gpu_with_traversal(TraversalRequest::RayQuery) else { return };
    let compute = compute_context();
    let mut scene = common::two_meshes::two_meshes_in_a_room();
    let clay = scene.meshes[0].triangle_materials[0];
    let floor = match scene.shapes[0] {
        caustica::scene::Shape::Quad { material, .. } => material,
        _ => clay,
    };
    // A ring of small spheres and a row of tilted quads on the floor.
    for i in 0..caustica::render::FEW_PRIMITIVES {
        let angle = i as f32 * 0.39;
        let center = glam::Vec3::new(1.3 * angle.cos(), -0.35 + 0.02 * i as f32, 1.3 * angle.sin() - 0.2);
        scene.shapes.push(caustica::scene::Shape::Sphere { center, radius: 0.12, material: clay });
    }
    for i in 0..4 {
        scene.shapes.push(caustica::scene::Shape::Quad {
            origin: glam::Vec3::new(-1.2 + 0.6 * i as f32, -0.5, -0.8),
            u: glam::Vec3::new(0.4, 0.0, 0.0),
            v: glam::Vec3::new(0.0, 0.5, 0.2),
            material: floor,
        });
    }
    (scene.film.width, scene.film.height) = (8 * BLOCK, 6 * BLOCK);
    let catches = assert_traversals_agree(&compute, &ray_query, &scene).expect("a walk for ray queries to replace");
    assert!(catches < 0.04, "the comparison catches only biases above {:.1} %", catches * 100.0);
}

/// `auto` takes the compute walk on a CPU device even where it has ray queries (Mesa 25's
/// lavapipe): the walk measured 1.3-3.2x faster there (docs/benchmarks.md, 2026-12-07).
#[test]
fn auto_takes_the_compute_walk_on_lavapipe() {
    let Some((_lock, ctx)) = gpu_with_traversal(TraversalRequest::Auto) else { return };
    assert_eq!(ctx.info.kind, caustica::gpu::DeviceType::Cpu, "the tests run on lavapipe");
    assert_eq!(ctx.traversal, Traversal::Compute, "{}", ctx.info.driver_info);
}
