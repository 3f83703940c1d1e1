//! Where a kernel walks its rays from a queue its subgroup shares (shaders/walk_queue.glsl and
//! queued_paths.glsl): each lane carries two paths, queues a walk of each instance its rays enter,
//! and every lane of the subgroup takes the next walk as soon as it is free. On lavapipe that fills
//! the lanes a mesh walk leaves idle (docs/benchmarks/history.md, 2026-12-04, `d1c2c17`); the images are the plain
//! kernel's bit for bit.
//!
//! By default it is compiled only where all of these hold:
//! - **lavapipe**: the lanes hand walks to each other through shared memory without a barrier,
//!   which is sound where gallivm runs a subgroup as one SIMD thread;
//! - **loops run to their end** (no loop limit to count: the rounds need every lane);
//! - **a top level of its root alone** (two to four instances): a scene of one instance walks
//!   every ray, and the queue's walk, slower per pass, loses there; a deeper top level would need
//!   its walk to collect the instances;
//! - **the queue fits the device's shared memory**.
//!
//! The `walk-queue` kernel option (`CAUSTICA_WALK_QUEUE`, kernel_options.rs) changes the first condition, for an A/B of one binary: `0` compiles no
//! queue, `1` compiles it on any device (a GPU's kernel then has subgroup barriers between the
//! round's steps, since its lanes need not run in step), and `barriers` also gives lavapipe's
//! kernel the barriers, where a workgroup is one subgroup (gallivm makes a subgroup barrier a
//! workgroup barrier, which cuts loops short where the workgroup's subgroups run different
//! numbers of rounds): what tests/walk_queue.rs checks the barriers' kernel with. On a GPU the
//! queue is unmeasured, hence not the default there.

use super::features::SceneFeatures;
use super::layout::{GpuInstance, INSTANCE_PRIMITIVES};
use crate::bvh::{WideNode, CHILD_NONE, WIDTH};
use crate::gpu::DeviceInfo;
use anyhow::{bail, Result};

/// The queue a kernel is compiled with: `QUEUE_WALKS_PER_RAY` of walk_queue.glsl.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct WalkQueue {
    /// Instances one ray can walk: those under the top level's root that rays walk.
    pub walks_per_ray: u32,
    /// Subgroup barriers between queueing, walking and reading (`QUEUE_SUBGROUP_BARRIERS`):
    /// wherever the lanes of a subgroup need not run in step, that is on every device but lavapipe.
    pub subgroup_barriers: bool,
}

/// Shared memory a queued walk takes (walk_queue.glsl: `queue_origin`, `queue_dir`, `queue_instance`).
pub const SHARED_BYTES_PER_WALK: u32 = 16 + 16 + 8;

/// Walks a lane queues in a round at most, per instance a ray walks: two paths, each with a path
/// ray and a shadow ray (queued_paths.glsl).
const WALKS_PER_LANE_PER_INSTANCE: u32 = 2 * 2;

/// What was asked of the queue (kernel_options.rs: `walk-queue`, `CAUSTICA_WALK_QUEUE`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QueueRequest {
    Off,
    /// Where the scene qualifies, with subgroup barriers except on lavapipe.
    On,
    /// Where the scene qualifies, with subgroup barriers on every device.
    WithBarriers,
}

impl WalkQueue {
    /// Shared memory the queue takes in a workgroup of `lanes` invocations: its walks and each
    /// subgroup's two counters.
    pub fn shared_bytes(self, lanes: u32) -> u32 {
        lanes * WALKS_PER_LANE_PER_INSTANCE * self.walks_per_ray * SHARED_BYTES_PER_WALK + 2 * lanes * 4
    }

    /// The queue for a scene with these `features`, whose top-level root is `root` over
    /// `instances`, on `device` (whose loops are cut short where `loop_limit`) in workgroups of
    /// `lanes` invocations; `None` where the kernel walks each lane's rays itself (see the
    /// module's conditions). An error where `request` asks for what cannot run.
    pub fn for_scene(
        request: QueueRequest,
        device: &DeviceInfo,
        loop_limit: bool,
        lanes: u32,
        features: &SceneFeatures,
        root: Option<&WideNode>,
        instances: &[GpuInstance],
    ) -> Result<Option<WalkQueue>> {
        let lavapipe = device.is_lavapipe();
        if request == QueueRequest::Off {
            return Ok(None);
        }
        let subgroup_barriers = !lavapipe || request == QueueRequest::WithBarriers;
        if lavapipe && subgroup_barriers && lanes > device.subgroup_size {
            bail!("walk-queue=barriers: lavapipe runs a subgroup barrier as a workgroup barrier, so its kernel needs a workgroup of one subgroup ({} lanes, e.g. workgroup={}x1), not {lanes}", device.subgroup_size, device.subgroup_size);
        }
        let flat_top_level = features.bvh() && features.top_level && !features.top_level_tree;
        // A scene with media traces its shadow rays through null boundaries and media, a loop the
        // queue does not take (shaders/medium.glsl): it runs without it.
        if loop_limit || !flat_top_level || features.media {
            return Ok(None);
        }
        let Some(root) = root else { return Ok(None) };
        // As walk_queue.glsl's instance_walked: a group of shapes is walked only where its shapes
        // are not tested before the walk.
        let walked = |instance: &GpuInstance| instance.info[0] != INSTANCE_PRIMITIVES || features.walked_shapes();
        let walks_per_ray = (0..WIDTH)
            .filter(|&k| root.kind(k) != CHILD_NONE && instances.get(root.links[k] as usize).is_some_and(walked))
            .count() as u32;
        let queue = WalkQueue { walks_per_ray, subgroup_barriers };
        Ok((walks_per_ray > 0 && queue.shared_bytes(lanes) <= device.max_compute_shared_memory_size).then_some(queue))
    }

    /// The kernel's `#define`s for the queue, or for none.
    pub fn defines(queue: Option<WalkQueue>) -> Vec<(&'static str, String)> {
        vec![
            ("WALK_QUEUE", u32::from(queue.is_some()).to_string()),
            ("QUEUE_WALKS_PER_RAY", format!("{}u", queue.map_or(0, |q| q.walks_per_ray))),
            ("QUEUE_SUBGROUP_BARRIERS", u32::from(queue.is_some_and(|q| q.subgroup_barriers)).to_string()),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_bytes_match_the_kernels_arrays() {
        // 64 lanes x 4 walks x 2 instances x 40 bytes, and two counters a lane.
        assert_eq!(WalkQueue { walks_per_ray: 2, subgroup_barriers: false }.shared_bytes(64), 64 * 4 * 2 * 40 + 512);
        let glsl = include_str!("../../shaders/walk_queue.glsl");
        for array in ["shared vec4 queue_origin[", "shared vec4 queue_dir[", "shared uvec2 queue_instance["] {
            assert!(glsl.contains(array), "walk_queue.glsl no longer declares `{array}`: update SHARED_BYTES_PER_WALK");
        }
        assert!(glsl.contains("const uint QUEUE_WALKS_PER_LANE = 2u * 2u * QUEUE_WALKS_PER_RAY;"));
    }

    #[test]
    fn four_instances_do_not_fit_lavapipes_32_kib() {
        assert!(WalkQueue { walks_per_ray: 3, subgroup_barriers: false }.shared_bytes(64) <= 32 * 1024);
        assert!(WalkQueue { walks_per_ray: 4, subgroup_barriers: false }.shared_bytes(64) > 32 * 1024);
    }
}
