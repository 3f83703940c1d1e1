//! How the plain four-wide walk (shaders/bvh.glsl, walk_instance) orders a node's children for a
//! shadow ray, which needs any hit before its light and stops at the first (`any_hit`): sorted by
//! where the ray enters them, as for the rays that need the closest hit (the default), or in
//! their stored order, without the sorting network. Sorting costs five compare-and-swaps a node;
//! the nearest child first finds an occluder sooner where it lies near. Which wins depends on the
//! device, and shadow rays' walks were 55-80 % of the mesh scenes' time on an NVIDIA H200
//! (docs/benchmarks.md).
//!
//! The `shadow-walk` kernel option (`CAUSTICA_SHADOW_WALK`: `sorted` or `unsorted`) chooses, for an
//! A/B of one binary. A shadow ray's answer (occluded or not) is the same either way, so the images
//! are the same bit for bit (tests/bvh_width.rs). The eight-wide walk (bvh_width.rs) never sorts,
//! and the walk queue (walk_queue.rs) keeps its own sorted walk.

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ShadowWalk {
    /// Children sorted by entry distance, as for the closest hit.
    #[default]
    Sorted,
    /// Children in their stored order.
    Unsorted,
}

impl ShadowWalk {
    pub fn label(self) -> &'static str {
        match self {
            ShadowWalk::Sorted => "sorted",
            ShadowWalk::Unsorted => "unsorted",
        }
    }

    /// The kernel's `#define`.
    pub fn defines(self) -> [(&'static str, String); 1] {
        [("SHADOW_WALK_UNSORTED", u32::from(self == ShadowWalk::Unsorted).to_string())]
    }
}
