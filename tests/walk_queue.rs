//! The walk queue (src/render/walk_queue.rs, shaders/walk_queue.glsl and queued_paths.glsl)
//! renders the plain kernel's sums bit for bit: every vertex, shadow ray and sample the same, and
//! the samples added in sample order, whatever order a lane's two paths end in and however the
//! render is split into passes. The general kernel (no queue: its top level is a tree) is the
//! reference. A hit taken from another walk's slot, a shadow ray's light added after its vertex's
//! or the samples added as they end would each change the sums (the mutations `queue-*` of
//! tests/mutations.toml).

mod common;

use caustica::render::{KernelChoice, WALK_QUEUE_VAR, WORKGROUP_VAR};
use common::two_meshes::{sums, two_meshes_in_a_room};
use common::{gpu, loops_end_early};

#[test]
fn the_walk_queue_renders_the_plain_kernels_sums_bit_for_bit() {
    let (_lock, ctx) = gpu();
    let scene = two_meshes_in_a_room();
    let spp = scene.film.spp;
    // The queue is the default on lavapipe only; on another device (scripts/test.sh with
    // CAUSTICA_LAVAPIPE=none) it is asked for, so that its form with subgroup barriers is checked
    // on the device's own lanes. Read when a renderer is made; the lock keeps this binary's other
    // test from making one meanwhile.
    let asked = !ctx.info.is_lavapipe();
    let queued_sums = |passes: &[u32]| {
        if asked {
            std::env::set_var(WALK_QUEUE_VAR, "1");
        }
        let made = sums(&ctx, &scene, KernelChoice::ForScene, passes);
        std::env::remove_var(WALK_QUEUE_VAR);
        made
    };
    let (queued, queued_aovs, queue, _) = queued_sums(&[spp]);
    if queue.is_none() {
        // The queue is compiled where loops run to their end (lavapipe from Mesa 24) and, asked
        // for, where its walks fit the workgroup's shared memory.
        if asked {
            eprintln!(
                "SKIPPED: {} did not take the walk queue asked for (its shared memory or loop limit)",
                ctx.info.driver_info
            );
            return;
        }
        assert!(
            ctx.loop_limit().expect("probe").is_some(),
            "{}: the scene's kernel did not walk from the queue",
            ctx.info.driver_info
        );
        eprintln!("SKIPPED: {} ends loops early, so it has no walk queue", ctx.info.driver_info);
        return;
    }
    let (plain, plain_aovs, general_queue, _) = sums(&ctx, &scene, KernelChoice::General, &[spp]);
    assert!(general_queue.is_none(), "the general kernel walks each lane's rays itself");
    let differing = queued.iter().zip(&plain).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing,
        0,
        "{differing} of {} pixels differ between the queue's kernel and the plain one",
        plain.len()
    );
    assert!(queued_aovs == plain_aovs, "the AOV sums differ between the queue's kernel and the plain one");
    // Passes of 2, then 3, then 2 samples: the pixels resume with either path.
    let (split, split_aovs, _, _) = queued_sums(&[2, 3, spp - 5]);
    assert!(
        split == queued && split_aovs == queued_aovs,
        "the queue's sums depend on how the render is split into passes"
    );
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
    if loops_end_early(&ctx, "walk queue") {
        return;
    }
    let scene = two_meshes_in_a_room();
    let spp = scene.film.spp;
    // The overrides are read when a renderer is made; the lock keeps this binary's other test
    // from making one meanwhile.
    std::env::set_var(WALK_QUEUE_VAR, "barriers");
    std::env::set_var(WORKGROUP_VAR, format!("{}x1", ctx.info.subgroup_size));
    let (with_barriers, aovs_with_barriers, queue, _) = sums(&ctx, &scene, KernelChoice::ForScene, &[2, spp - 2]);
    std::env::remove_var(WALK_QUEUE_VAR);
    std::env::remove_var(WORKGROUP_VAR);
    assert!(
        queue.is_some_and(|q| q.subgroup_barriers),
        "the scene's kernel walked from the queue, with barriers: {queue:?}"
    );
    let (plain, plain_aovs, _, _) = sums(&ctx, &scene, KernelChoice::General, &[spp]);
    let differing = with_barriers.iter().zip(&plain).filter(|(a, b)| a != b).count();
    assert_eq!(
        differing,
        0,
        "{differing} of {} pixels differ between the queue's kernel with barriers and the plain one",
        plain.len()
    );
    assert!(
        aovs_with_barriers == plain_aovs,
        "the AOV sums differ between the queue's kernel with barriers and the plain one"
    );
}
