//! pbrt-v4's environment maps: square images in Clarberg's equal-area octahedral mapping of the
//! sphere ("Fast Equal-Area Mapping of the (Hemi)Sphere using SIMD", 2008), the map's +z at the
//! image centre, -z at its corners, +x towards the right edge and +y towards the bottom (row 0 at
//! the top, as pbrt reads images). caustica's kernel reads lat-long maps, so an equal-area map is
//! resampled to one on load.

use crate::image::RgbImage;
use glam::{DMat3, DVec2, DVec3};
use std::f64::consts::{FRAC_PI_2, PI};

/// The tallest lat-long map made (twice as wide): as detailed as an equal-area map of this size.
const MAX_LATLONG_HEIGHT: u32 = 8192;

/// Where a unit direction (in the map's frame) lies on the square, in [0, 1]^2.
pub fn sphere_to_square(d: DVec3) -> DVec2 {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let b = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = b.atan() / FRAC_PI_2;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    DVec2::new(0.5 * (u.copysign(d.x) + 1.0), 0.5 * (v.copysign(d.y) + 1.0))
}

/// The unit direction of a point of the square (the inverse of [`sphere_to_square`]; pbrt's
/// `EqualAreaSquareToSphere`).
pub fn square_to_sphere(p: DVec2) -> DVec3 {
    let (u, v) = (2.0 * p.x - 1.0, 2.0 * p.y - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed_distance = 1.0 - (up + vp);
    let r = 1.0 - signed_distance.abs();
    let phi = (if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 }) * std::f64::consts::FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed_distance);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    DVec3::new(phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z)
}

/// The lat-long map (caustica's convention, docs/scene-format.md "Environment map conventions") of the square
/// equal-area map `image`, whose x, y and z axes point along the columns of `axes` in the world
/// (orthonormal: a rotation, or a rotation and a mirror). Texels are looked up nearest, so each
/// lat-long texel takes the equal-area texel its centre falls in.
pub fn to_latlong(image: &RgbImage, axes: DMat3) -> RgbImage {
    let height = image.height.clamp(1, MAX_LATLONG_HEIGHT);
    let mut out = RgbImage::new(2 * height, height);
    // Orthonormal, so the inverse is the transpose.
    let to_map = axes.transpose();
    let n = image.width as f64;
    for y in 0..out.height {
        let theta = (y as f64 + 0.5) / out.height as f64 * PI;
        for x in 0..out.width {
            let phi = ((x as f64 + 0.5) / out.width as f64 - 0.5) * 2.0 * PI;
            let world = DVec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos());
            let p = sphere_to_square((to_map * world).normalize());
            let (sx, sy) = (((p.x * n) as u32).min(image.width - 1), ((p.y * n) as u32).min(image.height - 1));
            out.set(x, y, image.get(sx, sy));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_two_mappings_invert_each_other_and_put_the_axes_where_pbrt_has_them() {
        assert!(square_to_sphere(DVec2::splat(0.5)).abs_diff_eq(DVec3::Z, 1e-12));
        assert!(square_to_sphere(DVec2::new(0.0, 0.0)).abs_diff_eq(-DVec3::Z, 1e-12));
        assert!(square_to_sphere(DVec2::new(1.0, 0.5)).abs_diff_eq(DVec3::X, 1e-12));
        assert!(square_to_sphere(DVec2::new(0.5, 1.0)).abs_diff_eq(DVec3::Y, 1e-12));
        for i in 0..40 {
            for j in 0..40 {
                let p = DVec2::new((i as f64 + 0.5) / 40.0, (j as f64 + 0.5) / 40.0);
                let d = square_to_sphere(p);
                assert!((d.length() - 1.0).abs() < 1e-12);
                assert!(sphere_to_square(d).abs_diff_eq(p, 1e-9), "{p} -> {d} -> {}", sphere_to_square(d));
            }
        }
    }

    #[test]
    fn equal_areas_of_the_square_are_equal_solid_angles() {
        // The fraction of square cells whose centres map into the cap z > 0.5 is the cap's share
        // of the sphere, (1 - 0.5) / 2.
        let n = 400;
        let inside = (0..n * n)
            .filter(|k| square_to_sphere(DVec2::new((k % n) as f64 + 0.5, (k / n) as f64 + 0.5) / n as f64).z > 0.5)
            .count();
        assert!((inside as f64 / (n * n) as f64 - 0.25).abs() < 2e-3, "{inside}");
    }

    #[test]
    fn a_map_bright_towards_its_z_is_bright_where_its_z_axis_points() {
        // Bright where the map's z > 0 (the diamond in the middle), its z turned to the world's +y.
        let mut image = RgbImage::new(32, 32);
        for y in 0..32 {
            for x in 0..32 {
                let d = square_to_sphere(DVec2::new((x as f64 + 0.5) / 32.0, (y as f64 + 0.5) / 32.0));
                image.set(x, y, if d.z > 0.0 { [1.0; 3] } else { [0.0; 3] });
            }
        }
        let z_up = DMat3::from_cols(DVec3::X, -DVec3::Z, DVec3::Y);
        let latlong = to_latlong(&image, z_up);
        assert_eq!((latlong.width, latlong.height), (64, 32));
        for y in [0, 5, 10] {
            assert!((0..64).all(|x| latlong.get(x, y)[0] == 1.0), "row {y}: the upper hemisphere is bright");
            assert!((0..64).all(|x| latlong.get(x, 31 - y)[0] == 0.0), "row {}: the lower one dark", 31 - y);
        }
    }
}
