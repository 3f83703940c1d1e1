//! Binned SAH builder: produces a pointer tree that `flatten` lays out for the GPU.

use glam::Vec3;

use super::{Aabb, MAX_LEAF_SIZE};

/// Most bins per axis. 16 is the usual point where more bins stop paying for the extra sweep.
const BINS: usize = 16;

/// Subtrees larger than this are built as two rayon tasks; smaller ones are cheaper to build inline.
const PARALLEL_THRESHOLD: usize = 4096;

/// A primitive while building: its bounds travel with its caller index so partitions walk memory linearly.
#[derive(Clone, Copy, Debug)]
pub(super) struct BuildPrim {
    pub bounds: Aabb,
    pub index: u32,
}

pub(super) enum BuildNode {
    /// Primitives `first..first + count` of the reordered primitive array.
    Leaf {
        bounds: Aabb,
        first: u32,
        count: u32,
    },
    Interior {
        bounds: Aabb,
        axis: usize,
        children: Box<[BuildNode; 2]>,
    },
}

/// Builds the tree over `prims` and reorders them into leaf order. No leaf lies deeper than
/// `max_depth` (root = 0), which must be at least ceil(log2(prims.len())).
pub(super) fn build_tree(prims: &mut [BuildPrim], max_depth: usize) -> BuildNode {
    debug_assert!(ceil_log2(prims.len()) <= max_depth);
    build_node(prims, SetBounds::of(prims), 0, max_depth)
}

/// Bounds of a primitive set and of its centroids, gathered by the pass that forms the set.
#[derive(Clone, Copy, Debug)]
struct SetBounds {
    bounds: Aabb,
    centroids: Aabb,
}

impl SetBounds {
    const EMPTY: SetBounds = SetBounds {
        bounds: Aabb::EMPTY,
        centroids: Aabb::EMPTY,
    };

    fn of(prims: &[BuildPrim]) -> SetBounds {
        let mut set = SetBounds::EMPTY;
        prims
            .iter()
            .for_each(|p| set.add(&p.bounds, p.bounds.centroid()));
        set
    }

    fn add(&mut self, bounds: &Aabb, centroid: Vec3) {
        self.bounds = self.bounds.union(bounds);
        self.centroids.grow(centroid);
    }
}

/// `set` bounds `prims`, which sit at `first` in the whole array; `levels_left` is how many levels
/// may still hang below this node.
fn build_node(
    prims: &mut [BuildPrim],
    set: SetBounds,
    first: usize,
    levels_left: usize,
) -> BuildNode {
    let SetBounds {
        bounds,
        centroids: centroid_bounds,
    } = set;
    let count = prims.len();
    let leaf = BuildNode::Leaf {
        bounds,
        first: first as u32,
        count: count as u32,
    };
    if count <= 1 {
        return leaf;
    }

    // Median splits halve the count, so a subtree of `count` prims needs ceil(log2(count)) more levels.
    // Once the depth budget is down to that, only median splits keep every leaf within it.
    let sah_allowed = ceil_log2(count) < levels_left;
    let split = if sah_allowed {
        best_split(prims, &centroid_bounds)
    } else {
        None
    };

    let (axis, mid, [left_set, right_set]) = match split {
        // Costs in units of area * prims: split = A + S (traversal 1, intersection 1), leaf = A * count.
        Some(s)
            if count > MAX_LEAF_SIZE
                || bounds.surface_area() + s.cost < bounds.surface_area() * count as f32 =>
        {
            let (mid, sets) = partition(prims, |c| s.binning.bin(c[s.axis]) <= s.last_left_bin);
            (s.axis, mid, sets)
        }
        _ if count <= MAX_LEAF_SIZE => return leaf,
        _ => median_split(prims, &centroid_bounds),
    };

    let (left, right) = prims.split_at_mut(mid);
    let levels_left = levels_left - 1;
    let children = if count > PARALLEL_THRESHOLD {
        rayon::join(
            || build_node(left, left_set, first, levels_left),
            || build_node(right, right_set, first + mid, levels_left),
        )
    } else {
        (
            build_node(left, left_set, first, levels_left),
            build_node(right, right_set, first + mid, levels_left),
        )
    };
    BuildNode::Interior {
        bounds,
        axis,
        children: Box::new([children.0, children.1]),
    }
}

fn ceil_log2(n: usize) -> usize {
    n.next_power_of_two().trailing_zeros() as usize
}

/// Maps centroid coordinates along one axis to bin indices.
#[derive(Clone, Copy, Debug)]
struct Binning {
    min: f32,
    scale: f32,
    bin_count: usize,
}

impl Binning {
    fn new(centroid_bounds: &Aabb, axis: usize, bin_count: usize) -> Binning {
        let extent = centroid_bounds.max[axis] - centroid_bounds.min[axis];
        // A flat or non-finite extent gets scale 0: everything lands in bin 0 and the axis offers no split.
        let scale = if extent > 0.0 && extent.is_finite() {
            bin_count as f32 / extent
        } else {
            0.0
        };
        Binning {
            min: centroid_bounds.min[axis],
            scale,
            bin_count,
        }
    }

    fn bin(&self, c: f32) -> usize {
        // `as` saturates and sends NaN to 0, so even non-finite centroids land in a valid bin.
        (((c - self.min) * self.scale) as usize).min(self.bin_count - 1)
    }
}

#[derive(Clone, Copy, Debug)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

impl Bin {
    const EMPTY: Bin = Bin {
        bounds: Aabb::EMPTY,
        count: 0,
    };

    fn merge(&self, o: &Bin) -> Bin {
        Bin {
            bounds: self.bounds.union(&o.bounds),
            count: self.count + o.count,
        }
    }

    fn cost(&self) -> f32 {
        self.bounds.surface_area() * self.count as f32
    }
}

/// Bins `0..=last_left_bin` of `axis` go left. `cost` = area(L) * |L| + area(R) * |R|.
#[derive(Clone, Copy, Debug)]
struct Split {
    axis: usize,
    binning: Binning,
    last_left_bin: usize,
    cost: f32,
}

/// Cheapest bin boundary over all three axes that leaves both sides non-empty; None when every
/// centroid falls into one bin or every candidate cost is non-finite.
fn best_split(prims: &[BuildPrim], centroid_bounds: &Aabb) -> Option<Split> {
    // Small nodes get one bin per primitive rather than sweeping mostly empty bins.
    let bin_count = prims.len().min(BINS);
    let binnings: [Binning; 3] =
        std::array::from_fn(|axis| Binning::new(centroid_bounds, axis, bin_count));
    let mut bins = [[Bin::EMPTY; BINS]; 3];
    for p in prims {
        let c = p.bounds.centroid();
        for axis in 0..3 {
            let bin = &mut bins[axis][binnings[axis].bin(c[axis])];
            bin.bounds = bin.bounds.union(&p.bounds);
            bin.count += 1;
        }
    }

    let mut best: Option<Split> = None;
    for (axis, bins) in bins.iter().enumerate() {
        // right_cost[i]: cost of bins i+1.. (the right side of a split after bin i).
        let mut right_cost = [0.0; BINS - 1];
        let mut right = Bin::EMPTY;
        for i in (1..bin_count).rev() {
            right = right.merge(&bins[i]);
            right_cost[i - 1] = right.cost();
        }
        let mut left = Bin::EMPTY;
        for i in 0..bin_count - 1 {
            left = left.merge(&bins[i]);
            if left.count == 0 || left.count as usize == prims.len() {
                continue;
            }
            let cost = left.cost() + right_cost[i];
            if cost < best.map_or(f32::INFINITY, |b| b.cost) {
                best = Some(Split {
                    axis,
                    binning: binnings[axis],
                    last_left_bin: i,
                    cost,
                });
            }
        }
    }
    best
}

/// Moves the primitives whose centroid satisfies `goes_left` to the front; returns how many there
/// are and the bounds of both sides, gathered on the way so the children need no pass of their own.
fn partition(prims: &mut [BuildPrim], goes_left: impl Fn(Vec3) -> bool) -> (usize, [SetBounds; 2]) {
    let mut sets = [SetBounds::EMPTY; 2];
    let mut mid = 0;
    for i in 0..prims.len() {
        let (bounds, centroid) = (prims[i].bounds, prims[i].bounds.centroid());
        if goes_left(centroid) {
            prims.swap(i, mid);
            mid += 1;
            sets[0].add(&bounds, centroid);
        } else {
            sets[1].add(&bounds, centroid);
        }
    }
    (mid, sets)
}

/// Halves the primitives by centroid along the largest centroid axis. Ties are broken by caller index
/// so the result does not depend on the selection algorithm's handling of equal keys.
fn median_split(prims: &mut [BuildPrim], centroid_bounds: &Aabb) -> (usize, usize, [SetBounds; 2]) {
    let axis = centroid_bounds.largest_axis();
    let mid = prims.len() / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        let (ca, cb) = (a.bounds.centroid()[axis], b.bounds.centroid()[axis]);
        ca.total_cmp(&cb).then(a.index.cmp(&b.index))
    });
    let (left, right) = prims.split_at(mid);
    (axis, mid, [SetBounds::of(left), SetBounds::of(right)])
}

#[cfg(test)]
mod tests {
    use super::super::flatten::flatten;
    use super::super::test_scenes::{assert_well_formed, Rng};
    use super::super::{build, Aabb, Bvh, MAX_DEPTH};
    use super::*;
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
            assert!(
                bvh.stats().leaves > count / 8,
                "{count} prims in {} leaves",
                bvh.stats().leaves
            );
        }
    }

    #[test]
    fn single_primitive_is_one_leaf() {
        let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let bvh = build(&[b]);
        assert_eq!(bvh.prim_order, vec![0]);
        assert_eq!(bvh.nodes.len(), 1);
        assert_eq!(
            (
                bvh.nodes[0].prim_count(),
                bvh.nodes[0].offset,
                bvh.nodes[0].bounds()
            ),
            (1, 0, b)
        );
    }

    #[test]
    fn identical_bounds_terminate_balanced() {
        let boxes = vec![Aabb::new(Vec3::splat(0.25), Vec3::splat(0.75)); 10_000];
        let bvh = build(&boxes);
        assert_well_formed(&bvh, &boxes);
        let stats = bvh.stats();
        // Median splits halve 10000 until a set fits a leaf: 11 levels, 2^11 leaves of 4 or 5.
        assert_eq!(
            (stats.max_depth, stats.leaves, stats.max_leaf_size),
            (11, 2048, 5)
        );
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
            let mut prims: Vec<BuildPrim> = boxes
                .iter()
                .enumerate()
                .map(|(i, &bounds)| BuildPrim {
                    bounds,
                    index: i as u32,
                })
                .collect();
            let tree = build_tree(&mut prims, max_depth);
            let bvh = Bvh {
                nodes: flatten(&tree, prims.len()),
                prim_order: prims.iter().map(|p| p.index).collect(),
            };
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
        assert!(
            stats.max_depth <= MAX_DEPTH && stats.max_leaf_size <= 8,
            "{stats:?}"
        );
    }

    #[test]
    fn build_is_deterministic_across_thread_counts() {
        let mut rng = Rng::new(9);
        let boxes = random_boxes(&mut rng, 50_000, 0.02);
        let build_on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
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
