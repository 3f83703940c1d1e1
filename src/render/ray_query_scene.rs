//! The scene as the ray-query traversal sees it (shaders/ray_query.glsl): one bottom-level
//! acceleration structure a mesh, stored once however often it is placed, one for the scene's own
//! shapes as boxes, and the top level over the instances, in the order of the kernel's
//! `instances` so that a hit's instance index is the same whichever traversal found it.

use super::features::SceneFeatures;
use super::layout::{GpuPrimitive, ALPHA_OPAQUE, PRIM_QUAD, PRIM_SPHERE, PRIM_TRIANGLE};
use super::scene_data::SceneData;
use crate::gpu::{BottomGeometry, GpuContext, Placement, SceneStructure, MAX_CUSTOM_INDEX};
use crate::scene::Scene;
use anyhow::{bail, Result};
use glam::Vec3;

/// Cull masks, as ray_query.glsl's RAY_QUERY_MESHES and RAY_QUERY_SHAPES.
const MESH_MASK: u8 = 1;
const SHAPE_MASK: u8 = 2;

/// A shape's box, widened a little on every axis: the device's box test need only be
/// conservative, and a flat quad's or triangle's box has no thickness of its own. The exact test
/// decides every hit (intersect.glsl).
fn shape_box(p: &GpuPrimitive) -> [[f32; 3]; 2] {
    let v = |a: [f32; 4]| Vec3::new(a[0], a[1], a[2]);
    let (a, b, c) = (v(p.a), v(p.b), v(p.c));
    let points: Vec<Vec3> = match p.b[3].to_bits() {
        PRIM_SPHERE => vec![a - Vec3::splat(p.a[3]), a + Vec3::splat(p.a[3])],
        PRIM_QUAD => vec![a, a + b, a + c, a + b + c],
        PRIM_TRIANGLE => vec![a, a + b, a + c],
        // An unknown kind has no surface (intersect.glsl): an empty box far away is never met.
        _ => vec![Vec3::splat(f32::MAX / 4.0)],
    };
    let (min, max) = points.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &q| (lo.min(q), hi.max(q)));
    let pad = 1e-5 * ((max - min).max_element() + min.abs().max(max.abs()).max_element()) + 1e-30;
    [(min - Vec3::splat(pad)).to_array(), (max + Vec3::splat(pad)).to_array()]
}

/// Builds the structures of `scene` (uploaded as `data`, whose kernel was compiled for `features`).
pub fn build(ctx: &GpuContext, scene: &Scene, data: &SceneData, features: &SceneFeatures) -> Result<SceneStructure> {
    let a = &data.acceleration;
    let alpha_material = |m: u32| data.materials.get(m as usize).is_some_and(|m| m.alpha[3].to_bits() != ALPHA_OPAQUE);
    let mut bottoms = Vec::new();
    // Per mesh: its bottom level and where its triangles begin in `mesh_triangles`.
    let mut mesh_levels: Vec<Option<(usize, u32)>> = vec![None; scene.meshes.len()];
    for &mesh in a.instance_meshes.iter().flatten() {
        let m = mesh as usize;
        if mesh_levels[m].is_some() {
            continue;
        }
        let (source, slots) = (&scene.meshes[m], &a.triangle_slots[m]);
        let first = slots.iter().copied().min().unwrap_or(0);
        if first as usize + slots.len() > MAX_CUSTOM_INDEX as usize + 1 {
            bail!(
                "{}: ray queries reach {} mesh triangles at most ({} with mesh {m}); use --traversal compute",
                scene.name,
                MAX_CUSTOM_INDEX as usize + 1,
                first as usize + slots.len()
            );
        }
        // The triangles in the order of `mesh_triangles`, by their own vertices.
        let mut positions = vec![[0.0f32; 3]; 3 * slots.len()];
        for (t, &slot) in slots.iter().enumerate() {
            let at = 3 * (slot - first) as usize;
            for (k, &vertex) in source.triangles[t].iter().enumerate() {
                positions[at + k] = source.positions[vertex as usize].to_array();
            }
        }
        let opaque = !features.alpha || !slots.iter().any(|&slot| alpha_material(a.triangle_materials[slot as usize]));
        mesh_levels[m] = Some((bottoms.len(), first));
        bottoms.push(BottomGeometry::Triangles { positions, opaque });
    }
    let shapes_level = bottoms.len();
    bottoms.push(BottomGeometry::Boxes(a.primitives.iter().map(shape_box).collect()));
    let placements = a
        .instances
        .iter()
        .zip(&a.instance_meshes)
        .map(|(instance, mesh)| match mesh {
            Some(m) => {
                let (bottom, first) = mesh_levels[*m as usize].expect("every placed mesh has its level");
                Placement { bottom, object_to_world: instance.object_to_world, custom_index: first, mask: MESH_MASK }
            }
            // The shapes are met by the query only where the walk would meet them; a scene's few
            // shapes are tested before it (bvh.glsl).
            None => Placement {
                bottom: shapes_level,
                object_to_world: instance.object_to_world,
                custom_index: 0,
                mask: if features.walked_shapes() { SHAPE_MASK } else { 0 },
            },
        })
        .collect::<Vec<_>>();
    SceneStructure::build(ctx, &bottoms, &placements)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_boxes_hold_their_shapes_with_room_on_flat_axes() {
        let quad = crate::render::acceleration::gpu_primitive(&crate::scene::Shape::Quad {
            origin: Vec3::new(1.0, 2.0, 3.0),
            u: Vec3::new(2.0, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, -1.0),
            material: 0,
        });
        let [min, max] = shape_box(&quad);
        assert!(min[0] < 1.0 && max[0] > 3.0 && min[2] < 2.0 && max[2] > 3.0, "{min:?} {max:?}");
        assert!(min[1] < 2.0 && max[1] > 2.0, "the flat axis has some thickness: {min:?} {max:?}");
        let sphere = crate::render::acceleration::gpu_primitive(&crate::scene::Shape::Sphere {
            center: Vec3::ZERO,
            radius: 0.5,
            material: 0,
        });
        let [min, max] = shape_box(&sphere);
        assert!(min.iter().all(|&m| m < -0.5) && max.iter().all(|&m| m > 0.5), "{min:?} {max:?}");
    }
}
