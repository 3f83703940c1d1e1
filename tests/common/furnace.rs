//! The white furnace: a unit sphere under a uniform environment of radiance 1, and which pixels
//! see the sphere, the background or both.

use super::parse;
use caustica::image::RgbImage;
use caustica::render::{frame_params, SceneData};
use caustica::scene::Scene;
use glam::Vec3;

/// A sphere of radius 1 at the origin, seen from z = 3.5, in a uniform environment of radiance 1.
pub fn furnace(material: &str, size: u32, spp: u32) -> Scene {
    parse(&format!(
        r#"
        [camera]
        position = [0.0, 0.0, 3.5]
        look_at = [0.0, 0.0, 0.0]
        fov = 40.0
        [film]
        width = {size}
        height = {size}
        spp = {spp}
        [materials.m]
        {material}
        [[spheres]]
        center = [0.0, 0.0, 0.0]
        radius = 1.0
        material = "m"
        [environment]
        color = [1.0, 1.0, 1.0]
        "#
    ))
}

#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Coverage {
    Sphere,
    Background,
    Edge,
}

/// Which pixels see only the unit sphere at the origin, only the background, or both, from the
/// camera's own ray directions with a margin of 1.5 pixels around the silhouette.
pub fn coverage(scene: &Scene) -> Vec<Coverage> {
    let data = SceneData::new(scene, 0);
    let p = frame_params(scene, &data, 0);
    let (w, h) = (scene.film.width, scene.film.height);
    let eye = Vec3::from_slice(&p.cam_origin);
    let forward = Vec3::from_slice(&p.cam_forward);
    let right = Vec3::from_slice(&p.cam_right);
    let up = Vec3::from_slice(&p.cam_up);
    let tan_half = p.tan_half_fov;
    let to_center = (-eye).normalize();
    let silhouette = (1.0 / eye.length()).asin();
    let margin = 1.5 * 2.0 * tan_half / h as f32;
    let mut out = vec![];
    for y in 0..h {
        for x in 0..w {
            let fx = (2.0 * (x as f32 + 0.5) / w as f32 - 1.0) * tan_half * p.aspect;
            let fy = (1.0 - 2.0 * (y as f32 + 0.5) / h as f32) * tan_half;
            let d = (forward + fx * right + fy * up).normalize();
            let angle = d.dot(to_center).clamp(-1.0, 1.0).acos();
            out.push(if angle < silhouette - margin {
                Coverage::Sphere
            } else if angle > silhouette + margin {
                Coverage::Background
            } else {
                Coverage::Edge
            });
        }
    }
    out
}

/// Mean over the pixels of `region` (every channel) of two independent renders, and its standard
/// error from the renders' difference.
pub fn region_mean(a: &RgbImage, b: &RgbImage, cover: &[Coverage], region: Coverage) -> (f64, f64) {
    let mut sum = 0.0;
    let mut noise = 0.0;
    let mut n = 0.0;
    for (i, c) in cover.iter().enumerate() {
        if *c != region {
            continue;
        }
        for ch in 0..3 {
            let (pa, pb) = (a.pixels[i][ch] as f64, b.pixels[i][ch] as f64);
            sum += 0.5 * (pa + pb);
            noise += 0.5 * (pa - pb).powi(2) / 2.0; // variance of the two-render average
            n += 1.0;
        }
    }
    assert!(n > 30.0, "only {n} samples in region {region:?}");
    (sum / n, (noise / n / n).sqrt())
}

/// Asserts the mean over the pixels of `region` equals `expected` within 5 standard errors, the
/// per-pixel noise estimated from two independent renders of the region.
pub fn assert_region_mean(a: &RgbImage, b: &RgbImage, cover: &[Coverage], region: Coverage, expected: f64, what: &str) {
    let (mean, stderr) = region_mean(a, b, cover, region);
    let tolerance = 5.0 * stderr + 1e-5 * expected; // float rounding where a region has no noise
    assert!(
        (mean - expected).abs() <= tolerance,
        "{what}: {region:?} mean {mean:.5}, expected {expected} within {tolerance:.5} (5 standard errors = {:.5})",
        5.0 * stderr
    );
}
