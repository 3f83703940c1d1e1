//! CPU traversal of the flattened layout, step for step the algorithm the GLSL kernel runs:
//! explicit stack of MAX_DEPTH entries, nearer child first by the sign of the direction along the
//! split axis, slab test against a precomputed inverse direction, boxes culled beyond the current t.

use std::ops::{ControlFlow, Range};

use glam::Vec3;

use super::{Bvh, MAX_DEPTH};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

/// 1 + 2γ₃ (PBR, "Robust ray-bounds intersections"): widening the exit distance by this covers the
/// rounding of the three slab computations, so a box is never missed by a ray that hits its contents.
const EXIT_SLACK: f32 = {
    let half_eps = f32::EPSILON * 0.5;
    1.0 + 2.0 * (3.0 * half_eps / (1.0 - 3.0 * half_eps))
};

/// Ray/box slab test over (t_min, t_max). Entry and exit planes are chosen by the direction's sign,
/// not by min/max of the two plane hits, so an inverted box (like `BvhNode::EMPTY_ROOT`) always has
/// entry > exit and is never hit. Zero direction components work through the infinite inverse.
pub fn ray_box(bmin: Vec3, bmax: Vec3, origin: Vec3, inv_dir: Vec3, t_min: f32, t_max: f32) -> bool {
    let negative = inv_dir.cmplt(Vec3::ZERO);
    let near = (Vec3::select(negative, bmax, bmin) - origin) * inv_dir;
    let far = (Vec3::select(negative, bmin, bmax) - origin) * inv_dir;
    // f32::max/min skip a NaN (origin on a plane with a zero direction component): that slab
    // then does not constrain the interval.
    let enter = t_min.max(near.x).max(near.y).max(near.z);
    let exit = t_max.min(far.x.min(far.y).min(far.z) * EXIT_SLACK);
    enter <= exit
}

/// Closest hit: `intersect(prim_index_in_leaf_order, ray, t_max)` returns a hit distance in
/// (t_min, t_max). Returns (t, prim_index_in_leaf_order) for the closest.
pub fn closest_hit(
    bvh: &Bvh,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    mut intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
) -> Option<(f32, u32)> {
    let mut closest = None;
    walk(bvh, ray, t_min, t_max, |prims, mut t_max| {
        for prim in prims {
            if let Some(t) = intersect(prim, ray, t_max) {
                t_max = t;
                closest = Some((t, prim));
            }
        }
        ControlFlow::Continue(t_max)
    });
    closest
}

/// Any hit (shadow rays): stops at the first primitive that reports a hit in (t_min, t_max).
pub fn any_hit(
    bvh: &Bvh,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
    mut intersect: impl FnMut(u32, &Ray, f32) -> Option<f32>,
) -> bool {
    let mut hit = false;
    walk(bvh, ray, t_min, t_max, |mut prims, t_max| {
        hit = prims.any(|prim| intersect(prim, ray, t_max).is_some());
        if hit {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(t_max)
        }
    });
    hit
}

/// Visits every leaf whose box the ray enters before `t_max`, handing `visit_leaf` the leaf's
/// primitive range and the current `t_max`; it answers with the new `t_max` or stops the walk.
fn walk(
    bvh: &Bvh,
    ray: &Ray,
    t_min: f32,
    mut t_max: f32,
    mut visit_leaf: impl FnMut(Range<u32>, f32) -> ControlFlow<(), f32>,
) {
    let inv_dir = ray.dir.recip();
    // Holds the far child of each interior node on the path to the current one: at most one per level.
    let mut stack = [0u32; MAX_DEPTH];
    let mut stack_len = 0;
    let mut index = 0u32;
    loop {
        let node = &bvh.nodes[index as usize];
        if ray_box(node.min.into(), node.max.into(), ray.origin, inv_dir, t_min, t_max) {
            if node.is_leaf() {
                match visit_leaf(node.offset..node.offset + node.prim_count(), t_max) {
                    ControlFlow::Continue(t) => t_max = t,
                    ControlFlow::Break(()) => return,
                }
            } else {
                let (near, far) =
                    if ray.dir[node.axis()] < 0.0 { (node.offset, index + 1) } else { (index + 1, node.offset) };
                stack[stack_len] = far;
                stack_len += 1;
                index = near;
                continue;
            }
        }
        if stack_len == 0 {
            return;
        }
        stack_len -= 1;
        index = stack[stack_len];
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_scenes::{random_rays, random_spheres, random_triangles, Rng, Sphere, Triangle};
    use super::super::{build, Aabb, BvhNode};
    use super::*;

    const T_MIN: f32 = 1e-4;

    fn brute_closest(
        ray: &Ray,
        count: usize,
        intersect: impl Fn(usize, &Ray, f32) -> Option<f32>,
    ) -> Option<(f32, u32)> {
        let mut closest = None;
        let mut t_max = f32::INFINITY;
        for i in 0..count {
            if let Some(t) = intersect(i, ray, t_max) {
                t_max = t;
                closest = Some((t, i as u32));
            }
        }
        closest
    }

    /// Compares closest_hit and any_hit with brute force over every ray; `intersect` takes an
    /// original primitive index. Returns (hits, misses) so callers can check both were exercised.
    fn agrees_with_brute_force(
        prim_bounds: &[Aabb],
        rays: &[Ray],
        rng: &mut Rng,
        intersect: impl Fn(usize, &Ray, f32) -> Option<f32>,
    ) -> (usize, usize) {
        let bvh = build(prim_bounds);
        let (mut hits, mut misses) = (0, 0);
        for (r, ray) in rays.iter().enumerate() {
            let in_leaf_order =
                |prim: u32, ray: &Ray, t_max: f32| intersect(bvh.prim_order[prim as usize] as usize, ray, t_max);
            let expected = brute_closest(ray, prim_bounds.len(), &intersect);
            let got = closest_hit(&bvh, ray, T_MIN, f32::INFINITY, in_leaf_order)
                .map(|(t, prim)| (t, bvh.prim_order[prim as usize]));
            match (expected, got) {
                (None, None) => misses += 1,
                (Some((te, pe)), Some((tg, pg))) => {
                    assert_eq!(pe, pg, "ray {r}: closest primitive");
                    assert!((te - tg).abs() <= 1e-5 * te, "ray {r}: t {tg} vs {te}");
                    hits += 1;
                }
                _ => panic!("ray {r}: brute force {expected:?}, bvh {got:?}"),
            }

            let shadow_t_max = rng.range(0.05, 1.5);
            let blocked = (0..prim_bounds.len()).any(|i| intersect(i, ray, shadow_t_max).is_some());
            assert_eq!(any_hit(&bvh, ray, T_MIN, shadow_t_max, in_leaf_order), blocked, "ray {r}: any_hit");
        }
        (hits, misses)
    }

    #[test]
    fn triangles_match_brute_force() {
        let mut rng = Rng::new(7);
        let triangles: Vec<Triangle> = random_triangles(&mut rng, 3000);
        let bounds: Vec<Aabb> = triangles.iter().map(Triangle::bounds).collect();
        let rays = random_rays(&mut rng, 2000);
        let (hits, misses) = agrees_with_brute_force(&bounds, &rays, &mut rng, |i, ray, t_max| {
            triangles[i].intersect(ray, T_MIN, t_max)
        });
        assert!(hits > 400 && misses > 100, "hits {hits}, misses {misses}");
    }

    #[test]
    fn spheres_match_brute_force() {
        let mut rng = Rng::new(11);
        let spheres: Vec<Sphere> = random_spheres(&mut rng, 3000);
        let bounds: Vec<Aabb> = spheres.iter().map(Sphere::bounds).collect();
        let rays = random_rays(&mut rng, 2000);
        let (hits, misses) =
            agrees_with_brute_force(&bounds, &rays, &mut rng, |i, ray, t_max| spheres[i].intersect(ray, T_MIN, t_max));
        assert!(hits > 400 && misses > 100, "hits {hits}, misses {misses}");
    }

    #[test]
    fn empty_bvh_is_never_entered() {
        let bvh = build(&[]);
        assert_eq!(bvh.nodes, vec![BvhNode::EMPTY_ROOT]);
        let mut rng = Rng::new(3);
        let mut rays = random_rays(&mut rng, 500);
        // Origins far out and on the root's planes, directions with zero and negative-zero components.
        rays.push(Ray { origin: Vec3::splat(1e30), dir: Vec3::new(-1.0, 0.0, -0.0) });
        rays.push(Ray { origin: Vec3::splat(f32::MAX), dir: Vec3::new(0.0, -0.0, 1.0) });
        rays.push(Ray { origin: Vec3::splat(-f32::MAX), dir: Vec3::new(-0.0, 0.0, -1.0) });
        for ray in &rays {
            let root = &bvh.nodes[0];
            assert!(
                !ray_box(root.min.into(), root.max.into(), ray.origin, ray.dir.recip(), 0.0, f32::INFINITY),
                "{ray:?}"
            );
            assert_eq!(closest_hit(&bvh, ray, 0.0, f32::INFINITY, |_, _, _| panic!("intersect called")), None);
            assert!(!any_hit(&bvh, ray, 0.0, f32::INFINITY, |_, _, _| panic!("intersect called")));
        }
    }

    #[test]
    fn ray_box_slabs() {
        let (lo, hi) = (Vec3::ZERO, Vec3::ONE);
        let hits = |origin: Vec3, dir: Vec3, t_max: f32| ray_box(lo, hi, origin, dir.recip(), 0.0, t_max);
        assert!(hits(Vec3::new(-1.0, 0.5, 0.5), Vec3::X, f32::INFINITY));
        assert!(hits(Vec3::new(2.0, 0.5, 0.5), -Vec3::X, f32::INFINITY));
        assert!(!hits(Vec3::new(-1.0, 0.5, 0.5), -Vec3::X, f32::INFINITY), "box behind the ray");
        assert!(!hits(Vec3::new(-1.0, 0.5, 0.5), Vec3::X, 0.5), "box beyond t_max");
        assert!(!hits(Vec3::new(-1.0, 1.5, 0.5), Vec3::X, f32::INFINITY), "parallel outside the y slab");
        assert!(hits(Vec3::splat(0.5), Vec3::new(0.3, -0.2, 0.9), f32::INFINITY), "origin inside");
    }

    #[test]
    fn nearer_child_first_culls_the_farther_box() {
        // Two pairs of boxes far apart along x (one leaf each); a ray along -x must test the right
        // leaf first and skip the left one.
        let boxes = [0.0, 1.0, 40.0, 41.0].map(|x| Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0)));
        let bvh = build(&boxes);
        assert_eq!((bvh.nodes.len(), bvh.nodes[0].axis()), (3, 0));
        let ray = Ray { origin: Vec3::new(50.0, 0.5, 0.5), dir: -Vec3::X };
        let mut tested = Vec::new();
        let hit = closest_hit(&bvh, &ray, 0.0, f32::INFINITY, |prim, ray, t_max| {
            let original = bvh.prim_order[prim as usize];
            tested.push(original);
            let t = (boxes[original as usize].max.x - ray.origin.x).abs();
            (t < t_max).then_some(t)
        });
        tested.sort_unstable();
        assert_eq!(tested, vec![2, 3]);
        assert_eq!(hit.map(|(t, prim)| (t, bvh.prim_order[prim as usize])), Some((8.0, 3)));
    }
}
