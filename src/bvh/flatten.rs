//! Lays the build tree out depth-first in the GPU node format.

use super::sah::BuildNode;
use super::BvhNode;

/// Depth-first layout: an interior node's first child follows it, `offset` points at its second child.
/// `prim_count` only sizes the allocation (a binary tree over n prims has at most 2n - 1 nodes).
pub(super) fn flatten(root: &BuildNode, prim_count: usize) -> Vec<BvhNode> {
    let mut nodes = Vec::with_capacity(2 * prim_count);
    push_subtree(root, &mut nodes);
    nodes
}

fn push_subtree(node: &BuildNode, nodes: &mut Vec<BvhNode>) {
    match node {
        BuildNode::Leaf {
            bounds,
            first,
            count,
        } => nodes.push(BvhNode::leaf(bounds, *first, *count)),
        BuildNode::Interior {
            bounds,
            axis,
            children,
        } => {
            let at = nodes.len();
            // Placeholder until the second child's index is known.
            nodes.push(BvhNode::EMPTY_ROOT);
            push_subtree(&children[0], nodes);
            let second_child = nodes.len() as u32;
            push_subtree(&children[1], nodes);
            nodes[at] = BvhNode::interior(bounds, *axis, second_child);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Aabb;
    use super::*;
    use glam::Vec3;

    fn leaf(first: u32, count: u32) -> BuildNode {
        BuildNode::Leaf {
            bounds: Aabb::new(Vec3::splat(first as f32), Vec3::splat(first as f32 + 1.0)),
            first,
            count,
        }
    }

    fn interior(axis: usize, a: BuildNode, b: BuildNode) -> BuildNode {
        BuildNode::Interior {
            bounds: Aabb::new(Vec3::ZERO, Vec3::splat(9.0)),
            axis,
            children: Box::new([a, b]),
        }
    }

    #[test]
    fn first_child_follows_parent_and_offset_is_second_child() {
        // root(axis 1) -> [inner(axis 2) -> [leaf 0..2, leaf 2..3], leaf 3..5]
        let tree = interior(1, interior(2, leaf(0, 2), leaf(2, 1)), leaf(3, 2));
        let nodes = flatten(&tree, 5);
        assert_eq!(nodes.len(), 5);
        assert_eq!(
            (nodes[0].is_leaf(), nodes[0].axis(), nodes[0].offset),
            (false, 1, 4)
        );
        assert_eq!(
            (nodes[1].is_leaf(), nodes[1].axis(), nodes[1].offset),
            (false, 2, 3)
        );
        assert_eq!((nodes[2].offset, nodes[2].prim_count()), (0, 2));
        assert_eq!((nodes[3].offset, nodes[3].prim_count()), (2, 1));
        assert_eq!((nodes[4].offset, nodes[4].prim_count()), (3, 2));
        assert_eq!(nodes[4].min, [3.0; 3]);
    }
}
