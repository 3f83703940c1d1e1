//! Where the light tree meets the kernel's lights: the one array of u32 (`light_tree_index`) by
//! which the kernel finds a light's leaf, and the light an emitter hit by BSDF sampling is, so
//! that it can evaluate that light's pick probability for the MIS weight
//! (shaders/light_tree.glsl). The kernel's area lights are listed (scene_data.rs `world_lights`)
//! as the scene's emissive shapes in `Scene::shapes` order, then each scene instance's emissive
//! mesh triangles in `Mesh::triangles` order; then the point, spot and directional lights.
//!
//! Layout, for L lights, I instances, P shapes and T mesh triangles (the kernel's arrays):
//! - `[0, L)`: per light, its leaf in the tree (LIGHT_TREE_NONE: none);
//! - `[L, L + 2I)`: per instance (in `instances` order), a pair: the light its table's entries
//!   count from, and where its table starts in this array;
//! - the shapes' table (P entries, in `prims` order): each shape's light (LIGHT_TREE_NONE for a
//!   shape that does not emit); the light of a hit on a shape is pair.x (0) + this;
//! - the mesh triangles' table (T entries, in `mesh_triangles` order; left out when no mesh
//!   emits): each emissive triangle's rank among its mesh's emissive triangles, so that the light
//!   of a hit on instance k's triangle is pair.x (the instance's first light) + this. Instances of
//!   one mesh share the table.

use super::acceleration::Acceleration;
use super::layout::LIGHT_TREE_NONE;
use super::light_tree::LightTree;
use crate::scene::Scene;

/// The light tree as the kernel reads it: its nodes and the index above.
#[derive(Clone, Debug)]
pub struct KernelLightTree {
    pub tree: LightTree,
    pub index: Vec<u32>,
}

impl KernelLightTree {
    /// The index for `tree` over `scene`'s lights, as `acceleration` places them. `emissive`
    /// tells an emissive material.
    pub fn new(tree: LightTree, scene: &Scene, acceleration: &Acceleration, emissive: impl Fn(u32) -> bool) -> Self {
        let mut index = tree.leaf_of_light.clone();
        let instance_table = index.len();
        let instances = acceleration.instance_sources.len();
        let shapes_start = (instance_table + 2 * instances) as u32;
        let triangles_start = shapes_start + acceleration.primitives.len() as u32;

        // Each emissive shape's light, in scene order.
        let mut shape_light = vec![LIGHT_TREE_NONE; scene.shapes.len()];
        let mut next_light = 0u32;
        for (s, shape) in scene.shapes.iter().enumerate() {
            if emissive(shape.material()) {
                shape_light[s] = next_light;
                next_light += 1;
            }
        }
        // Each scene instance's first light, after the shapes' and the earlier instances'.
        let mut first_light = Vec::with_capacity(scene.instances.len());
        for inst in &scene.instances {
            first_light.push(next_light);
            let mesh = &scene.meshes[inst.mesh as usize];
            next_light += mesh.triangle_materials.iter().filter(|&&m| emissive(m)).count() as u32;
        }
        for source in &acceleration.instance_sources {
            index.extend(match source {
                None => [0, shapes_start],
                Some(i) => [first_light[*i as usize], triangles_start],
            });
        }
        index.extend(acceleration.shape_order.iter().map(|&s| shape_light[s as usize]));
        if scene.meshes.iter().any(|m| m.triangle_materials.iter().any(|&m| emissive(m))) {
            let mut ranks = vec![LIGHT_TREE_NONE; acceleration.triangles.len()];
            for (mesh, slots) in scene.meshes.iter().zip(&acceleration.triangle_slots) {
                let emitters = mesh.triangle_materials.iter().zip(slots).filter(|(&m, _)| emissive(m));
                for (rank, (_, &slot)) in emitters.enumerate() {
                    ranks[slot as usize] = rank as u32;
                }
            }
            index.extend(ranks);
        }
        Self { tree, index }
    }

    /// The light of a hit on entry `prim` of instance `instance`'s table, as the kernel finds it
    /// (shaders/light_tree.glsl `hit_light`).
    pub fn hit_light(&self, instance: u32, prim: u32) -> u32 {
        let pair = self.tree.leaf_of_light.len() + 2 * instance as usize;
        let (base, table) = (self.index[pair], self.index[pair + 1]);
        base.wrapping_add(self.index[(table + prim) as usize])
    }

    /// Bytes the kernel's copy takes.
    pub fn gpu_bytes(&self) -> u64 {
        self.tree.gpu_bytes() + std::mem::size_of_val(&self.index[..]) as u64
    }
}
