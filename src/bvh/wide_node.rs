//! The node format the kernel walks: a four-wide BVH with quantized child boxes, 64 bytes a node.
//!
//! Each node holds up to four children taken from the binary levels below it, chosen by a
//! surface-area cost (`wide_nodes`), so a ray tests four boxes per node fetched. The children's
//! boxes are stored as 8-bit offsets from the node's own min corner in steps of a power of two per
//! axis (Ylitie, Karras and Laine 2017, "Efficient incoherent ray traversal on GPUs through
//! compressed wide BVHs", section 3), rounded outwards, so the four boxes cost 24 bytes where full
//! floats cost 96: one node is four 16-byte loads, where the pair nodes it replaced needed eight
//! loads for four boxes. Loads are what traversal pays for, on lavapipe most of all
//! (docs/benchmarks/history.md). Leaves get no node of their own: a leaf child names its primitives
//! directly.

use super::{Aabb, BvhNode};

/// Children a node holds.
pub const WIDTH: usize = 4;

/// A child's kind byte: an interior child (its link is a node)...
pub const CHILD_INTERIOR: u32 = 0;
/// ...or an empty slot; the kinds between are leaves, the byte their primitive count.
pub const CHILD_NONE: u32 = 0xff;

/// Steps of the 8-bit grid a child's box is snapped to.
const QUANTA: f64 = 255.0;

/// How far, in quanta, a stored bound lies at least outside the exact one (unless it is the
/// node's own min, stored as step 0). The kernel computes a child's planes as
/// from + steps * per_step (shaders/bvh.glsl), which can be off by a few ulps of the node's size
/// where the ray starts inside the node; 1/64 of a quantum (the node's size / 16,320) is a
/// thousand times that, so rounding never moves a plane inside the child's box.
const MARGIN: f64 = 1.0 / 64.0;

/// GPU node, std430-compatible: 64 bytes, mirrors GLSL `struct WideNode` (shaders/layout.glsl).
/// Byte k of each packed word belongs to child k.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
pub struct WideNode {
    /// The node's box's min corner, where the children's quantized bounds start.
    pub origin: [f32; 3],
    /// Per axis (bytes 0, 1, 2) the exponent of the quantum, biased as an f32's exponent field:
    /// the quantum along that axis is 2^(byte - 127), so the GPU gets it by one shift.
    pub exponents: u32,
    /// The children's boxes in quanta from `origin`: min x, max x, min y, max y, min z, max z.
    /// Mins are rounded down and maxes up, so a decoded box holds the exact one.
    pub quantized: [u32; 6],
    /// Each child's kind: [`CHILD_INTERIOR`], a leaf's primitive count (1 to `MAX_LEAF_SIZE`), or
    /// [`CHILD_NONE`].
    pub kinds: u32,
    /// Zero; pads the node to four 16-byte loads.
    pub unused: u32,
    /// Per child: an interior child's node, or a leaf's first primitive (in `Bvh::prim_order`
    /// order); zero for an empty slot.
    pub links: [u32; WIDTH],
}

/// One child of a wide node before quantization: an interior child names its node by its index
/// in the list [`wide_tree`] returns.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum WideChild {
    Interior { bounds: Aabb, node: u32 },
    Leaf { bounds: Aabb, first: u32, count: u32 },
}

impl WideChild {
    pub(super) fn bounds(&self) -> Aabb {
        match *self {
            WideChild::Interior { bounds, .. } | WideChild::Leaf { bounds, .. } => bounds,
        }
    }
}

impl WideNode {
    /// A node of no children: the root of an empty BVH, which no ray enters.
    pub const EMPTY: WideNode =
        WideNode { origin: [0.0; 3], exponents: 0, quantized: [0; 6], kinds: u32::MAX, unused: 0, links: [0; WIDTH] };

    /// Packs up to [`WIDTH`] children, quantizing their boxes against their union; the slots
    /// after them stay empty.
    fn new(children: &[WideChild]) -> WideNode {
        assert!(children.len() <= WIDTH, "{} children in a {WIDTH}-wide node", children.len());
        let bounds = children.iter().fold(Aabb::EMPTY, |b, c| b.union(&c.bounds()));
        let mut node = WideNode::EMPTY;
        if children.is_empty() {
            return node;
        }
        node.origin = bounds.min.into();
        let exponents: [u32; 3] = std::array::from_fn(|axis| quantum_exponent(bounds.min[axis], bounds.max[axis]));
        node.exponents = exponents[0] | exponents[1] << 8 | exponents[2] << 16;
        for (k, child) in children.iter().enumerate() {
            let shift = 8 * k as u32;
            let (kind, link) = match *child {
                WideChild::Interior { node, .. } => (CHILD_INTERIOR, node),
                WideChild::Leaf { first, count, .. } => {
                    assert!((1..CHILD_NONE).contains(&count), "a leaf of {count} primitives");
                    (count, first)
                }
            };
            node.kinds = node.kinds & !(0xff << shift) | kind << shift;
            node.links[k] = link;
            let b = child.bounds();
            for (axis, &exponent) in exponents.iter().enumerate() {
                let (low, high) = quantize(b.min[axis], b.max[axis], node.origin[axis], exponent);
                node.quantized[2 * axis] |= low << shift;
                node.quantized[2 * axis + 1] |= high << shift;
            }
        }
        node
    }

    /// Child `k`'s kind byte.
    pub fn kind(&self, k: usize) -> u32 {
        byte(self.kinds, k)
    }

    /// The quantum along `axis`.
    fn quantum_along(&self, axis: usize) -> f64 {
        quantum(byte(self.exponents, axis))
    }

    /// Child `k`'s box as stored: the origin plus a whole number of quanta per bound, rounded once
    /// to f32 (the kernel tests these planes, `wide_child_entries` in shaders/bvh.glsl).
    pub fn child_bounds(&self, k: usize) -> Aabb {
        let decode =
            |word: u32, axis: usize| self.origin[axis] + byte(word, k) as f32 * self.quantum_along(axis) as f32;
        let q = &self.quantized;
        Aabb::new(
            glam::Vec3::new(decode(q[0], 0), decode(q[2], 1), decode(q[4], 2)),
            glam::Vec3::new(decode(q[1], 0), decode(q[3], 1), decode(q[5], 2)),
        )
    }
}

/// A child's bounds `min..max` along one axis in steps of 2^(`exponent` - 127) from `origin`: the
/// min rounded down and the max up, each at least [`MARGIN`] of a step outside the exact bound.
pub(super) fn quantize(min: f32, max: f32, origin: f32, exponent: u32) -> (u32, u32) {
    let quantum = quantum(exponent);
    let from_origin = |v: f32| (v as f64 - origin as f64) / quantum;
    let low = (from_origin(min) - MARGIN).floor().clamp(0.0, QUANTA) as u32;
    let high = (from_origin(max) + MARGIN).ceil().clamp(0.0, QUANTA) as u32;
    (low, high)
}

/// Byte `k` of a packed word (`child_bytes` in shaders/bvh.glsl).
pub(super) fn byte(word: u32, k: usize) -> u32 {
    word >> (8 * k) & 0xff
}

/// 2^(biased - 127), as an f32 exponent field of `biased` means (biased 1 to 254).
pub(super) fn quantum(biased: u32) -> f64 {
    2f64.powi(biased as i32 - 127)
}

/// The smallest exponent (biased as an f32's) whose quantum spans [min, max] in [`QUANTA`] steps
/// with [`MARGIN`] to spare, so that a max bound plus the margin still fits in 255 steps. A flat
/// axis gets the smallest normal quantum.
pub(super) fn quantum_exponent(min: f32, max: f32) -> u32 {
    let extent = max as f64 - min as f64;
    let spans = |biased: u32| (QUANTA - MARGIN) * quantum(biased) >= extent;
    let mut biased = if extent > 0.0 { ((extent / QUANTA).log2().ceil() as i32 + 127).clamp(1, 254) as u32 } else { 1 };
    // log2 rounds: step down while a finer quantum still spans the box, up while this one does not.
    while biased > 1 && spans(biased - 1) {
        biased -= 1;
    }
    while biased < 254 && !spans(biased) {
        biased += 1;
    }
    biased
}

/// What a wide node's visit costs against one primitive test, in the surface-area cost that
/// chooses the wide tree's shape (`plan_subtree`): a visit decodes and tests four boxes and sorts
/// them. Measured on lavapipe (docs/benchmarks/history.md, 2026-12-05, `eef345d`): 2 gains; 4 merges more leaves and
/// is level, 8 merges more still and loses 3 % on the mesh box.
const NODE_COST: f32 = 2.0;

/// The binary BVH `nodes` (depth-first, root at 0, layout contract on [`BvhNode`]) as wide nodes,
/// root at 0, each node's children chosen from the binary levels below it by a surface-area cost
/// (Ylitie, Karras and Laine 2017, section 3.1): a binary subtree becomes an interior child, a leaf
/// child of at most `max_leaf_size` primitives (its primitives are contiguous, the binary tree being
/// depth-first), or is opened into more of the node's four slots, whichever costs least. Taking
/// two binary levels a node instead left a quarter of the slots empty. Each wide level takes at
/// least one binary level, so the wide tree is no deeper than the binary one, the bound the
/// kernel's stack is sized by (`STACK_SIZE` in bvh.glsl). A root that is a leaf becomes a node of
/// that one leaf; an empty BVH the node of no children.
pub fn wide_nodes(nodes: &[BvhNode], max_leaf_size: usize) -> Vec<WideNode> {
    wide_tree(nodes, max_leaf_size, WIDTH).iter().map(|children| WideNode::new(children)).collect()
}

/// Most children a node of [`wide_tree`] may take (the eight-wide nodes' width, eight_wide.rs).
pub(super) const MAX_WIDTH: usize = 8;

/// The wide tree of [`wide_nodes`] with up to `width` children a node (2 to [`MAX_WIDTH`]), before
/// quantization: each node's children, root first, a node before the nodes below it (depth-first),
/// an interior child naming its node by its index in the list.
pub(super) fn wide_tree(nodes: &[BvhNode], max_leaf_size: usize, width: usize) -> Vec<Vec<WideChild>> {
    assert!((2..=MAX_WIDTH).contains(&width), "width {width}");
    let root = &nodes[0];
    if root.is_leaf() {
        return vec![vec![leaf_child(root)]];
    }
    if nodes.len() == 1 {
        return vec![Vec::new()];
    }
    let mut plans = vec![Plan::UNSET; nodes.len()];
    plan_subtree(nodes, 0, max_leaf_size as u32, width, &mut plans);
    let mut wide = Vec::with_capacity(nodes.len() / (width - 1) + 1);
    emit_node(nodes, &plans, 0, width, &mut wide);
    wide
}

/// How a binary subtree is laid out in at most `slots` of a wide node's children.
#[derive(Clone, Copy, Debug)]
enum Layout {
    /// One leaf child holding all its primitives (slots >= 1).
    Leaf,
    /// One interior child: a wide node of its own (slots >= 1).
    Node,
    /// As in one slot fewer.
    Fewer,
    /// Its binary children opened: the first in k slots, the second in the rest.
    Opened(usize),
}

/// The cheapest layout of a binary subtree in 1 to `width` slots, and the primitives below it.
#[derive(Clone, Copy, Debug)]
struct Plan {
    first: u32,
    count: u32,
    /// cost[i]: the surface-area cost in at most i slots (index 0 unused), areas absolute.
    cost: [f32; MAX_WIDTH + 1],
    layout: [Layout; MAX_WIDTH + 1],
}

impl Plan {
    const UNSET: Plan =
        Plan { first: 0, count: 0, cost: [f32::INFINITY; MAX_WIDTH + 1], layout: [Layout::Fewer; MAX_WIDTH + 1] };
}

/// Fills `plans` for the subtree at binary node `index`, children before parents.
fn plan_subtree(nodes: &[BvhNode], index: usize, max_leaf_size: u32, width: usize, plans: &mut [Plan]) {
    let n = &nodes[index];
    let area = n.bounds().surface_area();
    let mut plan = Plan::UNSET;
    if n.is_leaf() {
        (plan.first, plan.count) = (n.offset, n.prim_count());
        plan.cost = [area * plan.count as f32; MAX_WIDTH + 1];
        plan.layout[1] = Layout::Leaf;
    } else {
        let [a, b] = binary_children(nodes, index);
        plan_subtree(nodes, a, max_leaf_size, width, plans);
        plan_subtree(nodes, b, max_leaf_size, width, plans);
        let (pa, pb) = (plans[a], plans[b]);
        (plan.first, plan.count) = (pa.first, pa.count + pb.count);
        let leaf = if plan.count <= max_leaf_size { area * plan.count as f32 } else { f32::INFINITY };
        let node = area * NODE_COST + opened(&pa, &pb, width).0;
        (plan.cost[1], plan.layout[1]) = if leaf <= node { (leaf, Layout::Leaf) } else { (node, Layout::Node) };
        for slots in 2..=width {
            let (cost, k) = opened(&pa, &pb, slots);
            (plan.cost[slots], plan.layout[slots]) = if plan.cost[slots - 1] <= cost {
                (plan.cost[slots - 1], Layout::Fewer)
            } else {
                (cost, Layout::Opened(k))
            };
        }
    }
    plans[index] = plan;
}

/// The cheapest split of `slots` between two binary children's plans: (cost, the first's slots).
fn opened(a: &Plan, b: &Plan, slots: usize) -> (f32, usize) {
    (1..slots)
        .map(|k| (a.cost[k] + b.cost[slots - k], k))
        .min_by(|x, y| x.0.total_cmp(&y.0))
        .expect("two slots or more")
}

/// The binary nodes that become the children of a subtree laid out in `slots`, in order.
fn slot_roots(nodes: &[BvhNode], plans: &[Plan], index: usize, slots: usize, roots: &mut Vec<usize>) {
    match plans[index].layout[slots] {
        Layout::Fewer => slot_roots(nodes, plans, index, slots - 1, roots),
        Layout::Opened(k) => {
            let [a, b] = binary_children(nodes, index);
            slot_roots(nodes, plans, a, k, roots);
            slot_roots(nodes, plans, b, slots - k, roots);
        }
        Layout::Leaf | Layout::Node => roots.push(index),
    }
}

/// Appends the wide node of binary interior node `index` (its two children opened into the
/// `width` slots) and, depth first, those below it; returns its index in `wide`.
fn emit_node(nodes: &[BvhNode], plans: &[Plan], index: usize, width: usize, wide: &mut Vec<Vec<WideChild>>) -> u32 {
    let at = wide.len();
    wide.push(Vec::new());
    let [a, b] = binary_children(nodes, index);
    let k = opened(&plans[a], &plans[b], width).1;
    let mut roots = Vec::with_capacity(width);
    slot_roots(nodes, plans, a, k, &mut roots);
    slot_roots(nodes, plans, b, width - k, &mut roots);
    let children: Vec<WideChild> = roots
        .into_iter()
        .map(|c| {
            let (plan, bounds) = (&plans[c], nodes[c].bounds());
            match plan.layout[1] {
                Layout::Leaf => WideChild::Leaf { bounds, first: plan.first, count: plan.count },
                _ => WideChild::Interior { bounds, node: emit_node(nodes, plans, c, width, wide) },
            }
        })
        .collect();
    wide[at] = children;
    at as u32
}

/// The surface-area cost [`wide_nodes`] minimizes, of the tree it built: [`NODE_COST`] for each node
/// visit and one for each primitive test, areas relative to the root's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WideCost {
    /// With the children's boxes as stored, quantized outwards: what the kernel's walk pays.
    pub stored: f32,
    /// With the exact boxes of what lies below each child: the same tree with float boxes.
    pub exact: f32,
}

impl WideCost {
    /// The wide tree `wide` of `bvh` (over `prim_bounds`, in input order): its cost both ways, so
    /// that `stored / exact` is what the 8-bit boxes cost in node visits and primitive tests.
    pub fn of(wide: &[WideNode], bvh: &super::Bvh, prim_bounds: &[Aabb]) -> WideCost {
        let mut cost = WideCost { stored: 0.0, exact: 0.0 };
        let root = cost.add_children(wide, 0, bvh, prim_bounds);
        let root_area = root.surface_area();
        if root_area > 0.0 {
            cost.stored = NODE_COST + cost.stored / root_area;
            cost.exact = NODE_COST + cost.exact / root_area;
        }
        cost
    }

    /// Adds node `index`'s children (and everything below them) in absolute areas; returns the
    /// exact bounds of what lies below the node.
    fn add_children(&mut self, wide: &[WideNode], index: u32, bvh: &super::Bvh, prim_bounds: &[Aabb]) -> Aabb {
        let node = &wide[index as usize];
        let mut below = Aabb::EMPTY;
        for k in 0..WIDTH {
            let (exact, visit) = match node.kind(k) {
                CHILD_NONE => continue,
                CHILD_INTERIOR => (self.add_children(wide, node.links[k], bvh, prim_bounds), NODE_COST),
                count => {
                    let prims = node.links[k] as usize..(node.links[k] + count) as usize;
                    let exact =
                        bvh.prim_order[prims].iter().fold(Aabb::EMPTY, |b, &p| b.union(&prim_bounds[p as usize]));
                    (exact, count as f32)
                }
            };
            self.stored += node.child_bounds(k).surface_area() * visit;
            self.exact += exact.surface_area() * visit;
            below = below.union(&exact);
        }
        below
    }
}

fn binary_children(nodes: &[BvhNode], index: usize) -> [usize; 2] {
    [index + 1, nodes[index].offset as usize]
}

fn leaf_child(n: &BvhNode) -> WideChild {
    WideChild::Leaf { bounds: n.bounds(), first: n.offset, count: n.prim_count() }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::build;
    use glam::Vec3;
    use std::mem::{offset_of, size_of};

    #[test]
    fn layout_matches_the_glsl_struct() {
        assert_eq!(offset_of!(WideNode, exponents), 12);
        assert_eq!(offset_of!(WideNode, quantized), 16);
        assert_eq!(offset_of!(WideNode, kinds), 40);
        assert_eq!(offset_of!(WideNode, links), 48);
        assert_eq!(size_of::<WideNode>(), 64);
    }

    fn scattered_boxes(count: usize, scale: f32, offset: Vec3) -> Vec<Aabb> {
        (0..count)
            .map(|i| {
                let c = Vec3::new((i * 37 % 101) as f32, (i * 53 % 97) as f32, (i % 7) as f32) * scale + offset;
                Aabb::new(c, c + 0.5 * scale)
            })
            .collect()
    }

    /// Walks the wide tree below `index`: counts each primitive reached in `seen`, checks that
    /// every decoded child box holds the primitives below it and is at most one quantum (plus
    /// rounding) larger per side, and returns the exact bounds of everything below and the depth.
    fn check_subtree(
        wide: &[WideNode],
        index: u32,
        bvh: &crate::bvh::Bvh,
        bounds: &[Aabb],
        seen: &mut [u32],
    ) -> (Aabb, usize) {
        let node = &wide[index as usize];
        let (mut below, mut depth) = (Aabb::EMPTY, 1);
        for k in 0..WIDTH {
            let kind = node.kind(k);
            if kind == CHILD_NONE {
                continue;
            }
            let exact = if kind == CHILD_INTERIOR {
                let (exact, d) = check_subtree(wide, node.links[k], bvh, bounds, seen);
                depth = depth.max(d + 1);
                exact
            } else {
                let prims = node.links[k]..node.links[k] + kind;
                prims.map(|i| bvh.prim_order[i as usize] as usize).fold(Aabb::EMPTY, |b, prim| {
                    seen[prim] += 1;
                    b.union(&bounds[prim])
                })
            };
            let decoded = node.child_bounds(k);
            assert!(decoded.contains(&exact), "child box {decoded:?} does not hold {exact:?}");
            // The stored bounds (in reals, before the f32 rounding that only moves them outwards)
            // keep the margin the kernel's rounding needs, except a min at the node's own.
            for a in 0..3 {
                let q = node.quantum_along(a);
                let (low, high) = (byte(node.quantized[2 * a], k) as f64, byte(node.quantized[2 * a + 1], k) as f64);
                let origin = node.origin[a] as f64;
                assert!(
                    low == 0.0 || exact.min[a] as f64 - (origin + low * q) >= MARGIN * q,
                    "min {a} within the margin"
                );
                assert!(origin + high * q - exact.max[a] as f64 >= MARGIN * q, "max {a} within the margin");
            }
            let quanta = Vec3::from_array(std::array::from_fn(|a| node.quantum_along(a) as f32));
            let slack = (exact.min - decoded.min).max(decoded.max - exact.max);
            let rounding = exact.max.abs().max(exact.min.abs()) * 1e-6;
            assert!(
                slack.cmple(quanta * (1.0 + MARGIN as f32) + rounding).all(),
                "slack {slack:?} over quanta {quanta:?}"
            );
            below = below.union(&exact);
        }
        (below, depth)
    }

    /// Every primitive is reachable exactly once through conservative, tight boxes, the wide tree is
    /// no deeper than the binary one (the bound the kernel's stack needs) and fills its slots.
    #[test]
    fn wide_nodes_cover_the_binary_tree_with_conservative_boxes() {
        // Far from the origin and tiny, where f32 rounding of origin + steps * quantum matters.
        for (scale, offset) in [(1.0, Vec3::ZERO), (1e-3, Vec3::new(1e4, -3e3, 7.0)), (37.0, Vec3::splat(-1e5))] {
            let bounds = scattered_boxes(3000, scale, offset);
            let bvh = build(&bounds);
            let wide = wide_nodes(&bvh.nodes, crate::bvh::MAX_LEAF_SIZE);
            let mut seen = vec![0u32; bounds.len()];
            let (_, depth) = check_subtree(&wide, 0, &bvh, &bounds, &mut seen);
            assert!(seen.iter().all(|&s| s == 1), "every primitive once");
            let binary_levels = bvh.stats().max_depth + 1;
            assert!(depth <= binary_levels, "wide depth {depth}, binary {binary_levels}");
            let slots: usize = wide.iter().map(|n| (0..WIDTH).filter(|&k| n.kind(k) != CHILD_NONE).count()).sum();
            assert!(slots as f64 >= 3.25 * wide.len() as f64, "{slots} children in {} nodes", wide.len());
            assert!(wide.len() * 2 <= bvh.nodes.len(), "{} wide nodes for {} binary", wide.len(), bvh.nodes.len());
        }
    }

    /// The 8-bit boxes cost a few per cent in the tree's surface-area cost (1.7-1.9 % on the Stanford
    /// scans, docs/benchmarks/history.md, 2026-12-06, `273e196`), never less than nothing. Fails boxes four times as
    /// coarse (6-bit steps: +10 % here), and a cost that ignores the stored boxes.
    #[test]
    fn stored_boxes_cost_a_few_per_cent_over_exact_ones() {
        let bounds = scattered_boxes(3000, 1.0, Vec3::ZERO);
        let bvh = build(&bounds);
        let wide = wide_nodes(&bvh.nodes, crate::bvh::MAX_LEAF_SIZE);
        let cost = WideCost::of(&wide, &bvh, &bounds);
        let overhead = cost.stored / cost.exact;
        assert!(cost.exact > NODE_COST && (1.001..1.04).contains(&overhead), "{cost:?}: overhead {overhead}");
    }

    #[test]
    fn a_leaf_root_is_one_child_and_an_empty_tree_has_none() {
        let one = build(&[Aabb::new(Vec3::ZERO, Vec3::ONE)]);
        let wide = wide_nodes(&one.nodes, crate::bvh::MAX_LEAF_SIZE);
        assert_eq!(wide.len(), 1);
        assert_eq!((wide[0].kind(0), wide[0].links[0]), (1, 0));
        assert!((1..WIDTH).all(|k| wide[0].kind(k) == CHILD_NONE));
        let stored = wide[0].child_bounds(0);
        assert!(
            stored.contains(&Aabb::new(Vec3::ZERO, Vec3::ONE)) && stored.max.cmplt(Vec3::splat(1.01)).all(),
            "{stored:?}"
        );
        assert_eq!(wide_nodes(&build(&[]).nodes, crate::bvh::MAX_LEAF_SIZE), vec![WideNode::EMPTY]);
        assert!((0..WIDTH).all(|k| WideNode::EMPTY.kind(k) == CHILD_NONE));
    }

    #[test]
    fn quantum_spans_the_box_and_no_finer_one_does() {
        for (min, max) in [(0.0f32, 1.0f32), (-3.5, 1e6), (1e4, 1e4 + 1e-3), (2.0, 2.0), (-1e-30, 1e-30)] {
            let e = quantum_exponent(min, max);
            let extent = max as f64 - min as f64;
            assert!((QUANTA - MARGIN) * quantum(e) >= extent, "{min}..{max}: exponent {e} too fine");
            assert!(e == 1 || (QUANTA - MARGIN) * quantum(e - 1) < extent, "{min}..{max}: exponent {e} too coarse");
        }
    }
}
