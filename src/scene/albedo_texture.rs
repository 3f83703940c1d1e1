//! A TOML material's `albedo_texture`: an image file, or Mitsuba's checkerboard baked into one,
//! and its `to_uv` map, which is applied to the texture coordinates of the meshes that use the
//! material (so any affine map is exact, and the kernel reads textures as it always does).

use super::asset::load_texture;
use super::format::{AlbedoTextureFile, Array, Triple};
use super::{srgb_to_linear, Texture, Wrap};
use crate::input_file::InputFiles;
use anyhow::{bail, Result};
use glam::{Affine2, Mat2, Vec2, Vec3};
use std::path::Path;

/// Texels along each side of a baked checkerboard: each square spans 128, so the one-texel blend of
/// bilinear filtering at the square's edges is under 1% of it.
const CHECKERBOARD_TEXELS: u32 = 256;

/// The texture of `materials.NAME.albedo_texture` (`key`) and its map of texture coordinates.
pub fn load(t: &AlbedoTextureFile, key: &str, base: &Path, files: &InputFiles) -> Result<(Texture, Affine2)> {
    let texture = match (&t.file, &t.checkerboard) {
        (Some(file), None) => load_texture(files, &super::resolve(base, file))?,
        (None, Some(Array([a, b]))) => {
            let colors = [
                super::non_negative3(&format!("{key}.checkerboard"), *a)?,
                super::non_negative3(&format!("{key}.checkerboard"), *b)?,
            ];
            if colors.iter().any(|c| c.max_element() > 1.0) {
                bail!(
                    "{key}.checkerboard: colours must be at most 1 per channel (energy conservation), got {colors:?}"
                );
            }
            checkerboard(colors)
        }
        _ => bail!("{key}: give one of file and checkerboard"),
    };
    Ok((texture, to_uv(t.to_uv, key)?))
}

/// A texture's `to_uv` rows (`key`.to_uv) as an affine map; absent: the identity.
pub(super) fn to_uv(rows: Option<Array<Triple, 2>>, key: &str) -> Result<Affine2> {
    match rows {
        None => Ok(Affine2::IDENTITY),
        Some(Array([Array([a, b, c]), Array([d, e, f])])) => {
            let m = Affine2::from_mat2_translation(Mat2::from_cols(Vec2::new(a, d), Vec2::new(b, e)), Vec2::new(c, f));
            if !m.is_finite() {
                bail!("{key}.to_uv must be finite, got {rows:?}");
            }
            Ok(m)
        }
    }
}

/// Mitsuba's checkerboard over [0, 1]^2 (colour 0 where u and v are on the same side of 1/2), in
/// whichever 8-bit encoding, linear or sRGB, stores the two colours the closer.
fn checkerboard(colors: [Vec3; 2]) -> Texture {
    let srgb = encoding_error(colors, true) < encoding_error(colors, false);
    let texels_of = colors.map(|c| encode(c, srgb));
    let n = CHECKERBOARD_TEXELS;
    let texels = (0..n * n)
        .map(|k| {
            let (x, y) = (k % n, k / n);
            texels_of[usize::from((x >= n / 2) != (y >= n / 2))]
        })
        .collect();
    Texture { name: "checkerboard".to_owned(), width: n, height: n, texels, srgb, wrap: [Wrap::Repeat; 2] }
}

fn encode(c: Vec3, srgb: bool) -> [u8; 4] {
    let channel = |v: f32| {
        let stored = if srgb { linear_to_srgb(v) } else { v };
        (stored.clamp(0.0, 1.0) * 255.0).round() as u8
    };
    [channel(c.x), channel(c.y), channel(c.z), 255]
}

/// The largest relative error of the colours once stored and decoded.
fn encoding_error(colors: [Vec3; 2], srgb: bool) -> f32 {
    let decode = |b: u8| if srgb { srgb_to_linear(b) } else { f32::from(b) / 255.0 };
    let mut worst = 0.0f32;
    for c in colors {
        let stored = encode(c, srgb);
        for (v, b) in c.to_array().into_iter().zip(stored) {
            worst = worst.max((decode(b) - v).abs() / v.max(1e-3));
        }
    }
    worst
}

fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_checkerboard_has_colour_0_where_u_and_v_agree_and_stores_0_4_and_0_2_exactly() {
        let t = checkerboard([Vec3::splat(0.4), Vec3::splat(0.2)]);
        let n = t.width;
        let at = |u: f32, v: f32| t.texels[(v * n as f32) as usize * n as usize + (u * n as f32) as usize];
        assert!(!t.srgb, "0.4 and 0.2 are exact in linear 8 bits (102 and 51)");
        assert_eq!(at(0.25, 0.25), [102, 102, 102, 255]);
        assert_eq!(at(0.75, 0.75), [102, 102, 102, 255]);
        assert_eq!(at(0.75, 0.25), [51, 51, 51, 255]);
        assert_eq!(at(0.25, 0.75), [51, 51, 51, 255]);
    }

    #[test]
    fn dark_colours_are_stored_as_srgb() {
        assert!(checkerboard([Vec3::splat(0.01), Vec3::splat(0.003)]).srgb);
    }
}
