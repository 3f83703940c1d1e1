//! Random scenes and reference intersectors shared by the BVH tests.

use glam::Vec3;

use super::{Aabb, Bvh, Ray, MAX_DEPTH, MAX_LEAF_SIZE};

/// xorshift64*: deterministic test randomness without a dependency.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Rng {
        Rng(seed | 1)
    }

    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }

    pub fn vec3(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }

    pub fn direction(&mut self) -> Vec3 {
        loop {
            let v = self.vec3(-1.0, 1.0);
            if v.length_squared() > 1e-4 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

pub struct Triangle(pub [Vec3; 3]);

impl Triangle {
    pub fn bounds(&self) -> Aabb {
        let mut b = Aabb::EMPTY;
        self.0.iter().for_each(|&v| b.grow(v));
        b
    }

    /// Möller–Trumbore.
    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let [v0, v1, v2] = self.0;
        let (e1, e2) = (v1 - v0, v2 - v0);
        let p = ray.dir.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv_det = 1.0 / det;
        let s = ray.origin - v0;
        let u = s.dot(p) * inv_det;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = ray.dir.dot(q) * inv_det;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = e2.dot(q) * inv_det;
        (t > t_min && t < t_max).then_some(t)
    }
}

pub struct Sphere {
    pub center: Vec3,
    pub radius: f32,
}

impl Sphere {
    pub fn bounds(&self) -> Aabb {
        Aabb::new(self.center - self.radius, self.center + self.radius)
    }

    pub fn intersect(&self, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
        let oc = ray.origin - self.center;
        let a = ray.dir.dot(ray.dir);
        let half_b = oc.dot(ray.dir);
        let c = oc.dot(oc) - self.radius * self.radius;
        let discriminant = half_b * half_b - a * c;
        if discriminant < 0.0 {
            return None;
        }
        let root = discriminant.sqrt();
        [(-half_b - root) / a, (-half_b + root) / a].into_iter().find(|&t| t > t_min && t < t_max)
    }
}

/// Small triangles scattered through the unit cube.
pub fn random_triangles(rng: &mut Rng, count: usize) -> Vec<Triangle> {
    (0..count)
        .map(|_| {
            let v0 = rng.vec3(0.0, 1.0);
            Triangle([v0, v0 + rng.vec3(-0.08, 0.08), v0 + rng.vec3(-0.08, 0.08)])
        })
        .collect()
}

pub fn random_spheres(rng: &mut Rng, count: usize) -> Vec<Sphere> {
    (0..count).map(|_| Sphere { center: rng.vec3(0.0, 1.0), radius: rng.range(0.005, 0.05) }).collect()
}

/// Rays from inside and around the unit cube; every eighth runs along a coordinate axis
/// (two zero direction components, alternating signs) to exercise infinite inverse directions.
pub fn random_rays(rng: &mut Rng, count: usize) -> Vec<Ray> {
    (0..count)
        .map(|i| {
            let origin = rng.vec3(-0.5, 1.5);
            let dir = if i % 8 == 0 {
                let mut d = Vec3::ZERO;
                d[i / 8 % 3] = if i % 16 == 0 { 1.0 } else { -1.0 };
                d
            } else {
                rng.direction()
            };
            Ray { origin, dir }
        })
        .collect()
}

/// Checks the layout contract and the build invariants: depth-first order (each subtree is the
/// contiguous block after its root), every primitive in exactly one leaf, boxes nested, depth and
/// leaf size within limits.
pub fn assert_well_formed(bvh: &Bvh, prim_bounds: &[Aabb]) {
    let mut seen = vec![false; prim_bounds.len()];
    for &p in &bvh.prim_order {
        assert!(!std::mem::replace(&mut seen[p as usize], true), "primitive {p} appears twice");
    }
    assert_eq!(bvh.prim_order.len(), prim_bounds.len(), "prim_order is not a permutation");

    let mut next_prim = 0;
    let end = check_subtree(bvh, prim_bounds, 0, 0, &mut next_prim);
    assert_eq!(end, bvh.nodes.len(), "nodes unreachable from the root");
    assert_eq!(next_prim, prim_bounds.len(), "leaves do not cover all primitives");
}

/// Returns the index one past the subtree rooted at `index`.
fn check_subtree(bvh: &Bvh, prim_bounds: &[Aabb], index: usize, depth: usize, next_prim: &mut usize) -> usize {
    assert!(depth <= MAX_DEPTH, "node {index} at depth {depth}");
    let node = &bvh.nodes[index];
    let bounds = node.bounds();
    if node.is_leaf() {
        let (first, count) = (node.offset as usize, node.prim_count() as usize);
        assert!(count <= MAX_LEAF_SIZE, "leaf {index} holds {count}");
        assert_eq!(first, *next_prim, "leaf {index} does not continue leaf order");
        *next_prim += count;
        for &p in &bvh.prim_order[first..first + count] {
            assert!(bounds.contains(&prim_bounds[p as usize]), "leaf {index} misses primitive {p}");
        }
        return index + 1;
    }
    let second = check_subtree(bvh, prim_bounds, index + 1, depth + 1, next_prim);
    assert_eq!(node.offset as usize, second, "node {index}: second child is not after the first subtree");
    for child in [index + 1, second] {
        assert!(bounds.contains(&bvh.nodes[child].bounds()), "node {index} misses child {child}");
    }
    check_subtree(bvh, prim_bounds, second, depth + 1, next_prim)
}
