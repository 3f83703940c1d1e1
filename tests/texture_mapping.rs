//! Where textures are read on lavapipe (issue 13): glTF `KHR_texture_transform` (offset, rotation,
//! scale, its texCoord override), `texCoord` 1, and sampler wrap modes (REPEAT, CLAMP_TO_EDGE,
//! MIRRORED_REPEAT), each against a reference lookup computed here.
//!
//! A glTF square with an emission texture of four blocks of colour fills a 16 x 16 view. Its base
//! colour is black and the sky too, so a pixel is its emission alone, without noise: wherever the
//! reference says the whole pixel reads one block, the pixel is that block's colour to f32 rounding.

mod common;

use caustica::image::RgbImage;
use caustica::scene::Scene;
use common::gltf_square::{png_uri, write_gltf_square};
use common::*;
use std::path::Path;

const BLOCKS: [[u8; 3]; 4] = [[255, 64, 0], [0, 200, 100], [30, 30, 230], [128, 128, 128]];
const SIZE: u32 = 16;

/// 8 x 8 texels: four 4 x 4 blocks, top-left, top-right, bottom-left, bottom-right.
fn block_of_texel(x: i64, y: i64) -> usize {
    (y as usize / 4) * 2 + x as usize / 4
}

fn texture_png() -> Vec<u8> {
    let texels: Vec<[u8; 3]> = (0..64).map(|i| BLOCKS[block_of_texel(i % 8, i / 8)]).collect();
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, 8, 8);
    encoder.set_color(png::ColorType::Rgb);
    encoder.write_header().unwrap().write_image_data(&texels.concat()).unwrap();
    bytes
}

#[derive(Clone, Copy)]
enum Wrap {
    Repeat,
    Clamp,
    Mirror,
}

impl Wrap {
    fn gl(self) -> u32 {
        match self {
            Wrap::Repeat => 10497,
            Wrap::Clamp => 33071,
            Wrap::Mirror => 33648,
        }
    }

    /// The texel whole-numbered position `i` reads in an axis of `n`, as glTF (and OpenGL) define
    /// the mode.
    fn texel(self, i: i64, n: i64) -> i64 {
        match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::Clamp => i.clamp(0, n - 1),
            Wrap::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n {
                    m
                } else {
                    2 * n - 1 - m
                }
            }
        }
    }
}

/// A texture reference: the set it names, its transform (offset, rotation, scale, texCoord
/// override) and its sampler's wrap modes.
struct Mapping {
    tex_coord: u32,
    offset: [f64; 2],
    rotation: f64,
    scale: [f64; 2],
    override_set: Option<u32>,
    wrap: [Wrap; 2],
}

const PLAIN: Mapping = Mapping {
    tex_coord: 0,
    offset: [0.0, 0.0],
    rotation: 0.0,
    scale: [1.0, 1.0],
    override_set: None,
    wrap: [Wrap::Repeat, Wrap::Repeat],
};

impl Mapping {
    /// The texture coordinates read at TEXCOORD_0 = (u, v): the set the mapping names (set 1 swaps
    /// u and v), transformed by T x R x S as the extension defines.
    fn uv(&self, u: f64, v: f64) -> (f64, f64) {
        let (u, v) = if self.override_set.unwrap_or(self.tex_coord) == 1 { (v, u) } else { (u, v) };
        let (u, v) = (u * self.scale[0], v * self.scale[1]);
        let (s, c) = self.rotation.sin_cos();
        (c * u + s * v + self.offset[0], -s * u + c * v + self.offset[1])
    }

    /// The block whose texels a bilinear lookup at (u, v) reads, or None where it blends blocks.
    fn block(&self, u: f64, v: f64) -> Option<usize> {
        let (u, v) = self.uv(u, v);
        let (px, py) = (u * 8.0 - 0.5, v * 8.0 - 0.5);
        let (x0, y0) = (px.floor() as i64, py.floor() as i64);
        let blocks: Vec<usize> = [(x0, y0), (x0 + 1, y0), (x0, y0 + 1), (x0 + 1, y0 + 1)]
            .iter()
            .map(|&(x, y)| block_of_texel(self.wrap[0].texel(x, 8), self.wrap[1].texel(y, 8)))
            .collect();
        blocks.iter().all(|&b| b == blocks[0]).then_some(blocks[0])
    }

    /// The emissive texture reference, the texture and the sampler, as glTF JSON.
    fn json(&self) -> (String, String) {
        let override_set = self.override_set.map_or(String::new(), |s| format!(r#", "texCoord": {s}"#));
        let info = format!(
            r#"{{"index": 0, "texCoord": {}, "extensions": {{"KHR_texture_transform": {{"offset": [{}, {}], "rotation": {}, "scale": [{}, {}]{override_set}}}}}}}"#,
            self.tex_coord, self.offset[0], self.offset[1], self.rotation, self.scale[0], self.scale[1]
        );
        let resources = format!(
            r#""extensionsUsed": ["KHR_texture_transform"], "samplers": [{{"wrapS": {}, "wrapT": {}}}], "textures": [{{"source": 0, "sampler": 0}}], "images": [{{"uri": "{}"}}],"#,
            self.wrap[0].gl(),
            self.wrap[1].gl(),
            png_uri(&texture_png())
        );
        (info, resources)
    }
}

/// The square seen from 0.5 below with a field of view of 90 degrees, which it fills. Looking up
/// with image up = -z, image right is -x: pixel (x, y) sees u = 1 - (x + 0.5) / 16 and
/// v = (y + 0.5) / 16 of TEXCOORD_0.
fn render_square(ctx: &caustica::gpu::GpuContext, dir: &Path, mapping: &Mapping) -> RgbImage {
    let (info, resources) = mapping.json();
    let material = format!(
        r#"{{"pbrMetallicRoughness": {{"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0, "roughnessFactor": 1}}, "emissiveFactor": [1, 1, 1], "emissiveTexture": {info}}}"#
    );
    write_gltf_square(dir, "square.gltf", 0.0, 0.5, &material, &resources);
    let scene: Scene = Scene::parse(
        &format!(
            r#"
            camera = {{ position = [0.0, -0.5, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = 90.0 }}
            film = {{ width = {SIZE}, height = {SIZE}, spp = 4 }}
            [[meshes]]
            file = "square.gltf"
            "#
        ),
        "test scene",
        dir,
    )
    .expect("valid test scene");
    render(ctx, &scene, 1)
}

/// Every pixel whose whole footprint (its corners and centre: the box filter keeps each sample in
/// its pixel) reads one block by the reference is that block's colour; at least `least` pixels
/// are checked, so that a case cannot pass by checking nothing.
fn assert_reads_as_mapped(image: &RgbImage, mapping: &Mapping, least: usize, what: &str) {
    let mut checked = 0;
    for y in 0..SIZE {
        for x in 0..SIZE {
            let uv =
                |dx: f64, dy: f64| (1.0 - (x as f64 + 0.5 + dx) / SIZE as f64, (y as f64 + 0.5 + dy) / SIZE as f64);
            let offsets = [(0.0, 0.0), (-0.5, -0.5), (0.5, -0.5), (-0.5, 0.5), (0.5, 0.5)];
            let blocks: Vec<Option<usize>> = offsets
                .iter()
                .map(|&(dx, dy)| {
                    let (u, v) = uv(dx, dy);
                    mapping.block(u, v)
                })
                .collect();
            let Some(block) = blocks[0] else { continue };
            if blocks.iter().any(|&b| b != Some(block)) {
                continue;
            }
            checked += 1;
            let p = image.get(x, y);
            for c in 0..3 {
                let expected = srgb_to_linear(BLOCKS[block][c]);
                assert!(
                    (p[c] - expected).abs() <= 1e-4 * expected + 1e-6,
                    "{what}: pixel ({x}, {y}) channel {c} is {}, expected block {block}'s {expected}",
                    p[c]
                );
            }
        }
    }
    assert!(checked >= least, "{what}: only {checked} pixels read one block");
}

/// Offsets, rotations, scales and wrap modes, each read where the reference says: a transform
/// applied in the wrong order (S x R instead of R x S), rotated the wrong way, offset by the wrong
/// sign, a texCoord override ignored, or a wrap mode read as repeat shows a different block
/// somewhere in the view (each case below differs from the plain view and from its alternatives).
#[test]
fn textures_are_read_through_their_transform_texcoord_and_wrap_modes() {
    let (_lock, ctx) = gpu();
    let dir = temp_dir("texture-mapping");
    let cases = [
        (PLAIN, "plain"),
        (Mapping { offset: [0.5, 0.25], ..PLAIN }, "offset (0.5, 0.25)"),
        (Mapping { scale: [2.0, 2.0], ..PLAIN }, "scale 2, repeat"),
        (Mapping { scale: [2.0, 1.5], wrap: [Wrap::Clamp, Wrap::Clamp], ..PLAIN }, "scale (2, 1.5), clamp to edge"),
        (
            Mapping { scale: [2.0, 2.0], wrap: [Wrap::Mirror, Wrap::Clamp], ..PLAIN },
            "scale 2, mirrored repeat in u, clamp in v",
        ),
        (
            Mapping { rotation: 0.5, scale: [1.5, 1.0], offset: [0.1, 0.2], ..PLAIN },
            "rotation 0.5 after scale (1.5, 1), offset (0.1, 0.2)",
        ),
        (
            Mapping { rotation: std::f64::consts::FRAC_PI_2, wrap: [Wrap::Repeat, Wrap::Mirror], ..PLAIN },
            "rotation 90 degrees, mirrored in v",
        ),
        (Mapping { tex_coord: 1, ..PLAIN }, "texCoord 1"),
        (
            Mapping { override_set: Some(1), offset: [0.25, 0.0], ..PLAIN },
            "KHR_texture_transform's texCoord 1 override",
        ),
    ];
    for (mapping, what) in &cases {
        let image = render_square(&ctx, &dir, mapping);
        assert_reads_as_mapped(&image, mapping, 30, what);
    }
}
