//! Flattens a `Scene` into the arrays the kernel reads: primitives in BVH leaf order, the BVH
//! nodes, materials, the emitter list and the environment texels.

use super::layout::*;
use crate::bvh::{self, Aabb, BuildStats, BvhNode};
use crate::scene::{Environment, MapProjection, Scene, Shape};
use glam::Vec3;

pub struct SceneData {
    pub primitives: Vec<GpuPrimitive>,
    pub nodes: Vec<BvhNode>,
    pub materials: Vec<GpuMaterial>,
    /// Indices into `primitives` of every emitter.
    pub lights: Vec<u32>,
    /// Environment map texels, top row first (one black texel for a constant sky).
    pub env_texels: Vec<[f32; 4]>,
    pub env_kind: u32,
    pub env_size: [u32; 2],
    /// Multiplier for a map, or the radiance of a constant sky.
    pub env_color: Vec3,
    pub env_rotation_deg: f32,
    pub bvh_stats: BuildStats,
}

fn shape_bounds(shape: &Shape) -> Aabb {
    match *shape {
        Shape::Sphere { center, radius, .. } => Aabb { min: center - Vec3::splat(radius), max: center + Vec3::splat(radius) },
        Shape::Quad { origin, u, v, .. } => corners_bounds(&[origin, origin + u, origin + v, origin + u + v]),
        Shape::Triangle { v, .. } => corners_bounds(&v),
    }
}

fn corners_bounds(points: &[Vec3]) -> Aabb {
    let mut b = Aabb::EMPTY;
    for &p in points {
        b.grow(p);
    }
    b
}

fn gpu_primitive(shape: &Shape) -> GpuPrimitive {
    let tag = |kind: u32, material: u32| (f32::from_bits(kind), f32::from_bits(material));
    match *shape {
        Shape::Sphere { center, radius, material } => {
            let (k, m) = tag(PRIM_SPHERE, material);
            GpuPrimitive { a: center.extend(radius).into(), b: [0.0, 0.0, 0.0, k], c: [0.0, 0.0, 0.0, m] }
        }
        Shape::Quad { origin, u, v, material } => {
            let (k, m) = tag(PRIM_QUAD, material);
            GpuPrimitive { a: origin.extend(0.0).into(), b: u.extend(k).into(), c: v.extend(m).into() }
        }
        Shape::Triangle { v, material } => {
            let (k, m) = tag(PRIM_TRIANGLE, material);
            GpuPrimitive { a: v[0].extend(0.0).into(), b: (v[1] - v[0]).extend(k).into(), c: (v[2] - v[0]).extend(m).into() }
        }
    }
}

impl SceneData {
    pub fn new(scene: &Scene) -> SceneData {
        let bounds: Vec<Aabb> = scene.shapes.iter().map(shape_bounds).collect();
        let bvh = bvh::build(&bounds);
        let primitives: Vec<GpuPrimitive> = bvh.prim_order.iter().map(|&i| gpu_primitive(&scene.shapes[i as usize])).collect();
        let lights = bvh
            .prim_order
            .iter()
            .enumerate()
            .filter(|(_, &i)| scene.materials[scene.shapes[i as usize].material() as usize].is_emissive())
            .map(|(leaf_index, _)| leaf_index as u32)
            .collect();
        let materials = scene
            .materials
            .iter()
            .map(|m| GpuMaterial {
                albedo_r: m.albedo.extend(m.reflectivity).into(),
                emission_t: m.emission.extend(m.transparency).into(),
                params: [m.ior, if m.two_sided { 1.0 } else { 0.0 }, 0.0, 0.0],
            })
            .collect();
        let (env_texels, env_kind, env_size, env_color, env_rotation_deg) = match &scene.environment {
            Environment::Constant(c) => (vec![[0.0; 4]], ENV_CONSTANT, [1, 1], *c, 0.0),
            Environment::Map(map) => (
                map.image.pixels.iter().map(|p| [p[0], p[1], p[2], 0.0]).collect(),
                match map.projection {
                    MapProjection::Angular => ENV_ANGULAR,
                    MapProjection::LatLong => ENV_LATLONG,
                },
                [map.image.width, map.image.height],
                Vec3::splat(map.intensity),
                map.rotation_deg,
            ),
        };
        SceneData {
            bvh_stats: bvh.stats(),
            primitives,
            nodes: bvh.nodes,
            materials,
            lights,
            env_texels,
            env_kind,
            env_size,
            env_color,
            env_rotation_deg,
        }
    }

    /// Bytes of GPU memory the scene needs (excluding the image).
    pub fn gpu_bytes(&self) -> u64 {
        (std::mem::size_of_val(&self.primitives[..])
            + std::mem::size_of_val(&self.nodes[..])
            + std::mem::size_of_val(&self.materials[..])
            + std::mem::size_of_val(&self.lights[..])
            + std::mem::size_of_val(&self.env_texels[..])) as u64
    }
}
