//! Binned SAH builder: top-down over boxes and caller indices partitioned in place. Subtrees above
//! `PARALLEL_THRESHOLD` are rayon tasks; smaller ones are built sequentially straight into
//! depth-first node blocks that `flatten` stitches together.

use super::binning::{self, Bins};
use super::box_a::BoxA;
use super::flatten::Subtree;
use super::partition::{self, SetBounds};
use super::{Aabb, BvhNode};

/// Cost of visiting an interior node in units of one primitive intersection (SAH: split =
/// TRAVERSAL_COST * A + A_L * N_L + A_R * N_R, leaf = A * N). The kernel walks the four-wide tree
/// that `wide_nodes` chooses from this one by a cost of its own, so the binary tree only offers
/// the choices: at 1 its leaves are small (~1.9 primitives) and the wide tree can merge them where
/// that pays. 1 with that choice measured 4 % faster on lavapipe than 2 with two binary levels a
/// wide node, and 1 alone (two binary levels a node) 3 % slower (docs/benchmarks/history.md, 2026-12-05, `eef345d`).
const TRAVERSAL_COST: f32 = 1.0;

/// Subtrees larger than this are built as two rayon tasks; smaller ones are cheaper to build inline.
const PARALLEL_THRESHOLD: usize = 8 * 1024;

/// Builds the tree over `prims` and reorders them (with `indices`) into leaf order. No leaf lies
/// deeper than `max_depth` (root = 0), which must be at least ceil(log2(prims.len())), or holds
/// more than `max_leaf_size` primitives (at least 1).
pub(super) fn build_tree(prims: &mut [BoxA], indices: &mut [u32], max_depth: usize, max_leaf_size: usize) -> Subtree {
    debug_assert!(ceil_log2(prims.len()) <= max_depth);
    let set = super::blocks::map_merge(prims, SetBounds::of, SetBounds::merge);
    build_parallel(Range { prims, indices, set, first: 0, levels_left: max_depth, max_leaf_size })
}

/// A range of the primitive arrays being built: `first` is its position in the whole array and
/// `levels_left` how many levels may still hang below its node.
struct Range<'a> {
    prims: &'a mut [BoxA],
    indices: &'a mut [u32],
    set: SetBounds,
    first: usize,
    levels_left: usize,
    max_leaf_size: usize,
}

/// An interior node's split axis and its two children's ranges.
type Children<'a> = (usize, [Range<'a>; 2]);

fn build_parallel(range: Range) -> Subtree {
    if range.prims.len() <= PARALLEL_THRESHOLD {
        let mut nodes = Vec::with_capacity(2 * range.prims.len() - 1);
        build_sequential(range, &mut Bins::new(), &mut nodes);
        return Subtree::Block(nodes);
    }
    let bounds = Aabb::from(&range.set.bounds);
    let (axis, [left, right]) = split(range, &mut Bins::new()).expect("large sets are always split");
    let children = rayon::join(|| build_parallel(left), || build_parallel(right));
    Subtree::split(BvhNode::interior(&bounds, axis, 0), children)
}

/// Appends the subtree depth-first to `nodes`; interior offsets count from the start of `nodes`.
fn build_sequential(range: Range, bins: &mut Bins, nodes: &mut Vec<BvhNode>) {
    let bounds = Aabb::from(&range.set.bounds);
    let (first, count) = (range.first as u32, range.prims.len() as u32);
    let Some((axis, [left, right])) = split(range, bins) else {
        nodes.push(BvhNode::leaf(&bounds, first, count));
        return;
    };
    let at = nodes.len();
    // Placeholder until the second child's index is known.
    nodes.push(BvhNode::EMPTY_ROOT);
    build_sequential(left, bins, nodes);
    let second_child = nodes.len() as u32;
    build_sequential(right, bins, nodes);
    nodes[at] = BvhNode::interior(&bounds, axis, second_child);
}

/// Decides between a leaf (None) and a split, and performs the split.
fn split<'a>(range: Range<'a>, bins: &mut Bins) -> Option<Children<'a>> {
    let Range { prims, indices, set, first, levels_left, max_leaf_size } = range;
    let count = prims.len();
    // A split costs at least TRAVERSAL_COST * A, so it cannot beat a leaf of that many primitives.
    if count <= 1 || (count <= max_leaf_size && count as f32 <= TRAVERSAL_COST) {
        return None;
    }

    // Median splits halve the count, so a subtree of `count` prims needs ceil(log2(count)) more levels.
    // Once the depth budget is down to that, only median splits keep every leaf within it.
    let sah_allowed = ceil_log2(count) < levels_left;
    let best = if sah_allowed { binning::best_split(prims, &set.centroids, bins) } else { None };

    let area = set.bounds.surface_area();
    let (axis, mid, [left_set, right_set]) = match best {
        Some(s) if count > max_leaf_size || TRAVERSAL_COST * area + s.cost < area * count as f32 => {
            let (mid, [left_centroids, right_centroids]) =
                partition::partition(prims, indices, |p| s.binning.bin(p.centroid2(), s.axis) <= s.last_left_bin);
            let sets = [
                SetBounds { bounds: s.bounds[0], centroids: left_centroids },
                SetBounds { bounds: s.bounds[1], centroids: right_centroids },
            ];
            (s.axis, mid, sets)
        }
        _ if count <= max_leaf_size => return None,
        _ => partition::median_split(prims, indices, &set.centroids),
    };

    let (left_prims, right_prims) = prims.split_at_mut(mid);
    let (left_indices, right_indices) = indices.split_at_mut(mid);
    let levels_left = levels_left - 1;
    Some((
        axis,
        [
            Range { prims: left_prims, indices: left_indices, set: left_set, first, levels_left, max_leaf_size },
            Range {
                prims: right_prims,
                indices: right_indices,
                set: right_set,
                first: first + mid,
                levels_left,
                max_leaf_size,
            },
        ],
    ))
}

fn ceil_log2(n: usize) -> usize {
    n.next_power_of_two().trailing_zeros() as usize
}

#[cfg(test)]
mod tests {
    use super::super::test_scenes::{assert_well_formed, Rng};
    use super::super::{build, build_with_depth, Aabb, MAX_DEPTH};
    use glam::Vec3;
    use std::time::Instant;

    fn random_boxes(rng: &mut Rng, count: usize, size: f32) -> Vec<Aabb> {
        (0..count)
            .map(|_| {
                let min = rng.vec3(0.0, 1.0);
                Aabb::new(min, min + rng.vec3(0.0, size))
            })
            .collect()
    }

    #[test]
    fn random_boxes_build_well_formed_trees() {
        let mut rng = Rng::new(1);
        for count in [2, 3, 9, 100, 5000, 20_000] {
            let boxes = random_boxes(&mut rng, count, 0.05);
            let bvh = build(&boxes);
            assert_well_formed(&bvh, &boxes);
            assert!(bvh.stats().leaves > count / 8, "{count} prims in {} leaves", bvh.stats().leaves);
        }
    }

    #[test]
    fn single_primitive_is_one_leaf() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let bvh = build(&[b]);
        assert_eq!(bvh.prim_order, vec![0]);
        assert_eq!(bvh.nodes.len(), 1);
        assert_eq!((bvh.nodes[0].prim_count(), bvh.nodes[0].offset, bvh.nodes[0].bounds()), (1, 0, b));
    }

    #[test]
    fn identical_bounds_terminate_balanced() {
        let boxes = vec![Aabb::new(Vec3::splat(0.25), Vec3::splat(0.75)); 10_000];
        let bvh = build(&boxes);
        assert_well_formed(&bvh, &boxes);
        let stats = bvh.stats();
        // Median splits halve 10000 until a set fits a leaf: 11 levels, 2^11 leaves of 4 or 5.
        assert_eq!((stats.max_depth, stats.leaves, stats.max_leaf_size), (11, 2048, 5));
    }

    #[test]
    fn depth_budget_caps_unbalanced_trees() {
        // Geometrically growing boxes: SAH peels a few primitives off per level, reaching depth 33
        // unconstrained. Smaller budgets must switch to median splits in time.
        let boxes: Vec<Aabb> = (0..200)
            .map(|i| {
                let x = 1.5f32.powi(i);
                Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x * 1.1, 1.0, 1.0))
            })
            .collect();
        let depth_with = |max_depth| {
            let bvh = build_with_depth(&boxes, max_depth);
            assert_well_formed(&bvh, &boxes);
            bvh.stats().max_depth
        };
        assert!(depth_with(MAX_DEPTH) > 20, "input no longer unbalanced");
        for max_depth in [8, 12, 20] {
            let depth = depth_with(max_depth);
            assert!(depth <= max_depth, "depth {depth} over budget {max_depth}");
        }
    }

    #[test]
    fn non_finite_bounds_do_not_break_the_build() {
        let mut rng = Rng::new(5);
        let mut boxes = random_boxes(&mut rng, 10_000, 0.01);
        let weird = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX];
        for i in (0..boxes.len()).step_by(7) {
            boxes[i].min[i % 3] = weird[i % 4];
            boxes[i].max[(i + 1) % 3] = weird[(i / 4) % 4];
        }
        boxes.extend([Aabb::EMPTY; 50]);
        boxes.extend([Aabb::new(Vec3::NAN, Vec3::NAN); 50]);
        let bvh = build(&boxes);
        let mut order = bvh.prim_order.clone();
        order.sort_unstable();
        assert!(order.iter().copied().eq(0..boxes.len() as u32));
        let stats = bvh.stats();
        assert!(stats.max_depth <= MAX_DEPTH && stats.max_leaf_size <= 8, "{stats:?}");
    }

    #[test]
    fn build_is_deterministic_across_thread_counts() {
        let mut rng = Rng::new(9);
        let boxes = random_boxes(&mut rng, 50_000, 0.02);
        let build_on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| build(&boxes))
        };
        let single = build_on(1);
        assert_eq!(single, build_on(4));
        assert_eq!(single, build(&boxes));
    }

    #[test]
    #[ignore = "timing; run with --release -- --ignored --nocapture"]
    fn build_time_one_million_boxes() {
        let mut rng = Rng::new(13);
        let boxes = random_boxes(&mut rng, 1_000_000, 0.01);
        let start = Instant::now();
        let bvh = build(&boxes);
        let elapsed = start.elapsed();
        println!(
            "1M boxes: build {:.1} ms on {} threads, {:?}",
            elapsed.as_secs_f64() * 1e3,
            rayon::current_num_threads(),
            bvh.stats()
        );
        assert_well_formed(&bvh, &boxes);
    }
}
