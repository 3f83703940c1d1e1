//! pbrt-v4 materials as caustica materials. caustica's materials take constant values but for the
//! diffuse reflectance, which may be a texture (`textures.rs`): a texture that varies anywhere
//! else is an error naming the file and line. docs/importers.md ("pbrt-v4") lists each mapping.

use super::super::scene_parts::{f32x3, relative_to};
use super::super::spectrum;
use super::mapping::Mapper;
use super::params::{Directive, Param};
use super::parser::MaterialDef;
use super::texture_value::TextureValue;
use crate::scene::format::{AlbedoTextureFile, Array, Encoding, ImageTextureFile, MaterialFile, Triple};
use crate::scene::METALS;
use anyhow::{anyhow, Result};
use glam::DVec3;

/// pbrt's named conductor spectra that caustica has measured indices of (`optics::METALS`).
const NAMED_METALS: [(&str, &str); 4] = [("Au", "gold"), ("Ag", "silver"), ("Cu", "copper"), ("Al", "aluminium")];

/// pbrt's named glasses and their index at the helium d line (587.6 nm), from the Schott catalogue.
const NAMED_GLASSES: [(&str, f64); 7] = [
    ("glass-BK7", 1.5168),
    ("glass-BAF10", 1.67003),
    ("glass-FK51A", 1.48656),
    ("glass-LASF9", 1.85025),
    ("glass-F5", 1.6727),
    ("glass-F10", 1.72825),
    ("glass-F11", 1.78472),
];

/// A conductor's index: one of caustica's named metals, or eta and k per channel.
enum Conductor {
    Named(&'static str),
    Complex(DVec3, DVec3),
}

impl Mapper<'_> {
    /// The material `def` describes; None for `interface`, which is no surface at all.
    pub(super) fn material(&mut self, def: &MaterialDef) -> Result<Option<MaterialFile>> {
        let d = &def.directive;
        let defaults = MaterialFile::default();
        let material = match def.ty.as_str() {
            "diffuse" => {
                let (albedo, albedo_texture) = self.albedo(d)?;
                MaterialFile { albedo: f32x3(albedo), albedo_texture, ..defaults }
            }
            "conductor" => {
                let (roughness, roughness_v) = self.roughness(d)?;
                let (metal, eta, k) = self.conductor(d, "")?;
                MaterialFile { reflectivity: Some(1.0), roughness, roughness_v, metal, eta, k, ..defaults }
            }
            "dielectric" => {
                let (roughness, roughness_v) = self.roughness(d)?;
                MaterialFile { transparency: 1.0, ior: self.dielectric_eta(d, "eta")?, roughness, roughness_v, ..defaults }
            }
            "coateddiffuse" => {
                self.warn("coated", || {
                    format!(
                        "{}: {}: coateddiffuse becomes caustica's coat over a diffuse base, the light the coat reflects back down summed in closed form (rho (1 - Fin) / (1 - rho Fin)) where pbrt follows it by random walks through a coat of some thickness",
                        d.at,
                        d.describe()
                    )
                });
                self.clear_layer(d)?;
                let (albedo, albedo_texture) = self.albedo(d)?;
                let (roughness, roughness_v) = self.roughness(d)?;
                // pbrt's random walk follows the light the coat reflects back down onto the base.
                MaterialFile { albedo: f32x3(albedo), albedo_texture, coat: true, coat_internal_reflections: true, ior: self.dielectric_eta(d, "eta")?, roughness, roughness_v, ..defaults }
            }
            "interface" => {
                d.check_all_used()?;
                return Ok(None);
            }
            // pbrt-v4's thindielectric is smooth: it has no roughness parameters.
            "thindielectric" => MaterialFile { transparency: 1.0, ior: self.dielectric_eta(d, "eta")?, thin: true, ..defaults },
            "coatedconductor" => {
                self.warn("coatedconductor", || {
                    format!(
                        "{}: {}: coatedconductor becomes caustica's clear coat (glTF's KHR_materials_clearcoat, factor 1) over the conductor: the coat reflects by its Fresnel term and the conductor, as seen from air, takes the rest; pbrt follows light between the two layers by random walks, with the conductor's index relative to the coat's",
                        d.at,
                        d.describe()
                    )
                });
                self.clear_layer(d)?;
                let coat_eta = self.dielectric_eta(d, "interface.eta")?;
                if coat_eta != 1.5 {
                    self.warn("coat eta", || format!("{}: {}: the coat's interface.eta {coat_eta} becomes 1.5, the index of caustica's clear coat", d.at, d.describe()));
                }
                let (clearcoat_roughness, coat_v) = self.roughness_of(d, "interface.")?;
                if coat_v.is_some() {
                    return Err(d.error("an anisotropic coat (interface.uroughness != interface.vroughness) is not supported: caustica's clear coat is isotropic"));
                }
                let (roughness, roughness_v) = self.roughness_of(d, "conductor.")?;
                let (metal, eta, k) = self.conductor(d, "conductor.")?;
                MaterialFile { reflectivity: Some(1.0), roughness, roughness_v, metal, eta, k, clearcoat: Some(1.0), clearcoat_roughness: Some(clearcoat_roughness), ..defaults }
            }
            _ => return Err(d.error("this material is not supported (diffuse, conductor, dielectric, thindielectric, coateddiffuse, coatedconductor, interface)")),
        };
        let material = MaterialFile { normal_texture: self.normal_map(d)?, ..material };
        d.check_all_used()?;
        Ok(Some(material))
    }

    /// A material's `normalmap`: pbrt reads the image as linear RGB at (u, 1 - v), which is
    /// caustica's (u, w) on a PLY (whose v it turns into w = 1 - v as it reads it), in the frame of
    /// dp/du and cross(n, dp/du): caustica's `normal_texture` as it stands.
    fn normal_map(&mut self, d: &Directive) -> Result<Option<ImageTextureFile>> {
        let Some(name) = d.string("normalmap")?.map(str::to_owned) else { return Ok(None) };
        let (path, _) = self.texture_image(d, &name)?;
        Ok(Some(ImageTextureFile {
            file: relative_to(&path, self.base),
            to_uv: None,
            encoding: Some(Encoding::Linear),
        }))
    }

    /// caustica's roughness and roughness_v from pbrt's `uroughness` and `vroughness` (each
    /// defaulting to `roughness`): with `remaproughness` (the default) pbrt's alpha is
    /// sqrt(roughness) (TrowbridgeReitzDistribution::RoughnessToAlpha), else the roughness
    /// itself; caustica's roughness is sqrt(alpha), the same Trowbridge-Reitz (GGX) distribution.
    /// pbrt's alpha_x lies along dp/du as caustica's roughness does; roughness_v is None where
    /// the two are equal (isotropic).
    fn roughness(&mut self, d: &Directive) -> Result<(f32, Option<f32>)> {
        self.roughness_of(d, "")
    }

    /// [`Mapper::roughness`] of one layer of a layered material: `prefix` is `interface.` or
    /// `conductor.` (pbrt's `remaproughness` is the material's, for both).
    fn roughness_of(&mut self, d: &Directive, prefix: &str) -> Result<(f32, Option<f32>)> {
        let key = |name: &str| format!("{prefix}{name}");
        let r = self.scalar(d, &key("roughness"), 0.0)?;
        let (u, v) = (
            self.scalar_if_given(d, &key("uroughness"))?.unwrap_or(r),
            self.scalar_if_given(d, &key("vroughness"))?.unwrap_or(r),
        );
        let remap = d.boolean("remaproughness", true)?;
        let roughness = |name: &str, r: f64| {
            let alpha = if remap { r.max(0.0).sqrt() } else { r };
            if !(0.0..=1.0).contains(&alpha) || r < 0.0 {
                return Err(d.error(format!("the {name} must give an alpha in [0, 1], got {name} {r} (alpha {alpha})")));
            }
            Ok(alpha.sqrt() as f32)
        };
        let along_u = roughness(&key(if u == r { "roughness" } else { "uroughness" }), u)?;
        let along_v = roughness(&key(if v == r { "roughness" } else { "vroughness" }), v)?;
        Ok((along_u, (u != v).then_some(along_v)))
    }

    /// A dielectric's index, the parameter `name` (`eta`, a coat's `interface.eta`): a number, or
    /// a named glass at its d-line index (a warning: pbrt disperses light through a spectral
    /// index, caustica does not).
    fn dielectric_eta(&mut self, d: &Directive, name: &str) -> Result<f32> {
        let eta = match d.param(name) {
            None => 1.5,
            Some(p) if p.ty == "spectrum" => match p.strings() {
                [name] => {
                    let (_, n) = NAMED_GLASSES.iter().find(|(g, _)| g == name).ok_or_else(|| {
                        let known: Vec<_> = NAMED_GLASSES.iter().map(|(g, _)| *g).collect();
                        p.error(format!("unknown glass (known: {})", known.join(", ")))
                    })?;
                    self.warn("dispersion", || format!("{}: a spectral eta (\"{name}\") becomes its index at 587.6 nm: caustica does not disperse light", p.at));
                    *n
                }
                _ => return Err(p.error("a dielectric's spectral eta must be a named glass or a number")),
            },
            Some(p) => self.scalar_param(p)?,
        };
        if !(eta > 0.0 && eta.is_finite()) {
            return Err(d.error(format!("{name} must be > 0, got {eta}")));
        }
        Ok(eta as f32)
    }

    /// A conductor's index: `reflectance` (pbrt's eta 1 and the k that gives that reflectance at
    /// normal incidence, caustica's eta and k exactly; 1 in every channel is the perfect mirror,
    /// None), or `eta` and `k` (default pbrt's copper), named metals taken by caustica's name.
    /// `prefix` is that of the `eta` and `k` parameters (`conductor.` in a coatedconductor).
    /// As the scene file's (metal, eta, k).
    fn conductor(&mut self, d: &Directive, prefix: &str) -> Result<(Option<String>, Option<Triple>, Option<Triple>)> {
        Ok(match self.conductor_index(d, prefix)? {
            None => (None, None, None),
            Some(Conductor::Named(name)) => (Some(name.to_owned()), None, None),
            Some(Conductor::Complex(eta, k)) => (None, Some(f32x3(eta)), Some(f32x3(k))),
        })
    }

    fn conductor_index(&mut self, d: &Directive, prefix: &str) -> Result<Option<Conductor>> {
        let (eta_name, k_name) = (format!("{prefix}eta"), format!("{prefix}k"));
        if d.params.iter().any(|p| p.name == "reflectance") {
            if d.param(&eta_name).is_some() || d.param(&k_name).is_some() {
                return Err(d.error(format!("give reflectance or {eta_name} and {k_name}, not both")));
            }
            let r = self.reflectance(d, "reflectance", 1.0)?;
            if r.min_element() >= 1.0 {
                return Ok(None);
            }
            // 1 in some channels only: as close to 1 as k can stay finite.
            let r = r.min(DVec3::splat(0.9999));
            let k = DVec3::new(r.x, r.y, r.z).map(|r| 2.0 * r.sqrt() / (1.0 - r).sqrt());
            return Ok(Some(Conductor::Complex(DVec3::ONE, k)));
        }
        let eta = self.metal_spectrum(d, &eta_name, "eta")?;
        let k = self.metal_spectrum(d, &k_name, "k")?;
        Ok(Some(match (eta, k) {
            (Ok(a), Ok(b)) if a == b => Conductor::Named(a),
            (eta, k) => {
                let values = |named: Result<&'static str, DVec3>, which: usize| {
                    named.map_or_else(
                        |v| v,
                        |name| {
                            let (_, eta, k) =
                                METALS.iter().find(|(n, _, _)| *n == name).expect("NAMED_METALS are METALS");
                            DVec3::from(if which == 0 { *eta } else { *k }.map(f64::from))
                        },
                    )
                };
                Conductor::Complex(values(eta, 0), values(k, 1))
            }
        }))
    }

    /// A conductor's `eta` or `k` (`which`), the parameter `name`: Ok(caustica's metal name) for a
    /// named spectrum (pbrt's copper by default), Err(the values) for a colour.
    fn metal_spectrum(
        &mut self,
        d: &Directive,
        name: &str,
        which: &str,
    ) -> Result<std::result::Result<&'static str, DVec3>> {
        let named = match d.param(name) {
            None => format!("metal-Cu-{which}"),
            Some(p) if p.ty == "spectrum" && !p.strings().is_empty() => p.strings()[0].clone(),
            Some(p) => {
                let v = self.color_param(p, "spectrum", 0)?;
                if v.min_element() < 0.0 {
                    return Err(p.error("must not be negative"));
                }
                return Ok(Err(v));
            }
        };
        let suffix = format!("-{which}");
        let metal = named.strip_prefix("metal-").and_then(|m| m.strip_suffix(suffix.as_str()));
        match metal.and_then(|m| NAMED_METALS.iter().find(|(n, _)| *n == m)) {
            Some((_, caustica)) => Ok(Ok(caustica)),
            None => {
                let known: Vec<_> = NAMED_METALS.iter().map(|(m, _)| format!("metal-{m}{suffix}")).collect();
                Err(anyhow!(
                    "{}: {}: the spectrum \"{named}\" for {name} is not supported (known: {})",
                    d.at,
                    d.describe(),
                    known.join(", ")
                ))
            }
        }
    }

    /// The parameters of a coat's medium and of pbrt's stochastic evaluation of a layered material,
    /// which caustica's closed-form coats have no use for; a scattering medium (`albedo` > 0) is an
    /// error.
    fn clear_layer(&mut self, d: &Directive) -> Result<()> {
        let albedo = self.color(d, "albedo", 0.0, "spectrum")?;
        if albedo != DVec3::ZERO {
            return Err(d.error("a scattering coat (albedo > 0) is not supported"));
        }
        self.scalar(d, "thickness", 0.01)?;
        self.scalar(d, "g", 0.0)?;
        d.integer("maxdepth")?;
        d.integer("nsamples")?;
        Ok(())
    }

    /// A diffuse `reflectance` (default 0.5): a constant, or a texture and the constant that
    /// multiplies it, each channel of which lies in [0, 1] (pbrt clamps a textured albedo there).
    fn albedo(&mut self, d: &Directive) -> Result<(DVec3, Option<AlbedoTextureFile>)> {
        let Some(p) = d.param("reflectance") else { return Ok((DVec3::splat(0.5), None)) };
        let (factor, texture) = match self.texture_param(p, "spectrum", 0)? {
            TextureValue::Constant(c) => (c, None),
            TextureValue::Varying { texture, factor } => (factor, Some(texture)),
        };
        let colors = texture
            .as_ref()
            .and_then(|t| t.checkerboard)
            .map_or(vec![], |Array(c)| c.map(|c| DVec3::from(c.0.map(f64::from))).to_vec());
        for c in colors.iter().chain([&factor]) {
            if !(c.min_element() >= 0.0 && c.max_element() <= 1.0) {
                return Err(p.error(format!("must be in [0, 1] per channel (energy conservation), got {c}")));
            }
        }
        Ok((factor, texture))
    }

    /// A colour each channel of which lies in [0, 1].
    fn reflectance(&mut self, d: &Directive, name: &str, default: f64) -> Result<DVec3> {
        let c = self.color(d, name, default, "spectrum")?;
        if !(c.min_element() >= 0.0 && c.max_element() <= 1.0) {
            return Err(d.error(format!("{name} must be in [0, 1] per channel (energy conservation), got {c}")));
        }
        Ok(c)
    }

    /// A spectrum-valued parameter (rgb, spectrum pairs, or a constant spectrum texture).
    fn color(&mut self, d: &Directive, name: &str, default: f64, value_type: &str) -> Result<DVec3> {
        match d.param(name) {
            None => Ok(DVec3::splat(default)),
            Some(p) => self.color_param(p, value_type, 0),
        }
    }

    fn scalar(&mut self, d: &Directive, name: &str, default: f64) -> Result<f64> {
        Ok(self.scalar_if_given(d, name)?.unwrap_or(default))
    }

    fn scalar_if_given(&mut self, d: &Directive, name: &str) -> Result<Option<f64>> {
        d.param(name).map(|p| self.scalar_param(p)).transpose()
    }

    /// A float-valued parameter (a float or a constant float texture).
    pub(super) fn scalar_param(&mut self, p: &Param) -> Result<f64> {
        Ok(self.color_param(p, "float", 0)?.x)
    }

    /// The constant value of a parameter of `value_type` (spectrum or float; a float is a grey).
    pub(super) fn color_param(&mut self, p: &Param, value_type: &str, depth: usize) -> Result<DVec3> {
        match (p.ty.as_str(), value_type) {
            ("texture", _) => match self.texture_param(p, value_type, depth)? {
                TextureValue::Constant(v) => Ok(v),
                TextureValue::Varying { .. } => Err(p.error("the texture varies over the surface; caustica takes a varying texture only as a diffuse or coateddiffuse reflectance")),
            },
            ("float", "float") => match p.numbers() {
                [v] => Ok(DVec3::splat(*v)),
                v => Err(p.error(format!("needs one number, got {}", v.len()))),
            },
            ("rgb", "spectrum") => match p.numbers() {
                [r, g, b] => Ok(DVec3::new(*r, *g, *b)),
                v => Err(p.error(format!("needs 3 numbers, got {}", v.len()))),
            },
            ("spectrum", "spectrum") => self.sampled_spectrum(p),
            (ty, _) => Err(p.error(format!("a {value_type} value cannot be given as {ty}"))),
        }
    }

    /// Wavelength-value pairs reduced to linear sRGB, with a warning; a named spectrum other
    /// than a conductor's or a glass's is an error.
    pub(super) fn sampled_spectrum(&mut self, p: &Param) -> Result<DVec3> {
        if let [name] = p.strings() {
            return Err(p.error(format!("the named spectrum \"{name}\" is not supported here (named spectra are read for a conductor's eta and k and a dielectric's eta)")));
        }
        let v = p.numbers();
        if v.len() < 4 || !v.len().is_multiple_of(2) {
            return Err(p.error(format!("needs wavelength-value pairs (at least two), got {} numbers", v.len())));
        }
        let pairs: Vec<(f64, f64)> = v.chunks_exact(2).map(|c| (c[0], c[1])).collect();
        if pairs.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err(p.error("the wavelengths must increase"));
        }
        self.warn("spectrum", || {
            format!("{}: spectra given as wavelengths are reduced to linear sRGB (CIE 1931 fit)", p.at)
        });
        Ok(spectrum::to_rgb(&pairs))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_named_metals_are_caustica_metals() {
        for (_, caustica) in NAMED_METALS {
            assert!(METALS.iter().any(|(n, _, _)| *n == caustica), "{caustica}");
        }
    }
}
