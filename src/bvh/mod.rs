//! Bounding volume hierarchy over primitive bounds: built on the CPU with binned SAH (in parallel)
//! as binary 32-byte `BvhNode`s in depth-first order, walkable on the CPU, and turned into the
//! 64-byte four-wide, quantized `WideNode`s the GLSL kernel walks (wide_node.rs), or, for the
//! meshes' and shapes' own BVHs, into the 80-byte eight-wide nodes of eight_wide.rs
//! (`bvh-width=8`).
//!
//! A BVH over zero primitives is the single node `BvhNode::EMPTY_ROOT`: an inverted box that the
//! sign-ordered slab test of `ray_box` never hits. As wide nodes it is a root of no children,
//! which the kernel never enters either; the host also passes a node count of 0 for an
//! empty scene, and the kernel then skips traversal at once.

mod aabb;
mod binning;
mod blocks;
mod box_a;
mod eight_wide;
mod flatten;
mod node;
mod partition;
mod sah;
mod stats;
#[cfg(test)]
mod test_scenes;
mod traverse;
mod wide_node;

use rayon::prelude::*;

use box_a::BoxA;

pub use aabb::Aabb;
pub use eight_wide::{EightWideNode, EightWideTree, EIGHT_WIDTH, RECORDS_PER_EIGHT_WIDE_NODE};
pub use node::BvhNode;
pub use stats::BuildStats;
pub use traverse::{any_hit, closest_hit, ray_box, Ray};
pub use wide_node::{wide_nodes, WideCost, WideNode, CHILD_INTERIOR, CHILD_NONE, WIDTH};

/// Deepest leaf level (root = 0) the builder emits. It is also the traversal stack size: the stack
/// holds at most one pending far child per level above the current node.
pub const MAX_DEPTH: usize = 64;

/// Most primitives in one leaf; larger sets are always split.
pub const MAX_LEAF_SIZE: usize = 8;

#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    /// Depth-first node array, root at 0 (layout contract on `BvhNode`).
    pub nodes: Vec<BvhNode>,
    /// `prim_order[i]` = original index of the i-th primitive in leaf order.
    pub prim_order: Vec<u32>,
}

impl Bvh {
    pub fn is_empty(&self) -> bool {
        self.prim_order.is_empty()
    }
}

/// Builds from per-primitive bounds. Deterministic: the same input gives the same nodes whatever the
/// thread count. Non-finite bounds do not panic or stall the build but give useless boxes; callers
/// are expected to have rejected them (`Aabb::is_valid`).
///
/// Panics when there are more than `u32::MAX` primitives, which the node format cannot index.
pub fn build(prim_bounds: &[Aabb]) -> Bvh {
    build_with_limits(prim_bounds, MAX_DEPTH, MAX_LEAF_SIZE)
}

/// `build` with one primitive a leaf: for a top level, whose every primitive (an instance) is a
/// whole BVH to enter, so a leaf child stands for one stack entry.
pub fn build_single_leaves(prim_bounds: &[Aabb]) -> Bvh {
    build_with_limits(prim_bounds, MAX_DEPTH, 1)
}

/// `build` with leaves no deeper than `max_depth`, which must be at least ceil(log2(prim count)).
#[cfg(test)]
fn build_with_depth(prim_bounds: &[Aabb], max_depth: usize) -> Bvh {
    build_with_limits(prim_bounds, max_depth, MAX_LEAF_SIZE)
}

/// `build` with leaves no deeper than `max_depth`, which must be at least ceil(log2(prim count)),
/// and holding at most `max_leaf_size` primitives (1 to [`MAX_LEAF_SIZE`]).
fn build_with_limits(prim_bounds: &[Aabb], max_depth: usize, max_leaf_size: usize) -> Bvh {
    debug_assert!((1..=MAX_LEAF_SIZE).contains(&max_leaf_size));
    if prim_bounds.is_empty() {
        return Bvh { nodes: vec![BvhNode::EMPTY_ROOT], prim_order: Vec::new() };
    }
    assert!(u32::try_from(prim_bounds.len()).is_ok(), "{} primitives exceed u32 indices", prim_bounds.len());
    let mut prims: Vec<BoxA> = prim_bounds.par_iter().map(BoxA::from).collect();
    let mut prim_order: Vec<u32> = (0..prim_bounds.len() as u32).collect();
    let tree = sah::build_tree(&mut prims, &mut prim_order, max_depth, max_leaf_size);
    Bvh { nodes: flatten::flatten(&tree), prim_order }
}
