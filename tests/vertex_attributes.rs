//! What is interpolated across mesh triangles, pixel by pixel (issue 51): glTF vertex colours
//! (COLOR_0, in each encoding glTF allows) multiplying the base colour, texture coordinates and
//! vertex normals; and what the glTF loader does to vertices before the kernel sees them
//! (KHR_mesh_quantization, morph targets, skins, doubleSided).
//!
//! The colour and texture tests make a glTF square (two triangles, corners of distinct values) a
//! smooth mirror (metallic 1, roughness 0: glTF's Schlick Fresnel with the base colour as F0)
//! under a white constant sky, seen head-on from far away through a narrow field of view. Every
//! camera ray meets it within 0.15 degrees of its normal, where Schlick's term adds less than
//! 1e-12 to F0, and reflects into the sky: each sample is exactly the base colour at the point it
//! meets. The film plane maps linearly onto the square, and what is interpolated is linear across
//! each triangle, so a pixel's mean over its box filter is the value at its centre: a closed form
//! for every pixel off the diagonal, where the two triangles' interpolations meet. The normal test
//! lights a matte square by a directional light instead (the Lambert term of the interpolated
//! normal). Each render is deterministic (a fixed seed), and its tolerance is derived from the
//! spread of 64 box-filtered samples over a pixel.

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

impl Attribute {
    /// Bytes of one element, unpadded.
    fn element_bytes(&self) -> usize {
        let components = match self.kind {
            "SCALAR" => 1,
            "VEC2" => 2,
            "VEC3" => 3,
            "VEC4" => 4,
            "MAT4" => 16,
            other => panic!("no such accessor type {other}"),
        };
        let size = match self.component_type {
            5120 | 5121 => 1,
            5122 | 5123 => 2,
            _ => 4,
        };
        components * size
    }

    /// The view of this attribute's bytes at `offset` in the buffer, and the bytes to put there:
    /// glTF aligns each vertex's element to 4 bytes, so elements of other sizes (three shorts,
    /// three bytes) are padded and the view given that stride.
    fn view(&self, offset: usize) -> (String, Vec<u8>) {
        let element = self.element_bytes();
        let stride = element.div_ceil(4) * 4;
        let mut bytes = Vec::new();
        for e in self.bytes.chunks(element) {
            bytes.extend(e);
            bytes.resize(bytes.len() + stride - element, 0);
        }
        let stride_member = if stride == element { String::new() } else { format!(r#", "byteStride": {stride}"#) };
        (format!(r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {}{stride_member}}}"#, bytes.len()), bytes)
    }
}

fn floats(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// `square.gltf` in `dir`: the square with POSITION, `attributes`, and material 0 = `material`.
fn write_square(dir: &Path, attributes: &[Attribute], material: &str) {
    let position = Attribute {
        name: "POSITION",
        component_type: 5126,
        kind: "VEC3",
        normalized: false,
        bytes: floats(&CORNERS.concat()),
    };
    write_square_with(dir, &position, attributes, material, &Extras::default());
}

/// JSON members a test adds to the square's file: to its mesh (`"weights": [...]`), to its node
/// (`"scale": ...`), and at the top level (`"extensionsRequired": [...]`), each starting with a
/// comma; and more nodes (flat JSON objects, each after a comma), all roots of the scene.
#[derive(Default)]
struct Extras {
    mesh: String,
    node: String,
    nodes: String,
    top: String,
}

/// [`write_square`] with its own POSITION accessor (min and max are the corners'; glTF asks for
/// them) and `extras`. An attribute named `T<k>/<NAME>` is morph target k's NAME.
fn write_square_with(dir: &Path, position: &Attribute, attributes: &[Attribute], material: &str, extras: &Extras) {
    let (view, mut buffer) = position.view(0);
    let mut views = vec![view];
    let mut accessors = vec![format!(
        r#"{{"bufferView": 0, "componentType": {}, "normalized": {}, "count": 4, "type": "VEC3", "min": [{m}, 0, {m}], "max": [{h}, 0, {h}]}}"#,
        position.component_type,
        position.normalized,
        m = if position.component_type == 5126 { -HALF } else { -500.0 },
        h = if position.component_type == 5126 { HALF } else { 500.0 },
    )];
    let mut members = vec![r#""POSITION": 0"#.to_owned()];
    let mut targets: Vec<Vec<String>> = Vec::new();
    for a in attributes {
        while buffer.len() % 4 != 0 {
            buffer.push(0);
        }
        let (view, bytes) = a.view(buffer.len());
        views.push(view);
        buffer.extend(bytes);
        match a.name.strip_prefix('T').and_then(|t| t.split_once('/')) {
            // Data for something other than the primitive (a skin's matrices): an accessor alone.
            _ if a.name.starts_with('#') => {}
            Some((k, name)) => {
                let k: usize = k.parse().unwrap();
                targets.resize(targets.len().max(k + 1), Vec::new());
                targets[k].push(format!(r#""{name}": {}"#, accessors.len()));
            }
            None => members.push(format!(r#""{}": {}"#, a.name, accessors.len())),
        }
        accessors.push(format!(
            r#"{{"bufferView": {}, "componentType": {}, "normalized": {}, "count": {}, "type": "{}"}}"#,
            views.len() - 1,
            a.component_type,
            a.normalized,
            a.bytes.len() / a.element_bytes(),
            a.kind
        ));
    }
    views.push(format!(r#"{{"buffer": 0, "byteOffset": {}, "byteLength": 12}}"#, buffer.len()));
    buffer.extend(TRIANGLES.concat().iter().flat_map(|&i| (i as u16).to_le_bytes()));
    accessors
        .push(format!(r#"{{"bufferView": {}, "componentType": 5123, "count": 6, "type": "SCALAR"}}"#, views.len() - 1));
    let targets = match targets.is_empty() {
        true => String::new(),
        false => {
            let list: Vec<String> = targets.iter().map(|t| format!("{{{}}}", t.join(", "))).collect();
            format!(r#", "targets": [{}]"#, list.join(", "))
        }
    };
    let node_count = 1 + extras.nodes.matches('}').count();
    let scene_nodes: Vec<String> = (0..node_count).map(|n| n.to_string()).collect();
    let Extras { mesh: mesh_extra, node: node_extra, nodes, top } = extras;
    let json = format!(
        r#"{{
  "asset": {{"version": "2.0"}}{top},
  "scene": 0, "scenes": [{{"nodes": [{}]}}], "nodes": [{{"mesh": 0{node_extra}}}{nodes}],
  "meshes": [{{"primitives": [{{"attributes": {{{}}}, "indices": {}, "material": 0{targets}}}]{mesh_extra}}}],
  "materials": [{material}],
  "buffers": [{{"byteLength": {}, "uri": "data:application/octet-stream;base64,{}"}}],
  "bufferViews": [{}],
  "accessors": [{}]
}}"#,
        scene_nodes.join(", "),
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
    render_square_in(ctx, dir, "environment = { color = [1.0, 1.0, 1.0] }", "")
}

/// The square of `dir` seen as [`render_square`] sees it, in a scene of `world` (TOML: lights,
/// environment, materials) with `mesh` (TOML keys) added to its `[[meshes]]` entry.
fn render_square_in(ctx: &caustica::gpu::GpuContext, dir: &Path, world: &str, mesh: &str) -> RgbImage {
    let fov = 2.0 * (HALF / DISTANCE).atan().to_degrees();
    let scene = Scene::parse(
        &format!(
            r#"
            camera = {{ position = [0.0, -{DISTANCE}, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = {fov} }}
            film = {{ width = {SIZE}, height = {SIZE}, spp = {SPP} }}
            {world}
            [[meshes]]
            file = "square.gltf"
            {mesh}
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
    let Err(err) = Scene::parse(toml, "test scene", &dir) else { panic!("a VEC2 COLOR_0 is refused") };
    let err = format!("{err:#}");
    assert!(err.contains("square.gltf") && err.contains("COLOR_0"), "{err}");
}

fn shorts(values: &[i16]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// `KHR_mesh_quantization`, as gltfpack writes it: integer positions (here signed shorts, not
/// normalized, 1000 a unit, scaled back by the node), normals as normalized signed bytes (each
/// padded to 4 bytes) and texture coordinates as normalized unsigned shorts, read as the
/// numbers they stand for; the file may require the extension.
#[test]
fn quantized_attributes_are_read_as_the_numbers_they_stand_for() {
    let dir = temp_dir("quantized");
    let position = Attribute {
        name: "POSITION",
        component_type: 5122,
        kind: "VEC3",
        normalized: false,
        bytes: shorts(&CORNERS.concat().iter().map(|&c| (c * 1000.0) as i16).collect::<Vec<_>>()),
    };
    let normals = Attribute {
        name: "NORMAL",
        component_type: 5120,
        kind: "VEC3",
        normalized: true,
        bytes: [[0i8, -127, 0]; 4].concat().iter().map(|&c| c as u8).collect(),
    };
    let uvs = Attribute {
        name: "TEXCOORD_0",
        component_type: 5123,
        kind: "VEC2",
        normalized: true,
        bytes: [[0u16, 0], [65535, 0], [65535, 65535], [0, 65535]]
            .concat()
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect(),
    };
    let extras = Extras {
        node: r#", "scale": [0.001, 0.001, 0.001]"#.to_owned(),
        top: r#", "extensionsUsed": ["KHR_mesh_quantization"], "extensionsRequired": ["KHR_mesh_quantization"]"#
            .to_owned(),
        ..Extras::default()
    };
    write_square_with(&dir, &position, &[normals, uvs], &mirror_material(), &extras);
    let asset = caustica::scene::load_asset(&dir.join("square.gltf")).expect("a quantized square loads");
    let mesh = &asset.meshes[0];
    let corners: Vec<glam::Vec3> = CORNERS.iter().map(|&c| glam::Vec3::from(c) * 1000.0).collect();
    assert_eq!(mesh.positions, corners, "positions are the shorts' values");
    assert!(mesh.normals.iter().all(|&n| (n - glam::Vec3::NEG_Y).length() < 1e-6), "{:?}", mesh.normals);
    let uvs = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(glam::Vec2::from);
    assert_eq!(mesh.uvs, uvs, "normalized shorts are fractions of 65535");
    let world = asset.instances[0].1.transform_point3(mesh.positions[2]);
    assert!((world - glam::Vec3::from(CORNERS[2])).length() < 1e-6, "the node scales them back: {world}");
}

/// Morph targets displace the vertices by the mesh's default `weights`, and a node's own
/// `weights` replace the mesh's for that node's instance alone (a second, differently morphed
/// copy of the mesh). Targets without a weight weigh 0.
#[test]
fn morph_targets_are_applied_with_the_mesh_s_or_the_node_s_weights() {
    let dir = temp_dir("morph");
    let lift = |corner: usize, height: f32| {
        let mut d = [[0.0f32; 3]; 4];
        d[corner][1] = height;
        floats(&d.concat())
    };
    let targets = [
        Attribute { name: "T0/POSITION", component_type: 5126, kind: "VEC3", normalized: false, bytes: lift(2, 1.0) },
        Attribute { name: "T1/POSITION", component_type: 5126, kind: "VEC3", normalized: false, bytes: lift(0, 2.0) },
        Attribute { name: "T2/POSITION", component_type: 5126, kind: "VEC3", normalized: false, bytes: lift(1, 4.0) },
    ];
    let position = Attribute {
        name: "POSITION",
        component_type: 5126,
        kind: "VEC3",
        normalized: false,
        bytes: floats(&CORNERS.concat()),
    };
    let extras = Extras {
        mesh: r#", "weights": [0.5, 0.25]"#.to_owned(),
        nodes: r#", {"mesh": 0, "weights": [0.0, 1.0, 0.0]}"#.to_owned(),
        ..Extras::default()
    };
    write_square_with(&dir, &position, &targets, &mirror_material(), &extras);
    let asset = caustica::scene::load_asset(&dir.join("square.gltf")).expect("a morphed square loads");
    let heights = |mesh: usize| asset.meshes[mesh].positions.iter().map(|p| p.y).collect::<Vec<_>>();
    assert_eq!(asset.instances.len(), 2);
    let (default_instance, node_instance) = (asset.instances[0].0, asset.instances[1].0);
    assert_eq!(heights(default_instance), vec![0.5, 0.0, 0.5, 0.0], "the mesh's weights: 0.5 x 1 and 0.25 x 2");
    assert_ne!(default_instance, node_instance, "the node's weights need a mesh of their own");
    assert_eq!(heights(node_instance), vec![2.0, 0.0, 0.0, 0.0], "the node's weights replace the mesh's");
}

/// `doubleSided: false` (glTF's default) is a one-sided surface, black from behind, unless it
/// transmits; `doubleSided: true` is two-sided.
#[test]
fn double_sided_false_is_one_sided_unless_transmissive() {
    let dir = temp_dir("double-sided");
    for (material, one_sided) in [
        (r#"{"doubleSided": false}"#, true),
        (r#"{}"#, true),
        (r#"{"doubleSided": true}"#, false),
        (r#"{"extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}}"#, false),
    ] {
        write_square(&dir, &[], material);
        let asset = caustica::scene::load_asset(&dir.join("square.gltf")).expect("the square loads");
        assert_eq!(asset.materials[0].one_sided, one_sided, "{material}");
    }
}

/// A skinned square is posed by its joints at their nodes' transforms: corners weighted to a joint
/// raised by 1 rise by 1, a corner split evenly between the joints by half that, and the skinned
/// node's own transform (a shift along x) is ignored, as glTF says. The inverse bind matrix of
/// the second joint undoes a shift of its node along z, which therefore moves nothing.
#[test]
fn skins_are_posed_by_their_joints() {
    let dir = temp_dir("skin");
    let joints = Attribute {
        name: "JOINTS_0",
        component_type: 5121,
        kind: "VEC4",
        normalized: false,
        bytes: [[0u8, 1, 0, 0]; 4].concat(),
    };
    // Corner 0 stays with joint 0, corners 2 and 3 follow joint 1, corner 1 is split evenly.
    let weights = Attribute {
        name: "WEIGHTS_0",
        component_type: 5126,
        kind: "VEC4",
        normalized: false,
        bytes: floats(
            &[[1.0f32, 0.0, 0.0, 0.0], [0.5, 0.5, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]].concat(),
        ),
    };
    // Inverse bind matrices (column-major): identity for joint 0, a shift by -3 along z for
    // joint 1, bound where its node stood before it was raised.
    let mut binds = vec![0.0f32; 32];
    for (m, shift) in [(0, 0.0), (1, -3.0)] {
        for d in 0..4 {
            binds[16 * m + 5 * d] = 1.0;
        }
        binds[16 * m + 14] = shift;
    }
    let ibm = Attribute {
        name: "#inverseBindMatrices",
        component_type: 5126,
        kind: "MAT4",
        normalized: false,
        bytes: floats(&binds),
    };
    let position = Attribute {
        name: "POSITION",
        component_type: 5126,
        kind: "VEC3",
        normalized: false,
        bytes: floats(&CORNERS.concat()),
    };
    let extras = Extras {
        node: r#", "skin": 0, "translation": [5, 0, 0]"#.to_owned(),
        nodes: r#", {"translation": [0, 0, 0]}, {"translation": [0, 1, 3]}"#.to_owned(),
        // Accessor 4 is the IBM attribute's: POSITION, JOINTS_0, WEIGHTS_0, IBM, then indices.
        top: r#", "skins": [{"joints": [1, 2], "inverseBindMatrices": 3}]"#.to_owned(),
        ..Extras::default()
    };
    write_square_with(&dir, &position, &[joints, weights, ibm], &mirror_material(), &extras);
    let asset = caustica::scene::load_asset(&dir.join("square.gltf")).expect("a skinned square loads");
    assert_eq!(asset.instances.len(), 1);
    let (mesh, transform) = asset.instances[0];
    assert_eq!(transform, glam::Mat4::IDENTITY, "a posed skin is in world space");
    let posed = &asset.meshes[mesh].positions;
    let expected = [
        glam::Vec3::from(CORNERS[0]),
        glam::Vec3::from(CORNERS[1]) + glam::Vec3::new(0.0, 0.5, 0.0),
        glam::Vec3::from(CORNERS[2]) + glam::Vec3::Y,
        glam::Vec3::from(CORNERS[3]) + glam::Vec3::Y,
    ];
    for (k, (got, want)) in posed.iter().zip(expected).enumerate() {
        assert!((*got - want).length() < 1e-6, "corner {k}: {got}, expected {want}");
    }
}

/// Smooth shading: a diffuse square (albedo 0.5) whose corners' normals lean different ways, lit
/// by a directional light of irradiance pi from below, under a black sky. Each sample is the
/// Lambert term 0.5 x cos(shading normal, light) of the normal interpolated where it meets the
/// square and normalized; the pixel's mean is that at its centre to within the curvature of the
/// cosine over a pixel (below 1e-3 here). A normal interpolated with the wrong corner's weight, or
/// flat shading (the geometric normal, -y, everywhere), is off by 0.02 to 0.2 over most pixels.
#[test]
fn vertex_normals_are_interpolated_pixel_by_pixel() {
    let (_lock, ctx) = gpu();
    let dir = temp_dir("vertex-normals");
    let normals: [[f32; 3]; 4] = [[0.5, -1.0, 0.0], [0.0, -1.0, 0.6], [-0.4, -1.0, -0.3], [0.3, -1.0, 0.7]];
    let unit = normals.map(|n| glam::Vec3::from(n).normalize());
    let attribute = Attribute {
        name: "NORMAL",
        component_type: 5126,
        kind: "VEC3",
        normalized: false,
        bytes: floats(&unit.map(|n| n.to_array()).concat()),
    };
    write_square(&dir, &[attribute], &mirror_material());
    let travels = glam::Vec3::new(0.2, 1.0, -0.3).normalize();
    let world = format!(
        r#"
        [materials.matte]
        albedo = [0.5, 0.5, 0.5]
        [[lights]]
        type = "directional"
        direction = [{}, {}, {}]
        irradiance = [{pi}, {pi}, {pi}]
        "#,
        travels.x,
        travels.y,
        travels.z,
        pi = std::f32::consts::PI
    );
    let image = render_square_in(&ctx, &dir, &world, r#"material = "matte""#);
    assert_pixels(
        &image,
        |tri, w| {
            let n: glam::Vec3 = tri.iter().zip(w).map(|(&k, w)| w * unit[k]).sum::<glam::Vec3>().normalize();
            [0.5 * n.dot(-travels).max(0.0); 3]
        },
        0.01,
        "smooth-shaded square",
    );
}

/// Texture coordinates: the mirror square with a 2 x 2 base colour texture (clamped at its
/// edges, so bilinear lookups blend the four texels smoothly across it) and corner coordinates
/// that no single affine map gives, so each triangle maps the texture its own way. Each pixel is
/// the texture at the coordinates interpolated at its centre, in closed form (bilinear filtering,
/// sRGB decoded per texel). Coordinates interpolated with the wrong corner's weight fail.
#[test]
fn texture_coordinates_are_interpolated_pixel_by_pixel() {
    let (_lock, ctx) = gpu();
    let dir = temp_dir("vertex-uvs");
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.1], [0.8, 1.0], [0.1, 0.6]];
    let attribute = Attribute {
        name: "TEXCOORD_0",
        component_type: 5126,
        kind: "VEC2",
        normalized: false,
        bytes: floats(&uvs.concat()),
    };
    // Texels, top row first: distinct values in each channel.
    let texels: [[u8; 4]; 4] = [[255, 0, 40, 255], [0, 255, 120, 255], [60, 30, 255, 255], [200, 200, 0, 255]];
    let mut png = Vec::new();
    let mut encoder = png::Encoder::new(&mut png, 2, 2);
    encoder.set_color(png::ColorType::Rgba);
    encoder.write_header().unwrap().write_image_data(&texels.concat()).unwrap();
    let material = format!(
        r#"{{"pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicFactor": 1, "roughnessFactor": 0}}}}],
  "textures": [{{"source": 0, "sampler": 0}}], "samplers": [{{"wrapS": 33071, "wrapT": 33071}}],
  "images": [{{"uri": "{}"}}"#,
        common::gltf_square::png_uri(&png)
    );
    write_square(&dir, &[attribute], &material);
    let image = render_square(&ctx, &dir);
    let linear = texels.map(|t| [0, 1, 2].map(|c| srgb_to_linear(t[c])));
    let bilinear = |u: f32, v: f32| {
        // Texel centres at 0.25 and 0.75; clamped outside them.
        let x = (2.0 * u - 0.5).clamp(0.0, 1.0);
        let y = (2.0 * v - 0.5).clamp(0.0, 1.0);
        [0, 1, 2].map(|c| {
            let top = linear[0][c] * (1.0 - x) + linear[1][c] * x;
            let bottom = linear[2][c] * (1.0 - x) + linear[3][c] * x;
            top * (1.0 - y) + bottom * y
        })
    };
    assert_pixels(
        &image,
        |tri, w| {
            let (mut u, mut v) = (0.0, 0.0);
            for (k, &corner) in tri.iter().enumerate() {
                u += w[k] * uvs[corner][0];
                v += w[k] * uvs[corner][1];
            }
            bilinear(u, v)
        },
        0.02,
        "UV-textured square",
    );
}
