//! Optical constants behind the materials: named metals as RGB complex indices of refraction, and
//! the dielectric Fresnel average a plastic's coat needs. The kernel's twins are in
//! shaders/fresnel.glsl.

use glam::Vec3;

/// Complex IOR (eta, k) of the named metals, RGB at about 650, 550 and 450 nm (the usual fits to
/// measured spectra, as in pbrt's and Mitsuba's tables).
pub const METALS: [(&str, [f32; 3], [f32; 3]); 4] = [
    ("gold", [0.143, 0.374, 1.442], [3.983, 2.386, 1.603]),
    ("silver", [0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
    ("copper", [0.200, 0.924, 1.102], [3.912, 2.452, 2.142]),
    ("aluminium", [1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
];

/// (eta, k) of a metal in [`METALS`].
pub fn metal(name: &str) -> Option<(Vec3, Vec3)> {
    METALS.iter().find(|(n, _, _)| *n == name).map(|&(_, eta, k)| (Vec3::from(eta), Vec3::from(k)))
}

/// Unpolarised reflectance entering a medium of relative index `ior` at cos_i in [0, 1].
pub fn fresnel_dielectric(cos_i: f64, ior: f64) -> f64 {
    let eta = 1.0 / ior;
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Cosine-weighted hemispherical average 2 ∫ F(mu) mu dmu of the reflectance entering `ior`.
pub fn average_fresnel(ior: f32) -> f32 {
    const STEPS: usize = 4096;
    let h = 1.0 / STEPS as f64;
    let sum: f64 = (0..STEPS)
        .map(|i| {
            let mu = (i as f64 + 0.5) * h;
            fresnel_dielectric(mu, ior as f64) * mu
        })
        .sum();
    (2.0 * sum * h) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_is_the_textbook_value() {
        assert!((fresnel_dielectric(1.0, 1.5) - 0.04).abs() < 1e-12);
        assert_eq!(fresnel_dielectric(0.0, 1.5), 1.0);
    }

    #[test]
    fn average_fresnel_matches_the_known_diffuse_reflectance() {
        // 0.0918 for n = 1.5 (the external diffuse Fresnel reflectance of e.g. Jensen et al. 2001).
        let f = average_fresnel(1.5);
        assert!((f - 0.0918).abs() < 5e-4, "{f}");
        assert_eq!(average_fresnel(1.0), 0.0);
    }

    #[test]
    fn every_metal_has_positive_constants() {
        for (name, eta, k) in METALS {
            assert!(eta.iter().chain(&k).all(|v| *v > 0.0), "{name}");
            assert_eq!(metal(name), Some((Vec3::from(eta), Vec3::from(k))));
        }
        assert_eq!(metal("brass"), None);
    }
}
