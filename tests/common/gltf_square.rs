//! A glTF file of one square written for a test: the material, textures, samplers and images are
//! the test's JSON; the geometry is fixed and simple enough to reason about pixel by pixel.

use base64::Engine as _;
use std::path::Path;

/// Base64 of `bytes`, for data URIs.
pub fn base64(bytes: &[u8]) -> String {
    base64::engine::general_purpose::STANDARD.encode(bytes)
}

/// A data URI of a PNG.
pub fn png_uri(png: &[u8]) -> String {
    format!("data:image/png;base64,{}", base64(png))
}

/// `name` in `dir`: a square of half side `half` at height `y` in the xz plane, facing down, with
/// material 0 = `material` (a JSON object) and `resources` (JSON members such as `"textures": [...],
/// "images": [...], "samplers": [...],`, each followed by a comma, or nothing). TEXCOORD_0 is
/// u = x / 2 half + 0.5, v = z / 2 half + 0.5 (the texture's top row at z = -half); TEXCOORD_1 is
/// the same with u and v swapped.
pub fn write_gltf_square(dir: &Path, name: &str, y: f32, half: f32, material: &str, resources: &str) {
    let corners = [[-half, y, -half], [half, y, -half], [half, y, half], [-half, y, half]];
    let uv0 = [[0.0f32, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let uv1 = uv0.map(|[u, v]| [v, u]);
    let mut buffer: Vec<u8> = corners
        .iter()
        .flatten()
        .chain(uv0.iter().flatten())
        .chain(uv1.iter().flatten())
        .flat_map(|v| v.to_le_bytes())
        .collect();
    buffer.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 1, "TEXCOORD_1": 2}}, "indices": 3, "material": 0}}]}}],
  "materials": [{material}],
  {resources}
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 48}}, {{"buffer": 0, "byteOffset": 48, "byteLength": 32}},
    {{"buffer": 0, "byteOffset": 80, "byteLength": 32}}, {{"buffer": 0, "byteOffset": 112, "byteLength": 12}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [{m}, {y}, {m}], "max": [{half}, {y}, {half}]}},
    {{"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}},
    {{"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}}
  ]
}}"#,
        buffer.len(),
        base64(&buffer),
        m = -half,
    );
    std::fs::write(dir.join(name), json).unwrap();
}
