//! Stitches the builder's depth-first node blocks into the final array in the GPU node format.

use rayon::join;

use super::BvhNode;

/// Depth-first layout: an interior node's first child follows it, `offset` points at its second child.
pub(super) enum Subtree {
    /// A complete subtree laid out depth-first; interior offsets count from the block's start.
    Block(Vec<BvhNode>),
    /// An interior node (offset not yet set) over two subtrees built in parallel.
    Split { node: BvhNode, children: Box<(Subtree, Subtree)>, len: usize },
}

impl Subtree {
    pub fn split(node: BvhNode, children: (Subtree, Subtree)) -> Subtree {
        let len = 1 + children.0.len() + children.1.len();
        Subtree::Split { node, children: Box::new(children), len }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        match self {
            Subtree::Block(nodes) => nodes.len(),
            Subtree::Split { len, .. } => *len,
        }
    }
}

pub(super) fn flatten(root: &Subtree) -> Vec<BvhNode> {
    // Zeroed allocation is lazily zeroed memory: no pass over the array before it is written.
    let mut nodes = bytemuck::zeroed_vec(root.len());
    write(root, &mut nodes, 0);
    nodes
}

/// Writes `subtree` into `out`, which starts at node index `base` of the final array.
fn write(subtree: &Subtree, out: &mut [BvhNode], base: u32) {
    match subtree {
        Subtree::Block(nodes) => {
            for (o, n) in out.iter_mut().zip(nodes) {
                *o = *n;
                if !n.is_leaf() {
                    o.offset += base;
                }
            }
        }
        Subtree::Split { node, children, .. } => {
            let second_child = 1 + children.0.len();
            out[0] = BvhNode { offset: base + second_child as u32, ..*node };
            let (left, right) = out[1..].split_at_mut(second_child - 1);
            join(|| write(&children.0, left, base + 1), || write(&children.1, right, base + second_child as u32));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::Aabb;
    use super::*;
    use glam::Vec3;

    fn leaf(first: u32, count: u32) -> BvhNode {
        let corner = Vec3::splat(first as f32);
        BvhNode::leaf(&Aabb::new(corner, corner + 1.0), first, count)
    }

    fn interior(axis: usize, second_child: u32) -> BvhNode {
        BvhNode::interior(&Aabb::new(Vec3::ZERO, Vec3::splat(9.0)), axis, second_child)
    }

    #[test]
    fn first_child_follows_parent_and_offset_is_second_child() {
        // root(axis 1) -> [inner(axis 2) -> [leaf 0..2, leaf 2..3], leaf 3..5], the inner subtree
        // and the last leaf built as separate blocks.
        let inner = Subtree::Block(vec![interior(2, 2), leaf(0, 2), leaf(2, 1)]);
        let tree = Subtree::split(interior(1, 0), (inner, Subtree::Block(vec![leaf(3, 2)])));
        let nodes = flatten(&tree);
        assert_eq!(nodes.len(), 5);
        assert_eq!((nodes[0].is_leaf(), nodes[0].axis(), nodes[0].offset), (false, 1, 4));
        assert_eq!((nodes[1].is_leaf(), nodes[1].axis(), nodes[1].offset), (false, 2, 3));
        assert_eq!((nodes[2].offset, nodes[2].prim_count()), (0, 2));
        assert_eq!((nodes[3].offset, nodes[3].prim_count()), (2, 1));
        assert_eq!((nodes[4].offset, nodes[4].prim_count()), (3, 2));
        assert_eq!(nodes[4].min, [3.0; 3]);
    }
}
