//! The two traversals (src/gpu/traversal.rs) render the same images in expectation: caustica's
//! compute walk of its BVH and the device's ray queries over Vulkan acceleration structures
//! (shaders/ray_query.glsl), on every checked-in scene. Their hits differ in the last bits (the
//! device's triangle test is not Moller-Trumbore, and alpha's coin is tossed with the object-space
//! ray the device computes), so the images are compared statistically, not bit for bit. And a
//! device without ray queries refuses `--traversal ray-query`, naming itself.
//! The rest of the tests that trace rays run with each traversal too: scripts/test.sh runs them
//! again under CAUSTICA_TRAVERSAL=ray-query (tests/common/mod.rs).

mod common;

use caustica::bench::{suite_entries, SuiteEntry};
use caustica::gpu::{GpuContext, Traversal, TraversalRequest};
use caustica::render::{AovSet, KernelChoice, Renderer};
use caustica::scene::Scene;
use common::{gpu_with_traversal, LAVAPIPE_ICD};
use std::path::Path;

/// Side of the square blocks of pixels whose means are compared.
const BLOCK: u32 = 8;
/// Samples per pixel of each of the two independent halves a traversal renders.
const HALF_SPP: u32 = 8;

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

/// Compares the block means of both traversals' renders of `scene`. Under the hypothesis that the
/// images agree in expectation, each block's difference D has the variance of the two means, which
/// each traversal's two independent halves estimate ((h1 - h2)^2 / 4 for their mean), and the sum
/// of D^2 over the blocks is about the sum of those variances; a ratio above 3 fails. Returns
/// the smallest uniform relative bias the test catches on this scene: the one whose squared sum
/// over the blocks raises the ratio by 2 more than it is.
fn assert_traversals_agree(compute: &GpuContext, ray_query: &GpuContext, scene: &Scene) -> f64 {
    let (c, tc) = block_halves(compute, scene, HALF_SPP);
    let (r, tr) = block_halves(ray_query, scene, HALF_SPP);
    assert_eq!(tc, Traversal::Compute, "{}", scene.name);
    let name = &scene.name;
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
    let catches = (2.0 * variances / squared_means.max(1e-30)).sqrt();
    eprintln!(
        "{name}: traversals {} and {}: block differences {ratio:.2}x their variance (at most 3); catches a bias of {:.2} %",
        tc.name(),
        tr.name(),
        catches * 100.0
    );
    assert!(
        ratio <= 3.0,
        "{name}: the block means of the compute walk and of ray queries differ by {ratio:.2}x their estimated variance"
    );
    catches
}

#[test]
fn every_checked_in_scene_renders_alike_with_either_traversal() {
    let Some((_lock, ray_query)) = gpu_with_traversal(TraversalRequest::RayQuery) else { return };
    let compute = GpuContext::new(&caustica::gpu::ContextOptions {
        device: None,
        validation: true,
        storage_binding_limit: None,
        traversal: TraversalRequest::Compute,
    })
    .expect("a Vulkan device");
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let (mut compared, mut meshes) = (0, 0);
    for entry in suite_entries(&scenes, &caustica::scene::data_dir()).expect("the scenes folder lists") {
        let (name, path) = match entry {
            SuiteEntry::Skip { name, reason } => {
                eprintln!("SKIPPED {name}: {reason}");
                continue;
            }
            SuiteEntry::Run { name, path, .. } => (name, path),
        };
        let mut scene = match path {
            Some(path) => Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e:#}")),
            None => Scene::default_scene(),
        };
        (scene.film.width, scene.film.height) = (6 * BLOCK, 4 * BLOCK);
        let catches = assert_traversals_agree(&compute, &ray_query, &scene);
        assert!(catches < 0.1, "{name}: the comparison catches only biases above {:.1} %", catches * 100.0);
        compared += 1;
        meshes += usize::from(!scene.meshes.is_empty());
    }
    assert!(compared >= 5 && meshes >= 1, "{compared} scenes compared, {meshes} with meshes");
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
