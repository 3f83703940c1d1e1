//! Lights without a surface (`[[lights]]`): point, spot and directional, the last optionally a
//! disk of the sun's kind. They are validated here into [`Light`]s in radiometric units; the
//! kernel samples them in lights.glsl, and light_selection.rs gives each its power.

use super::format::{DirectionalLightFile, LightFile, PointLightFile, SpotLightFile};
use super::{finite, non_negative3, vec3};
use anyhow::{bail, Result};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Radiates `intensity` (W/sr) equally in every direction.
    Point { position: Vec3, intensity: Vec3 },
    /// A point light limited to a cone around `axis` (unit): `intensity` within `falloff_start`
    /// of the axis, nothing beyond `cone_angle`, linear in the angle between (radians both).
    Spot { position: Vec3, axis: Vec3, intensity: Vec3, cone_angle: f32, falloff_start: f32 },
    /// Light from infinitely far along `-direction` (unit; the way it travels), giving `irradiance`
    /// (W/m^2) on a surface facing it. An `angular_diameter` (radians) > 0 makes it a disk of
    /// uniform radiance filling that cone; 0 is a delta light.
    Directional { direction: Vec3, irradiance: Vec3, angular_diameter: f32 },
}

impl Light {
    /// Radiance of a directional light's disk: its irradiance over the cosine-weighted solid angle
    /// of the disk, pi sin^2(angular radius); None for lights that are not disks.
    pub fn disk_radiance(&self) -> Option<Vec3> {
        match *self {
            Light::Directional { irradiance, angular_diameter, .. } if angular_diameter > 0.0 => {
                let sin = (0.5 * angular_diameter as f64).sin();
                Some((irradiance.as_dvec3() / (std::f64::consts::PI * sin * sin)).as_vec3())
            }
            Light::Point { .. } | Light::Spot { .. } | Light::Directional { .. } => None,
        }
    }
}

impl Light {
    /// The light placed by `m` (object to world): positions as points, directions as vectors.
    /// None when `m` collapses a direction (a zero scale).
    pub fn transformed(&self, m: glam::Mat4) -> Option<Light> {
        let direction = |d: Vec3| Some(m.transform_vector3(d).normalize_or_zero()).filter(|d| *d != Vec3::ZERO);
        Some(match *self {
            Light::Point { position, intensity } => Light::Point { position: m.transform_point3(position), intensity },
            Light::Spot { position, axis, intensity, cone_angle, falloff_start } => Light::Spot {
                position: m.transform_point3(position),
                axis: direction(axis)?,
                intensity,
                cone_angle,
                falloff_start,
            },
            Light::Directional { direction: d, irradiance, angular_diameter } => {
                Light::Directional { direction: direction(d)?, irradiance, angular_diameter }
            }
        })
    }
}

/// Every `[[lights]]` entry, validated; errors name the entry's key.
pub(super) fn lights_from(lights: &[LightFile]) -> Result<Vec<Light>> {
    lights
        .iter()
        .enumerate()
        .map(|(k, light)| {
            let key = |field: &str| format!("lights[{k}].{field}");
            match light {
                LightFile::Point(p) => point_from(p, &key),
                LightFile::Spot(s) => spot_from(s, &key),
                LightFile::Directional(d) => directional_from(d, &key),
            }
        })
        .collect()
}

fn point_from(p: &PointLightFile, key: &dyn Fn(&str) -> String) -> Result<Light> {
    Ok(Light::Point {
        position: vec3(&key("position"), p.position)?,
        intensity: non_negative3(&key("intensity"), p.intensity)?,
    })
}

fn spot_from(s: &SpotLightFile, key: &dyn Fn(&str) -> String) -> Result<Light> {
    let position = vec3(&key("position"), s.position)?;
    let axis = vec3(&key("look_at"), s.look_at)? - position;
    if axis.length() == 0.0 {
        bail!("{} must differ from {}", key("look_at"), key("position"));
    }
    let cone_angle = finite(&key("cone_angle"), s.cone_angle)?;
    if !(cone_angle > 0.0 && cone_angle <= 180.0) {
        bail!("{} must be in (0, 180] degrees, got {cone_angle}", key("cone_angle"));
    }
    let falloff_start = finite(&key("falloff_start"), s.falloff_start)?;
    if !(0.0..=cone_angle).contains(&falloff_start) {
        bail!("{} must be in [0, cone_angle = {cone_angle}] degrees, got {falloff_start}", key("falloff_start"));
    }
    Ok(Light::Spot {
        position,
        axis: axis.normalize(),
        intensity: non_negative3(&key("intensity"), s.intensity)?,
        cone_angle: cone_angle.to_radians(),
        falloff_start: falloff_start.to_radians(),
    })
}

/// The narrowest directional light disk, in degrees (the sun is 0.53): anything narrower is a
/// delta light.
pub const MIN_DISK_DEGREES: f32 = 1e-3;

fn directional_from(d: &DirectionalLightFile, key: &dyn Fn(&str) -> String) -> Result<Light> {
    let direction = vec3(&key("direction"), d.direction)?;
    if direction.length() == 0.0 {
        bail!("{} must not be zero", key("direction"));
    }
    let angular_diameter = finite(&key("angular_diameter"), d.angular_diameter)?;
    if !(0.0..180.0).contains(&angular_diameter) {
        bail!("{} must be in [0, 180) degrees, got {angular_diameter}", key("angular_diameter"));
    }
    // Narrower disks' sampling pdfs (1 / (2 pi (1 - cos))) overflow f32 when squared by the MIS
    // weight, and their shadows cannot be told from a delta light's: they are taken as one.
    let angular_diameter = if angular_diameter < MIN_DISK_DEGREES {
        if angular_diameter > 0.0 {
            log::warn!(
                "{} = {angular_diameter} degrees is below {MIN_DISK_DEGREES}: taken as 0, a delta light",
                key("angular_diameter")
            );
        }
        0.0
    } else {
        angular_diameter
    };
    Ok(Light::Directional {
        direction: direction.normalize(),
        irradiance: non_negative3(&key("irradiance"), d.irradiance)?,
        angular_diameter: angular_diameter.to_radians(),
    })
}

#[cfg(test)]
mod tests {
    use crate::scene::{Light, Scene};
    use glam::Vec3;
    use std::path::Path;

    fn scene_with(lights: &str) -> anyhow::Result<Scene> {
        Scene::parse(
            &format!("camera = {{ position = [0, 0, 3], look_at = [0, 0, 0] }}\n{lights}"),
            "lights.toml",
            Path::new("."),
        )
    }

    fn error(lights: &str) -> String {
        format!("{:#}", scene_with(lights).expect_err("an invalid light"))
    }

    #[test]
    fn each_type_is_read_in_radiometric_units() {
        let scene = scene_with(
            "[[lights]]\ntype = \"point\"\nposition = [1, 2, 3]\nintensity = [4, 5, 6]\n\
             [[lights]]\ntype = \"spot\"\nposition = [0, 2, 0]\nlook_at = [0, 0, 0]\nintensity = [1, 1, 1]\ncone_angle = 30\nfalloff_start = 20\n\
             [[lights]]\ntype = \"directional\"\ndirection = [0, -2, 0]\nirradiance = [3, 3, 3]\nangular_diameter = 0.53",
        )
        .unwrap();
        assert_eq!(
            scene.lights[0],
            Light::Point { position: Vec3::new(1.0, 2.0, 3.0), intensity: Vec3::new(4.0, 5.0, 6.0) }
        );
        assert_eq!(
            scene.lights[1],
            Light::Spot {
                position: Vec3::Y * 2.0,
                axis: -Vec3::Y,
                intensity: Vec3::ONE,
                cone_angle: 30f32.to_radians(),
                falloff_start: 20f32.to_radians()
            }
        );
        let Light::Directional { direction, angular_diameter, .. } = scene.lights[2] else {
            panic!("a directional light")
        };
        assert_eq!((direction, angular_diameter), (-Vec3::Y, 0.53f32.to_radians()));
        // irradiance / (pi sin^2(diameter / 2)).
        let radiance = scene.lights[2].disk_radiance().unwrap().x as f64;
        let expected = 3.0 / (std::f64::consts::PI * (0.5 * 0.53f64.to_radians()).sin().powi(2));
        assert!((radiance / expected - 1.0).abs() < 1e-6, "{radiance} against {expected}");
        assert_eq!(scene.lights[0].disk_radiance(), None);
    }

    #[test]
    fn disks_narrower_than_the_bound_are_delta_lights() {
        let sun = |diameter: &str| {
            let text = format!(
                "[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]\nangular_diameter = {diameter}"
            );
            let Light::Directional { angular_diameter, .. } = scene_with(&text).unwrap().lights[0] else {
                panic!("a directional light")
            };
            angular_diameter
        };
        for tiny in ["1e-8", "1e-30", "0.0009"] {
            assert_eq!(sun(tiny), 0.0, "{tiny} degrees");
        }
        assert_eq!(sun("0.001"), 0.001f32.to_radians());
    }

    #[test]
    fn negative_or_non_finite_values_are_errors_naming_the_key() {
        let point =
            |intensity: &str| format!("[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = {intensity}");
        assert!(
            error(&point("[1, -1, 1]")).contains("lights[0].intensity must not be negative"),
            "{}",
            error(&point("[1, -1, 1]"))
        );
        assert!(error(&point("[1, nan, 1]")).contains("lights[0].intensity must be finite"));
        assert!(error(&point("[1, inf, 1]")).contains("lights[0].intensity must be finite"));
        let sun = |irradiance: &str, diameter: &str| {
            format!("[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = {irradiance}\nangular_diameter = {diameter}")
        };
        assert!(error(&sun("[-1, 1, 1]", "0")).contains("lights[0].irradiance must not be negative"));
        assert!(error(&sun("[1, 1, 1]", "-0.5")).contains("lights[0].angular_diameter must be in [0, 180)"));
        assert!(error(&sun("[1, 1, 1]", "nan")).contains("lights[0].angular_diameter must be finite"));
        let no_direction = "[[lights]]\ntype = \"directional\"\ndirection = [0, 0, 0]\nirradiance = [1, 1, 1]";
        assert!(error(no_direction).contains("lights[0].direction must not be zero"));
        let spot = |cone: &str, falloff: &str| {
            format!("[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = [1, 1, 1]\n[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\nlook_at = [0, 0, 0]\nintensity = [1, 1, 1]\ncone_angle = {cone}\nfalloff_start = {falloff}")
        };
        assert!(error(&spot("-30", "0")).contains("lights[1].cone_angle must be in (0, 180]"));
        assert!(error(&spot("30", "40")).contains("lights[1].falloff_start must be in [0, cone_angle = 30]"));
        assert!(error(&spot("30", "-1")).contains("lights[1].falloff_start must be in"));
        assert!(error(&spot("inf", "1")).contains("lights[1].cone_angle must be finite"));
        let aimless = "[[lights]]\ntype = \"spot\"\nposition = [0, 1, 0]\nlook_at = [0, 1, 0]\nintensity = [1, 1, 1]\ncone_angle = 30\nfalloff_start = 10";
        assert!(error(aimless).contains("lights[0].look_at must differ from lights[0].position"));
    }

    #[test]
    fn zero_intensity_is_fine_and_unknown_types_or_keys_are_errors() {
        assert!(scene_with("[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensity = [0, 0, 0]").is_ok());
        let unknown = error("[[lights]]\ntype = \"area\"\nposition = [0, 1, 0]");
        assert!(unknown.contains("area") && unknown.contains("point") && unknown.contains("directional"), "{unknown}");
        let misspelt = error("[[lights]]\ntype = \"point\"\nposition = [0, 1, 0]\nintensty = [1, 1, 1]");
        assert!(misspelt.contains("intensty"), "{misspelt}");
    }
}
