//! Emitters with an emission texture: how bright each of their triangles is on average, for
//! next-event estimation to pick it by its texture-weighted power. A textured emitter glows only
//! where its texture is bright (DamagedHelmet's lights are small details of one texture that
//! covers the whole mesh), so picking its triangles by area would spend most shadow rays on black
//! ones.
//!
//! The mean is over the triangle's texture footprint: the texture filtered as the kernel filters
//! it (textures.glsl: sRGB decoded, bilinear, wrapped by the texture's modes) at the centroids of a regular split of
//! the triangle into n^2 equal parts, n growing with the texels it covers. It needs no exactness:
//! the kernel reads the same number for picking and for the pick's probability (lights.glsl), so
//! any value gives an unbiased image, and a closer one less noise.

use super::luminance;
use crate::scene::{srgb_to_linear, Texture, Wrap};
use glam::{Vec2, Vec3};

/// Most subdivisions of a triangle's edge: n^2 = 1024 lookups for triangles that span many texels.
const MAX_SPLIT: u32 = 32;

/// Mean luminance of `emission` times the texture over the triangle whose corners have texture
/// coordinates `uv`.
pub fn mean_triangle_luminance(texture: &Texture, emission: Vec3, uv: [Vec2; 3]) -> f64 {
    let size = Vec2::new(texture.width as f32, texture.height as f32);
    let footprint_texels = 0.5 * ((uv[1] - uv[0]) * size).perp_dot((uv[2] - uv[0]) * size).abs();
    let n = (footprint_texels.sqrt().ceil() as u32).clamp(1, MAX_SPLIT);
    let at = |b1: f32, b2: f32| {
        let p = uv[0] + b1 * (uv[1] - uv[0]) + b2 * (uv[2] - uv[0]);
        luminance(&(emission * filtered(texture, p)).to_array())
    };
    let inv = 1.0 / n as f32;
    let mut sum = 0.0;
    // Row i, column j of the split: an upright part, and beside it (except at the row's end) an
    // upside-down one; each has area 1 / n^2 of the triangle.
    for i in 0..n {
        for j in 0..n - i {
            let (i, j) = (i as f32, j as f32);
            sum += at((i + 1.0 / 3.0) * inv, (j + 1.0 / 3.0) * inv);
            if i + j + 1.0 < n as f32 {
                sum += at((i + 2.0 / 3.0) * inv, (j + 2.0 / 3.0) * inv);
            }
        }
    }
    sum / (n * n) as f64
}

/// The texel that whole-numbered position `i` reads in an axis of `n` texels, as wrapped_texel()
/// in textures.glsl.
fn wrapped(i: i64, n: i64, wrap: Wrap) -> i64 {
    match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::MirroredRepeat => {
            let m = i.rem_euclid(2 * n);
            if m < n {
                m
            } else {
                2 * n - 1 - m
            }
        }
    }
}

/// Linear RGB of `texture` at `uv`, as texture_rgb() in textures.glsl computes it.
fn filtered(texture: &Texture, uv: Vec2) -> Vec3 {
    let (w, h) = (texture.width as i64, texture.height as i64);
    let p = uv * Vec2::new(w as f32, h as f32) - 0.5;
    let f = p - p.floor();
    let (x0, y0) = (p.x.floor() as i64, p.y.floor() as i64);
    let texel = |x: i64, y: i64| {
        let t = texture.texels[(wrapped(y, h, texture.wrap[1]) * w + wrapped(x, w, texture.wrap[0])) as usize];
        let channel = |c: u8| if texture.srgb { srgb_to_linear(c) } else { f32::from(c) / 255.0 };
        Vec3::new(channel(t[0]), channel(t[1]), channel(t[2]))
    };
    let top = texel(x0, y0).lerp(texel(x0 + 1, y0), f.x);
    let bottom = texel(x0, y0 + 1).lerp(texel(x0 + 1, y0 + 1), f.x);
    top.lerp(bottom, f.y)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(width: u32, height: u32, texels: Vec<[u8; 4]>) -> Texture {
        Texture { name: "t".into(), width, height, texels, srgb: true, wrap: Default::default() }
    }

    #[test]
    fn a_uniform_texture_gives_its_value_times_the_emission() {
        let grey = texture(2, 2, vec![[188, 188, 188, 255]; 4]);
        let uv = [Vec2::ZERO, Vec2::new(3.0, 0.0), Vec2::new(0.0, 0.5)];
        let expected = luminance(&[2.0, 4.0, 6.0]) * srgb_to_linear(188) as f64;
        let mean = mean_triangle_luminance(&grey, Vec3::new(2.0, 4.0, 6.0), uv);
        assert!((mean - expected).abs() < 1e-5 * expected, "{mean} vs {expected}");
    }

    /// The left half of the texture white, the right half black: the triangle below the
    /// texture's diagonal covers three quarters white, one inside the white half is as bright as
    /// white, and one inside the black half dark.
    #[test]
    fn the_mean_follows_the_footprint() {
        let mut texels = vec![[0, 0, 0, 255]; 64 * 64];
        for row in texels.chunks_mut(64) {
            row[..32].fill([255, 255, 255, 255]);
        }
        let half = texture(64, 64, texels);
        let lower_left = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.0, 1.0)];
        let mean = mean_triangle_luminance(&half, Vec3::ONE, lower_left);
        assert!((mean - 0.75).abs() < 0.01, "{mean}");
        let white = [Vec2::new(0.05, 0.1), Vec2::new(0.4, 0.1), Vec2::new(0.05, 0.9)];
        assert!((mean_triangle_luminance(&half, Vec3::ONE, white) - 1.0).abs() < 1e-6);
        let black = [Vec2::new(0.55, 0.1), Vec2::new(0.95, 0.1), Vec2::new(0.55, 0.9)];
        assert_eq!(mean_triangle_luminance(&half, Vec3::ONE, black), 0.0);
    }
}
