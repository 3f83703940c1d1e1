//! Texture maps of mesh files on lavapipe: emission textures (what an emitter shows, and how it
//! lights) and normal maps, against closed forms and against untextured equivalents.
//!
//! The meshes are OBJ quads with an MTL library and PNG textures written for each test.

mod common;

use caustica::image::RgbImage;
use caustica::scene::Scene;
use common::*;
use std::path::Path;

/// An RGB PNG of `width` x `height` texels, top row first.
fn png(width: u32, height: u32, texels: &[[u8; 3]]) -> Vec<u8> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.write_header().unwrap().write_image_data(&texels.concat()).unwrap();
    bytes
}

/// An OBJ square of side 1 at height `y` in the xz plane (x and z in [-0.5, 0.5]) facing down
/// (`up` false) or up, with texture coordinates u = x + 0.5 and v = z + 0.5 (its texture's top row
/// at z = -0.5) and vertex normals, using material `lamp` of `quad.mtl` (`mtl`), which may name
/// `tex.png` (`texture`). `flip_v`: v = 0.5 - z instead, the texture upside down.
fn write_square(dir: &Path, y: f32, up: bool, flip_v: bool, mtl: &str, texture: &[u8]) {
    let (normal, faces) = if up {
        (1, "f 1/1/1 3/3/1 2/2/1\nf 1/1/1 4/4/1 3/3/1")
    } else {
        (-1, "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1")
    };
    // OBJ's v runs up the image; the loader turns it into glTF's 1 - v.
    let vt = if flip_v { "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1" } else { "vt 0 1\nvt 1 1\nvt 1 0\nvt 0 0" };
    let obj = format!(
        "mtllib quad.mtl\nv -0.5 {y} -0.5\nv 0.5 {y} -0.5\nv 0.5 {y} 0.5\nv -0.5 {y} 0.5\n\
         {vt}\nvn 0 {normal} 0\nusemtl lamp\n{faces}\n"
    );
    std::fs::write(dir.join("quad.obj"), obj).unwrap();
    std::fs::write(dir.join("quad.mtl"), format!("newmtl lamp\n{mtl}\n")).unwrap();
    std::fs::write(dir.join("tex.png"), texture).unwrap();
}

/// A black square facing down with emission `mtl`.
fn write_quad(dir: &Path, y: f32, mtl: &str, texture: &[u8]) {
    write_square(dir, y, false, false, &format!("Kd 0 0 0\n{mtl}"), texture);
}

fn parse_in(dir: &Path, toml: &str) -> Scene {
    Scene::parse(toml, "test scene", dir).expect("valid test scene")
}

const KE: [f32; 3] = [2.0, 1.0, 0.5];

/// An emission texture seen directly equals texel x factor. The quad fills a 16 x 16 view from
/// below; its 8 x 8 texture is four blocks of 4 x 4 equal texels, so that inside each block
/// (away from its edges, where the bilinear filter blends blocks) every pixel is exactly one
/// block's colour, sRGB-decoded, times `Ke`. The emitter's albedo is black and the sky too, so a
/// pixel is its emission alone, without noise: the tolerance is f32 rounding (1e-4 relative), and
/// a texel decoded without sRGB (-50 % and more), the factor or the texture left out, or the
/// blocks mirrored fail it.
#[test]
fn an_emission_texture_seen_directly_is_texel_times_factor() {
    let (_lock, ctx) = gpu();
    let dir = temp_dir("emission-texture-direct");
    let blocks = [[255, 64, 0], [0, 200, 100], [30, 30, 230], [128, 128, 128]];
    let texels: Vec<[u8; 3]> = (0..64).map(|i| blocks[(i / 32) * 2 + (i % 8) / 4]).collect();
    write_quad(&dir, 0.0, &format!("Ke {} {} {}\nmap_Ke tex.png", KE[0], KE[1], KE[2]), &png(8, 8, &texels));
    // Looking up from below at the quad's front with image up = -z, image right is -x: the view
    // shows the texture mirrored left to right. fov 90 from 0.5 below fills it with the quad.
    let scene = parse_in(
        &dir,
        r#"
        camera = { position = [0.0, -0.5, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = 90.0 }
        film = { width = 16, height = 16, spp = 4 }
        [[meshes]]
        file = "quad.obj"
        "#,
    );
    let image = render(&ctx, &scene, 1);
    for (block, texel) in blocks.iter().enumerate() {
        let (bx, by) = (8 * (1 - block as u32 % 2), 8 * (block as u32 / 2));
        let expected: Vec<f32> = (0..3).map(|c| srgb_to_linear(texel[c]) * KE[c]).collect();
        for y in by + 2..by + 6 {
            for x in bx + 2..bx + 6 {
                let p = image.get(x, y);
                for c in 0..3 {
                    assert!(
                        (p[c] - expected[c]).abs() <= 1e-4 * expected[c] + 1e-6,
                        "pixel ({x}, {y}) channel {c}: {} vs texel x Ke {}",
                        p[c],
                        expected[c]
                    );
                }
            }
        }
    }
}

/// A 64 x 1 emission texture, white over texels `white` and black elsewhere.
fn band_texture(white: std::ops::Range<usize>) -> Vec<u8> {
    let texels: Vec<[u8; 3]> = (0..64).map(|i| if white.contains(&i) { [255; 3] } else { [0; 3] }).collect();
    png(64, 1, &texels)
}

/// The floor lit by the textured quad at height 1 (placed with `placement`, TOML keys of its
/// `[[meshes]]` entry) or, when `lamp` is given, by that untextured TOML quad instead; a small
/// second lamp at the side in both, so that light selection weighs the two by power.
fn floor_under(ctx: &caustica::gpu::GpuContext, dir: &Path, placement: &str, lamp: Option<&str>) -> RgbImage {
    let light = match lamp {
        Some(quad) => format!("[[quads]]\n{quad}\nmaterial = \"lamp\""),
        None => format!("[[meshes]]\nfile = \"quad.obj\"\n{placement}"),
    };
    let scene = parse_in(
        dir,
        &format!(
            r#"
            camera = {{ position = [0.0, 0.9, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = 90.0 }}
            film = {{ width = 24, height = 24, spp = 64 }}
            [materials.floor]
            albedo = [0.5, 0.5, 0.5]
            [materials.lamp]
            emission = [4.0, 4.0, 4.0]
            [materials.side]
            emission = [1.0, 1.0, 1.0]
            [[quads]]
            origin = [-2.0, 0.0, 2.0]
            edge_u = [4.0, 0.0, 0.0]
            edge_v = [0.0, 0.0, -4.0]
            material = "floor"
            [[quads]]
            origin = [0.8, 1.0, -0.1]
            edge_u = [0.2, 0.0, 0.0]
            edge_v = [0.0, 0.0, 0.2]
            material = "side"
            {light}
            "#
        ),
    );
    render(ctx, &scene, 7)
}

/// Textured emitters are lights for next-event estimation: a quad whose emission texture is white
/// over a band and black elsewhere lights the floor as an untextured quad over just the band, and
/// so does the same quad mirrored (its vertices reordered to keep the front side, which the light
/// sample must undo to find its texture coordinates). A light sample that ignored the texture
/// would make the floor 2.7 x (mirrored 2.7 x) too bright, one that read the band mirrored would
/// light the wrong side; the images must agree within 5 standard errors of their difference in
/// each quadrant.
#[test]
fn a_textured_emitter_lights_like_an_untextured_one_over_its_bright_texels() {
    let (_lock, ctx) = gpu();
    let dir = temp_dir("emission-texture-lights");
    // White over u in [0.125, 0.5): x in [-0.375, 0), so unmirrored the band lies at x < 0.
    write_quad(&dir, 1.0, "Ke 4 4 4\nmap_Ke tex.png", &band_texture(8..32));
    let band = "origin = [-0.375, 1.0, -0.5]\nedge_u = [0.375, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]";
    let mirrored_band = "origin = [0.0, 1.0, -0.5]\nedge_u = [0.375, 0.0, 0.0]\nedge_v = [0.0, 0.0, 1.0]";
    let textured = floor_under(&ctx, &dir, "", None);
    let reference = floor_under(&ctx, &dir, "", Some(band));
    assert_same_mean(&textured, &reference, 5.0, "textured quad against an untextured quad over its white band");
    let mirrored = floor_under(&ctx, &dir, "scale = [-1.0, 1.0, 1.0]", None);
    let mirrored_reference = floor_under(&ctx, &dir, "", Some(mirrored_band));
    assert_same_mean(&mirrored, &mirrored_reference, 5.0, "mirrored textured quad against the mirrored band");
}

/// A diffuse floor (albedo 0.5) whose normal map holds one texel, `texel`, seen from above under a
/// directional light of irradiance 2 arriving from `from` (towards the light), `bm` the map's scale,
/// the map upside down when `flip_v`.
fn normal_mapped_floor(
    ctx: &caustica::gpu::GpuContext,
    dir: &Path,
    texel: [u8; 3],
    from: glam::DVec3,
    bm: f32,
    flip_v: bool,
) -> RgbImage {
    write_square(dir, 0.0, true, flip_v, &format!("Kd 0.5 0.5 0.5\nnorm -bm {bm} tex.png"), &png(1, 1, &[texel]));
    let travel = -from;
    let scene = parse_in(
        dir,
        &format!(
            r#"
            camera = {{ position = [0.0, 0.5, 0.0], look_at = [0.0, 0.0, 0.0], up = [0.0, 0.0, -1.0], fov = 60.0 }}
            film = {{ width = 12, height = 12, spp = 4 }}
            [[meshes]]
            file = "quad.obj"
            [[lights]]
            type = "directional"
            direction = [{}, {}, {}]
            irradiance = [2.0, 2.0, 2.0]
            "#,
            travel.x, travel.y, travel.z
        ),
    );
    render(ctx, &scene, 5)
}

/// A normal map tilting a diffuse floor's normal by a known angle changes its brightness under a
/// directional light by that cosine: every pixel is albedo / pi x E x cos(bent normal, light).
/// The texel tilts the normal by 30 degrees (as stored in 8 bits) towards the tangent (+x, where
/// u grows) or the bitangent (-z: the image's up, where v falls, glTF's convention). Lit from
/// straight above the floor shows cos 30; lit from 30 degrees towards the side the normal leans
/// to it is as bright as a floor facing the light (a tangent or bitangent of the wrong sign gives
/// cos 60, half); with `-bm 0.5` the tilt halves. With the map upside down the image's up is +z,
/// and the bitangent with it (MikkTSpace's sign -1). Delta lights leave no noise: the tolerance
/// is f32 rounding (1e-4 relative).
#[test]
fn a_normal_map_changes_a_diffuse_plane_s_brightness_by_the_cosine_of_its_tilt() {
    use glam::DVec3;
    let (_lock, ctx) = gpu();
    let dir = temp_dir("normal-map-tilt");
    let tilt = 30f64.to_radians();
    let encode = |v: f64| ((v + 1.0) / 2.0 * 255.0).round() as u8;
    let decode = |c: u8| c as f64 / 255.0 * 2.0 - 1.0;
    let towards_tangent = [encode(tilt.sin()), encode(0.0), encode(tilt.cos())];
    let towards_bitangent = [encode(0.0), encode(tilt.sin()), encode(tilt.cos())];
    // The map's x along +x (the tangent), y along -z (the bitangent; +z upside down), z along +y
    // (the normal).
    let bent = |texel: [u8; 3], scale: f64, flip_v: bool| {
        let up = if flip_v { 1.0 } else { -1.0 };
        DVec3::new(scale * decode(texel[0]), decode(texel[2]), up * scale * decode(texel[1])).normalize()
    };
    let leaning = |x: f64, z: f64| DVec3::new(x * tilt.sin(), tilt.cos(), z * tilt.sin());
    for (texel, from, scale, flip_v, what) in [
        (towards_tangent, DVec3::Y, 1.0, false, "towards the tangent, light from above"),
        (towards_tangent, leaning(1.0, 0.0), 1.0, false, "towards the tangent, light from the side it leans to"),
        (towards_tangent, DVec3::Y, 0.5, false, "towards the tangent, light from above, map scale 0.5"),
        (towards_bitangent, leaning(0.0, -1.0), 1.0, false, "towards the bitangent, light from the side it leans to"),
        (
            towards_bitangent,
            leaning(0.0, 1.0),
            1.0,
            true,
            "towards the bitangent of the upside-down map, light from the side it leans to",
        ),
    ] {
        let image = normal_mapped_floor(&ctx, &dir, texel, from, scale as f32, flip_v);
        let expected = 0.5 / std::f64::consts::PI * 2.0 * bent(texel, scale, flip_v).dot(from);
        for (i, p) in image.pixels.iter().enumerate() {
            for (c, &value) in p.iter().enumerate() {
                let value = value as f64;
                assert!(
                    (value - expected).abs() <= 1e-4 * expected,
                    "{what}: pixel {i} channel {c} is {value:.6}, expected {expected:.6} (a flat floor: {:.6})",
                    0.5 / std::f64::consts::PI * 2.0 * from.y
                );
            }
        }
    }
}
