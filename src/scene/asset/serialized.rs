//! Mitsuba's `.serialized` meshes: several zlib-compressed triangle meshes in one file, picked by
//! `shape_index`. The layout is the one Mitsuba 3 documents and reads (src/shapes/serialized.cpp):
//! little endian; per mesh an uncompressed header (u16 0x041C, u16 version 3 or 4), then a zlib
//! stream of u32 flags, (version 4) a NUL-terminated name, u64 vertex and u64 triangle counts,
//! positions, normals (flag 0x1), texture coordinates (0x2), colours (0x8), all f32 or, with flag
//! 0x2000, f64, and u32 indices. The file ends with each mesh's byte offset (u64 in version 4, u32
//! in version 3) and the u32 number of meshes.
//!
//! Texture coordinates are kept as stored: Mitsuba reads them with (0, 0) at the image's top-left
//! corner, caustica's convention too. A mesh without normals gets angle-weighted vertex normals,
//! as Mitsuba computes them (smooth shading). The face-normals flag (0x10) is ignored, as Mitsuba 3
//! ignores it (only the shape's `face_normals` parameter turns its normals off).

use std::io::Read;
use std::path::Path;

use flate2::read::ZlibDecoder;
use glam::{Vec2, Vec3};

use super::{single_mesh_asset, unit_normals, Asset, AssetError, Material, MeshData};
use crate::input_file::{InputFiles, InputKind};

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_UVS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
const DOUBLE_PRECISION: u32 = 0x2000;
/// The longest mesh name read (version 4): names are labels, never this long in a real file.
const MAX_NAME_BYTES: usize = 1 << 16;
/// How many times its compressed size a mesh's data may be. DEFLATE expands at most about 1032
/// times, but only data as repetitive as a zlib bomb's comes near that: meshes' floats and
/// indices compress a few times at most, so counts promising more are refused before any of it is
/// decompressed (1.2 MB declaring 50M triangles, all one triangle, exhausted the memory).
const MAX_MESH_RATIO: u64 = 100;

/// Mesh `shape_index` of the file at `path`, with the default grey material.
pub(super) fn load(files: &InputFiles, path: &Path, shape_index: u32) -> Result<Asset, AssetError> {
    let bytes = files.read(path, InputKind::Mesh)?;
    let mesh = decode(&bytes, shape_index)
        .map_err(|message| AssetError::invalid(path, format!("shape_index {shape_index}: {message}")))?;
    let mut mesh = mesh;
    let dropped = mesh.drop_degenerate();
    Ok(single_mesh_asset(mesh, vec![Material::default()], Vec::new(), dropped))
}

/// Mesh `shape_index` of a whole `.serialized` file's bytes; the error is the reason alone.
pub fn decode(bytes: &[u8], shape_index: u32) -> Result<MeshData, String> {
    let version = header(bytes, 0)?;
    let start = if shape_index == 0 { 0 } else { mesh_offset(bytes, version, shape_index)? };
    if header(bytes, start)? != version {
        return Err(format!("mesh at byte {start} has another format version than the file"));
    }
    let compressed = &bytes[start + 4..];
    // What the counts may promise: no more than the rest of the file can inflate to.
    let budget = (compressed.len() as u64).saturating_mul(MAX_MESH_RATIO);
    let mut stream = Stream(ZlibDecoder::new(compressed));
    let flags = u32::from_le_bytes(stream.array()?);
    if version == 4 {
        stream.name()?;
    }
    let vertex_count = u64::from_le_bytes(stream.array()?);
    let triangle_count = u64::from_le_bytes(stream.array()?);
    let scalar: usize = if flags & DOUBLE_PRECISION != 0 { 8 } else { 4 };
    let per_vertex = 3
        + 3 * u64::from(flags & HAS_NORMALS != 0)
        + 2 * u64::from(flags & HAS_UVS != 0)
        + 3 * u64::from(flags & HAS_COLORS != 0);
    let promised = u128::from(vertex_count) * u128::from(per_vertex * scalar as u64) + u128::from(triangle_count) * 12;
    if vertex_count > u64::from(u32::MAX) || promised > u128::from(budget) {
        return Err(format!("{vertex_count} vertices and {triangle_count} triangles are more than {MAX_MESH_RATIO} times the {} compressed bytes that follow (a corrupt file or a zlib bomb)", compressed.len()));
    }
    let vertex_count = vertex_count as usize;
    let positions = stream.floats(vertex_count * 3, scalar)?;
    let normals = if flags & HAS_NORMALS != 0 { stream.floats(vertex_count * 3, scalar)? } else { Vec::new() };
    let uvs = if flags & HAS_UVS != 0 { stream.floats(vertex_count * 2, scalar)? } else { Vec::new() };
    if flags & HAS_COLORS != 0 {
        stream.floats(vertex_count * 3, scalar)?;
    }
    let indices = stream.bytes(triangle_count as usize * 12)?;

    let mut mesh = MeshData {
        positions: positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect(),
        ..MeshData::default()
    };
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(format!("vertex {i} has a non-finite position {}", mesh.positions[i]));
    }
    for (t, corners) in indices.chunks_exact(12).enumerate() {
        let triangle = [0, 4, 8].map(|k| u32::from_le_bytes(corners[k..k + 4].try_into().expect("4 bytes")));
        if let Some(&bad) = triangle.iter().find(|&&i| i as usize >= vertex_count) {
            return Err(format!("triangle {t} uses vertex {bad} but the mesh has {vertex_count} vertices"));
        }
        mesh.triangles.push(triangle);
        mesh.triangle_materials.push(0);
    }
    let uvs: Vec<Vec2> = uvs.chunks_exact(2).map(|uv| Vec2::new(uv[0], uv[1])).collect();
    if uvs.iter().all(|uv| uv.is_finite()) {
        mesh.uvs = uvs;
    }
    mesh.normals = if normals.is_empty() {
        angle_weighted_normals(&mesh)
    } else {
        unit_normals(&normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2])).collect::<Vec<_>>())
    };
    Ok(mesh)
}

/// The format version of the mesh header at byte `at`.
fn header(bytes: &[u8], at: usize) -> Result<u16, String> {
    let Some(h) = bytes.get(at..at + 4) else {
        return Err(format!("truncated: no mesh header at byte {at} of {}", bytes.len()));
    };
    let (magic, version) = (u16::from_le_bytes([h[0], h[1]]), u16::from_le_bytes([h[2], h[3]]));
    if magic != MAGIC {
        return Err(format!(
            "not a Mitsuba serialized mesh (format id {magic:#06x} at byte {at}, expected {MAGIC:#06x})"
        ));
    }
    if !matches!(version, 3 | 4) {
        return Err(format!("format version {version} is not supported (3, 4)"));
    }
    Ok(version)
}

/// Where mesh `shape_index` starts, from the dictionary at the end of the file.
fn mesh_offset(bytes: &[u8], version: u16, shape_index: u32) -> Result<usize, String> {
    let truncated = || "truncated: the file ends before its dictionary of meshes".to_owned();
    let count_at = bytes.len().checked_sub(4).ok_or_else(truncated)?;
    let count = u32::from_le_bytes(bytes[count_at..].try_into().expect("4 bytes"));
    if shape_index >= count {
        return Err(format!("out of range: the file has {count} meshes (0 to {})", count.saturating_sub(1)));
    }
    let width = if version == 4 { 8 } else { 4 };
    let table = count_at.checked_sub(count as usize * width).ok_or_else(truncated)?;
    let entry = &bytes[table + shape_index as usize * width..][..width];
    let offset = if width == 8 {
        u64::from_le_bytes(entry.try_into().expect("8 bytes"))
    } else {
        u64::from(u32::from_le_bytes(entry.try_into().expect("4 bytes")))
    };
    usize::try_from(offset).ok().filter(|&o| o < table).ok_or_else(|| {
        format!("the dictionary puts mesh {shape_index} at byte {offset}, past the meshes' {table} bytes")
    })
}

/// The decompressed stream of one mesh.
struct Stream<'a>(ZlibDecoder<&'a [u8]>);

impl Stream<'_> {
    /// Exactly `n` bytes: memory grows only as decompressed data arrives, so a count that lies
    /// fails at the end of the data instead of allocating what it promised.
    fn bytes(&mut self, n: usize) -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        (&mut self.0).take(n as u64).read_to_end(&mut out).map_err(|e| format!("corrupt compressed data: {e}"))?;
        if out.len() < n {
            return Err(format!("truncated: the compressed data ends {} bytes early", n - out.len()));
        }
        Ok(out)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], String> {
        Ok(self.bytes(N)?.try_into().expect("N bytes"))
    }

    /// `count` numbers of `scalar` bytes (4: f32, 8: f64) as f32.
    fn floats(&mut self, count: usize, scalar: usize) -> Result<Vec<f32>, String> {
        let bytes = self.bytes(count * scalar)?;
        Ok(match scalar {
            8 => bytes.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")) as f32).collect(),
            _ => bytes.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().expect("4 bytes"))).collect(),
        })
    }

    /// Skips the NUL-terminated mesh name.
    fn name(&mut self) -> Result<(), String> {
        for _ in 0..MAX_NAME_BYTES {
            if self.array::<1>()? == [0] {
                return Ok(());
            }
        }
        Err(format!("the mesh name runs past {MAX_NAME_BYTES} bytes (corrupt file)"))
    }
}

/// Each vertex's normal as the sum of its triangles' unit normals weighted by the triangle's angle
/// at the vertex. A vertex no triangle gives a direction (unused, or where normals cancel) gets +z:
/// unused it is never shaded, and an arbitrary unit normal beats dropping every normal.
fn angle_weighted_normals(mesh: &MeshData) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; mesh.positions.len()];
    for t in &mesh.triangles {
        let p = t.map(|i| mesh.positions[i as usize]);
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        for k in 0..3 {
            let (a, b) = ((p[(k + 1) % 3] - p[k]).normalize_or_zero(), (p[(k + 2) % 3] - p[k]).normalize_or_zero());
            sums[t[k] as usize] += n * a.dot(b).clamp(-1.0, 1.0).acos();
        }
    }
    sums.iter().map(|s| s.try_normalize().unwrap_or(Vec3::Z)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// A version 4 file of two quads, the second with normals and texture coordinates.
    fn two_quads() -> Vec<u8> {
        let mesh = |flags: u32, extra: &[f32]| {
            let mut raw = flags.to_le_bytes().to_vec();
            raw.extend(b"q\0");
            raw.extend(4u64.to_le_bytes());
            raw.extend(2u64.to_le_bytes());
            let positions = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];
            raw.extend(positions.iter().chain(extra).flat_map(|v| v.to_le_bytes()));
            raw.extend([0u32, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
            let mut z = flate2::write::ZlibEncoder::new(vec![0x1C, 0x04, 4, 0], flate2::Compression::default());
            z.write_all(&raw).unwrap();
            z.finish().unwrap()
        };
        let normals_uvs: Vec<f32> =
            [[0.0, 0.0, 1.0]; 4].concat().into_iter().chain([0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]).collect();
        let (a, b) = (mesh(0x1000, &[]), mesh(0x1003, &normals_uvs));
        let mut file = [a.clone(), b].concat();
        file.extend(0u64.to_le_bytes());
        file.extend((a.len() as u64).to_le_bytes());
        file.extend(2u32.to_le_bytes());
        file
    }

    #[test]
    fn mutated_files_give_a_mesh_or_an_error_never_a_panic() {
        let file = two_quads();
        assert_eq!(decode(&file, 1).unwrap().uvs.len(), 4);
        // A small xorshift: the same mutations on every run.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for _ in 0..3000 {
            let mut bytes = file.clone();
            for _ in 0..1 + next() % 4 {
                let at = (next() % bytes.len() as u64) as usize;
                bytes[at] ^= 1 << (next() % 8);
            }
            let cut = bytes.len() - (next() % 8) as usize * usize::from(next() % 3 == 0);
            for index in [0, 1, 2, u32::MAX] {
                let _ = decode(&bytes[..cut], index);
            }
        }
    }

    #[test]
    fn counts_far_beyond_the_compressed_bytes_are_refused_before_decompressing() {
        // One triangle, then 5M copies of it: 60 MB of indices, compressed about 1000 times.
        let mut raw = 0u32.to_le_bytes().to_vec();
        raw.extend(3u64.to_le_bytes());
        let triangles = 5_000_000u64;
        raw.extend(triangles.to_le_bytes());
        raw.extend([0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0].iter().flat_map(|v| v.to_le_bytes()));
        let mut z = flate2::write::ZlibEncoder::new(vec![0x1C, 0x04, 3, 0], flate2::Compression::best());
        z.write_all(&raw).unwrap();
        let triangle: Vec<u8> = [0u32, 1, 2].iter().flat_map(|i| i.to_le_bytes()).collect();
        for _ in 0..triangles {
            z.write_all(&triangle).unwrap();
        }
        let file = z.finish().unwrap();
        assert!(file.len() < 200_000, "{} bytes", file.len());
        let error = decode(&file, 0).unwrap_err();
        assert!(error.starts_with("3 vertices and 5000000 triangles are more than 100 times the"), "{error}");
    }

    #[test]
    fn a_flat_square_gets_normals_along_its_face() {
        let mesh = MeshData {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..MeshData::default()
        };
        let normals = angle_weighted_normals(&mesh);
        assert_eq!(normals.len(), 4);
        assert!(normals.iter().all(|n| n.abs_diff_eq(Vec3::Z, 1e-6)), "{normals:?}");
    }
}
