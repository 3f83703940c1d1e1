//! glTF skins, posed once on load: each vertex of a skinned mesh moves by the blend of its joints'
//! matrices, joint world transform × inverse bind matrix, weighted by WEIGHTS_n over JOINTS_n
//! (glTF's linear blend skinning). The joints stand at their nodes' own transforms (the pose the
//! file is saved in: the bind pose, unless the author posed the skeleton); animations do not
//! move them. The skinned mesh lands in world space, and the skinned node's own transform is
//! ignored, as glTF says.

use glam::{Mat3, Mat4, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions, Iter};

use super::gltf_accessors::{read_floats, AccessorLimits};
use super::MeshData;

/// How many joints may sway one vertex: JOINTS_0 / WEIGHTS_0 and JOINTS_1 / WEIGHTS_1.
const INFLUENCE_SETS: u32 = 2;

/// The joints (indices into the skin's joint list) and weights of every vertex of a merged mesh;
/// empty when no primitive of the mesh has JOINTS_0.
#[derive(Debug, Default, Clone)]
pub(super) struct VertexInfluences {
    pub(super) influences: Vec<Vec<(u16, f32)>>,
}

impl VertexInfluences {
    /// Appends the influences of `primitive`'s `vertices` vertices: none where it has no joints.
    pub(super) fn append(
        &mut self,
        primitive: &gltf::Primitive,
        vertices: usize,
        limits: &mut AccessorLimits,
    ) -> Result<(), String> {
        let p = primitive.index();
        let first = self.influences.len();
        self.influences.resize(first + vertices, Vec::new());
        for set in 0..INFLUENCE_SETS {
            let (Some(joints), Some(weights)) =
                (primitive.get(&gltf::Semantic::Joints(set)), primitive.get(&gltf::Semantic::Weights(set)))
            else {
                continue;
            };
            limits
                .admit(&joints, Dimensions::Vec4, &[DataType::U8, DataType::U16])
                .map_err(|m| format!("primitive {p}: JOINTS_{set} {m}"))?;
            limits
                .admit(&weights, Dimensions::Vec4, &[DataType::F32, DataType::U8, DataType::U16])
                .map_err(|m| format!("primitive {p}: WEIGHTS_{set} {m}"))?;
            let outside =
                || format!("primitive {p}: the JOINTS_{set} or WEIGHTS_{set} accessor lies outside its buffer");
            let data = |buffer: gltf::Buffer| limits.buffers().get(buffer.index()).map(|b| b.as_slice());
            let joints: Vec<[u16; 4]> = match joints.data_type() {
                DataType::U8 => {
                    Iter::<[u8; 4]>::new(joints, data).ok_or_else(outside)?.map(|j| j.map(u16::from)).collect()
                }
                _ => Iter::<[u16; 4]>::new(joints, data).ok_or_else(outside)?.collect(),
            };
            let weights = read_floats::<4>(weights, limits.buffers()).ok_or_else(outside)?;
            if joints.len() != vertices || weights.len() != vertices {
                return Err(format!("primitive {p}: JOINTS_{set} or WEIGHTS_{set} has not one value a vertex"));
            }
            for (v, (j, w)) in joints.iter().zip(&weights).enumerate() {
                for k in 0..4 {
                    if w[k] != 0.0 {
                        self.influences[first + v].push((j[k], w[k]));
                    }
                }
            }
        }
        Ok(())
    }

    pub(super) fn is_empty(&self) -> bool {
        self.influences.iter().all(Vec::is_empty)
    }
}

/// `mesh` posed by `skin` in world space: `joint_worlds` are the world transforms of the skin's
/// joints (by the skin's order), `node_world` the skinned node's, which places the vertices that no
/// joint sways. Normals and tangents turn with their vertex's blended matrix.
pub(super) fn pose(
    mesh: &MeshData,
    influences: &VertexInfluences,
    skin: &gltf::Skin,
    joint_worlds: &[Mat4],
    node_world: Mat4,
    limits: &mut AccessorLimits,
) -> Result<MeshData, String> {
    let s = skin.index();
    let inverse_binds: Vec<Mat4> = match skin.inverse_bind_matrices() {
        Some(accessor) => {
            limits
                .admit(&accessor, Dimensions::Mat4, &[DataType::F32])
                .map_err(|m| format!("skin {s}: inverseBindMatrices {m}"))?;
            let data = |buffer: gltf::Buffer| limits.buffers().get(buffer.index()).map(|b| b.as_slice());
            Iter::<[[f32; 4]; 4]>::new(accessor, data)
                .ok_or_else(|| format!("skin {s}: the inverseBindMatrices accessor lies outside its buffer"))?
                .map(|m| Mat4::from_cols_array_2d(&m))
                .collect()
        }
        None => vec![Mat4::IDENTITY; joint_worlds.len()],
    };
    if inverse_binds.len() < joint_worlds.len() {
        return Err(format!(
            "skin {s} has {} joints but {} inverse bind matrices",
            joint_worlds.len(),
            inverse_binds.len()
        ));
    }
    let joint_matrices: Vec<Mat4> = joint_worlds.iter().zip(&inverse_binds).map(|(j, b)| *j * *b).collect();
    if joint_matrices.iter().any(|m| !m.is_finite()) {
        return Err(format!("skin {s}: a joint matrix is not finite"));
    }
    let mut posed = mesh.clone();
    for (v, influences) in influences.influences.iter().enumerate().take(mesh.positions.len()) {
        let total: f32 = influences.iter().map(|&(_, w)| w).sum();
        let matrix = if total > 0.0 {
            let mut blended = Mat4::ZERO;
            for &(joint, weight) in influences {
                let m = joint_matrices.get(joint as usize).ok_or_else(|| {
                    format!("skin {s}: vertex {v} names joint {joint} but the skin has {}", joint_matrices.len())
                })?;
                // Weights normalized to sum 1, as glTF asks of them (quantized ones miss by a step).
                blended += *m * (weight / total);
            }
            blended
        } else {
            node_world
        };
        posed.positions[v] = matrix.transform_point3(mesh.positions[v]);
        let linear = Mat3::from_mat4(matrix);
        if let Some(n) = posed.normals.get_mut(v) {
            *n = (linear.inverse().transpose() * mesh.normals[v]).normalize_or_zero();
        }
        if let Some(t) = posed.tangents.get_mut(v) {
            let direction = (linear * mesh.tangents[v].truncate()).normalize_or_zero();
            *t = direction.extend(mesh.tangents[v].w);
        }
    }
    if let Some(i) = posed.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("skin {s}: posed vertex {i} is not finite"));
    }
    // A joint matrix that flattens the mesh leaves no normal: flat shading is always right.
    if posed.normals.contains(&Vec3::ZERO) {
        posed.normals.clear();
        posed.tangents.clear();
    }
    if posed.tangents.iter().any(|t| t.truncate() == Vec3::ZERO) {
        posed.tangents = Vec::<Vec4>::new();
    }
    Ok(posed)
}
