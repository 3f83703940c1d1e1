//! Triangle meshes from OBJ files (via tobj), transformed into world space.

use anyhow::{anyhow, bail, Result};
use glam::{Mat4, Vec3};
use std::path::Path;

/// World-space triangles of every object in an OBJ file. Degenerate (zero-area) triangles are
/// dropped with a note on stderr; non-finite vertices and out-of-range indices are errors.
pub fn load_obj(path: &Path, transform: Mat4) -> Result<Vec<[Vec3; 3]>> {
    let options = tobj::LoadOptions { triangulate: true, single_index: false, ..Default::default() };
    let (models, _materials) = tobj::load_obj(path, &options).map_err(|e| anyhow!("{}: cannot load OBJ: {e}", path.display()))?;
    let mut triangles = Vec::new();
    let mut degenerate = 0usize;
    for model in &models {
        let mesh = &model.mesh;
        let positions = &mesh.positions;
        if positions.iter().any(|p| !p.is_finite()) {
            bail!("{}: object '{}' has a non-finite vertex coordinate", path.display(), model.name);
        }
        let vertex_count = positions.len() / 3;
        let vertex = |i: u32| -> Result<Vec3> {
            let i = i as usize;
            if i >= vertex_count {
                bail!("{}: object '{}' has a face index {} past its {} vertices", path.display(), model.name, i + 1, vertex_count);
            }
            Ok(transform.transform_point3(Vec3::new(positions[3 * i], positions[3 * i + 1], positions[3 * i + 2])))
        };
        for face in mesh.indices.chunks_exact(3) {
            let v = [vertex(face[0])?, vertex(face[1])?, vertex(face[2])?];
            if (v[1] - v[0]).cross(v[2] - v[0]).length_squared() > 0.0 {
                triangles.push(v);
            } else {
                degenerate += 1;
            }
        }
    }
    if degenerate > 0 {
        eprintln!("caustica: {}: dropped {degenerate} zero-area triangle(s)", path.display());
    }
    if triangles.is_empty() {
        bail!("{}: the OBJ file has no triangles", path.display());
    }
    Ok(triangles)
}
