//! Which light next-event estimation samples: each in proportion to its power (the flux it
//! emits), through a Walker/Vose alias table, so that a scene with thousands of dim emissive
//! triangles and one bright lamp spends its shadow rays on the lamp. The table covers the area
//! lights and then the point, spot and directional lights. The kernel picks a table entry and
//! keeps it or takes its alias in lights.glsl, and recomputes the area lights' power formula there
//! (`light_power`) for the pick probability of an emitter hit by BSDF sampling; a punctual light
//! carries its power to the kernel in its struct.
//!
//! The powers, in luminance (Rec. 709) of the light's colour:
//! - area light: area x pi x radiance (a Lambertian emitter), twice for a two-sided flat one;
//! - point: 4 pi x intensity;
//! - spot: 2 pi x intensity x (1 - (sin c - sin f) / (c - f)), the integral of its falloff
//!   (full to the angle f = falloff_start, linear in the angle to c = cone_angle) over the sphere;
//!   2 pi x intensity x (1 - cos c) when f = c;
//! - directional (delta or disk): irradiance x pi r^2, r the radius of the scene's bounding
//!   sphere: what crosses a disk that covers the scene (as pbrt does). A scene with nothing in it
//!   gives it no power.
//!
//! Any positive powers give unbiased images (the kernel divides by the probability it picked
//! with); these make the noise of each light's contribution roughly even.

use super::layout::GpuAliasEntry;
use super::luminance;
use crate::scene::{Light, Material, Shape};
use std::f64::consts::PI;

/// What the kernel gets: the table (empty for uniform selection) and the total power it divides
/// by (0 for uniform selection, which the kernel reads as "pick uniformly").
pub struct LightDistribution {
    pub table: Vec<GpuAliasEntry>,
    pub total_power: f32,
}

/// Flux of a world-space emitter whose radiance has luminance `luminance` (its emission's, or for
/// a textured emitter its texture-weighted mean: textured_emission.rs): area x pi x luminance (a
/// Lambertian emitter), twice for a two-sided quad or triangle (a sphere shows only its outside).
/// The kernel's `light_power` in lights.glsl is the same formula on the GPU form of the shape.
pub fn area_light_power(shape: &Shape, material: &Material, luminance: f64) -> f64 {
    let (area, sides) = match *shape {
        Shape::Sphere { radius, .. } => (4.0 * PI * (radius as f64).powi(2), 1.0),
        Shape::Quad { u, v, .. } => (u.as_dvec3().cross(v.as_dvec3()).length(), two_sided(material)),
        Shape::Triangle { v, .. } => {
            (0.5 * (v[1] - v[0]).as_dvec3().cross((v[2] - v[0]).as_dvec3()).length(), two_sided(material))
        }
    };
    area * PI * luminance * sides
}

/// Luminance of a material's (untextured) emission.
pub fn emission_luminance(material: &Material) -> f64 {
    luminance(&material.emission.to_array())
}

/// Flux of a point, spot or directional light by the formulas above; `scene_radius` is the
/// radius of the scene's bounding sphere.
pub fn punctual_light_power(light: &Light, scene_radius: f64) -> f64 {
    match *light {
        Light::Point { intensity, .. } => 4.0 * PI * luminance(&intensity.to_array()),
        Light::Spot { intensity, cone_angle, falloff_start, .. } => {
            let (c, f) = (cone_angle as f64, falloff_start as f64);
            let cone_fraction = if c - f > 1e-6 { 1.0 - (c.sin() - f.sin()) / (c - f) } else { 1.0 - c.cos() };
            2.0 * PI * luminance(&intensity.to_array()) * cone_fraction
        }
        Light::Directional { irradiance, .. } => luminance(&irradiance.to_array()) * PI * scene_radius * scene_radius,
    }
}

/// How many sides of a flat emitter radiate.
fn two_sided(material: &Material) -> f64 {
    if material.two_sided {
        2.0
    } else {
        1.0
    }
}

impl LightDistribution {
    /// Selection in proportion to `powers` (one per light, in the kernel's light order); uniform
    /// when `by_power` is false or no light has power.
    pub fn new(powers: &[f64], by_power: bool) -> LightDistribution {
        let uniform = LightDistribution { table: Vec::new(), total_power: 0.0 };
        if !by_power {
            return uniform;
        }
        let total: f64 = powers.iter().sum();
        // Non-finite or all-zero powers leave nothing to be proportional to.
        if !(total > 0.0 && total.is_finite() && (total as f32).is_normal()) {
            return uniform;
        }
        LightDistribution { table: alias_table(powers), total_power: total as f32 }
    }
}

/// Vose's alias table for `weights` (non-negative, positive sum): entry i keeps i with probability
/// `threshold` and otherwise gives `alias`, so picking an entry uniformly and then one of its two
/// yields i with probability weights[i] / sum. A zero weight is never kept nor anyone's alias.
pub fn alias_table(weights: &[f64]) -> Vec<GpuAliasEntry> {
    let n = weights.len();
    let total: f64 = weights.iter().sum();
    // Each entry's share scaled so that the average is 1.
    let mut scaled: Vec<f64> = weights.iter().map(|w| w * n as f64 / total).collect();
    let mut table: Vec<GpuAliasEntry> = (0..n as u32).map(|i| GpuAliasEntry { threshold: 1.0, alias: i }).collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        table[s] = GpuAliasEntry { threshold: scaled[s] as f32, alias: l as u32 };
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left holds a share of 1 up to rounding, and keeps itself (threshold 1) — except a
    // zero weight, which rounding must not make pickable: it hands its entry to the heaviest.
    let heaviest = (0..n).max_by(|&a, &b| weights[a].total_cmp(&weights[b])).unwrap_or(0);
    for i in small.into_iter().chain(large) {
        table[i] = if weights[i] > 0.0 {
            GpuAliasEntry { threshold: 1.0, alias: i as u32 }
        } else {
            GpuAliasEntry { threshold: 0.0, alias: heaviest as u32 }
        };
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// The probability of each index that the table gives: (its kept share + the shares others
    /// hand it) / n.
    fn table_pmf(table: &[GpuAliasEntry]) -> Vec<f64> {
        let n = table.len() as f64;
        let mut pmf = vec![0.0; table.len()];
        for (i, e) in table.iter().enumerate() {
            pmf[i] += e.threshold as f64 / n;
            pmf[e.alias as usize] += (1.0 - e.threshold as f64) / n;
        }
        pmf
    }

    fn assert_reproduces(weights: &[f64]) {
        let table = alias_table(weights);
        let total: f64 = weights.iter().sum();
        for (i, (p, w)) in table_pmf(&table).iter().zip(weights).enumerate() {
            // f32 thresholds: each entry's share is exact to 2^-24 of 1/n.
            let expected = w / total;
            assert!(
                (p - expected).abs() <= 1e-7 * (1.0 + expected * weights.len() as f64),
                "index {i}: table gives {p:e}, weights {expected:e}"
            );
            if *w == 0.0 {
                assert_eq!(*p, 0.0, "index {i} has no weight but can be picked");
            }
        }
    }

    #[test]
    fn one_light_is_always_picked() {
        assert_eq!(alias_table(&[3.5]), vec![GpuAliasEntry { threshold: 1.0, alias: 0 }]);
    }

    #[test]
    fn the_table_reproduces_the_pmf() {
        assert_reproduces(&[1.0, 2.0, 3.0, 4.0]);
        assert_reproduces(&[1.0, 1.0, 1.0]);
        assert_reproduces(&[1e-9, 1.0, 1e9]);
    }

    #[test]
    fn zero_power_lights_are_never_picked() {
        assert_reproduces(&[0.0, 1.0, 0.0, 0.0, 5.0, 0.0]);
        assert_reproduces(&[0.0, 0.0, 0.0, 1e-30]);
    }

    #[test]
    fn many_lights_of_widely_different_power() {
        // Thousands of dim emitters, a few bright ones, some dark (a deterministic LCG spread).
        let mut state = 12345u64;
        let weights: Vec<f64> = (0..20_000)
            .map(|i| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                let u = (state >> 11) as f64 / (1u64 << 53) as f64;
                match i % 1000 {
                    0 => 1e4 * u,
                    7 => 0.0,
                    _ => 1e-3 + u,
                }
            })
            .collect();
        assert_reproduces(&weights);
    }

    fn material(emission: [f32; 3], two_sided: bool) -> Material {
        Material {
            name: "lamp".into(),
            albedo: Vec3::ZERO,
            emission: Vec3::from(emission),
            two_sided,
            ..Default::default()
        }
    }

    #[test]
    fn power_is_area_times_pi_times_luminance() {
        let (one_sided, two_sided) = (material([1.0, 1.0, 1.0], false), material([0.0, 2.0, 0.0], true));
        let sphere = Shape::Sphere { center: Vec3::ZERO, radius: 0.5, material: 0 };
        let quad =
            Shape::Quad { origin: Vec3::ZERO, u: Vec3::new(2.0, 0.0, 0.0), v: Vec3::new(0.0, 0.0, 3.0), material: 0 };
        let triangle =
            Shape::Triangle { v: [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 3.0)], material: 1 };
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9 * b;
        let power = |shape: &Shape, m: &Material| area_light_power(shape, m, emission_luminance(m));
        assert!(close(power(&sphere, &one_sided), PI * PI));
        // A two-sided sphere still shows only its outside.
        assert!(close(power(&sphere, &material([1.0, 1.0, 1.0], true)), PI * PI));
        assert!(close(power(&quad, &one_sided), 6.0 * PI));
        assert!(close(power(&quad, &material([1.0, 1.0, 1.0], true)), 12.0 * PI));
        // Half the quad's area, two sides, luminance 2 x 0.7152.
        assert!(close(power(&triangle, &two_sided), 3.0 * PI * 2.0 * 2.0 * 0.7152));
    }

    /// The spot's power is its intensity integrated over the sphere: the closed form against a
    /// midpoint sum of 2 pi I(theta) sin(theta), with and without a falloff band.
    #[test]
    fn spot_power_is_its_intensity_integrated_over_the_sphere() {
        for (cone_deg, falloff_deg) in [(30.0f64, 20.0f64), (60.0, 0.0), (45.0, 45.0), (170.0, 100.0)] {
            let (c, f) = (cone_deg.to_radians(), falloff_deg.to_radians());
            let intensity = |t: f64| {
                if t <= f {
                    1.0
                } else if t >= c {
                    0.0
                } else {
                    (c - t) / (c - f)
                }
            };
            let steps = 200_000;
            let dt = PI / steps as f64;
            let numeric: f64 =
                (0..steps).map(|i| (i as f64 + 0.5) * dt).map(|t| 2.0 * PI * intensity(t) * t.sin() * dt).sum();
            let spot = Light::Spot {
                position: Vec3::ZERO,
                axis: Vec3::Y,
                intensity: Vec3::ONE,
                cone_angle: c as f32,
                falloff_start: f as f32,
            };
            let closed = punctual_light_power(&spot, 0.0);
            assert!(
                (closed / numeric - 1.0).abs() < 1e-5,
                "cone {cone_deg}, falloff {falloff_deg}: {closed} against {numeric}"
            );
        }
        let point = Light::Point { position: Vec3::ZERO, intensity: Vec3::ONE };
        assert!((punctual_light_power(&point, 0.0) - 4.0 * PI).abs() < 1e-9);
        let sun = Light::Directional { direction: -Vec3::Y, irradiance: Vec3::splat(2.0), angular_diameter: 0.01 };
        assert!((punctual_light_power(&sun, 3.0) - 2.0 * PI * 9.0).abs() < 1e-6);
    }

    #[test]
    fn uniform_selection_and_powerless_scenes_upload_no_table() {
        let by_power = LightDistribution::new(&[PI, PI], true);
        assert_eq!((by_power.table.len(), by_power.total_power), (2, 2.0 * std::f32::consts::PI));
        assert!(LightDistribution::new(&[PI, PI], false).table.is_empty());
        let none = LightDistribution::new(&[0.0], true);
        assert!(none.table.is_empty() && none.total_power == 0.0);
    }
}
