//! The node format the kernel walks: one node per interior node of the binary BVH, carrying both
//! children's boxes (Aila & Laine 2009). One 64-byte load tests both children and orders them by
//! where the ray enters each, where the binary format needs a load per child and can only order
//! them by the split axis. Leaves get no node of their own: a child that is a leaf names its
//! primitives directly.

use super::{Aabb, BvhNode};

/// Link of a missing child (the second child of a root that is itself a leaf, or both children of
/// an empty BVH's root).
pub const NO_CHILD: u32 = u32::MAX;

/// One child of a [`PairNode`]; mirrors the GLSL struct's half
/// `vec3 bmin; uint link; vec3 bmax; uint prim_count;`.
///
/// - interior child (`prim_count == 0`): `link` is its pair node;
/// - leaf child: primitives `link..link + prim_count` in `Bvh::prim_order` order.
///
/// A missing child has a point box at +infinity, which a ray with a finite `t_max` (every ray the
/// kernel traces) never enters, so traversal needs no test for it.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct ChildBox {
    pub min: [f32; 3],
    pub link: u32,
    pub max: [f32; 3],
    pub prim_count: u32,
}

impl ChildBox {
    pub const MISSING: ChildBox = ChildBox { min: [f32::INFINITY; 3], link: NO_CHILD, max: [f32::INFINITY; 3], prim_count: 0 };

    pub fn is_leaf(&self) -> bool {
        self.prim_count > 0
    }

    pub fn is_missing(&self) -> bool {
        self.link == NO_CHILD && !self.is_leaf()
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.min.into(), self.max.into())
    }
}

/// GPU node, std430-compatible: 64 bytes, mirrors GLSL `struct PairNode { ChildBox a; ChildBox b; }`
/// flattened into four vec4s (see shaders/layout.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct PairNode {
    pub children: [ChildBox; 2],
}

impl PairNode {
    /// Bounds of everything below this node.
    pub fn bounds(&self) -> Aabb {
        self.children.iter().filter(|c| !c.is_missing()).fold(Aabb::EMPTY, |b, c| b.union(&c.bounds()))
    }
}

/// The binary BVH `nodes` (depth-first, root at 0, layout contract on [`BvhNode`]) as pair nodes,
/// root at 0, in the same depth-first order of their interior nodes. A root that is a leaf becomes
/// a pair of it and a missing child; an empty BVH a pair of two missing children.
pub fn pair_nodes(nodes: &[BvhNode]) -> Vec<PairNode> {
    let root = &nodes[0];
    if root.is_leaf() {
        return vec![PairNode { children: [leaf_child(root), ChildBox::MISSING] }];
    }
    if nodes.len() == 1 {
        return vec![PairNode { children: [ChildBox::MISSING; 2] }];
    }
    // The pair node of each binary interior node: interior nodes numbered in array order.
    let mut pair_index = vec![NO_CHILD; nodes.len()];
    let mut count = 0u32;
    for (i, n) in nodes.iter().enumerate() {
        if !n.is_leaf() {
            pair_index[i] = count;
            count += 1;
        }
    }
    let child = |i: usize| {
        let n = &nodes[i];
        if n.is_leaf() {
            leaf_child(n)
        } else {
            ChildBox { min: n.min, link: pair_index[i], max: n.max, prim_count: 0 }
        }
    };
    nodes
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.is_leaf())
        .map(|(i, n)| PairNode { children: [child(i + 1), child(n.offset as usize)] })
        .collect()
}

fn leaf_child(n: &BvhNode) -> ChildBox {
    ChildBox { min: n.min, link: n.offset, max: n.max, prim_count: n.prim_count() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::build;
    use glam::Vec3;
    use std::mem::{offset_of, size_of};

    #[test]
    fn layout_matches_the_glsl_struct() {
        assert_eq!(size_of::<ChildBox>(), 32);
        assert_eq!(offset_of!(ChildBox, link), 12);
        assert_eq!(offset_of!(ChildBox, max), 16);
        assert_eq!(offset_of!(ChildBox, prim_count), 28);
        assert_eq!(size_of::<PairNode>(), 64);
    }

    /// Every primitive is reachable exactly once, each child's box is the binary node's, and the
    /// pair tree has one node per binary interior node.
    #[test]
    fn pairs_cover_the_binary_tree() {
        let bounds: Vec<Aabb> = (0..1000)
            .map(|i| {
                let c = Vec3::new((i * 37 % 101) as f32, (i * 53 % 97) as f32, (i % 7) as f32);
                Aabb::new(c, c + 0.5)
            })
            .collect();
        let bvh = build(&bounds);
        let pairs = pair_nodes(&bvh.nodes);
        assert_eq!(pairs.len(), bvh.nodes.iter().filter(|n| !n.is_leaf()).count());
        assert_eq!(pairs[0].bounds(), bvh.nodes[0].bounds());
        let mut seen = vec![0u32; bounds.len()];
        let mut stack = vec![0u32];
        while let Some(p) = stack.pop() {
            for c in pairs[p as usize].children {
                if c.is_leaf() {
                    for i in c.link..c.link + c.prim_count {
                        let prim = bvh.prim_order[i as usize] as usize;
                        seen[prim] += 1;
                        assert!(c.bounds().contains(&bounds[prim]), "leaf box holds its primitives");
                    }
                } else {
                    assert_eq!(pairs[c.link as usize].bounds(), c.bounds(), "child box is the subtree's");
                    stack.push(c.link);
                }
            }
        }
        assert!(seen.iter().all(|&s| s == 1), "every primitive once");
    }

    #[test]
    fn a_leaf_root_pairs_with_a_missing_child_and_an_empty_tree_has_none() {
        let one = build(&[Aabb::new(Vec3::ZERO, Vec3::ONE)]);
        let pairs = pair_nodes(&one.nodes);
        assert_eq!(pairs.len(), 1);
        assert_eq!((pairs[0].children[0].link, pairs[0].children[0].prim_count), (0, 1));
        assert_eq!(pairs[0].children[1], ChildBox::MISSING);
        assert_eq!(pair_nodes(&build(&[]).nodes), vec![PairNode { children: [ChildBox::MISSING; 2] }]);
    }
}
