//! What is interpolated across mesh triangles, pixel by pixel (issue 51): glTF vertex colours
//! (COLOR_0, in each encoding glTF allows) multiplying the base colour.
//!
//! A glTF square (two triangles, corners of distinct colours) is a smooth mirror (metallic 1,
//! roughness 0: glTF's Schlick Fresnel with the base colour as F0) under a white constant sky,
//! seen head-on from far away through a narrow field of view. Every camera ray meets it within
//! 0.15 degrees of its normal, where Schlick's term adds less than 1e-12 to F0, and reflects
//! into the sky: each sample is exactly the base colour times the colour interpolated at the
//! point it meets. The film plane maps linearly onto the square, and the colour is linear across
//! each triangle, so a pixel's mean over its box filter is the colour at its centre: a closed
//! form for every pixel off the diagonal, where the two triangles' interpolations meet.

mod common;

use caustica::image::RgbImage;
use caustica::scene::Scene;
use common::gltf_square::base64;
use common::*;
use std::path::Path;

/// Half side of the square and the camera's distance from it.
const HALF: f32 = 0.5;
const DISTANCE: f32 = 10.0;
const SIZE: u32 = 16;
const SPP: u32 = 64;

/// The square's corners (at height 0 in the xz plane, facing down, -y, towards the camera below)
/// and its two triangles.
const CORNERS: [[f32; 3]; 4] = [[-HALF, 0.0, -HALF], [HALF, 0.0, -HALF], [HALF, 0.0, HALF], [-HALF, 0.0, HALF]];
const TRIANGLES: [[usize; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

/// One vertex attribute of the square: its glTF name, accessor component type and type, whether
/// its integers are normalized, and its bytes (four elements, tightly packed).
struct Attribute {
    name: &'static str,
    component_type: u32,
    kind: &'static str,
    normalized: bool,
    bytes: Vec<u8>,
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// `square.gltf` in `dir`: the square with POSITION, `attributes`, and material 0 = `material`.
fn write_square(dir: &Path, attributes: &[Attribute], material: &str) {
    let mut buffer = floats(&CORNERS.concat());
    let mut views = vec![format!(r#"{{"buffer": 0, "byteOffset": 0, "byteLength": {}}}"#, buffer.len())];
    let mut accessors = vec![format!(
        r#"{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [{m}, 0, {m}], "max": [{HALF}, 0, {HALF}]}}"#,
        m = -HALF
    )];
    let mut members = vec![r#""POSITION": 0"#.to_owned()];
    for a in attributes {
        while buffer.len() % 4 != 0 {
            buffer.push(0);
        }
        views.push(format!(r#"{{"buffer": 0, "byteOffset": {}, "byteLength": {}}}"#, buffer.len(), a.bytes.len()));
        buffer.extend(&a.bytes);
        members.push(format!(r#""{}": {}"#, a.name, accessors.len()));
        accessors.push(format!(
            r#"{{"bufferView": {}, "componentType": {}, "normalized": {}, "count": 4, "type": "{}"}}"#,
            views.len() - 1,
            a.component_type,
            a.normalized,
            a.kind
        ));
    }
    views.push(format!(r#"{{"buffer": 0, "byteOffset": {}, "byteLength": 12}}"#, buffer.len()));
    buffer.extend(TRIANGLES.concat().iter().flat_map(|&i| (i as u16).to_le_bytes()));
    accessors
        .push(format!(r#"{{"bufferView": {}, "componentType": 5123, "count": 6, "type": "SCALAR"}}"#, views.len() - 1));
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "scene": 0, "scenes": [{{"nodes": [0]}}], "nodes": [{{"mesh": 0}}],
  "meshes": [{{"primitives": [{{"attributes": {{{}}}, "indices": {}, "material": 0}}]}}],
  "materials": [{material}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}],
  "bufferViews": [{}],
  "accessors": [{}]
}}"#,
        members.join(", "),
        accessors.len() - 1,
        buffer.len(),
        base64(&buffer),
        views.join(", "),
        accessors.join(", ")
    );
    std::fs::write(dir.join("square.gltf"), json).unwrap();
}

/// The square of `dir` seen head-on from `DISTANCE` below, filling a `SIZE` x `SIZE` film, under a
/// white sky.
fn render_square(ctx: &caustica::gpu::GpuContext, dir: &Path) -> RgbImage {
    let fov = 2.0 * (HALF / DISTANCE).atan().to_degrees();
    let scene = Scene::parse(
        &format!(
            r#"
            camera = {{ position = [0.0, -{DISTANCE}, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = {fov} }}
            film = {{ width = {SIZE}, height = {SIZE}, spp = {SPP} }}
            environment = {{ color = [1.0, 1.0, 1.0] }}
            [[meshes]]
            file = "square.gltf"
            "#
        ),
        "test scene",
        dir,
    )
    .expect("valid test scene");
    render(ctx, &scene, 5)
}

/// Where pixel (x, y)'s centre meets the square, as (x, z): the camera's right is -x and the
/// image's down +z (right = forward x up, forward +y, up -z).
fn pixel_point(x: u32, y: u32) -> (f32, f32) {
    let fx = (x as f32 + 0.5) / SIZE as f32;
    let fy = (y as f32 + 0.5) / SIZE as f32;
    (-(2.0 * fx - 1.0) * HALF, (2.0 * fy - 1.0) * HALF)
}

/// The barycentric weights of (x, z) in the square's triangle that holds it, with its corners;
/// None within `margin` of the diagonal the triangles share.
fn barycentrics(point: (f32, f32), margin: f32) -> Option<([usize; 3], [f32; 3])> {
    let (px, pz) = point;
    // The diagonal runs from corner 0 (-h, -h) to corner 2 (h, h); corner 1 has x > z.
    if (px - pz).abs() < margin {
        return None;
    }
    let tri = if px > pz { TRIANGLES[0] } else { TRIANGLES[1] };
    let [a, b, c] = tri.map(|i| (CORNERS[i][0], CORNERS[i][2]));
    let det = (b.0 - a.0) * (c.1 - a.1) - (c.0 - a.0) * (b.1 - a.1);
    let w1 = ((px - a.0) * (c.1 - a.1) - (c.0 - a.0) * (pz - a.1)) / det;
    let w2 = ((b.0 - a.0) * (pz - a.1) - (px - a.0) * (b.1 - a.1)) / det;
    Some((tri, [1.0 - w1 - w2, w1, w2]))
}

/// Asserts that every pixel off the diagonal is `expected` (of the corners' values interpolated
/// there) within `tolerance`, and returns how many pixels were compared.
fn assert_pixels(
    image: &RgbImage,
    expected: impl Fn([usize; 3], [f32; 3]) -> [f32; 3],
    tolerance: f32,
    what: &str,
) -> usize {
    let margin = 1.5 * 2.0 * HALF / SIZE as f32;
    let mut compared = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let Some((tri, w)) = barycentrics(pixel_point(x, y), margin) else { continue };
            let want = expected(tri, w);
            let got = image.get(x, y);
            for c in 0..3 {
                assert!(
                    (got[c] - want[c]).abs() <= tolerance,
                    "{what}: pixel ({x}, {y}) channel {c} is {}, expected {} (within {tolerance})",
                    got[c],
                    want[c]
                );
            }
            compared += 1;
        }
    }
    assert!(compared > (SIZE * SIZE / 2) as usize, "{what}: only {compared} pixels compared");
    compared
}

/// The base colour factor every test square multiplies its vertex colours by.
const BASE: [f32; 3] = [0.8, 1.0, 0.6];

/// A smooth mirror of base colour BASE: its F0 is BASE times the vertex colour.
fn mirror_material() -> String {
    format!(
        r#"{{"pbrMetallicRoughness": {{"baseColorFactor": [{}, {}, {}, 1], "metallicFactor": 1, "roughnessFactor": 0}}}}"#,
        BASE[0], BASE[1], BASE[2]
    )
}

/// The corners' colours: primaries, and a grey that is no mix of theirs.
const COLOURS: [[f32; 4]; 4] = [[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [0.4, 0.4, 0.4, 1.0]];

/// The pixel tolerance at SPP samples: within a pixel the colour changes by at most a sixteenth
/// of its range (one pixel of 16 across the square), a box-filtered sample spreads with standard
/// deviation at most (1/16) / sqrt(12) = 0.018 around the pixel's mean, and the mean of 64 with
/// 0.0023; six of those, rounded up, plus the u8 encoding's half step. A corner's colour off by
/// 0.02, or a barycentric weight given to the wrong corner (errors of 0.1 and more over most
/// pixels), fails.
const TOLERANCE: f32 = 0.016;

/// COLOR_0 multiplies the base colour, interpolated across each triangle, whether stored as
/// floats (RGB), normalized unsigned bytes or normalized unsigned shorts (RGBA): every pixel off
/// the diagonal matches the closed form, and all three encodings agree.
#[test]
fn vertex_colours_multiply_the_base_colour_pixel_by_pixel() {
    let (_lock, ctx) = gpu();
    let dir = temp_dir("vertex-colours");
    let encodings = [
        Attribute {
            name: "COLOR_0",
            component_type: 5126,
            kind: "VEC3",
            normalized: false,
            bytes: floats(&COLOURS.map(|c| [c[0], c[1], c[2]]).concat()),
        },
        Attribute {
            name: "COLOR_0",
            component_type: 5121,
            kind: "VEC4",
            normalized: true,
            bytes: COLOURS.concat().iter().map(|&c| (c * 255.0).round() as u8).collect(),
        },
        Attribute {
            name: "COLOR_0",
            component_type: 5123,
            kind: "VEC4",
            normalized: true,
            bytes: COLOURS.concat().iter().flat_map(|&c| ((c * 65535.0).round() as u16).to_le_bytes()).collect(),
        },
    ];
    for attribute in encodings {
        let what = format!("COLOR_0 {} of component type {}", attribute.kind, attribute.component_type);
        write_square(&dir, &[attribute], &mirror_material());
        let image = render_square(&ctx, &dir);
        assert_pixels(
            &image,
            |tri, w| {
                let mut c = [0.0; 3];
                for (k, &corner) in tri.iter().enumerate() {
                    for ch in 0..3 {
                        c[ch] += w[k] * COLOURS[corner][ch] * BASE[ch];
                    }
                }
                c
            },
            TOLERANCE,
            &what,
        );
    }
}

/// A COLOR_0 of a shape glTF does not allow is an error naming the file and the attribute.
#[test]
fn a_two_component_colour_is_an_error() {
    let dir = temp_dir("vertex-colours-bad");
    let attribute =
        Attribute { name: "COLOR_0", component_type: 5126, kind: "VEC2", normalized: false, bytes: floats(&[0.5; 8]) };
    write_square(&dir, &[attribute], &mirror_material());
    let toml = "camera = { position = [0.0, -1.0, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, 1.0] }\n[[meshes]]\nfile = \"square.gltf\"";
    let err = Scene::parse(toml, "test scene", &dir).err().expect("a VEC2 COLOR_0 is refused");
    let err = format!("{err:#}");
    assert!(err.contains("square.gltf") && err.contains("COLOR_0"), "{err}");
}
