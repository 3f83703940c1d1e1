//! Shape and quality figures of a built BVH, for logs and regression checks.

use super::Bvh;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BuildStats {
    pub nodes: usize,
    pub leaves: usize,
    /// Level of the deepest leaf, root = 0.
    pub max_depth: usize,
    /// SAH cost with traversal and intersection cost 1, areas relative to the root's
    /// (a root without area, all primitives on a line or point, weighs every node fully).
    pub sah_cost: f32,
    pub max_leaf_size: usize,
}

impl Bvh {
    /// Walks the tree; an empty BVH reports one node, no leaves and zero cost.
    pub fn stats(&self) -> BuildStats {
        let mut stats =
            BuildStats { nodes: self.nodes.len(), leaves: 0, max_depth: 0, sah_cost: 0.0, max_leaf_size: 0 };
        if self.is_empty() {
            return stats;
        }
        let root_area = self.nodes[0].bounds().surface_area();
        let relative_area = |a: f32| if root_area > 0.0 { a / root_area } else { 1.0 };
        let mut pending = vec![(0usize, 0usize)];
        while let Some((index, depth)) = pending.pop() {
            let node = &self.nodes[index];
            let weight = relative_area(node.bounds().surface_area());
            if node.is_leaf() {
                let count = node.prim_count() as usize;
                stats.leaves += 1;
                stats.max_depth = stats.max_depth.max(depth);
                stats.max_leaf_size = stats.max_leaf_size.max(count);
                stats.sah_cost += weight * count as f32;
            } else {
                stats.sah_cost += weight;
                pending.push((index + 1, depth + 1));
                pending.push((node.offset as usize, depth + 1));
            }
        }
        stats
    }
}

#[cfg(test)]
mod tests {
    use super::super::{build, Aabb};
    use glam::Vec3;

    #[test]
    fn distant_boxes_split_into_single_leaves() {
        let unit_box_at = |x: f32| Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0));
        let boxes = [0.0, 100.0, 200.0, 300.0].map(unit_box_at);
        let stats = build(&boxes).stats();
        assert_eq!((stats.nodes, stats.leaves, stats.max_depth, stats.max_leaf_size), (7, 4, 2, 1));
        // root 1 + two interior nodes over a pair, each of area 2 * (101 + 1 + 101) = 406, + four
        // leaves of one unit box (area 6), over the root's area 2 * (301 + 1 + 301) = 1206
        assert!(
            (stats.sah_cost - (1.0 + 2.0 * 406.0 / 1206.0 + 4.0 * 6.0 / 1206.0)).abs() < 1e-5,
            "{}",
            stats.sah_cost
        );
    }

    #[test]
    fn overlapping_pair_stays_one_leaf() {
        let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE), Aabb::new(Vec3::splat(0.1), Vec3::splat(0.9))];
        let stats = build(&boxes).stats();
        assert_eq!((stats.nodes, stats.leaves, stats.max_depth, stats.max_leaf_size), (1, 1, 0, 2));
        assert_eq!(stats.sah_cost, 2.0);
    }

    #[test]
    fn empty_bvh_stats() {
        let stats = build(&[]).stats();
        assert_eq!(
            (stats.nodes, stats.leaves, stats.max_depth, stats.sah_cost, stats.max_leaf_size),
            (1, 0, 0, 0.0, 0)
        );
    }
}
