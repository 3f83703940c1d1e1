//! PNG and JPEG textures as RGBA8, and shrinking a set of textures to fit a memory budget.

use std::io::Cursor;
use std::path::Path;

use image::{DynamicImage, ImageReader, Limits};

use super::{AssetError, TextureImage, Wrap};
use crate::input_file::{describe_bytes, InputFiles, InputKind};

/// Largest accepted width or height: GPUs commonly cap 2D images at 16384, and the check runs
/// before any pixel is decoded so a hostile header cannot demand gigabytes.
const MAX_TEXTURE_SIDE: u32 = 16384;

/// The most one decoded texture keeps, as RGBA8: the renderer's whole texture budget
/// (`render::TEXTURE_BUDGET_BYTES` is defined as this). A larger texture could never be uploaded at full size, so it
/// is reduced while decoding rather than kept whole only to be halved later.
pub const MAX_TEXTURE_BYTES: u64 = 512 << 20;

/// What the decoder may allocate: a texture of the largest accepted size in the widest format PNG
/// has (16-bit RGBA, 8 bytes a pixel: 2 GiB), and 64 MiB for the decoder's own work. The image
/// crate's default, 512 MiB, refused textures the budget above promises to downsample.
const DECODE_LIMIT: u64 = MAX_TEXTURE_SIDE as u64 * MAX_TEXTURE_SIDE as u64 * 8 + (64 << 20);

/// Reads a PNG or JPEG colour image (format guessed from its bytes) through `files` as
/// sRGB-encoded RGBA8.
pub fn load_texture(files: &InputFiles, path: &Path) -> Result<TextureImage, AssetError> {
    let bytes = files.read(path, InputKind::Texture)?;
    let name = path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
    decode_texture(&bytes, name, true).map_err(|message| AssetError::invalid(path, message))
}

/// Decodes an in-memory PNG or JPEG (grey, RGB, 16-bit, ... all become RGBA8) within
/// [`MAX_TEXTURE_BYTES`]; `srgb` records whether its values are sRGB-encoded colour or linear
/// data. The error is the reason only, naming the image; the caller adds the file it came from.
pub(super) fn decode_texture(bytes: &[u8], name: String, srgb: bool) -> Result<TextureImage, String> {
    decode_texture_within(bytes, name, srgb, MAX_TEXTURE_BYTES)
}

/// [`decode_texture`], keeping at most `max_bytes` of RGBA8 texels: a larger image is reduced
/// while decoding, both sides halved as often as needed (as [`downsample_to_fit`] would), with a
/// note on stderr.
fn decode_texture_within(bytes: &[u8], name: String, srgb: bool, max_bytes: u64) -> Result<TextureImage, String> {
    let guessed =
        || ImageReader::new(Cursor::new(bytes)).with_guessed_format().map_err(|e| format!("image '{name}': {e}"));
    let (width, height) = guessed()?.into_dimensions().map_err(|e| format!("image '{name}': {e}"))?;
    if width > MAX_TEXTURE_SIDE || height > MAX_TEXTURE_SIDE {
        return Err(format!(
            "image '{name}' is {width}x{height}; at most {MAX_TEXTURE_SIDE} pixels per side are supported"
        ));
    }
    let mut reader = guessed()?;
    let mut limits = Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    limits.max_alloc = Some(DECODE_LIMIT);
    reader.limits(limits);
    let image = reader.decode().map_err(|e| match e {
        image::ImageError::Limits(_) => format!(
            "image '{name}' ({width}x{height}) cannot be decoded within the {} caustica allows a decoder: {e}",
            describe_bytes(DECODE_LIMIT)
        ),
        e => format!("image '{name}': {e}"),
    })?;
    let factor = reduction(width, height, max_bytes);
    let (texels, new_width, new_height) = if factor == 1 {
        // Reinterpreted in place when the allocation allows it, so no second full-size copy.
        let texels = bytemuck::allocation::try_cast_vec(image.into_rgba8().into_raw())
            .unwrap_or_else(|(_, raw)| raw.chunks_exact(4).map(|t| [t[0], t[1], t[2], t[3]]).collect());
        (texels, width, height)
    } else {
        let reduced = reduce(&image, factor, srgb);
        log::warn!(
            "caustica: note: texture '{name}' ({width}x{height}, {} as RGBA8) reduced to {}x{} to fit the {} texture budget",
            describe_bytes(rgba_bytes(width, height)),
            reduced.1,
            reduced.2,
            describe_bytes(max_bytes)
        );
        reduced
    };
    Ok(TextureImage { name, width: new_width, height: new_height, texels, srgb, wrap: [Wrap::Repeat; 2] })
}

fn rgba_bytes(width: u32, height: u32) -> u64 {
    u64::from(width) * u64::from(height) * 4
}

/// The power of two by which both sides (rounded down, at least 1) must shrink for the RGBA8
/// texels to fit `max_bytes`, or for the image to be one texel.
fn reduction(width: u32, height: u32, max_bytes: u64) -> u32 {
    let mut factor = 1u32;
    loop {
        let (w, h) = ((width / factor).max(1), (height / factor).max(1));
        if rgba_bytes(w, h) <= max_bytes || (w == 1 && h == 1) {
            return factor;
        }
        factor *= 2;
    }
}

/// The image shrunk by `factor` (a power of two) on both sides, each texel the mean of the
/// factor x factor block it covers (clipped by the image), in linear light for sRGB colour: what
/// halving it log2(factor) times gives, up to rounding. It goes one band of `factor` rows at a
/// time, so no full-size RGBA8 copy is ever made.
fn reduce(image: &DynamicImage, factor: u32, srgb: bool) -> (Vec<[u8; 4]>, u32, u32) {
    let (width, height) = (image.width(), image.height());
    let (new_width, new_height) = ((width / factor).max(1), (height / factor).max(1));
    let decode: [f32; 256] = std::array::from_fn(|v| if srgb { srgb_to_linear(v as u8) } else { v as f32 / 255.0 });
    let mut texels = Vec::with_capacity(new_width as usize * new_height as usize);
    let mut sums = vec![[0.0f32; 4]; new_width as usize];
    for y in 0..new_height {
        let top = y * factor;
        let band = image.crop_imm(0, top, width, factor.min(height - top)).into_rgba8();
        sums.fill([0.0; 4]);
        for row in band.rows() {
            for (x, pixel) in row.enumerate().take((new_width * factor) as usize) {
                let sum = &mut sums[x / factor as usize];
                for c in 0..4 {
                    sum[c] += if c < 3 { decode[pixel[c] as usize] } else { f32::from(pixel[c]) / 255.0 };
                }
            }
        }
        let columns = factor.min(width);
        let count = (columns * band.height()) as f32;
        let stored = |v: f32| (v * 255.0).round() as u8;
        for sum in &sums {
            let [r, g, b, a] = sum.map(|s| s / count);
            let colour = |v: f32| if srgb { linear_to_srgb(v) } else { stored(v) };
            texels.push([colour(r), colour(g), colour(b), stored(a)]);
        }
    }
    (texels, new_width, new_height)
}

/// Halves the largest textures (2x2 box filter) until their total size, width * height * 4 bytes,
/// fits `budget_bytes`, or every texture is 1x1; returns the final total. sRGB colour is averaged
/// in linear light, as sRGB averages would darken edges; alpha and linear data are averaged as
/// stored.
pub fn downsample_to_fit(textures: &mut [TextureImage], budget_bytes: u64) -> u64 {
    let bytes = |t: &TextureImage| u64::from(t.width) * u64::from(t.height) * 4;
    let mut total: u64 = textures.iter().map(bytes).sum();
    while total > budget_bytes {
        let Some(largest) = textures.iter_mut().filter(|t| t.width > 1 || t.height > 1).max_by_key(|t| bytes(t)) else {
            break;
        };
        total -= bytes(largest);
        halve(largest);
        total += bytes(largest);
    }
    total
}

/// Halves each side (rounding down, at least 1); an odd last row or column is folded into its
/// neighbour's box by clamping.
fn halve(texture: &mut TextureImage) {
    let (width, height) = (texture.width as usize, texture.height as usize);
    let (new_width, new_height) = ((width / 2).max(1), (height / 2).max(1));
    let mut texels = Vec::with_capacity(new_width * new_height);
    for y in 0..new_height {
        let rows = [2 * y, (2 * y + 1).min(height - 1)];
        for x in 0..new_width {
            let columns = [2 * x, (2 * x + 1).min(width - 1)];
            let mut sum = [0.0f32; 4];
            for row in rows {
                for column in columns {
                    let texel = texture.texels[row * width + column];
                    for (c, s) in sum.iter_mut().enumerate() {
                        *s +=
                            if c < 3 && texture.srgb { srgb_to_linear(texel[c]) } else { f32::from(texel[c]) / 255.0 };
                    }
                }
            }
            let [r, g, b, a] = sum.map(|s| s / 4.0);
            let stored = |v: f32| (v * 255.0).round() as u8;
            let colour = |v: f32| if texture.srgb { linear_to_srgb(v) } else { stored(v) };
            texels.push([colour(r), colour(g), colour(b), stored(a)]);
        }
    }
    texture.width = new_width as u32;
    texture.height = new_height as u32;
    texture.texels = texels;
}

/// One sRGB-encoded 8-bit value as linear (the kernel decodes texels the same way, textures.glsl).
pub fn srgb_to_linear(value: u8) -> f32 {
    let v = f32::from(value) / 255.0;
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn linear_to_srgb(linear: f32) -> u8 {
    let v = if linear <= 0.003_130_8 { linear * 12.92 } else { 1.055 * linear.powf(1.0 / 2.4) - 0.055 };
    (v.clamp(0.0, 1.0) * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::super::test_dir;
    use super::*;

    fn write_png(path: &Path, width: u32, height: u32, color: png::ColorType, depth: png::BitDepth, data: &[u8]) {
        let file = std::fs::File::create(path).unwrap();
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
        encoder.set_color(color);
        encoder.set_depth(depth);
        encoder.write_header().unwrap().write_image_data(data).unwrap();
    }

    #[test]
    fn png_rgba_decodes_top_row_first() {
        let dir = test_dir("png-rgba");
        let path = dir.join("tex.png");
        let data: Vec<u8> = (0..32).collect();
        write_png(&path, 4, 2, png::ColorType::Rgba, png::BitDepth::Eight, &data);
        let texture = load_texture(&InputFiles::anywhere(), &path).unwrap();
        assert_eq!((texture.width, texture.height, texture.name.as_str()), (4, 2, "tex.png"));
        assert_eq!(texture.texels.len(), 8);
        assert_eq!(texture.texels[0], [0, 1, 2, 3]);
        assert_eq!(texture.texels[4], [16, 17, 18, 19]);
        assert_eq!(texture.texels[7], [28, 29, 30, 31]);
    }

    #[test]
    fn grey_and_sixteen_bit_become_rgba8() {
        let dir = test_dir("png-grey");
        let grey = dir.join("grey.png");
        write_png(&grey, 2, 1, png::ColorType::Grayscale, png::BitDepth::Eight, &[10, 200]);
        assert_eq!(
            load_texture(&InputFiles::anywhere(), &grey).unwrap().texels,
            vec![[10, 10, 10, 255], [200, 200, 200, 255]]
        );
        let rgb16 = dir.join("rgb16.png");
        write_png(&rgb16, 1, 1, png::ColorType::Rgb, png::BitDepth::Sixteen, &[0xff, 0xff, 0x80, 0x00, 0x00, 0x00]);
        assert_eq!(load_texture(&InputFiles::anywhere(), &rgb16).unwrap().texels, vec![[255, 128, 0, 255]]);
    }

    #[test]
    fn oversized_or_broken_images_are_errors() {
        let dir = test_dir("png-bad");
        let huge = dir.join("huge.png");
        // A valid 20000x1 PNG: its header alone must get it rejected.
        write_png(&huge, 20000, 1, png::ColorType::Grayscale, png::BitDepth::Eight, &[0; 20000]);
        let err = load_texture(&InputFiles::anywhere(), &huge).unwrap_err().to_string();
        assert!(err.contains("huge.png") && err.contains("20000x1"), "{err}");

        let junk = dir.join("junk.png");
        std::fs::write(&junk, b"not an image at all").unwrap();
        assert!(load_texture(&InputFiles::anywhere(), &junk).unwrap_err().to_string().contains("junk.png"));
        assert!(load_texture(&InputFiles::anywhere(), &dir.join("missing.png"))
            .unwrap_err()
            .to_string()
            .contains("missing.png"));
    }

    fn png_bytes(width: u32, height: u32, color: png::ColorType, depth: png::BitDepth, data: &[u8]) -> Vec<u8> {
        let mut bytes = Vec::new();
        let mut encoder = png::Encoder::new(&mut bytes, width, height);
        encoder.set_color(color);
        encoder.set_depth(depth);
        encoder.write_header().unwrap().write_image_data(data).unwrap();
        bytes
    }

    #[test]
    fn an_over_budget_texture_is_reduced_while_decoding_as_downsampling_would() {
        let (width, height) = (64, 32);
        let data: Vec<u8> = (0..width * height * 4).map(|i| (i * 37 % 251) as u8).collect();
        let bytes = png_bytes(width, height, png::ColorType::Rgba, png::BitDepth::Eight, &data);
        for srgb in [true, false] {
            let full = decode_texture_within(&bytes, "t.png".into(), srgb, u64::MAX).unwrap();
            assert_eq!((full.width, full.height), (64, 32));
            // Half of each side fits 2048 bytes exactly: one halving, the same arithmetic.
            let reduced = decode_texture_within(&bytes, "t.png".into(), srgb, 2048).unwrap();
            let mut halved = vec![full.clone()];
            downsample_to_fit(&mut halved, 2048);
            assert_eq!(reduced, halved[0], "srgb {srgb}");
            let quarter = decode_texture_within(&bytes, "t.png".into(), srgb, 2047).unwrap();
            assert_eq!((quarter.width, quarter.height, quarter.texels.len()), (16, 8, 128));
        }
        // A 16-bit grey image too, down to one texel: the mean of 0 and 65535 in linear data.
        let data: Vec<u8> = [0u16, 65535, 0, 65535].iter().flat_map(|v| v.to_be_bytes()).collect();
        let bytes = png_bytes(4, 1, png::ColorType::Grayscale, png::BitDepth::Sixteen, &data);
        let one = decode_texture_within(&bytes, "g.png".into(), false, 4).unwrap();
        assert_eq!((one.width, one.height, one.texels.clone()), (1, 1, vec![[128, 128, 128, 255]]));
    }

    #[test]
    fn textures_are_kept_within_the_renderers_whole_budget() {
        assert_eq!(reduction(16384, 16384, MAX_TEXTURE_BYTES), 2);
        assert_eq!(reduction(16384, 8192, MAX_TEXTURE_BYTES), 1);
        assert_eq!(reduction(3, 1, 0), 2, "one texel at the most");
    }

    #[test]
    fn downsampling_halves_the_largest_until_the_budget_fits() {
        let texture = |name: &str, width: u32, height: u32, texel: [u8; 4]| TextureImage {
            name: name.to_owned(),
            width,
            height,
            texels: vec![texel; (width * height) as usize],
            srgb: true,
            wrap: Default::default(),
        };
        let mut textures = vec![texture("big", 8, 8, [255, 0, 128, 255]), texture("small", 2, 2, [9, 9, 9, 9])];
        assert_eq!(downsample_to_fit(&mut textures, 1 << 20), 8 * 8 * 4 + 2 * 2 * 4);
        assert_eq!(downsample_to_fit(&mut textures, 100), 4 * 4 * 4 + 2 * 2 * 4);
        assert_eq!((textures[0].width, textures[0].height), (4, 4));
        assert_eq!(textures[0].texels, vec![[255, 0, 128, 255]; 16], "a uniform colour survives the filter");
        assert_eq!(textures[1].width, 2);
        assert_eq!(downsample_to_fit(&mut textures, 0), 8, "stops when everything is 1x1");

        // Black and white average to mid grey in linear light (sRGB 188), not sRGB 128.
        let mut stripes = vec![TextureImage {
            name: "s".into(),
            width: 2,
            height: 1,
            texels: vec![[0, 0, 0, 0], [255, 255, 255, 255]],
            srgb: true,
            wrap: Default::default(),
        }];
        assert_eq!(downsample_to_fit(&mut stripes, 4), 4);
        assert_eq!(stripes[0].texels, vec![[188, 188, 188, 128]]);

        // Linear data (metallic-roughness) averages as stored: 0 and 255 give 128 (127.5 rounded).
        let mut data = vec![TextureImage {
            name: "d".into(),
            width: 2,
            height: 1,
            texels: vec![[0, 0, 0, 0], [255, 255, 255, 255]],
            srgb: false,
            wrap: Default::default(),
        }];
        assert_eq!(downsample_to_fit(&mut data, 4), 4);
        assert_eq!(data[0].texels, vec![[128, 128, 128, 128]]);
    }
}
