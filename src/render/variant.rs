//! What a kernel is compiled with besides the split of its arrays: the scene's features and the
//! choices of how it walks, shares out work and reads its records. The bindings table (bindings.rs)
//! says which variants bind a buffer, and kernel.rs turns a variant into `#define`s.

use super::bvh_width::BvhWidth;
use super::features::SceneFeatures;
use super::shadow_walk::ShadowWalk;
use super::walk_queue::WalkQueue;
use super::walk_records::WalkRecords;
use super::wavefront::WavefrontStage;
use super::workgroup::Workgroup;
use crate::gpu::Traversal;

/// What a kernel is compiled with besides the split of the arrays: work that only some renders or
/// devices need, so that the others pay nothing for it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct KernelVariant {
    /// Also accumulate the denoiser features (the AOV sums of bindings.rs).
    pub aovs: bool,
    /// Count loop iterations per subgroup, for devices that end loops early (loop_limit.glsl).
    pub count_loop_iterations: bool,
    /// What of the kernel the scene uses (features.rs); the default is the general kernel.
    pub features: SceneFeatures,
    /// Rays walked from a queue the subgroup shares (walk_queue.rs), or each lane's by itself.
    pub walk_queue: Option<WalkQueue>,
    /// Its `local_size_x/y` (workgroup.rs).
    pub workgroup: Workgroup,
    /// Subgroups take their tiles from a counter (tile_taking.rs), or each workgroup renders its own.
    pub take_tiles: bool,
    /// One of the wavefront's kernels (wavefront.rs), or the megakernel.
    pub wavefront: Option<WavefrontStage>,
    /// How it reads the walk's nodes and mesh triangles (walk_records.rs).
    pub walk_records: WalkRecords,
    /// The node format of the meshes' and shapes' BVHs it walks (bvh_width.rs).
    pub bvh_width: BvhWidth,
    /// How a shadow ray's four-wide walk orders a node's children (shadow_walk.rs).
    pub shadow_walk: ShadowWalk,
    /// How it finds what rays hit: its own walk, or the device's ray queries (ray_query.glsl),
    /// which bind the scene's acceleration structure.
    pub traversal: Traversal,
}

/// Which kernel a renderer compiles (features.rs).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum KernelChoice {
    /// Compiled for what the scene uses: the default.
    #[default]
    ForScene,
    /// Every feature compiled in: what specialization is measured against.
    General,
}
