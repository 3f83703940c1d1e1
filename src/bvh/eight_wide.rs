//! The eight-wide compressed node format (`bvh-width=8`, src/render/bvh_width.rs): up to eight
//! children a node, their boxes quantized to 8 bits against the node's own as in the four-wide
//! [`WideNode`] (wide_node.rs), and the children placed in slots by the direction they lie in
//! from the node's centre, so that a ray visits them near to far without sorting: the compressed
//! wide BVH of Ylitie, Karras and Laine 2017 ("Efficient incoherent ray traversal on GPUs through
//! compressed wide BVHs", sections 3.1-3.2 and 4), 80 bytes a node.
//!
//! Eighty bytes hold eight children because the links are not stored a child: a node's interior
//! children are consecutive nodes from `child_base`, and its leaf children's primitives are
//! consecutive from `prim_base`, in slot order. So the build lays the primitives out anew
//! ([`EightWideTree::prim_order`]); the scene's triangles are stored in that order.
//!
//! The nodes live in the node array the four-wide top level shares (src/render/acceleration.rs),
//! whose records are 64 bytes: an eight-wide node takes two records, of which the kernel fetches
//! the five 16-byte texels the node has (shaders/bvh_eight_wide.glsl), not the three of padding.

use super::wide_node::{byte, quantize, quantum, quantum_exponent, wide_tree, WideChild};
use super::{Aabb, Bvh, WideNode};

/// Children a node holds.
pub const EIGHT_WIDTH: usize = 8;

/// Node records (64 bytes each, [`WideNode`]) an eight-wide node takes in the node array.
pub const RECORDS_PER_EIGHT_WIDE_NODE: u32 = 2;

/// GPU node, 80 bytes, five 16-byte texels (shaders/bvh_eight_wide.glsl, `EightWideNode`):
/// texel 0 `origin` and `exponents`, texel 1 `child_base`, `prim_base`, `leaf_counts` and
/// `masks`, texels 2 to 4 the quantized boxes along x, y and z. Byte (or nibble, or bit) k of a
/// packed word belongs to slot k, and the slots 4 to 7 to the second word of a pair.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct EightWideNode {
    /// The node's box's min corner, where the children's quantized bounds start.
    pub origin: [f32; 3],
    /// Per axis (bytes 0, 1, 2) the exponent of the quantum, biased as an f32's exponent field.
    pub exponents: u32,
    /// The node record of the first interior child; the others follow in slot order,
    /// [`RECORDS_PER_EIGHT_WIDE_NODE`] records apart.
    pub child_base: u32,
    /// The first primitive of the first leaf child (in `EightWideTree::prim_order` order); the
    /// other leaves' follow in slot order.
    pub prim_base: u32,
    /// Per slot (nibble k), a leaf child's primitive count (1 to 8); 0 for any other slot.
    pub leaf_counts: u32,
    /// Bits 0-7: the slots holding an interior child; bits 8-15: the slots holding any child.
    pub masks: u32,
    /// Per axis a, words 4a to 4a + 3: the min bounds of slots 0-3 and of slots 4-7, then the max
    /// bounds of slots 0-3 and of 4-7, in quanta from `origin` (mins rounded down, maxes up).
    pub quantized: [u32; 12],
}

/// An [`EightWideNode`] as it lies in the node array: the node and the rest of its second record.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct EightWideRecords {
    node: EightWideNode,
    unused: [u32; 12],
}

impl EightWideNode {
    /// A node of no children: the root of an empty BVH, which no ray enters.
    pub const EMPTY: EightWideNode = EightWideNode {
        origin: [0.0; 3],
        exponents: 0,
        child_base: 0,
        prim_base: 0,
        leaf_counts: 0,
        masks: 0,
        quantized: [0; 12],
    };

    /// Whether slot `k` holds a child.
    pub fn present(&self, k: usize) -> bool {
        self.masks >> (8 + k) & 1 == 1
    }

    /// Whether slot `k` holds an interior child.
    pub fn interior(&self, k: usize) -> bool {
        self.masks >> k & 1 == 1
    }

    /// Slot `k`'s primitive count where it is a leaf.
    pub fn leaf_count(&self, k: usize) -> u32 {
        self.leaf_counts >> (4 * k) & 0xf
    }

    /// The record of slot `k`'s node, where it is an interior child: `child_base` plus its rank
    /// among the interior slots (as the kernel's bitCount).
    pub fn child_node(&self, k: usize) -> u32 {
        let rank = (self.masks & 0xff & ((1 << k) - 1)).count_ones();
        self.child_base + RECORDS_PER_EIGHT_WIDE_NODE * rank
    }

    /// Slot `k`'s first primitive, where it is a leaf: `prim_base` plus the counts of the slots
    /// before it.
    pub fn leaf_first(&self, k: usize) -> u32 {
        self.prim_base + (0..k).map(|j| self.leaf_count(j)).sum::<u32>()
    }

    /// The word of slot `k`'s quantized `bound` (0: min, 1: max) along `axis`, and its byte in it.
    fn quantized_at(axis: usize, bound: usize, k: usize) -> (usize, usize) {
        (4 * axis + 2 * bound + k / 4, k % 4)
    }

    /// Slot `k`'s box as stored (the kernel tests these planes).
    pub fn child_bounds(&self, k: usize) -> Aabb {
        let decode = |axis: usize, bound: usize| {
            let (word, b) = Self::quantized_at(axis, bound, k);
            let step = quantum(byte(self.exponents, axis)) as f32;
            self.origin[axis] + byte(self.quantized[word], b) as f32 * step
        };
        Aabb::new(
            glam::Vec3::new(decode(0, 0), decode(1, 0), decode(2, 0)),
            glam::Vec3::new(decode(0, 1), decode(1, 1), decode(2, 1)),
        )
    }

    /// The node's two records of the node array.
    pub fn records(&self) -> [WideNode; 2] {
        bytemuck::cast(EightWideRecords { node: *self, unused: [0; 12] })
    }
}

/// Which slot each child takes: the slot whose side (bit a set: the positive side along axis a)
/// best matches where the child lies from the node's centre, chosen greedily by the smallest
/// cost (Ylitie et al. 2017, section 3.2). A ray whose direction's signs are the bits of `octant`
/// (bit a set: negative along a) then meets the children near to far, roughly, in the slots
/// `k ^ octant` for k = 0 to 7: slot 0 holds the child farthest along -x-y-z, met first by a ray
/// going +x+y+z.
fn octant_slots(children: &[WideChild]) -> [Option<usize>; EIGHT_WIDTH] {
    let node = children.iter().fold(Aabb::EMPTY, |b, c| b.union(&c.bounds()));
    let centre = (node.min + node.max) * 0.5;
    let mut costs = Vec::with_capacity(children.len() * EIGHT_WIDTH);
    for (c, child) in children.iter().enumerate() {
        let b = child.bounds();
        let offset = (b.min + b.max) * 0.5 - centre;
        for slot in 0..EIGHT_WIDTH {
            // Smallest where the child lies farthest toward the slot's side: the negative side
            // along the axes of its clear bits, the positive along those of its set bits.
            let toward = glam::Vec3::from_array(std::array::from_fn(|a| if slot >> a & 1 == 1 { -1.0 } else { 1.0 }));
            costs.push((offset.dot(toward), c, slot));
        }
    }
    // Ties (and NaN, which sorts last) broken by child and slot: the same tree for the same input.
    costs.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
    let mut slots = [None; EIGHT_WIDTH];
    let mut placed = vec![false; children.len()];
    for (_, c, slot) in costs {
        if !placed[c] && slots[slot].is_none() {
            slots[slot] = Some(c);
            placed[c] = true;
        }
    }
    slots
}

/// An eight-wide BVH: its nodes, root first, and the primitives in the order its leaves name them.
#[derive(Clone, Debug, PartialEq)]
pub struct EightWideTree {
    pub nodes: Vec<EightWideNode>,
    /// `prim_order[i]`: the input index of the i-th primitive in leaf order, as `Bvh::prim_order`.
    pub prim_order: Vec<u32>,
}

impl EightWideTree {
    /// The eight-wide tree of `bvh`, its children chosen as the four-wide tree's are (`wide_tree`,
    /// with the four-wide tree's node cost, measured on lavapipe for four-wide nodes and not
    /// tuned for eight) with leaves of at most `max_leaf_size` primitives, its nodes to lie in the node array from
    /// record `record_base` on and its primitives from `prim_base` on.
    pub fn new(bvh: &Bvh, max_leaf_size: usize, record_base: u32, prim_base: u32) -> EightWideTree {
        let wide = wide_tree(&bvh.nodes, max_leaf_size, EIGHT_WIDTH);
        let mut tree =
            EightWideTree { nodes: vec![EightWideNode::EMPTY], prim_order: Vec::with_capacity(bvh.prim_order.len()) };
        tree.emit(&wide, 0, 0, bvh, record_base, prim_base);
        tree
    }

    /// Writes wide node `index` at `at`: its interior children's nodes reserved next to each
    /// other at the end, its leaves' primitives appended, then the children's own nodes.
    fn emit(&mut self, wide: &[Vec<WideChild>], index: usize, at: usize, bvh: &Bvh, record_base: u32, prim_base: u32) {
        let children = &wide[index];
        if children.is_empty() {
            return;
        }
        let slots = octant_slots(children);
        let bounds = children.iter().fold(Aabb::EMPTY, |b, c| b.union(&c.bounds()));
        let mut node = EightWideNode::EMPTY;
        node.origin = bounds.min.into();
        let exponents: [u32; 3] = std::array::from_fn(|axis| quantum_exponent(bounds.min[axis], bounds.max[axis]));
        node.exponents = exponents[0] | exponents[1] << 8 | exponents[2] << 16;
        let first_child = self.nodes.len();
        node.child_base = record_base + RECORDS_PER_EIGHT_WIDE_NODE * first_child as u32;
        node.prim_base = prim_base + self.prim_order.len() as u32;
        let mut below = Vec::new();
        for (k, child) in slots.iter().enumerate() {
            let Some(c) = *child else { continue };
            node.masks |= 1 << (8 + k);
            match children[c] {
                WideChild::Interior { node: n, .. } => {
                    node.masks |= 1 << k;
                    below.push((n as usize, self.nodes.len()));
                    self.nodes.push(EightWideNode::EMPTY);
                }
                WideChild::Leaf { first, count, .. } => {
                    assert!((1..16).contains(&count), "a leaf of {count} primitives");
                    node.leaf_counts |= count << (4 * k);
                    self.prim_order.extend_from_slice(&bvh.prim_order[first as usize..(first + count) as usize]);
                }
            }
            let b = children[c].bounds();
            for (axis, &exponent) in exponents.iter().enumerate() {
                let (low, high) = quantize(b.min[axis], b.max[axis], node.origin[axis], exponent);
                let (min_word, shift) = EightWideNode::quantized_at(axis, 0, k);
                let (max_word, _) = EightWideNode::quantized_at(axis, 1, k);
                node.quantized[min_word] |= low << (8 * shift);
                node.quantized[max_word] |= high << (8 * shift);
            }
        }
        debug_assert_eq!(below.first().map_or(first_child, |b| b.1), first_child);
        self.nodes[at] = node;
        for (n, child_at) in below {
            self.emit(wide, n, child_at, bvh, record_base, prim_base);
        }
    }

    /// The nodes as records of the node array, two a node.
    pub fn records(&self) -> Vec<WideNode> {
        self.nodes.iter().flat_map(|n| n.records()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{build, MAX_LEAF_SIZE};
    use glam::Vec3;
    use std::mem::{offset_of, size_of};

    #[test]
    fn layout_is_five_texels_in_two_records() {
        assert_eq!(offset_of!(EightWideNode, exponents), 12);
        assert_eq!(offset_of!(EightWideNode, child_base), 16);
        assert_eq!(offset_of!(EightWideNode, masks), 28);
        assert_eq!(offset_of!(EightWideNode, quantized), 32);
        assert_eq!(size_of::<EightWideNode>(), 80);
        assert_eq!(size_of::<WideNode>() * RECORDS_PER_EIGHT_WIDE_NODE as usize, size_of::<EightWideRecords>());
        // The kernel reads texel 4 (the z bounds) as the second record's first texel.
        let mut node = EightWideNode::EMPTY;
        node.quantized[8..12].copy_from_slice(&[1, 2, 3, 4]);
        let [_, second] = node.records();
        assert_eq!(second.origin.map(f32::to_bits), [1, 2, 3]);
        assert_eq!(second.exponents, 4);
    }

    fn scattered_boxes(count: usize, scale: f32, offset: Vec3) -> Vec<Aabb> {
        (0..count)
            .map(|i| {
                let c = Vec3::new((i * 37 % 101) as f32, (i * 53 % 97) as f32, (i * 11 % 7) as f32) * scale + offset;
                Aabb::new(c, c + 0.5 * scale)
            })
            .collect()
    }

    /// Walks the tree below the node at `record`: counts each primitive reached, checks that each
    /// decoded box holds what lies below it, and returns those exact bounds and the depth.
    fn check(tree: &EightWideTree, record: u32, bounds: &[Aabb], seen: &mut [u32]) -> (Aabb, usize) {
        let node = &tree.nodes[(record / RECORDS_PER_EIGHT_WIDE_NODE) as usize];
        let (mut below, mut depth) = (Aabb::EMPTY, 1);
        for k in 0..EIGHT_WIDTH {
            if !node.present(k) {
                assert_eq!(node.leaf_count(k), 0);
                continue;
            }
            let exact = if node.interior(k) {
                let (exact, d) = check(tree, node.child_node(k), bounds, seen);
                depth = depth.max(d + 1);
                exact
            } else {
                let first = node.leaf_first(k);
                (first..first + node.leaf_count(k)).fold(Aabb::EMPTY, |b, i| {
                    let prim = tree.prim_order[i as usize] as usize;
                    seen[prim] += 1;
                    b.union(&bounds[prim])
                })
            };
            let decoded = node.child_bounds(k);
            assert!(decoded.contains(&exact), "slot {k}: {decoded:?} does not hold {exact:?}");
            let quanta = Vec3::from_array(std::array::from_fn(|a| quantum(byte(node.exponents, a)) as f32));
            let slack = (exact.min - decoded.min).max(decoded.max - exact.max);
            assert!(slack.cmple(quanta * 1.02 + exact.max.abs().max(exact.min.abs()) * 1e-6).all(), "{slack:?}");
            below = below.union(&exact);
        }
        (below, depth)
    }

    /// Every primitive is reached exactly once through conservative, tight boxes; the tree is no
    /// deeper than the binary one (the kernel's stack bound) and fills more than five of its
    /// eight slots a node.
    #[test]
    fn eight_wide_nodes_cover_the_binary_tree_with_conservative_boxes() {
        for (scale, offset) in [(1.0, Vec3::ZERO), (1e-3, Vec3::new(1e4, -3e3, 7.0)), (37.0, Vec3::splat(-1e5))] {
            let bounds = scattered_boxes(3000, scale, offset);
            let bvh = build(&bounds);
            let tree = EightWideTree::new(&bvh, MAX_LEAF_SIZE, 0, 0);
            let mut seen = vec![0u32; bounds.len()];
            let (_, depth) = check(&tree, 0, &bounds, &mut seen);
            assert!(seen.iter().all(|&s| s == 1), "every primitive once");
            assert!(depth <= bvh.stats().max_depth + 1);
            let slots: usize = tree.nodes.iter().map(|n| (0..EIGHT_WIDTH).filter(|&k| n.present(k)).count()).sum();
            assert!(slots as f64 >= 5.0 * tree.nodes.len() as f64, "{slots} children in {} nodes", tree.nodes.len());
            let mut order = tree.prim_order.clone();
            order.sort_unstable();
            assert_eq!(order, (0..bounds.len() as u32).collect::<Vec<_>>());
        }
    }

    /// Links are rebased: a tree placed at record 10 and primitive 100 names its children there.
    #[test]
    fn links_count_from_the_tree_s_place_in_the_shared_arrays() {
        let bounds = scattered_boxes(500, 1.0, Vec3::ZERO);
        let bvh = build(&bounds);
        let (at_zero, placed) =
            (EightWideTree::new(&bvh, MAX_LEAF_SIZE, 0, 0), EightWideTree::new(&bvh, MAX_LEAF_SIZE, 10, 100));
        assert_eq!(at_zero.prim_order, placed.prim_order);
        for (a, b) in at_zero.nodes.iter().zip(&placed.nodes) {
            assert_eq!((a.child_base + 10, a.prim_base + 100), (b.child_base, b.prim_base));
        }
    }

    /// A ray going +x+y+z meets slot 0 first: the child farthest along -x-y-z; a ray going -x
    /// meets slot 1 first, and so on (`k ^ octant`). Fails a slot order whose direction is flipped.
    #[test]
    fn slots_follow_the_directions_of_the_octants() {
        let child = |c: Vec3| WideChild::Leaf { bounds: Aabb::new(c - 0.1, c + 0.1), first: 0, count: 1 };
        let corners: Vec<Vec3> = (0..8)
            .map(|s| Vec3::from_array(std::array::from_fn(|a| if s >> a & 1 == 1 { 1.0 } else { -1.0 })))
            .collect();
        // Given in an order unrelated to their slots.
        let children: Vec<WideChild> = [5, 2, 7, 0, 3, 6, 1, 4].iter().map(|&s| child(corners[s])).collect();
        let slots = octant_slots(&children);
        for (slot, c) in slots.iter().enumerate() {
            assert_eq!(corners[slot], (children[c.unwrap()].bounds().min + 0.1), "slot {slot}");
        }
        // Slot 0 (all bits clear) lies toward -x-y-z.
        assert_eq!(corners[0], Vec3::splat(-1.0));
        // Three children: each takes the slot of its own direction.
        let three = [child(Vec3::new(1.0, -1.0, -1.0)), child(Vec3::new(-1.0, 1.0, 1.0)), child(Vec3::ZERO)];
        let slots = octant_slots(&three);
        assert_eq!((slots[1], slots[6]), (Some(0), Some(1)));
        assert_eq!(slots.iter().flatten().count(), 3);
    }

    #[test]
    fn a_leaf_root_is_one_child_and_an_empty_tree_has_none() {
        let one = build(&[Aabb::new(Vec3::ZERO, Vec3::ONE)]);
        let tree = EightWideTree::new(&one, MAX_LEAF_SIZE, 0, 0);
        assert_eq!(tree.nodes.len(), 1);
        let present: Vec<usize> = (0..EIGHT_WIDTH).filter(|&k| tree.nodes[0].present(k)).collect();
        assert_eq!(present.len(), 1);
        assert_eq!((tree.nodes[0].leaf_first(present[0]), tree.nodes[0].leaf_count(present[0])), (0, 1));
        let empty = EightWideTree::new(&build(&[]), MAX_LEAF_SIZE, 0, 0);
        assert_eq!(empty.nodes, vec![EightWideNode::EMPTY]);
        assert!(empty.prim_order.is_empty());
    }
}
