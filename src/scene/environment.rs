//! Environment lighting: a constant sky or an HDR map (Debevec angular light probe, or lat-long,
//! or pbrt-v4's equal-area octahedral map resampled to lat-long).
//! The direction conventions are those of shaders/environment.glsl: +y up, -z forward.

use super::equal_area_map;
use super::format::{Array, EnvironmentFile};
use crate::image::{self, RgbImage};
use crate::input_file::InputFiles;
use anyhow::{bail, Result};
use glam::{DMat3, DVec3, Vec2, Vec3};
use std::f64::consts::{PI, TAU};
use std::path::Path;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapProjection {
    /// Debevec's angular map: image centre looks down -z, the circumference straight back (+z).
    Angular,
    /// Equirectangular: centre column looks down -z, top row straight up.
    LatLong,
}

#[derive(Clone, Debug)]
pub struct EnvironmentMap {
    pub projection: MapProjection,
    pub image: RgbImage,
    pub intensity: f32,
    /// Degrees about +y.
    pub rotation_deg: f32,
}

#[derive(Clone, Debug)]
pub enum Environment {
    /// Radiance of a uniform sky.
    Constant(Vec3),
    Map(EnvironmentMap),
}

pub(super) fn from_file(e: &EnvironmentFile, base: &Path, files: &InputFiles) -> Result<Environment> {
    // An equal-area map is resampled to a lat-long one once read.
    let maps = [
        (e.probe.as_ref(), MapProjection::Angular),
        (e.latlong.as_ref(), MapProjection::LatLong),
        (e.octahedral.as_ref(), MapProjection::LatLong),
    ];
    let given: Vec<_> = maps.iter().filter_map(|(f, p)| f.map(|f| (f, *p))).collect();
    if given.len() + usize::from(e.color.is_some()) > 1 {
        bail!("environment: give only one of color, probe, latlong and octahedral");
    }
    let axes = match (e.axes, e.octahedral.is_some() || e.latlong.is_some()) {
        (Some(_), false) => bail!("environment.axes go with an octahedral or lat-long map"),
        (None, _) => DMat3::IDENTITY,
        (Some(Array(axes)), true) => {
            let m = DMat3::from_cols_array_2d(&axes.map(|a| a.0.map(f64::from)));
            if !(m.is_finite() && (m.transpose() * m).abs_diff_eq(DMat3::IDENTITY, 1e-4)) {
                bail!("environment.axes must be orthonormal (a rotation, possibly with a mirror), got {axes:?}");
            }
            m
        }
    };
    if !(e.intensity.is_finite() && e.intensity >= 0.0) {
        bail!("environment.intensity must be finite and >= 0, got {}", e.intensity);
    }
    if !e.rotation.is_finite() {
        bail!("environment.rotation must be finite, got {}", e.rotation);
    }
    let Some(&(file, projection)) = given.first() else {
        let color = Vec3::from(e.color.map_or([0.0; 3], |c| c.0));
        if !color.is_finite() || color.min_element() < 0.0 {
            bail!("environment.color must be finite and >= 0, got {color:?}");
        }
        return Ok(Environment::Constant(color * e.intensity));
    };
    let path = super::resolve(base, file);
    let mut image = image::read_image_from(files, &path)?;
    let name = path.display().to_string();
    image::pfm::check_finite(&image, &name)?;
    if image.pixels.iter().flatten().any(|&c| c < 0.0) {
        bail!("{name}: the environment map has negative radiance");
    }
    if (projection == MapProjection::Angular || e.octahedral.is_some()) && image.width != image.height {
        bail!(
            "{name}: an angular light probe or an equal-area octahedral map must be square, got {} x {}",
            image.width,
            image.height
        );
    }
    if projection == MapProjection::Angular {
        fill_outside_disk(&mut image);
    }
    if e.octahedral.is_some() {
        image = equal_area_map::to_latlong(&image, axes);
    } else if axes != DMat3::IDENTITY {
        image = rotated_latlong(&image, axes);
    }
    Ok(Environment::Map(EnvironmentMap { projection, image, intensity: e.intensity, rotation_deg: e.rotation }))
}

/// The lat-long map of the same size whose directions are those of `image` turned by `axes` (the
/// world directions of `image`'s x, y and z; orthonormal), each texel looked up bilinearly: the
/// kernel's lat-long maps turn only about +y (`rotation`), and a map given another orientation
/// (Mitsuba's `envmap` to_world) is resampled once on load instead.
fn rotated_latlong(image: &RgbImage, axes: DMat3) -> RgbImage {
    let (w, h) = (image.width as usize, image.height as usize);
    let mut out = RgbImage::new(image.width, image.height);
    // Orthonormal, so the inverse is the transpose.
    let to_map = axes.transpose();
    for y in 0..h {
        let theta = (y as f64 + 0.5) / h as f64 * PI;
        for x in 0..w {
            let phi = ((x as f64 + 0.5) / w as f64 - 0.5) * TAU;
            let world = DVec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos());
            let d = (to_map * world).normalize();
            // Texel coordinates of d in `image`, texel centres at whole numbers.
            let u = (0.5 + d.x.atan2(-d.z) / TAU) * w as f64 - 0.5;
            let v = d.y.clamp(-1.0, 1.0).acos() / PI * h as f64 - 0.5;
            let (x0, y0) = (u.floor(), v.floor());
            let (fx, fy) = ((u - x0) as f32, (v - y0) as f32);
            let column = |i: f64| (i.rem_euclid(w as f64) as usize).min(w - 1) as u32;
            let row = |i: f64| i.clamp(0.0, (h - 1) as f64) as u32;
            let texel = |i: f64, j: f64| image.get(column(i), row(j));
            let lerp = |a: [f32; 3], b: [f32; 3], t: f32| std::array::from_fn(|c| a[c] + (b[c] - a[c]) * t);
            let top = lerp(texel(x0, y0), texel(x0 + 1.0, y0), fx);
            let bottom = lerp(texel(x0, y0 + 1.0), texel(x0 + 1.0, y0 + 1.0), fx);
            out.set(x as u32, y as u32, lerp(top, bottom, fy));
        }
    }
    out
}

/// Debevec angular map (u, v) in [-1, 1]^2 for a unit direction, u right and v up; the mirror of
/// `angular_map_uv` in shaders/environment.glsl.
pub fn angular_map_uv(d: Vec3) -> Vec2 {
    let xy = Vec2::new(d.x, d.y).length();
    if xy < 1e-7 {
        return Vec2::new(0.0, if d.z < 0.0 { 0.0 } else { 1.0 });
    }
    let r = (-d.z).clamp(-1.0, 1.0).acos() / (std::f32::consts::PI * xy);
    Vec2::new(d.x, d.y) * r
}

/// Replaces every texel whose centre lies outside the probe's circle with the texel just inside the
/// circle on the same radius. The kernel filters bilinearly, so without this the black corners (and
/// the credit text printed there) would bleed into directions near straight back.
fn fill_outside_disk(image: &mut RgbImage) {
    let n = image.width as f32;
    let texel_uv = |x: u32, y: u32| Vec2::new((x as f32 + 0.5) / n * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / n * 2.0);
    let source = image.clone();
    let inner_radius = 1.0 - 1.0 / n;
    for y in 0..image.height {
        for x in 0..image.width {
            let uv = texel_uv(x, y);
            if uv.length() <= 1.0 {
                continue;
            }
            // Step inward along the radius until the texel centre is inside the disk.
            let mut r = inner_radius;
            let value = loop {
                let p = uv.normalize() * r;
                let sx = (((p.x + 1.0) * 0.5 * n) as u32).min(image.width - 1);
                let sy = (((1.0 - p.y) * 0.5 * n) as u32).min(image.height - 1);
                if texel_uv(sx, sy).length() <= 1.0 || r <= 0.0 {
                    break source.get(sx, sy);
                }
                r -= 0.5 / n;
            };
            image.set(x, y, value);
        }
    }
}
