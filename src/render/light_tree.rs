//! The light tree (`light_selection = "bvh"`): a binary BVH over every light next-event
//! estimation samples that has a position (area lights, point and spot lights), after Conty
//! Estevez and Kulla 2018 and pbrt-v4's `BVHLightSampler`. Each node bounds its lights' positions,
//! their total power and the cone of directions they emit into; a shading point descends it with
//! one random number, at each node taking a child in proportion to the child's *importance* there
//! (`importance`: power over squared distance, zero where the point lies outside every direction
//! the child's lights emit into). The probability of a light is the product of the choices on the
//! path from the root to its leaf; the kernel recomputes it for an emitter that BSDF sampling hits
//! by walking up from the leaf through parent links (shaders/light_tree.glsl), so the two MIS
//! weights of a path still come from the same pdfs.
//!
//! Directional lights have no position: they are picked beside the tree, as pbrt-v4 does, the
//! group of them with probability n / (n + 1) for n of them (the tree counting as one), each of
//! them within it in proportion to its power (irradiance x pi r^2, r the scene's bounding radius:
//! light_selection.rs). The environment map keeps its own share (SceneData::
//! env_selection_probability), outside all of this.
//!
//! The host's reference walk (`pick`, `pmf`) runs the same f32 arithmetic as the kernel's; the
//! tests compare the two (tests/light_tree.rs).

use super::layout::{GpuLightTreeNode, LIGHT_TREE_LEAF, LIGHT_TREE_NONE, LIGHT_TREE_TWO_SIDED};
use glam::{DVec3, Vec3};
use std::cmp::Ordering;
use std::f64::consts::PI;
use std::time::Instant;

/// What a light or a group of lights offers the importance estimate: where it is, how much it
/// emits, and in which directions (pbrt-v4's `LightBounds`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub min: Vec3,
    pub max: Vec3,
    /// Emitted power (light_selection.rs's formulas; a spot counts as the point light it cuts
    /// its cone from, as in pbrt-v4, since the cone below accounts for where it shines).
    pub phi: f32,
    /// The axis of the cone of surface normals (or spot axes) ...
    pub axis: Vec3,
    /// ... its half-angle's cosine (-1: every direction) ...
    pub cos_theta_o: f32,
    /// ... and the cosine of how far beyond a normal the light still emits (0: a hemisphere
    /// about each normal, a Lambertian emitter; cos(cone - falloff start) for a spot).
    pub cos_theta_e: f32,
    /// A flat emitter that radiates from both sides: the cone's test takes |cos|.
    pub two_sided: bool,
}

impl LightBounds {
    /// A light that emits in every direction from the box (min, max): a sphere or a point light.
    pub fn omnidirectional(min: Vec3, max: Vec3, phi: f64) -> Self {
        Self { min, max, phi: phi as f32, axis: Vec3::Z, cos_theta_o: -1.0, cos_theta_e: 0.0, two_sided: false }
    }

    /// A flat Lambertian emitter with unit `normal` whose corners are `corners`.
    pub fn flat(corners: &[Vec3], normal: Vec3, phi: f64, two_sided: bool) -> Self {
        let min = corners.iter().fold(Vec3::INFINITY, |a, &c| a.min(c));
        let max = corners.iter().fold(Vec3::NEG_INFINITY, |a, &c| a.max(c));
        Self { min, max, phi: phi as f32, axis: normal, cos_theta_o: 1.0, cos_theta_e: 0.0, two_sided }
    }

    /// A spot light at `position` along unit `axis`: full intensity to `falloff_start`, none
    /// beyond `cone_angle` (radians). `phi` is 4 pi x intensity (pbrt-v4's).
    pub fn spot(position: Vec3, axis: Vec3, cone_angle: f32, falloff_start: f32, phi: f64) -> Self {
        let falloff_start = falloff_start.min(cone_angle);
        Self {
            min: position,
            max: position,
            phi: phi as f32,
            axis,
            cos_theta_o: falloff_start.cos(),
            cos_theta_e: (cone_angle - falloff_start).cos(),
            two_sided: false,
        }
    }

    fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Both lights' bounds: the box around both, the powers summed, the cone around both cones
    /// and the wider emission spread (pbrt-v4's `Union`). A powerless side adds nothing.
    pub fn union(&self, other: &Self) -> Self {
        if self.phi == 0.0 {
            return *other;
        }
        if other.phi == 0.0 {
            return *self;
        }
        let (axis, cos_theta_o) = cone_union((self.axis, self.cos_theta_o), (other.axis, other.cos_theta_o));
        Self {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
            phi: self.phi + other.phi,
            axis,
            cos_theta_o,
            cos_theta_e: self.cos_theta_e.min(other.cos_theta_e),
            two_sided: self.two_sided || other.two_sided,
        }
    }

    /// The importance of these lights at `p` (pbrt-v4's `LightBounds::Importance` without the
    /// receiver's normal, which the kernel's hit-emitter pdf does not have): power over the
    /// squared distance to the box's centre (at least half its diagonal, so that a point inside a
    /// large node does not make it infinitely important), zero where the smallest angle between a
    /// direction from the lights to `p` and their cone of normals exceeds their emission spread.
    /// The same f32 operations as shaders/light_tree.glsl's `light_importance`.
    pub fn importance(&self, p: Vec3) -> f32 {
        importance(self.min, self.max, self.phi, self.axis, self.cos_theta_o, self.cos_theta_e, self.two_sided, p)
    }
}

/// See [`LightBounds::importance`]; the node's fields as the kernel reads them.
#[allow(clippy::too_many_arguments)]
fn importance(
    min: Vec3,
    max: Vec3,
    phi: f32,
    axis: Vec3,
    cos_theta_o: f32,
    cos_theta_e: f32,
    two_sided: bool,
    p: Vec3,
) -> f32 {
    let center = 0.5 * (min + max);
    let to_p = p - center;
    let distance2 = to_p.dot(to_p);
    let radius2 = (max - center).dot(max - center);
    // Inside the bounding sphere every direction may reach p: no angular bound.
    let mut cos_theta_p = 1.0;
    if distance2 > radius2 {
        let cos_theta_b = (1.0 - radius2 / distance2).max(0.0).sqrt();
        let sin_theta_b = (radius2 / distance2).min(1.0).sqrt();
        let mut cos_theta_w = axis.dot(to_p / distance2.sqrt());
        if two_sided {
            cos_theta_w = cos_theta_w.abs();
        }
        let sin_theta_w = (1.0 - cos_theta_w * cos_theta_w).max(0.0).sqrt();
        let sin_theta_o = (1.0 - cos_theta_o * cos_theta_o).max(0.0).sqrt();
        // theta_x = max(0, theta_w - theta_o), then theta' = max(0, theta_x - theta_b).
        let (cos_theta_x, sin_theta_x) = if cos_theta_w > cos_theta_o {
            (1.0, 0.0)
        } else {
            (
                cos_theta_w * cos_theta_o + sin_theta_w * sin_theta_o,
                sin_theta_w * cos_theta_o - cos_theta_w * sin_theta_o,
            )
        };
        cos_theta_p =
            if cos_theta_x > cos_theta_b { 1.0 } else { cos_theta_x * cos_theta_b + sin_theta_x * sin_theta_b };
    }
    if cos_theta_p <= cos_theta_e {
        return 0.0;
    }
    let diagonal = max - min;
    let clamped = distance2.max(0.5 * diagonal.dot(diagonal).sqrt());
    (phi * cos_theta_p / clamped).max(0.0)
}

/// The cone around two cones (axis, cos of half-angle), as pbrt-v4's `Union(DirectionCone,
/// DirectionCone)`; (any axis, -1) for the whole sphere.
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let (wa, wb) = (a.0.as_dvec3(), b.0.as_dvec3());
    let theta_a = (a.1 as f64).clamp(-1.0, 1.0).acos();
    let theta_b = (b.1 as f64).clamp(-1.0, 1.0).acos();
    let theta_d = wa.dot(wb).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    let sphere = (Vec3::Z, -1.0);
    if theta_o >= PI {
        return sphere;
    }
    let theta_r = theta_o - theta_a;
    let rotation_axis = wa.cross(wb);
    if rotation_axis.length_squared() < 1e-20 {
        return sphere;
    }
    let w = rotate(wa, rotation_axis.normalize(), theta_r);
    (w.as_vec3().normalize(), theta_o.cos() as f32)
}

/// `v` rotated by `angle` about unit `axis` (Rodrigues).
fn rotate(v: DVec3, axis: DVec3, angle: f64) -> DVec3 {
    let (s, c) = angle.sin_cos();
    v * c + axis.cross(v) * s + axis * axis.dot(v) * (1.0 - c)
}

/// The flattened tree, its light maps and the directional lights' shares.
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    /// Root at 0; an interior node's first child follows it, its second is at `links[0]`.
    pub nodes: Vec<GpuLightTreeNode>,
    /// Per light of the kernel's order (area lights, then point, spot and directional lights):
    /// its leaf, LIGHT_TREE_NONE for a directional light or a light without power.
    pub leaf_of_light: Vec<u32>,
    /// Per light: its probability when picked beside the tree (directional lights), else 0.
    pub infinite_share: Vec<f32>,
    /// The probability of descending the tree at all: 1 - the directional lights' shares (0
    /// when the tree is empty).
    pub tree_share: f32,
    /// Seconds the build took.
    pub build_seconds: f64,
}

/// One light as the tree sees it: bounded (with its bounds) or infinite (with its power).
#[derive(Clone, Copy, Debug)]
pub enum TreeLight {
    Bounded(LightBounds),
    Infinite { power: f64 },
}

/// Buckets per axis that the build's cost is evaluated at (pbrt-v4's 12).
const BUCKETS: usize = 12;

impl LightTree {
    /// The tree over `lights` (in the kernel's light order). Lights without power are left out:
    /// they are never picked, and their pdf is 0.
    pub fn build(lights: &[TreeLight]) -> Self {
        let start = Instant::now();
        let mut bounded: Vec<(u32, LightBounds)> = Vec::new();
        let mut infinite: Vec<(u32, f64)> = Vec::new();
        for (i, light) in lights.iter().enumerate() {
            match *light {
                TreeLight::Bounded(b) if b.phi > 0.0 && b.phi.is_finite() => bounded.push((i as u32, b)),
                TreeLight::Bounded(_) => {}
                TreeLight::Infinite { power } => infinite.push((i as u32, power)),
            }
        }
        let mut tree = LightTree {
            leaf_of_light: vec![LIGHT_TREE_NONE; lights.len()],
            infinite_share: vec![0.0; lights.len()],
            ..Default::default()
        };
        // pbrt-v4: the infinite lights together get n / (n + 1), the tree one share.
        let tree_count = usize::from(!bounded.is_empty());
        let infinite_total = infinite.len() as f64 / (infinite.len() + tree_count).max(1) as f64;
        let power_sum: f64 = infinite.iter().map(|&(_, p)| p).sum();
        for &(i, power) in &infinite {
            let within =
                if power_sum > 0.0 && power_sum.is_finite() { power / power_sum } else { 1.0 / infinite.len() as f64 };
            tree.infinite_share[i as usize] = (infinite_total * within) as f32;
        }
        tree.tree_share = if bounded.is_empty() { 0.0 } else { (1.0 - infinite_total) as f32 };
        if !bounded.is_empty() {
            tree.build_node(&mut bounded, LIGHT_TREE_NONE);
        }
        tree.build_seconds = start.elapsed().as_secs_f64();
        tree
    }

    /// Appends the subtree over `lights` with parent `parent`; returns its root's index.
    fn build_node(&mut self, lights: &mut [(u32, LightBounds)], parent: u32) -> u32 {
        let index = self.nodes.len() as u32;
        let bounds = lights.iter().skip(1).fold(lights[0].1, |b, l| b.union(&l.1));
        let mut node = GpuLightTreeNode {
            min_phi: bounds.min.extend(bounds.phi).into(),
            max_cos_theta_o: bounds.max.extend(bounds.cos_theta_o).into(),
            axis_cos_theta_e: bounds.axis.extend(bounds.cos_theta_e).into(),
            links: [0, parent, if bounds.two_sided { LIGHT_TREE_TWO_SIDED } else { 0 }, 0],
        };
        if let [(light, _)] = lights {
            node.links[0] = *light;
            node.links[2] |= LIGHT_TREE_LEAF;
            self.leaf_of_light[*light as usize] = index;
            self.nodes.push(node);
            return index;
        }
        self.nodes.push(node);
        let mid = split(lights, &bounds);
        let (first, second) = lights.split_at_mut(mid);
        self.build_node(first, index);
        let second_index = self.build_node(second, index);
        self.nodes[index as usize].links[0] = second_index;
        index
    }

    /// Bytes the kernel's copy takes.
    pub fn gpu_bytes(&self) -> u64 {
        std::mem::size_of_val(&self.nodes[..]) as u64
    }

    /// The bounds node `i` holds, as the kernel reads them.
    fn node_importance(&self, i: u32, p: Vec3) -> f32 {
        let n = &self.nodes[i as usize];
        importance(
            Vec3::from_slice(&n.min_phi[..3]),
            Vec3::from_slice(&n.max_cos_theta_o[..3]),
            n.min_phi[3],
            Vec3::from_slice(&n.axis_cos_theta_e[..3]),
            n.max_cos_theta_o[3],
            n.axis_cos_theta_e[3],
            n.links[2] & LIGHT_TREE_TWO_SIDED != 0,
            p,
        )
    }

    /// The host's reference of the kernel's pick at `p` with random number `u` in [0, 1): the
    /// light and its probability (without the environment map's share), or None where nothing
    /// can be picked (every light's importance is zero there).
    pub fn pick(&self, p: Vec3, mut u: f32) -> Option<(u32, f32)> {
        let infinite_total = 1.0 - self.tree_share;
        if u < infinite_total {
            let mut sum = 0.0f32;
            let mut last = None;
            for (i, &share) in self.infinite_share.iter().enumerate() {
                if share > 0.0 {
                    sum += share;
                    last = Some((i as u32, share));
                    if u < sum {
                        return last;
                    }
                }
            }
            return last;
        }
        if self.nodes.is_empty() {
            return None;
        }
        u = ((u - infinite_total) / self.tree_share).min(ONE_MINUS_EPSILON);
        let mut pmf = self.tree_share;
        let mut node = 0u32;
        loop {
            let n = &self.nodes[node as usize];
            if n.links[2] & LIGHT_TREE_LEAF != 0 {
                return (self.node_importance(node, p) > 0.0).then_some((n.links[0], pmf));
            }
            let (c0, c1) = (self.node_importance(node + 1, p), self.node_importance(n.links[0], p));
            // Neither child lights p (or a NaN crept in): nothing to pick, as in the kernel.
            if (c0 + c1).partial_cmp(&0.0) != Some(Ordering::Greater) {
                return None;
            }
            let p0 = c0 / (c0 + c1);
            if u < p0 {
                u = (u / p0).min(ONE_MINUS_EPSILON);
                pmf *= c0 / (c0 + c1);
                node += 1;
            } else {
                u = ((u - p0) / (1.0 - p0)).min(ONE_MINUS_EPSILON);
                pmf *= c1 / (c0 + c1);
                node = n.links[0];
            }
        }
    }

    /// The probability that [`Self::pick`] at `p` finds no light: that it reaches a node whose
    /// children both have no importance there (their lights all face away from `p`, though the
    /// node's wider cone does not). Next-event estimation then adds nothing, which is right, as
    /// none of those lights reaches `p`; the probabilities of the lights and this sum to 1.
    pub fn no_light_probability(&self, p: Vec3) -> f64 {
        if self.nodes.is_empty() {
            return if self.tree_share > 0.0 { self.tree_share as f64 } else { 0.0 };
        }
        let mut none = 0.0;
        let mut stack = vec![(0u32, self.tree_share as f64)];
        while let Some((node, reach)) = stack.pop() {
            let n = &self.nodes[node as usize];
            if n.links[2] & LIGHT_TREE_LEAF != 0 {
                if self.node_importance(node, p) <= 0.0 {
                    none += reach;
                }
                continue;
            }
            let (c0, c1) = (self.node_importance(node + 1, p) as f64, self.node_importance(n.links[0], p) as f64);
            if (c0 + c1).partial_cmp(&0.0) != Some(Ordering::Greater) {
                none += reach;
                continue;
            }
            stack.push((node + 1, reach * c0 / (c0 + c1)));
            stack.push((n.links[0], reach * c1 / (c0 + c1)));
        }
        none
    }

    /// The probability that [`Self::pick`] at `p` gives `light`: its infinite share, or the
    /// product of the choices from its leaf up to the root (as the kernel computes it for an
    /// emitter hit by BSDF sampling).
    pub fn pmf(&self, p: Vec3, light: u32) -> f32 {
        let share = self.infinite_share[light as usize];
        if share > 0.0 {
            return share;
        }
        let mut node = self.leaf_of_light[light as usize];
        if node == LIGHT_TREE_NONE || self.node_importance(node, p) <= 0.0 {
            return 0.0;
        }
        let mut pmf = self.tree_share;
        loop {
            let parent = self.nodes[node as usize].links[1];
            if parent == LIGHT_TREE_NONE {
                return pmf;
            }
            let second = self.nodes[parent as usize].links[0];
            let (c0, c1) = (self.node_importance(parent + 1, p), self.node_importance(second, p));
            pmf *= if node == second { c1 } else { c0 } / (c0 + c1);
            node = parent;
        }
    }
}

/// The largest f32 below 1: where a rescaled random number is clamped (pbrt's OneMinusEpsilon).
pub const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Orders `lights` and returns where to split them: at the bucket boundary of least cost
/// (pbrt-v4's: power x the solid angle the emission cone may reach x the box's surface area,
/// with a penalty for splitting across the box's thin side), else in the middle of the widest
/// axis of the centroids. Both sides are non-empty.
fn split(lights: &mut [(u32, LightBounds)], bounds: &LightBounds) -> usize {
    let (cmin, cmax) = lights
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), l| (lo.min(l.1.centroid()), hi.max(l.1.centroid())));
    let extent = cmax - cmin;
    let diagonal = (bounds.max - bounds.min).as_dvec3();
    let bucket_of = |l: &LightBounds, dim: usize| {
        let offset = (l.centroid()[dim] - cmin[dim]) / extent[dim];
        ((offset * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f64, usize, usize)> = None;
    for dim in 0..3 {
        if extent[dim] <= 0.0 {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (_, l) in lights.iter() {
            let b = &mut buckets[bucket_of(l, dim)];
            *b = Some(b.map_or(*l, |x| x.union(l)));
        }
        let union_of = |range: &[Option<LightBounds>]| {
            range.iter().flatten().fold(None, |acc: Option<LightBounds>, b| Some(acc.map_or(*b, |a| a.union(b))))
        };
        let thin_penalty = diagonal.max_element() / diagonal[dim].max(1e-30);
        for boundary in 1..BUCKETS {
            let (Some(below), Some(above)) = (union_of(&buckets[..boundary]), union_of(&buckets[boundary..])) else {
                continue;
            };
            let cost = (split_cost(&below) + split_cost(&above)) * thin_penalty;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, dim, boundary));
            }
        }
    }
    if let Some((_, dim, boundary)) = best {
        lights.sort_by_key(|(_, l)| bucket_of(l, dim));
        let mid = lights.partition_point(|(_, l)| bucket_of(l, dim) < boundary);
        if mid > 0 && mid < lights.len() {
            return mid;
        }
    }
    // No axis separates the centroids (lights at one point): halve the list in centroid order.
    let dim = extent.max_position();
    lights.sort_by(|a, b| a.1.centroid()[dim].total_cmp(&b.1.centroid()[dim]));
    lights.len() / 2
}

/// pbrt-v4's `EvaluateCost` without the axis penalty: power x the solid angle the cone of
/// normals widened by the emission spread covers x the box's surface area.
fn split_cost(b: &LightBounds) -> f64 {
    let theta_o = (b.cos_theta_o as f64).clamp(-1.0, 1.0).acos();
    let theta_e = (b.cos_theta_e as f64).clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(PI);
    let sin_theta_o = theta_o.sin();
    let m_omega = 2.0 * PI * (1.0 - theta_o.cos())
        + PI / 2.0
            * (2.0 * theta_w * sin_theta_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_theta_o
                + theta_o.cos());
    let d = (b.max - b.min).as_dvec3();
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    b.phi as f64 * m_omega * area
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(state: &mut u64) -> f32 {
        *state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((*state >> 40) as f32) / (1u64 << 24) as f32
    }

    fn scattered_lights(n: usize, seed: u64) -> Vec<TreeLight> {
        let mut s = seed;
        (0..n)
            .map(|i| {
                let c = Vec3::new(lcg(&mut s) * 10.0, lcg(&mut s) * 3.0, lcg(&mut s) * 10.0);
                let phi = 0.1 + lcg(&mut s) as f64 * 5.0;
                TreeLight::Bounded(match i % 4 {
                    0 => LightBounds::omnidirectional(c - 0.1, c + 0.1, phi),
                    1 => LightBounds::flat(&[c, c + Vec3::X * 0.3, c + Vec3::Z * 0.3], -Vec3::Y, phi, false),
                    2 => LightBounds::spot(c, Vec3::new(0.3, -1.0, 0.1).normalize(), 0.6, 0.3, phi),
                    _ => LightBounds::flat(&[c, c + Vec3::Y * 0.2, c + Vec3::Z * 0.2], Vec3::X, phi, true),
                })
            })
            .chain([TreeLight::Infinite { power: 3.0 }, TreeLight::Infinite { power: 1.0 }])
            .collect()
    }

    #[test]
    fn the_pmf_sums_to_one_over_every_light() {
        let lights = scattered_lights(200, 7);
        let tree = LightTree::build(&lights);
        assert_eq!(tree.nodes.len(), 2 * 200 - 1);
        assert!((tree.tree_share - 1.0 / 3.0).abs() < 1e-6);
        let mut s = 99;
        for _ in 0..200 {
            let p = Vec3::new(lcg(&mut s) * 12.0 - 1.0, lcg(&mut s) * 4.0 - 0.5, lcg(&mut s) * 12.0 - 1.0);
            let sum: f64 = (0..lights.len() as u32).map(|l| tree.pmf(p, l) as f64).sum();
            let none = tree.no_light_probability(p);
            assert!((sum + none - 1.0).abs() < 1e-5, "at {p}: the pmf sums to {sum}, and {none} finds nothing");
        }
    }

    #[test]
    fn the_pick_reports_the_pmf_of_what_it_picks() {
        let lights = scattered_lights(64, 3);
        let tree = LightTree::build(&lights);
        let mut s = 5;
        for _ in 0..2000 {
            let p = Vec3::new(lcg(&mut s) * 10.0, lcg(&mut s) * 3.0, lcg(&mut s) * 10.0);
            if let Some((light, pmf)) = tree.pick(p, lcg(&mut s)) {
                let expected = tree.pmf(p, light);
                assert!((pmf / expected - 1.0).abs() < 1e-5, "light {light} at {p}: {pmf} against {expected}");
            }
        }
    }

    #[test]
    fn a_light_facing_away_is_never_picked() {
        let down = LightBounds::flat(&[Vec3::ZERO, Vec3::X, Vec3::Z], -Vec3::Y, 1.0, false);
        let tree = LightTree::build(&[TreeLight::Bounded(down), TreeLight::Bounded(down)]);
        assert_eq!(tree.pmf(Vec3::new(0.3, 2.0, 0.3), 0), 0.0);
        assert!(tree.pmf(Vec3::new(0.3, -2.0, 0.3), 0) > 0.49);
    }

    #[test]
    fn nearer_lights_get_more_of_the_picks() {
        let a = LightBounds::omnidirectional(Vec3::ZERO, Vec3::ZERO, 1.0);
        let b = LightBounds::omnidirectional(Vec3::X * 10.0, Vec3::X * 10.0, 1.0);
        let tree = LightTree::build(&[TreeLight::Bounded(a), TreeLight::Bounded(b)]);
        let p = Vec3::new(1.0, 0.0, 0.0);
        // 1 / 1 against 1 / 81.
        assert!((tree.pmf(p, 0) - 81.0 / 82.0).abs() < 1e-6);
    }

    #[test]
    fn a_tree_of_directional_lights_alone_picks_them_by_power() {
        let tree = LightTree::build(&[TreeLight::Infinite { power: 1.0 }, TreeLight::Infinite { power: 3.0 }]);
        assert!(tree.nodes.is_empty() && tree.tree_share == 0.0);
        assert_eq!(tree.pmf(Vec3::ZERO, 1), 0.75);
        assert_eq!(tree.pick(Vec3::ZERO, 0.5), Some((1, 0.75)));
    }
}
