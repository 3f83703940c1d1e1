//! The two-level acceleration structure the kernel walks: one bottom-level BVH per mesh (and one
//! over the scene's own spheres, quads and triangles), a top-level BVH over their placements
//! (instances), all in one node array with the top-level root at node 0. A mesh placed many times
//! is stored once.

use super::bvh_width::BvhWidth;
use super::layout::*;
use crate::bvh::{self, wide_nodes, Aabb, BuildStats, EightWideTree, WideNode, CHILD_INTERIOR, CHILD_NONE, WIDTH};
use crate::scene::{Mesh, Scene, Shape};
use glam::{Mat4, Vec3};
use rayon::prelude::*;
use std::time::Instant;

pub struct Acceleration {
    /// Every BVH as wide nodes (crate::bvh::WideNode), the top level's root at 0; the bottom
    /// levels' nodes are eight-wide (two records each, crate::bvh::EightWideNode) where built
    /// with [`BvhWidth::Eight`].
    pub nodes: Vec<WideNode>,
    /// The bottom levels' node format.
    pub bvh_width: BvhWidth,
    /// In top-level leaf order.
    pub instances: Vec<GpuInstance>,
    /// Per instance, in the same order: the index of the mesh it places (into `triangle_slots`),
    /// `None` for the scene's own shapes. The ray-query traversal builds a structure a mesh from it.
    pub instance_meshes: Vec<Option<u32>>,
    /// Per instance, in the same order: the scene instance it is (`Scene::instances`), `None`
    /// for the scene's own shapes. The light tree's index finds a hit emitter's light by it.
    pub instance_sources: Vec<Option<u32>>,
    /// The scene's own shapes, in their bottom-level leaf order.
    pub primitives: Vec<GpuPrimitive>,
    /// Per entry of `primitives`: its index in `Scene::shapes`.
    pub shape_order: Vec<u32>,
    /// Every mesh's triangles by value, each mesh in its bottom-level leaf order (see
    /// [`GpuMeshTriangle`]), and their materials in the same order.
    pub triangles: Vec<GpuMeshTriangle>,
    pub triangle_materials: Vec<u32>,
    /// Per mesh, per triangle of `Mesh::triangles`: where it lies in `triangles`.
    pub triangle_slots: Vec<Vec<u32>>,
    /// Octahedral snorm16x2, one a vertex of meshes with normals (others have no entries).
    pub normals: Vec<u32>,
    /// One a vertex of meshes with texture coordinates; in a scene with textures, one a vertex of
    /// every mesh ((0, 0) for those without), so that a textured emitter's light sample can read
    /// them without knowing its mesh.
    pub uvs: Vec<[f32; 2]>,
    /// Tangent and bitangent sign, one a vertex of meshes with tangents (see `Mesh::tangents`;
    /// others have zeros where a later mesh needs entries).
    pub tangents: Vec<[f32; 4]>,
    /// Linear RGB colour (w unused, 1) one a vertex of meshes with vertex colours (see
    /// `Mesh::colors`; white where a later mesh needs entries), read only by kernels built
    /// with SCENE_VERTEX_COLORS.
    pub colors: Vec<[f32; 4]>,
    /// Everything placed, in world space (`Aabb::EMPTY` for an empty scene).
    pub bounds: Aabb,
    pub stats: AccelerationStats,
}

#[derive(Clone, Debug, Default)]
pub struct AccelerationStats {
    /// Triangles stored (each mesh once).
    pub mesh_triangles: usize,
    /// Triangles in the world (each instance counted).
    pub instanced_triangles: usize,
    pub primitives: usize,
    pub instances: usize,
    pub nodes: usize,
    pub build_seconds: f64,
    /// The top level's shape, and the largest bottom level's.
    pub top: Option<BuildStats>,
    pub largest_mesh: Option<BuildStats>,
}

impl AccelerationStats {
    /// Geometry plus BVH bytes per stored triangle (vertex data included).
    pub fn bytes_per_triangle(&self, gpu_bytes: u64) -> f64 {
        gpu_bytes as f64 / self.mesh_triangles.max(1) as f64
    }
}

struct BottomLevel {
    bvh: bvh::Bvh,
    root_bounds: Aabb,
}

fn points_bounds(points: impl IntoIterator<Item = Vec3>) -> Aabb {
    let mut b = Aabb::EMPTY;
    for p in points {
        b.grow(p);
    }
    b
}

fn shape_bounds(shape: &Shape) -> Aabb {
    match *shape {
        Shape::Sphere { center, radius, .. } => {
            Aabb { min: center - Vec3::splat(radius), max: center + Vec3::splat(radius) }
        }
        Shape::Quad { origin, u, v, .. } => points_bounds([origin, origin + u, origin + v, origin + u + v]),
        Shape::Triangle { v, .. } => points_bounds(v),
    }
}

pub fn gpu_primitive(shape: &Shape) -> GpuPrimitive {
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
        Shape::Triangle { v, material } => triangle_primitive(v, material),
    }
}

/// A triangle in the kernel's Primitive form; its front side faces (v1 - v0) x (v2 - v0).
pub fn triangle_primitive(v: [Vec3; 3], material: u32) -> GpuPrimitive {
    GpuPrimitive {
        a: v[0].extend(0.0).into(),
        b: (v[1] - v[0]).extend(f32::from_bits(PRIM_TRIANGLE)).into(),
        c: (v[2] - v[0]).extend(f32::from_bits(material)).into(),
    }
}

fn mesh_bottom_level(mesh: &Mesh) -> BottomLevel {
    let bounds: Vec<Aabb> =
        mesh.triangles.par_iter().map(|t| points_bounds(t.map(|i| mesh.positions[i as usize]))).collect();
    let bvh = bvh::build(&bounds);
    BottomLevel { root_bounds: bvh.nodes[0].bounds(), bvh }
}

/// Triangle `t` of `mesh` by value; its vertices are numbered from `vertex_base` in the shared
/// normal and texture coordinate arrays.
fn mesh_triangle(mesh: &Mesh, t: usize, vertex_base: u32) -> GpuMeshTriangle {
    let [a, b, c] = mesh.triangles[t];
    let p = |i: u32| mesh.positions[i as usize];
    let lane = |v: Vec3, index: u32| v.extend(f32::from_bits(index + vertex_base)).into();
    GpuMeshTriangle { v0: lane(p(a), a), e1: lane(p(b) - p(a), b), e2: lane(p(c) - p(a), c) }
}

/// Octahedral encoding into snorm16x2, x in the low half (GLSL unpackSnorm2x16; Cigolle et al. 2014).
pub fn pack_normal(n: Vec3) -> u32 {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs());
    let (x, y) =
        if n.z >= 0.0 { (n.x, n.y) } else { ((1.0 - n.y.abs()) * n.x.signum(), (1.0 - n.x.abs()) * n.y.signum()) };
    let snorm = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    snorm(x) | snorm(y) << 16
}

/// Rows of the 3x4 affine part of `m`.
fn affine_rows(m: Mat4) -> [[f32; 4]; 3] {
    let r = |i: usize| [m.x_axis[i], m.y_axis[i], m.z_axis[i], m.w_axis[i]];
    [r(0), r(1), r(2)]
}

/// World bounds of a box placed by `m` (its eight corners transformed).
fn transformed_bounds(b: &Aabb, m: Mat4) -> Aabb {
    points_bounds((0..8).map(|c| {
        let corner = Vec3::new(
            if c & 1 == 0 { b.min.x } else { b.max.x },
            if c & 2 == 0 { b.min.y } else { b.max.y },
            if c & 4 == 0 { b.min.z } else { b.max.z },
        );
        m.transform_point3(corner)
    }))
}

/// Appends a bottom level's nodes in the format `width` names, their links rebased onto the shared
/// node array and leaf ranges onto the shared primitive array, whose primitives from `prim_base`
/// on are to be stored in the order returned; returns its root's index too.
fn append_bottom_level(
    nodes: &mut Vec<WideNode>,
    bottom: &bvh::Bvh,
    prim_base: u32,
    width: BvhWidth,
) -> (u32, Vec<u32>) {
    match width {
        BvhWidth::Four => (append_nodes(nodes, bottom, prim_base), bottom.prim_order.clone()),
        BvhWidth::Eight => {
            let root = nodes.len() as u32;
            let tree = EightWideTree::new(bottom, bvh::MAX_LEAF_SIZE, root, prim_base);
            nodes.extend(tree.records());
            (root, tree.prim_order)
        }
    }
}

/// Appends a bottom level's nodes as wide nodes, rebasing child links onto the shared node array
/// and leaf ranges onto the shared primitive array; returns its root's index.
fn append_nodes(nodes: &mut Vec<WideNode>, bottom: &bvh::Bvh, prim_base: u32) -> u32 {
    let node_base = nodes.len() as u32;
    nodes.extend(wide_nodes(&bottom.nodes, bvh::MAX_LEAF_SIZE).into_iter().map(|mut n| {
        for k in 0..WIDTH {
            match n.kind(k) {
                CHILD_NONE => {}
                CHILD_INTERIOR => n.links[k] += node_base,
                _leaf => n.links[k] += prim_base,
            }
        }
        n
    }));
    node_base
}

impl Acceleration {
    /// The scene's acceleration structure in the default format: four-wide nodes throughout.
    pub fn build(scene: &Scene) -> Acceleration {
        Self::build_with(scene, BvhWidth::Four)
    }

    /// The scene's acceleration structure, its bottom levels' nodes as `width` says; the top level
    /// is four-wide either way (the walk queue and the top-level walk read it so).
    pub fn build_with(scene: &Scene, width: BvhWidth) -> Acceleration {
        let start = Instant::now();
        let group = (!scene.shapes.is_empty()).then(|| {
            let bounds: Vec<Aabb> = scene.shapes.iter().map(shape_bounds).collect();
            let bvh = bvh::build(&bounds);
            BottomLevel { root_bounds: bvh.nodes[0].bounds(), bvh }
        });
        let meshes: Vec<BottomLevel> = scene.meshes.par_iter().map(mesh_bottom_level).collect();

        // Placements: the shape group first (identity), then every mesh instance.
        let mut placements: Vec<(Option<usize>, Mat4, Aabb)> = Vec::new();
        if let Some(g) = &group {
            placements.push((None, Mat4::IDENTITY, g.root_bounds));
        }
        for inst in &scene.instances {
            let mesh = inst.mesh as usize;
            placements.push((
                Some(mesh),
                inst.transform,
                transformed_bounds(&meshes[mesh].root_bounds, inst.transform),
            ));
        }
        let top = bvh::build_single_leaves(&placements.iter().map(|p| p.2).collect::<Vec<_>>());
        // One instance a leaf, as the top level's walk reads them.
        let mut nodes = wide_nodes(&top.nodes, 1);

        let mut primitives = Vec::new();
        let mut group_root = 0;
        // The shapes in the order the primitive array holds them, which the eight-wide build
        // changes from its binary tree's (the light tree's index of hit emitters follows it).
        let mut shape_order = Vec::new();
        if let Some(g) = &group {
            (group_root, shape_order) = append_bottom_level(&mut nodes, &g.bvh, 0, width);
            primitives = shape_order.iter().map(|&i| gpu_primitive(&scene.shapes[i as usize])).collect();
        }

        let (mut triangles, mut triangle_materials) = (Vec::new(), Vec::new());
        let (mut vertex_count, mut normals, mut uvs, mut tangents) = (0u32, Vec::new(), Vec::new(), Vec::new());
        let mut colors = Vec::new();
        let mut mesh_roots = Vec::with_capacity(meshes.len());
        let mut triangle_slots = Vec::with_capacity(meshes.len());
        let mut mesh_flags = Vec::with_capacity(meshes.len());
        for (mesh, bottom) in scene.meshes.iter().zip(&meshes) {
            let (root, order) = append_bottom_level(&mut nodes, &bottom.bvh, triangles.len() as u32, width);
            mesh_roots.push(root);
            let vertex_base = vertex_count;
            vertex_count += mesh.positions.len() as u32;
            triangles.extend(order.iter().map(|&t| mesh_triangle(mesh, t as usize, vertex_base)));
            triangle_materials.extend(order.iter().map(|&t| mesh.triangle_materials[t as usize]));
            let mut slots = vec![0; mesh.triangles.len()];
            for (slot, &t) in (triangles.len() as u32 - mesh.triangles.len() as u32..).zip(&order) {
                slots[t as usize] = slot;
            }
            triangle_slots.push(slots);
            // Attribute arrays are indexed by global vertex index, so a mesh without normals
            // still needs placeholders when a later mesh has them.
            let mut flags = 0;
            if !mesh.normals.is_empty() {
                normals.resize(vertex_base as usize, 0);
                normals.extend(mesh.normals.iter().map(|&n| pack_normal(n)));
                flags |= INSTANCE_HAS_NORMALS;
            }
            if !mesh.uvs.is_empty() {
                uvs.resize(vertex_base as usize, [0.0; 2]);
                uvs.extend(mesh.uvs.iter().map(|uv| uv.to_array()));
                flags |= INSTANCE_HAS_UVS;
            }
            if !mesh.tangents.is_empty() {
                tangents.resize(vertex_base as usize, [0.0; 4]);
                tangents.extend(mesh.tangents.iter().map(|t| t.to_array()));
                flags |= INSTANCE_HAS_TANGENTS;
            }
            if !mesh.colors.is_empty() {
                colors.resize(vertex_base as usize, [1.0; 4]);
                colors.extend(mesh.colors.iter().map(|c| c.extend(1.0).to_array()));
                flags |= INSTANCE_HAS_COLORS;
            }
            mesh_flags.push(flags);
        }
        if !scene.textures.is_empty() {
            uvs.resize(vertex_count as usize, [0.0; 2]);
        }

        let instances = top
            .prim_order
            .iter()
            .map(|&p| {
                let (mesh, transform, _) = placements[p as usize];
                let info = match mesh {
                    None => [INSTANCE_PRIMITIVES, group_root, 0, 0],
                    Some(m) => [INSTANCE_MESH, mesh_roots[m], mesh_flags[m], 0],
                };
                GpuInstance {
                    world_to_object: affine_rows(transform.inverse()),
                    object_to_world: affine_rows(transform),
                    info,
                }
            })
            .collect::<Vec<_>>();

        let instance_meshes = top.prim_order.iter().map(|&p| placements[p as usize].0.map(|m| m as u32)).collect();
        // Placements list the shape group (when there is one) before the scene's instances.
        let first_instance = usize::from(group.is_some());
        let instance_sources = top
            .prim_order
            .iter()
            .map(|&p| placements[p as usize].0.map(|_| (p as usize - first_instance) as u32))
            .collect();
        let stats = AccelerationStats {
            mesh_triangles: triangles.len(),
            instanced_triangles: scene.instances.iter().map(|i| scene.meshes[i.mesh as usize].triangles.len()).sum(),
            primitives: primitives.len(),
            instances: instances.len(),
            nodes: if instances.is_empty() { 0 } else { nodes.len() },
            build_seconds: start.elapsed().as_secs_f64(),
            top: (!instances.is_empty()).then(|| top.stats()),
            largest_mesh: meshes.iter().max_by_key(|m| m.bvh.prim_order.len()).map(|m| m.bvh.stats()),
        };
        let bounds = if instances.is_empty() { Aabb::EMPTY } else { top.nodes[0].bounds() };
        Acceleration {
            nodes,
            bvh_width: width,
            instances,
            instance_meshes,
            instance_sources,
            primitives,
            shape_order,
            triangles,
            triangle_materials,
            triangle_slots,
            normals,
            uvs,
            tangents,
            colors,
            bounds,
            stats,
        }
    }

    pub fn gpu_bytes(&self) -> u64 {
        (std::mem::size_of_val(&self.nodes[..])
            + std::mem::size_of_val(&self.instances[..])
            + std::mem::size_of_val(&self.primitives[..])
            + std::mem::size_of_val(&self.triangles[..])
            + std::mem::size_of_val(&self.triangle_materials[..])
            + std::mem::size_of_val(&self.normals[..])
            + std::mem::size_of_val(&self.uvs[..])
            + std::mem::size_of_val(&self.tangents[..])
            + std::mem::size_of_val(&self.colors[..])) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Decodes like unpack_normal in shaders/surface.glsl.
    fn unpack_normal(p: u32) -> Vec3 {
        let s = |v: u32| ((v & 0xffff) as u16 as i16 as f32 / 32767.0).max(-1.0);
        let (x, y) = (s(p), s(p >> 16));
        let mut n = Vec3::new(x, y, 1.0 - x.abs() - y.abs());
        if n.z < 0.0 {
            let (ox, oy) = (n.x, n.y);
            n.x = (1.0 - oy.abs()) * if ox >= 0.0 { 1.0 } else { -1.0 };
            n.y = (1.0 - ox.abs()) * if oy >= 0.0 { 1.0 } else { -1.0 };
        }
        n.normalize()
    }

    #[test]
    fn packed_normals_round_trip_within_a_hundredth_of_a_degree() {
        // Angles from atan2(|a x b|, a . b): acos of a dot product near 1 has no precision left.
        let mut worst: f32 = 0.0;
        for i in 0..2000 {
            // A spiral over the whole sphere, poles and axes included.
            let z = 1.0 - 2.0 * (i as f32 / 1999.0);
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = i as f32 * 2.399_963;
            for n in [Vec3::new(r * phi.cos(), r * phi.sin(), z), Vec3::X, -Vec3::Y, -Vec3::Z] {
                let m = unpack_normal(pack_normal(n));
                worst = worst.max(m.cross(n).length().atan2(m.dot(n)).to_degrees());
            }
        }
        assert!(worst < 0.01, "worst error {worst} degrees");
    }

    #[test]
    fn affine_rows_apply_like_the_matrix() {
        let m = Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 3.0, 0.5),
            glam::Quat::from_rotation_y(0.7),
            Vec3::new(1.0, -2.0, 4.0),
        );
        let rows = affine_rows(m);
        let p = Vec3::new(0.3, -1.2, 2.5);
        let by_rows = Vec3::from_array(std::array::from_fn(|i| Vec3::from_slice(&rows[i][..3]).dot(p) + rows[i][3]));
        assert!((by_rows - m.transform_point3(p)).length() < 1e-5);
    }
}
