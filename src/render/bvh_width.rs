//! Which node format the kernel walks the meshes' and shapes' own BVHs in: the four-wide nodes of
//! src/bvh/wide_node.rs, sorted by entry distance at each visit (the default everywhere), or the
//! eight-wide compressed nodes of src/bvh/eight_wide.rs, visited in the order of the ray's octant
//! without sorting (Ylitie, Karras and Laine 2017). The top level over the placements is four-wide
//! either way. Both find the same closest hit (tests/bvh_width.rs); the eight-wide build stores the
//! primitives in another order, so a hit on the very edge shared by two triangles may be given to
//! the other one, and images agree to their statistical tolerance rather than bit for bit.
//!
//! The `bvh-width` kernel option (`CAUSTICA_BVH_WIDTH`: `4` or `8`) chooses, for an A/B of one
//! binary. The eight-wide walk is experimental: it was built for GPUs without ray-tracing hardware,
//! where Ylitie et al. measured 1.9-2.1x over a binary walk on incoherent rays, and is unmeasured
//! on one (scripts/gpu-measure.sh, STEPS=traversal); lavapipe's figures are in
//! docs/benchmarks.md.

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum BvhWidth {
    /// Four-wide nodes, 64 bytes, children sorted by entry distance.
    #[default]
    Four,
    /// Eight-wide compressed nodes, 80 bytes, children in the ray's octant order.
    Eight,
}

impl BvhWidth {
    pub fn label(self) -> &'static str {
        match self {
            BvhWidth::Four => "4",
            BvhWidth::Eight => "8",
        }
    }

    /// The kernel's `#define`: which walk bvh.glsl compiles for the bottom levels.
    pub fn defines(self) -> [(&'static str, String); 1] {
        [("BVH_WIDTH", self.label().to_string())]
    }
}
