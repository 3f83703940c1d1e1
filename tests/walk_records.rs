//! The walk's records (BVH nodes and mesh triangles) read from storage buffers render the sums of
//! the same records read as texels, bit for bit (src/render/walk_records.rs): in the walk queue's
//! kernel and in the plain walk, whole and split across bindings. A storage array declared with
//! another stride or window than the records uploaded, or a window's base lost, moves a node or
//! a triangle: the walk then finds other hits, and the sums differ.

mod common;

use caustica::render::{AovSet, KernelChoice, Renderer, WalkRecords, WALK_QUEUE_VAR, WALK_RECORDS_VAR};
use caustica::scene::Scene;
use common::gpu_with_storage_limit;
use common::two_meshes::{rendered_sums, two_meshes_in_a_room};

/// The sums of `scene` with the records read as `records`, the queue as `queue` says (`None`: the
/// device's choice), on a device whose bindings see `limit` bytes where given; and the windows the
/// mesh triangles span.
fn sums(
    scene: &Scene,
    records: &str,
    queue: Option<&str>,
    limit: Option<u64>,
) -> (Vec<[u32; 4]>, caustica::render::AovSums, u32) {
    let (_lock, ctx) = gpu_with_storage_limit(limit);
    // Read when a renderer is made; the lock keeps other tests of this binary from making one.
    std::env::set_var(WALK_RECORDS_VAR, records);
    if let Some(queue) = queue {
        std::env::set_var(WALK_QUEUE_VAR, queue);
    }
    let made = Renderer::with_kernel(&ctx, scene, 11, AovSet::ALL, KernelChoice::ForScene);
    std::env::remove_var(WALK_RECORDS_VAR);
    std::env::remove_var(WALK_QUEUE_VAR);
    let mut renderer = made.expect("scene uploads");
    let expected = if records == "storage" { WalkRecords::Storage } else { WalkRecords::Texels };
    assert_eq!(renderer.walk_records, expected, "{WALK_RECORDS_VAR}={records}");
    let windows =
        renderer.geometry.split_arrays.iter().find(|(name, _)| *name == "mesh triangles").map_or(1, |&(_, w)| w);
    let (bits, aovs) = rendered_sums(&mut renderer, &[2, 3]);
    (bits, aovs, windows)
}

#[test]
fn records_from_storage_buffers_render_the_sums_of_texels() {
    let scene = two_meshes_in_a_room();
    // The device's own walk (the queue's on Mesa 24 and newer), and the plain walk.
    for queue in [None, Some("0")] {
        let (texels, texel_aovs, _) = sums(&scene, "texels", queue, None);
        let (storage, storage_aovs, _) = sums(&scene, "storage", queue, None);
        assert!(texels.iter().any(|p| p[3] != 0), "nothing rendered");
        let differing = storage.iter().zip(&texels).filter(|(a, b)| a != b).count();
        assert_eq!(
            differing,
            0,
            "{differing} of {} pixels differ with the records from storage buffers ({WALK_QUEUE_VAR}: {queue:?})",
            texels.len()
        );
        assert!(
            storage_aovs == texel_aovs,
            "the AOV sums differ with the records from storage buffers ({WALK_QUEUE_VAR}: {queue:?})"
        );
    }
}

#[test]
fn records_from_storage_split_across_bindings_render_the_same_sums() {
    let scene = two_meshes_in_a_room();
    let (whole, whole_aovs, _) = sums(&scene, "texels", None, None);
    // 8 KiB a binding: the 488 triangles (23 KiB) span four windows of 128. (The nodes, 2-3 KiB,
    // fit one: a binding small enough to split them could not hold the triangles in eight. They
    // are declared and read by the same generated code.)
    let (split, split_aovs, windows) = sums(&scene, "storage", None, Some(8 << 10));
    assert!(windows > 1, "the triangles are split: {windows} window");
    assert!(split == whole && split_aovs == whole_aovs, "the records from split storage buffers give other sums");
}
