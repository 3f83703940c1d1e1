//! Stanford PLY meshes (ASCII, binary little and big endian), via ply-rs-bw.
//!
//! Reads `vertex` x, y, z (any numeric type) with optional nx, ny, nz and u, v (or s, t or
//! texture_u, texture_v), and `face` `vertex_indices` (or `vertex_index`) lists, fan-triangulated.
//! Other elements and properties (colours, confidence, ...) are skipped.

use std::io::Cursor;
use std::path::Path;

use glam::{Vec2, Vec3};
use ply_rs_bw::parser::{Parser, Reader};
use ply_rs_bw::ply::{
    ElementDef, Encoding, Header, Property, PropertyAccess, PropertyAccessResult, PropertyType, ScalarType,
};

use super::{single_mesh_asset, unit_normals, Asset, AssetError, Material, MeshData};
use crate::input_file::{InputFiles, InputKind};

/// Loads a PLY file as one mesh with the default material.
pub(super) fn load(files: &InputFiles, path: &Path) -> Result<Asset, AssetError> {
    let bytes = files.read(path, InputKind::Mesh)?;
    parse(&bytes, path)
}

/// The PLY mesh held in `bytes`, read as [`load`] reads a file (`path` names it in messages).
pub(super) fn parse(bytes: &[u8], path: &Path) -> Result<Asset, AssetError> {
    let error = |message: String| AssetError::invalid(path, message);
    let mut reader = Reader::new(Cursor::new(bytes));
    let header = Parser::<Vertex>::new().read_header(&mut reader).map_err(|e| error(format!("bad header: {e}")))?;
    let payload_bytes = bytes.len() as u64 - reader.get_ref().position();
    check_counts(&header, payload_bytes).map_err(error)?;

    let mut vertices = Vec::new();
    let mut faces = Vec::new();
    for element in header.elements.values() {
        let read_error = |e: ply_rs_bw::parser::ParseError| error(format!("element '{}': {e}", element.name));
        match element.name.as_str() {
            "vertex" => {
                vertices = Parser::<Vertex>::new()
                    .read_payload_for_element(&mut reader, element, &header)
                    .map_err(read_error)?
            }
            "face" => {
                faces =
                    Parser::<Face>::new().read_payload_for_element(&mut reader, element, &header).map_err(read_error)?
            }
            _ => {
                Parser::<Skipped>::new().read_payload_for_element(&mut reader, element, &header).map_err(read_error)?;
            }
        }
    }

    let vertex_def = header.elements.get("vertex").ok_or_else(|| error("no 'vertex' element".to_owned()))?;
    let has = |names: &[&str]| names.iter().all(|name| vertex_def.properties.contains_key(*name));
    if !has(&["x", "y", "z"]) {
        return Err(error("the vertex element lacks x, y or z".to_owned()));
    }
    let has_uvs = has(&["u", "v"]) || has(&["s", "t"]) || has(&["texture_u", "texture_v"]);
    let has_normals = has(&["nx", "ny", "nz"]);
    if !header.elements.get("face").is_some_and(|face| {
        face.properties.contains_key("vertex_indices") || face.properties.contains_key("vertex_index")
    }) {
        return Err(error("no 'face' element with vertex_indices (point clouds are not supported)".to_owned()));
    }

    let vertex_count = u32::try_from(vertices.len()).map_err(|_| error("more than 2^32 vertices".to_owned()))?;
    let mut mesh = MeshData::default();
    for (i, v) in vertices.iter().enumerate() {
        let position = Vec3::new(v.0[X] as f32, v.0[X + 1] as f32, v.0[X + 2] as f32);
        if !position.is_finite() {
            return Err(error(format!("vertex {i} has a non-finite position {position}")));
        }
        mesh.positions.push(position);
    }
    if has_normals {
        let normals: Vec<Vec3> =
            vertices.iter().map(|v| Vec3::new(v.0[NX] as f32, v.0[NX + 1] as f32, v.0[NX + 2] as f32)).collect();
        mesh.normals = unit_normals(&normals);
    }
    if has_uvs {
        mesh.uvs = vertices.iter().map(|v| Vec2::new(v.0[U] as f32, 1.0 - v.0[U + 1] as f32)).collect();
        if mesh.uvs.iter().any(|uv| !uv.is_finite()) {
            mesh.uvs.clear();
        }
    }

    let mut dropped = 0;
    for (f, face) in faces.iter().enumerate() {
        if let Some(&bad) = face.0.iter().find(|&&i| i < 0 || i >= i64::from(vertex_count)) {
            return Err(error(format!("face {f} uses vertex {bad} but the file has {vertex_count} vertices")));
        }
        // Fan triangulation: exact for the convex polygons scanners write.
        let corners: Vec<u32> = face.0.iter().map(|&i| i as u32).collect();
        if corners.len() < 3 {
            dropped += 1;
        }
        for pair in corners.windows(2).skip(1) {
            mesh.triangles.push([corners[0], pair[0], pair[1]]);
            mesh.triangle_materials.push(0);
        }
    }
    dropped += mesh.drop_degenerate();
    Ok(single_mesh_asset(mesh, vec![Material::default()], Vec::new(), dropped))
}

/// Rejects headers whose element counts cannot fit in the bytes that follow, before anything is
/// read or reserved, so `element vertex 1000000000` in a tiny file fails at once.
fn check_counts(header: &Header, payload_bytes: u64) -> Result<(), String> {
    let mut needed: u128 = 0;
    for element in header.elements.values() {
        let per_element: u64 = match header.encoding {
            // Each value takes a digit plus a separator; a line takes at least its newline.
            Encoding::Ascii => (2 * element.properties.len() as u64).max(1),
            Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
                element.properties.values().map(|p| minimum_binary_size(&p.data_type)).sum()
            }
        };
        needed += u128::from(per_element) * element.count as u128;
    }
    if needed > u128::from(payload_bytes) {
        let counts: Vec<String> =
            header.elements.values().map(|e: &ElementDef| format!("{} {}", e.count, e.name)).collect();
        return Err(format!(
            "the header promises {} (at least {needed} bytes) but only {payload_bytes} bytes follow it (truncated or corrupt file)",
            counts.join(", ")
        ));
    }
    Ok(())
}

/// Bytes of a binary property; a list takes at least its length field.
fn minimum_binary_size(property: &PropertyType) -> u64 {
    let size = |scalar: &ScalarType| match scalar {
        ScalarType::Char | ScalarType::UChar => 1,
        ScalarType::Short | ScalarType::UShort => 2,
        ScalarType::Int | ScalarType::UInt | ScalarType::Float => 4,
        ScalarType::Double => 8,
    };
    match property {
        PropertyType::Scalar(scalar) => size(scalar),
        PropertyType::List(length, _) => size(length),
    }
}

/// Slots of [`Vertex`]: position, normal, texture coordinate.
const X: usize = 0;
const NX: usize = 3;
const U: usize = 6;

/// The vertex properties we use, as f64 so double-precision files lose nothing before the check.
struct Vertex([f64; 8]);

impl PropertyAccess for Vertex {
    fn new() -> Self {
        Vertex([0.0; 8])
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let slot = match name {
            "x" => X,
            "y" => X + 1,
            "z" => X + 2,
            "nx" => NX,
            "ny" => NX + 1,
            "nz" => NX + 2,
            "u" | "s" | "texture_u" => U,
            "v" | "t" | "texture_v" => U + 1,
            _ => return PropertyAccessResult::Ignored,
        };
        self.0[slot] = match property {
            Property::Char(v) => v.into(),
            Property::UChar(v) => v.into(),
            Property::Short(v) => v.into(),
            Property::UShort(v) => v.into(),
            Property::Int(v) => v.into(),
            Property::UInt(v) => v.into(),
            Property::Float(v) => v.into(),
            Property::Double(v) => v,
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

/// A face's vertex indices, widened so negative and large unsigned values can be reported.
struct Face(Vec<i64>);

impl PropertyAccess for Face {
    fn new() -> Self {
        Face(Vec::new())
    }

    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        if name != "vertex_indices" && name != "vertex_index" {
            return PropertyAccessResult::Ignored;
        }
        self.0 = match property {
            Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
            Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
            Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
            Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
            _ => return PropertyAccessResult::UnsupportedType,
        };
        PropertyAccessResult::Set
    }
}

/// Elements we do not use (edges, materials, ...): parsed to stay in step, then dropped.
struct Skipped;

impl PropertyAccess for Skipped {
    fn new() -> Self {
        Skipped
    }
}

#[cfg(test)]
mod tests {
    use super::super::{load_asset, real_data, write_file, WrittenFiles};
    use super::*;
    use std::time::Instant;

    const HEADER_TAIL: &str = "element vertex 5
property float x
property float y
property float z
property float nx
property float ny
property float nz
property uchar red
property float u
property float v
element face 2
property list uchar int vertex_indices
end_header
";

    /// A unit quad (4 vertices + one spare) with normals (0, 0, 3), a colour to skip, uvs, and
    /// faces: a quad and a triangle.
    const VERTICES: [[f32; 8]; 5] = [
        [0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 0.0, 0.0],
        [1.0, 0.0, 0.0, 0.0, 0.0, 3.0, 1.0, 0.0],
        [1.0, 1.0, 0.0, 0.0, 0.0, 3.0, 1.0, 1.0],
        [0.0, 1.0, 0.0, 0.0, 0.0, 3.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 0.0, 0.0, 3.0, 0.5, 0.5],
    ];
    const FACES: [&[i32]; 2] = [&[0, 1, 2, 3], &[0, 1, 4]];

    fn ascii(faces: &[&[i32]]) -> Vec<u8> {
        let mut text = format!("ply\nformat ascii 1.0\ncomment test\n{HEADER_TAIL}");
        for v in VERTICES {
            text += &format!("{} {} {} {} {} {} 255 {} {}\n", v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7]);
        }
        for face in faces {
            text += &format!("{} {}\n", face.len(), face.iter().map(i32::to_string).collect::<Vec<_>>().join(" "));
        }
        text.into_bytes()
    }

    fn binary(big_endian: bool) -> Vec<u8> {
        let format = if big_endian { "binary_big_endian" } else { "binary_little_endian" };
        let mut bytes = format!("ply\nformat {format} 1.0\n{HEADER_TAIL}").into_bytes();
        let order = |mut word: [u8; 4]| {
            if big_endian {
                word.reverse();
            }
            word
        };
        for v in VERTICES {
            for (i, value) in v.iter().enumerate() {
                if i == 6 {
                    bytes.push(255); // the uchar colour between the normal and the uv
                }
                bytes.extend(order(value.to_le_bytes()));
            }
        }
        for face in FACES {
            bytes.push(face.len() as u8);
            for &i in face {
                bytes.extend(order(i.to_le_bytes()));
            }
        }
        bytes
    }

    fn write(tag: &str, bytes: &[u8]) -> WrittenFiles {
        write_file(tag, "mesh.ply", bytes)
    }

    fn check_quad(asset: &Asset) {
        let mesh = &asset.meshes[0];
        assert_eq!(mesh.positions.len(), 5);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 1, 4]], "the quad is fan-triangulated");
        assert_eq!(mesh.triangle_materials, vec![0; 3]);
        assert_eq!(mesh.normals, vec![Vec3::Z; 5]);
        assert_eq!(mesh.uvs[1], Vec2::new(1.0, 1.0), "v is flipped");
        assert_eq!(mesh.positions[4], Vec3::Z);
        assert_eq!(asset.materials, vec![Material::default()]);
    }

    #[test]
    fn ascii_and_binary_in_both_byte_orders() {
        check_quad(&load_asset(&write("ply-ascii", &ascii(&FACES))).unwrap());
        check_quad(&load_asset(&write("ply-le", &binary(false))).unwrap());
        check_quad(&load_asset(&write("ply-be", &binary(true))).unwrap());
    }

    #[test]
    fn truncated_binary_is_an_error() {
        let bytes = binary(false);
        let path = write("ply-truncated", &bytes[..bytes.len() - 3]);
        let err = load_asset(&path).unwrap_err().to_string();
        assert!(err.contains(&path.display().to_string()), "{err}");
    }

    #[test]
    fn huge_claimed_counts_fail_fast() {
        for format in ["ascii", "binary_little_endian"] {
            let header = format!("ply\nformat {format} 1.0\nelement vertex 1000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n");
            let start = Instant::now();
            let err = load_asset(&write("ply-huge", header.as_bytes())).unwrap_err().to_string();
            assert!(err.contains("1000000000 vertex"), "{err}");
            assert!(start.elapsed().as_millis() < 500);
        }
    }

    #[test]
    fn bad_index_negative_index_and_nan_are_errors() {
        let err = load_asset(&write("ply-index", &ascii(&[&[0, 1, 2], &[0, 1, 9]]))).unwrap_err().to_string();
        assert!(err.contains("face 1 uses vertex 9 but the file has 5 vertices"), "{err}");
        let err = load_asset(&write("ply-negative", &ascii(&[&[0, 1, 2], &[0, -1, 2]]))).unwrap_err().to_string();
        assert!(err.contains("face 1 uses vertex -1"), "{err}");
        // ASCII "nan" is already a syntax error for the parser; binary NaN reaches our check.
        let mut bytes = binary(false);
        let vertex_size = 8 * 4 + 1;
        let second_vertex = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11 + vertex_size;
        bytes[second_vertex..second_vertex + 4].copy_from_slice(&f32::NAN.to_le_bytes());
        let err = load_asset(&write("ply-nan", &bytes)).unwrap_err().to_string();
        assert!(err.contains("vertex 1 has a non-finite position"), "{err}");
        let text = String::from_utf8(ascii(&FACES)).unwrap().replacen("\n1 1 0 ", "\nnan 1 0 ", 1);
        let err = load_asset(&write("ply-nan-ascii", text.as_bytes())).unwrap_err().to_string();
        assert!(err.contains("mesh.ply") && err.contains("Line 19"), "{err}");
    }

    #[test]
    fn point_clouds_and_garbage_are_errors() {
        let cloud = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n";
        assert!(load_asset(&write("ply-cloud", cloud.as_bytes())).unwrap_err().to_string().contains("point clouds"));
        assert!(load_asset(&write("ply-garbage", b"\x00\xffnot a ply")).unwrap_err().to_string().contains("mesh.ply"));
    }

    #[test]
    fn real_scans() {
        for (file, vertices, faces) in
            [("meshes/bunny/bun_zipper.ply", 35_947, 69_451), ("meshes/lucy/Lucy100k.ply", 50_002, 100_000)]
        {
            let Some(path) = real_data(file) else {
                continue;
            };
            let start = Instant::now();
            let asset = load_asset(&path).unwrap();
            let mesh = &asset.meshes[0];
            println!(
                "{file}: {} vertices, {} triangles (+{} dropped) in {:?}",
                mesh.positions.len(),
                mesh.triangles.len(),
                asset.dropped_triangles,
                start.elapsed()
            );
            assert_eq!(mesh.positions.len(), vertices);
            assert_eq!(mesh.triangles.len() + asset.dropped_triangles, faces);
        }
    }
}
