use super::Aabb;

/// The builder's binary node, 32 bytes, in depth-first order. The kernel walks these as
/// `WideNode`s (wide_node.rs), one per binary interior node two levels apart.
///
/// - interior (`prim_count() == 0`): the first child is the next node, `offset` is the second child,
///   `axis()` is the split axis (visit the second child first when `ray.dir[axis] < 0`);
/// - leaf (`prim_count() > 0`): primitives `offset..offset + prim_count()` in `Bvh::prim_order` order.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub offset: u32,
    pub max: [f32; 3],
    pub meta: u32,
}

impl BvhNode {
    /// Root of a BVH over no primitives: an inverted box with finite, huge planes. The sign-ordered
    /// slab test in `ray_box` (the CPU traversal's) gets entry > exit on every axis for any finite
    /// ray, so traversal never looks at its (meaningless) interior encoding.
    pub const EMPTY_ROOT: BvhNode = BvhNode { min: [f32::MAX; 3], offset: 0, max: [-f32::MAX; 3], meta: 0 };

    pub fn leaf(bounds: &Aabb, first_prim: u32, prim_count: u32) -> BvhNode {
        debug_assert!(prim_count > 0 && prim_count < 1 << 30);
        BvhNode { min: bounds.min.into(), offset: first_prim, max: bounds.max.into(), meta: prim_count << 2 }
    }

    pub fn interior(bounds: &Aabb, axis: usize, second_child: u32) -> BvhNode {
        debug_assert!(axis < 3);
        BvhNode { min: bounds.min.into(), offset: second_child, max: bounds.max.into(), meta: axis as u32 }
    }

    pub fn prim_count(&self) -> u32 {
        self.meta >> 2
    }

    pub fn is_leaf(&self) -> bool {
        self.prim_count() > 0
    }

    pub fn axis(&self) -> usize {
        (self.meta & 3) as usize
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.min.into(), self.max.into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use std::mem::{align_of, offset_of, size_of};

    #[test]
    fn layout_matches_std430_glsl_struct() {
        assert_eq!(size_of::<BvhNode>(), 32);
        assert_eq!(align_of::<BvhNode>(), 4);
        assert_eq!(offset_of!(BvhNode, min), 0);
        assert_eq!(offset_of!(BvhNode, offset), 12);
        assert_eq!(offset_of!(BvhNode, max), 16);
        assert_eq!(offset_of!(BvhNode, meta), 28);
    }

    #[test]
    fn meta_packs_count_and_axis() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let leaf = BvhNode::leaf(&b, 7, 5);
        assert_eq!((leaf.is_leaf(), leaf.prim_count(), leaf.offset, leaf.meta), (true, 5, 7, 20));
        let inner = BvhNode::interior(&b, 2, 9);
        assert_eq!((inner.is_leaf(), inner.axis(), inner.offset, inner.meta), (false, 2, 9, 2));
        assert_eq!(inner.bounds(), b);
        let bytes: &[u8] = bytemuck::bytes_of(&leaf);
        assert_eq!(&bytes[12..16], &7u32.to_ne_bytes());
        assert_eq!(&bytes[28..32], &20u32.to_ne_bytes());
    }
}
