//! Tangents for normal maps, by MikkTSpace (the `mikktspace` crate): what glTF asks of files
//! without their own ("client implementations SHOULD calculate tangents using default MikkTSpace
//! algorithms") and what normal maps are baked against, so a map shows here as in other viewers.
//!
//! glTF's tangent frame has the bitangent towards the top of the image, where v falls (its v runs
//! down the image; OBJ's are flipped to that on load), and normal maps are made that way (green is
//! up). MikkTSpace's bitangent follows growing v, so it is handed 1 - v, as glTF viewers do.
//!
//! MikkTSpace gives a tangent per corner of a face. Corners of one vertex mostly agree, but not
//! where the texture mapping folds (mirrored halves sharing an edge): such a vertex is split, one
//! copy per distinct tangent, so every corner keeps the tangent it was given.

use super::MeshData;
use glam::{Vec3, Vec4};
use std::collections::HashMap;

/// The mesh seen by MikkTSpace: its faces (triangles) and the tangent of every corner.
struct Corners<'a> {
    mesh: &'a MeshData,
    tangents: Vec<[f32; 4]>,
}

impl mikktspace::Geometry for Corners<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.triangles.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.mesh.triangles[face][vert] as usize].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.mesh.triangles[face][vert] as usize].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        let uv = self.mesh.uvs[self.mesh.triangles[face][vert] as usize];
        [uv.x, 1.0 - uv.y]
    }

    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        self.tangents[3 * face + vert] = tangent;
    }
}

/// Gives `mesh` (which has normals and texture coordinates) MikkTSpace tangents, splitting the
/// vertices whose corners got different ones. False, leaving the mesh as it was, when MikkTSpace
/// fails.
pub fn generate(mesh: &mut MeshData) -> bool {
    debug_assert!(mesh.normals.len() == mesh.positions.len() && mesh.uvs.len() == mesh.positions.len());
    let mut corners = Corners { mesh, tangents: vec![[0.0; 4]; 3 * mesh.triangles.len()] };
    if !mikktspace::generate_tangents(&mut corners) {
        return false;
    }
    let corner_tangents = corners.tangents;
    let mut tangents = vec![Vec4::ZERO; mesh.positions.len()];
    let mut assigned = vec![false; mesh.positions.len()];
    // (vertex, tangent bits) → the vertex's copy with that tangent.
    let mut copies: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    for (corner, tangent) in corner_tangents.iter().enumerate() {
        let v = mesh.triangles[corner / 3][corner % 3];
        let tangent = Vec4::from_array(*tangent);
        // A degenerate mapping leaves no direction: any unit tangent will do, the map's x and y
        // then tilt along arbitrary axes on that corner only.
        let tangent = if tangent.truncate().length_squared() > 0.0 { tangent } else { Vec3::X.extend(1.0) };
        let key = (v, tangent.to_array().map(f32::to_bits));
        let index = match copies.get(&key) {
            Some(&index) => index,
            None if !assigned[v as usize] => {
                assigned[v as usize] = true;
                tangents[v as usize] = tangent;
                v
            }
            None => {
                mesh.positions.push(mesh.positions[v as usize]);
                mesh.normals.push(mesh.normals[v as usize]);
                mesh.uvs.push(mesh.uvs[v as usize]);
                if !mesh.colors.is_empty() {
                    mesh.colors.push(mesh.colors[v as usize]);
                }
                tangents.push(tangent);
                mesh.positions.len() as u32 - 1
            }
        };
        copies.insert(key, index);
        mesh.triangles[corner / 3][corner % 3] = index;
    }
    mesh.tangents = tangents;
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec2;

    /// A unit square in the xy plane facing +z, with texture coordinates `uv(position)`.
    fn square(uv: impl Fn(Vec3) -> Vec2) -> MeshData {
        let positions = vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        MeshData {
            uvs: positions.iter().map(|&p| uv(p)).collect(),
            normals: vec![Vec3::Z; 4],
            positions,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            triangle_materials: vec![0, 0],
            tangents: Vec::new(),
            colors: Vec::new(),
        }
    }

    /// The image upright on the square (u along +x, v down the image, so along -y): the tangent
    /// is +x and the bitangent cross(+z, +x) = +y, the image's up, so the sign is +1.
    #[test]
    fn the_tangent_follows_u_and_the_bitangent_the_image_s_up() {
        let mut mesh = square(|p| Vec2::new(p.x, 1.0 - p.y));
        assert!(generate(&mut mesh));
        assert_eq!(mesh.positions.len(), 4, "one tangent a vertex: nothing to split");
        for t in &mesh.tangents {
            assert!((t.truncate() - Vec3::X).length() < 1e-5 && t.w == 1.0, "{t}");
        }
        // The image upside down flips the bitangent (the sign), not the tangent.
        let mut flipped = square(|p| Vec2::new(p.x, p.y));
        assert!(generate(&mut flipped));
        for t in &flipped.tangents {
            assert!((t.truncate() - Vec3::X).length() < 1e-5 && t.w == -1.0, "{t}");
        }
    }

    /// The two triangles map the texture mirrored onto each other across the diagonal's vertices:
    /// those get one copy per tangent, and every corner keeps its triangle's tangent.
    #[test]
    fn vertices_where_the_mapping_folds_are_split() {
        let mut mesh = square(|p| Vec2::new(p.x, p.y));
        mesh.uvs[3] = Vec2::new(1.0, 0.0);
        assert!(generate(&mut mesh));
        assert_eq!(mesh.tangents.len(), mesh.positions.len());
        assert!(mesh.positions.len() > 4, "the shared vertices were split");
        for triangle in &mesh.triangles {
            let t = triangle.map(|v| mesh.tangents[v as usize]);
            assert!(t[0] == t[1] && t[1] == t[2], "a triangle's corners share its tangent: {t:?}");
        }
    }
}
