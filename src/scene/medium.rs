//! Participating media (`[[media]]`): what fills the space inside a material's closed shapes (its
//! `interior`) or the whole scene around the camera (`camera.medium`), and how light travels
//! through it: extinction sigma_t = sigma_a + sigma_s per world unit and channel, the share
//! sigma_s / sigma_t that scatters (the albedo), and the phase function that scatters it.

use super::format::{MediumFile, MediumKind, PhaseKind, Triple};
use super::grid_volume::{parse_vol, DensityGrid};
use crate::input_file::{InputFiles, InputKind};
use anyhow::{bail, Context as _, Result};
use glam::Vec3;
use std::path::Path;
use std::sync::Arc;

/// Most media a scene may define: the kernel tracks which medium a path is in as 8-bit codes
/// (render/layout.rs, MEDIUM_* constants), two of which mean "none" and "empty space".
pub const MAX_MEDIA: usize = 254;

/// A medium, coefficients per world unit with the file's `scale` applied: the same everywhere, or
/// times a density grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    pub name: String,
    /// Extinction sigma_a + sigma_s, per channel, finite and >= 0 (times the density, if any).
    pub sigma_t: Vec3,
    /// sigma_s / sigma_t per channel, in [0, 1] (0 where sigma_t is 0).
    pub albedo: Vec3,
    /// The phase function.
    pub phase: Phase,
    /// A heterogeneous medium's density grid, its `bounds` in world space (shared: scenes are
    /// cloned whole).
    pub density: Option<Arc<DensityGrid>>,
}

impl Medium {
    pub fn sigma_s(&self) -> Vec3 {
        self.sigma_t * self.albedo
    }

    pub fn sigma_a(&self) -> Vec3 {
        self.sigma_t - self.sigma_s()
    }
}

/// How a medium scatters: the distribution of the new direction about the old.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    /// Uniform over the sphere, 1 / (4 pi).
    Isotropic,
    /// Henyey-Greenstein of mean cosine `g`, in (-1, 1).
    HenyeyGreenstein { g: f32 },
}

impl Phase {
    /// Henyey-Greenstein's g; 0 for isotropic (which HG with g = 0 is).
    pub fn g(&self) -> f32 {
        match *self {
            Phase::Isotropic => 0.0,
            Phase::HenyeyGreenstein { g } => g,
        }
    }
}

/// Every `[[media]]` entry, in file order (their indices): names distinct, coefficients finite
/// and not negative, given as sigma_a + sigma_s or as sigma_t + albedo.
pub fn media_from(files: &[MediumFile], base: &Path, inputs: &InputFiles) -> Result<Vec<Medium>> {
    if files.len() > MAX_MEDIA {
        bail!("[[media]]: at most {MAX_MEDIA} media, got {}", files.len());
    }
    let mut media: Vec<Medium> = Vec::with_capacity(files.len());
    for (k, file) in files.iter().enumerate() {
        let medium = medium_from(k, file, base, inputs)?;
        if media.iter().any(|m| m.name == medium.name) {
            bail!("media[{k}].name: '{}' is defined twice", medium.name);
        }
        media.push(medium);
    }
    Ok(media)
}

fn medium_from(k: usize, file: &MediumFile, base: &Path, inputs: &InputFiles) -> Result<Medium> {
    let key = |field: &str| format!("media[{k}].{field}");
    if file.name.is_empty() {
        bail!("{}: a medium needs a name", key("name"));
    }
    let density = match (file.kind, &file.density) {
        (MediumKind::Homogeneous, None) => {
            if file.bounds.is_some() {
                bail!("{} is a density grid's: it needs type = \"heterogeneous\"", key("bounds"));
            }
            None
        }
        (MediumKind::Homogeneous, Some(_)) => {
            bail!("{} needs type = \"heterogeneous\" (a homogeneous medium has no grid)", key("density"))
        }
        (MediumKind::Heterogeneous, None) => bail!("{} = \"heterogeneous\" needs density (a .vol file)", key("type")),
        (MediumKind::Heterogeneous, Some(name)) => {
            let path = super::resolve(base, name);
            let bytes = inputs.read(&path, InputKind::DensityGrid)?;
            let mut grid = parse_vol(&bytes).with_context(|| format!("{}: {}", key("density"), path.display()))?;
            if let Some(bounds) = file.bounds {
                let (min, max) = (Vec3::from(bounds.0[0].0), Vec3::from(bounds.0[1].0));
                if !min.is_finite() || !max.is_finite() || min.cmpge(max).any() {
                    bail!(
                        "{} must be finite with min < max on every axis, got {:?}",
                        key("bounds"),
                        bounds.0.map(|b| b.0)
                    );
                }
                grid.bounds = (min, max);
            }
            Some(Arc::new(grid))
        }
    };
    let scale = file.scale;
    if !scale.is_finite() || scale < 0.0 {
        bail!("{} must be finite and >= 0, got {scale}", key("scale"));
    }
    let coefficient = |field: &str, v: Triple| -> Result<Vec3> {
        let v = Vec3::from(v.0);
        if !v.is_finite() || v.min_element() < 0.0 {
            bail!("{} must be finite and >= 0 per channel, got {:?}", key(field), v.to_array());
        }
        Ok(v)
    };
    let (sigma_t, albedo) = match (file.sigma_a, file.sigma_s, file.sigma_t, file.albedo) {
        (Some(a), Some(s), None, None) => {
            let (a, s) = (coefficient("sigma_a", a)?, coefficient("sigma_s", s)?);
            let t = a + s;
            (t, Vec3::select(t.cmpgt(Vec3::ZERO), s / t, Vec3::ZERO))
        }
        (None, None, Some(t), Some(albedo)) => {
            let albedo = coefficient("albedo", albedo)?;
            if albedo.max_element() > 1.0 {
                bail!("{} must be in [0, 1] per channel, got {:?}", key("albedo"), albedo.to_array());
            }
            (coefficient("sigma_t", t)?, albedo)
        }
        _ => bail!(
            "media[{k}] ('{}'): give sigma_a and sigma_s, or sigma_t and albedo (and no other coefficient)",
            file.name
        ),
    };
    let sigma_t = sigma_t * scale;
    if !sigma_t.is_finite() {
        bail!("{}: the coefficients times the scale overflow: {:?}", key("scale"), sigma_t.to_array());
    }
    let phase = match (file.phase, file.g) {
        (PhaseKind::Isotropic, None) => Phase::Isotropic,
        (PhaseKind::Isotropic, Some(_)) => bail!("{} is Henyey-Greenstein's: it needs phase = \"hg\"", key("g")),
        (PhaseKind::Hg, None) => bail!("{} = \"hg\" needs g, in (-1, 1)", key("phase")),
        (PhaseKind::Hg, Some(g)) => {
            if !(g > -1.0 && g < 1.0) {
                bail!("{} must be in (-1, 1), got {g}", key("g"));
            }
            Phase::HenyeyGreenstein { g }
        }
    };
    Ok(Medium { name: file.name.clone(), sigma_t, albedo, phase, density })
}

/// The index of the medium `name`, or an error naming `key` and the media defined.
pub fn medium_named(media: &[Medium], key: &str, name: &str) -> Result<u32> {
    match media.iter().position(|m| m.name == name) {
        Some(i) => Ok(i as u32),
        None => {
            let known: Vec<&str> = media.iter().map(|m| m.name.as_str()).collect();
            bail!(
                "{key}: unknown medium '{name}' (defined: {})",
                if known.is_empty() { "none".to_owned() } else { known.join(", ") }
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::format::Array;

    fn file() -> MediumFile {
        MediumFile {
            name: "fog".into(),
            kind: MediumKind::Homogeneous,
            density: None,
            bounds: None,
            sigma_a: Some(Array([0.1, 0.2, 0.3])),
            sigma_s: Some(Array([0.3, 0.2, 0.0])),
            sigma_t: None,
            albedo: None,
            scale: 2.0,
            phase: PhaseKind::Isotropic,
            g: None,
        }
    }

    #[test]
    fn sigma_a_and_sigma_s_become_sigma_t_and_albedo_scaled() {
        let m = media_from(&[file()], Path::new("."), &InputFiles::anywhere()).unwrap().remove(0);
        assert!((m.sigma_t - Vec3::new(0.8, 0.8, 0.6)).abs().max_element() < 1e-6, "{:?}", m.sigma_t);
        assert!((m.albedo - Vec3::new(0.75, 0.5, 0.0)).abs().max_element() < 1e-6, "{:?}", m.albedo);
        assert!((m.sigma_s() - Vec3::new(0.6, 0.4, 0.0)).abs().max_element() < 1e-6);
    }

    #[test]
    fn bad_coefficients_are_refused_naming_the_key() {
        let message =
            |f: MediumFile| format!("{:#}", media_from(&[f], Path::new("."), &InputFiles::anywhere()).unwrap_err());
        let e = message(MediumFile { sigma_a: Some(Array([-0.1, 0.0, 0.0])), ..file() });
        assert!(e.contains("media[0].sigma_a"), "{e}");
        let e = message(MediumFile { sigma_s: Some(Array([f32::NAN, 0.0, 0.0])), ..file() });
        assert!(e.contains("media[0].sigma_s"), "{e}");
        let e = message(MediumFile { scale: f32::INFINITY, ..file() });
        assert!(e.contains("media[0].scale"), "{e}");
        let e = message(MediumFile { sigma_t: Some(Array([1.0; 3])), ..file() });
        assert!(e.contains("sigma_t and albedo"), "{e}");
        let e = message(MediumFile {
            sigma_a: None,
            sigma_s: None,
            sigma_t: Some(Array([1.0; 3])),
            albedo: Some(Array([1.5, 0.0, 0.0])),
            ..file()
        });
        assert!(e.contains("media[0].albedo"), "{e}");
        let e = message(MediumFile { phase: PhaseKind::Hg, g: Some(1.0), ..file() });
        assert!(e.contains("media[0].g"), "{e}");
        let e = message(MediumFile { phase: PhaseKind::Hg, ..file() });
        assert!(e.contains("needs g"), "{e}");
        let e = format!("{:#}", media_from(&[file(), file()], Path::new("."), &InputFiles::anywhere()).unwrap_err());
        assert!(e.contains("defined twice"), "{e}");
    }
}
