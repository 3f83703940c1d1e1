//! pbrt-v4 materials and textures as caustica materials. caustica's materials take constant
//! values, so a texture is accepted where it is constant (`constant`, and `scale`, `mix` and
//! `checkerboard` of constants that do not vary); an image or a pattern is an error naming the
//! file and line. The README's "pbrt-v4" section lists each mapping.

use crate::scene::format::MaterialFile;
use super::super::scene_parts::f32x3;
use super::super::spectrum;
use super::mapping::Mapper;
use super::params::{Directive, Param};
use super::parser::{MaterialDef, TextureDef};
use crate::scene::METALS;
use anyhow::{anyhow, Result};
use glam::DVec3;

/// pbrt's named conductor spectra that caustica has measured indices of (`optics::METALS`).
const NAMED_METALS: [(&str, &str); 4] = [("Au", "gold"), ("Ag", "silver"), ("Cu", "copper"), ("Al", "aluminium")];

/// pbrt's named glasses and their index at the helium d line (587.6 nm), from the Schott catalogue.
const NAMED_GLASSES: [(&str, f64); 7] =
    [("glass-BK7", 1.5168), ("glass-BAF10", 1.67003), ("glass-FK51A", 1.48656), ("glass-LASF9", 1.85025), ("glass-F5", 1.6727), ("glass-F10", 1.72825), ("glass-F11", 1.78472)];

/// Texture references deeper than this are a cycle.
const MAX_TEXTURE_DEPTH: usize = 32;

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
            "diffuse" => MaterialFile { albedo: f32x3(self.reflectance(d, "reflectance", 0.5)?), ..defaults },
            "conductor" => {
                let (roughness, roughness_v) = self.roughness(d)?;
                let (metal, eta, k) = match self.conductor(d)? {
                    None => (None, None, None),
                    Some(Conductor::Named(name)) => (Some(name.to_owned()), None, None),
                    Some(Conductor::Complex(eta, k)) => (None, Some(f32x3(eta)), Some(f32x3(k))),
                };
                MaterialFile { reflectivity: Some(1.0), roughness, roughness_v, metal, eta, k, ..defaults }
            }
            "dielectric" => {
                let (roughness, roughness_v) = self.roughness(d)?;
                MaterialFile { transparency: 1.0, ior: self.dielectric_eta(d)?, roughness, roughness_v, ..defaults }
            }
            "coateddiffuse" => {
                self.warn("coated", || {
                    format!(
                        "{}: {}: coateddiffuse becomes caustica's coat over a diffuse base, which does not model light reflected inside the coat nor the coat's thickness (a little brighter than pbrt's)",
                        d.at,
                        d.describe()
                    )
                });
                let albedo = self.color(d, "albedo", 0.0, "spectrum")?;
                if albedo != DVec3::ZERO {
                    return Err(d.error("a scattering coat (albedo > 0) is not supported"));
                }
                // Parameters of the coat's medium and of pbrt's stochastic evaluation, which
                // caustica's closed-form coat has no use for.
                self.scalar(d, "thickness", 0.01)?;
                self.scalar(d, "g", 0.0)?;
                d.integer("maxdepth")?;
                d.integer("nsamples")?;
                let albedo = f32x3(self.reflectance(d, "reflectance", 0.5)?);
                let (roughness, roughness_v) = self.roughness(d)?;
                MaterialFile { albedo, coat: true, ior: self.dielectric_eta(d)?, roughness, roughness_v, ..defaults }
            }
            "interface" => {
                d.check_all_used()?;
                return Ok(None);
            }
            // pbrt-v4's thindielectric is smooth: it has no roughness parameters.
            "thindielectric" => MaterialFile { transparency: 1.0, ior: self.dielectric_eta(d)?, thin: true, ..defaults },
            "coatedconductor" => return Err(d.error("caustica's coat covers a diffuse base only, not a conductor")),
            _ => return Err(d.error("this material is not supported (diffuse, conductor, dielectric, thindielectric, coateddiffuse, interface)")),
        };
        d.check_all_used()?;
        Ok(Some(material))
    }

    /// caustica's roughness and roughness_v from pbrt's `uroughness` and `vroughness` (each
    /// defaulting to `roughness`): with `remaproughness` (the default) pbrt's alpha is
    /// sqrt(roughness) (TrowbridgeReitzDistribution::RoughnessToAlpha), else the roughness
    /// itself; caustica's roughness is sqrt(alpha), the same Trowbridge-Reitz (GGX) distribution.
    /// pbrt's alpha_x lies along dp/du as caustica's roughness does; roughness_v is None where
    /// the two are equal (isotropic).
    fn roughness(&mut self, d: &Directive) -> Result<(f32, Option<f32>)> {
        let r = self.scalar(d, "roughness", 0.0)?;
        let (u, v) = (self.scalar_if_given(d, "uroughness")?.unwrap_or(r), self.scalar_if_given(d, "vroughness")?.unwrap_or(r));
        let remap = d.boolean("remaproughness", true)?;
        let roughness = |name: &str, r: f64| {
            let alpha = if remap { r.max(0.0).sqrt() } else { r };
            if !(0.0..=1.0).contains(&alpha) || r < 0.0 {
                return Err(d.error(format!("the {name} must give an alpha in [0, 1], got {name} {r} (alpha {alpha})")));
            }
            Ok(alpha.sqrt() as f32)
        };
        let along_u = roughness(if u == r { "roughness" } else { "uroughness" }, u)?;
        let along_v = roughness(if v == r { "roughness" } else { "vroughness" }, v)?;
        Ok((along_u, (u != v).then_some(along_v)))
    }

    /// A dielectric's `eta`: a number, or a named glass at its d-line index (a warning: pbrt
    /// disperses light through a spectral index, caustica does not).
    fn dielectric_eta(&mut self, d: &Directive) -> Result<f32> {
        let eta = match d.param("eta") {
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
            return Err(d.error(format!("eta must be > 0, got {eta}")));
        }
        Ok(eta as f32)
    }

    /// A conductor's index: `reflectance` (pbrt's eta 1 and the k that gives that reflectance at
    /// normal incidence, caustica's eta and k exactly; 1 in every channel is the perfect mirror,
    /// None), or `eta` and `k` (default pbrt's copper), named metals taken by caustica's name.
    fn conductor(&mut self, d: &Directive) -> Result<Option<Conductor>> {
        if d.params.iter().any(|p| p.name == "reflectance") {
            if d.param("eta").is_some() || d.param("k").is_some() {
                return Err(d.error("give reflectance or eta and k, not both"));
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
        let eta = self.metal_spectrum(d, "eta", "metal-Cu-eta")?;
        let k = self.metal_spectrum(d, "k", "metal-Cu-k")?;
        Ok(Some(match (eta, k) {
            (Ok(a), Ok(b)) if a == b => Conductor::Named(a),
            (eta, k) => {
                let values = |named: Result<&'static str, DVec3>, which: usize| {
                    named.map_or_else(|v| v, |name| {
                        let (_, eta, k) = METALS.iter().find(|(n, _, _)| *n == name).expect("NAMED_METALS are METALS");
                        DVec3::from(if which == 0 { *eta } else { *k }.map(f64::from))
                    })
                };
                Conductor::Complex(values(eta, 0), values(k, 1))
            }
        }))
    }

    /// A conductor's `eta` or `k`: Ok(caustica's metal name) for a named spectrum, Err(the values)
    /// for a colour.
    fn metal_spectrum(&mut self, d: &Directive, name: &str, default: &str) -> Result<std::result::Result<&'static str, DVec3>> {
        let named = match d.param(name) {
            None => default.to_owned(),
            Some(p) if p.ty == "spectrum" && !p.strings().is_empty() => p.strings()[0].clone(),
            Some(p) => {
                let v = self.color_param(p, "spectrum", 0)?;
                if v.min_element() < 0.0 {
                    return Err(p.error("must not be negative"));
                }
                return Ok(Err(v));
            }
        };
        let suffix = format!("-{name}");
        let metal = named.strip_prefix("metal-").and_then(|m| m.strip_suffix(suffix.as_str()));
        match metal.and_then(|m| NAMED_METALS.iter().find(|(n, _)| *n == m)) {
            Some((_, caustica)) => Ok(Ok(caustica)),
            None => {
                let known: Vec<_> = NAMED_METALS.iter().map(|(m, _)| format!("metal-{m}{suffix}")).collect();
                Err(anyhow!("{}: {}: the spectrum \"{named}\" for {name} is not supported (known: {})", d.at, d.describe(), known.join(", ")))
            }
        }
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
    fn scalar_param(&mut self, p: &Param) -> Result<f64> {
        Ok(self.color_param(p, "float", 0)?.x)
    }

    /// The constant value of a parameter of `value_type` (spectrum or float; a float is a grey).
    fn color_param(&mut self, p: &Param, value_type: &str, depth: usize) -> Result<DVec3> {
        match (p.ty.as_str(), value_type) {
            ("texture", _) => match p.strings() {
                [name] => self.texture(value_type, name, p, depth),
                _ => Err(p.error("names one texture")),
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
        self.warn("spectrum", || format!("{}: spectra given as wavelengths are reduced to linear sRGB (CIE 1931 fit)", p.at));
        Ok(spectrum::to_rgb(&pairs))
    }

    /// The value of the texture `name` (of `value_type`), which must be constant.
    fn texture(&mut self, value_type: &str, name: &str, used_by: &Param, depth: usize) -> Result<DVec3> {
        if depth > MAX_TEXTURE_DEPTH {
            return Err(used_by.error(format!("textures refer to each other more than {MAX_TEXTURE_DEPTH} deep (a cycle?)")));
        }
        let model = self.model;
        let Some(t) = model.textures.get(&(value_type.to_owned(), name.to_owned())) else {
            return Err(used_by.error(format!("no {value_type} texture named \"{name}\"")));
        };
        let value = self.texture_value(t, depth)?;
        t.class.check_all_used()?;
        Ok(value)
    }

    fn texture_value(&mut self, t: &TextureDef, depth: usize) -> Result<DVec3> {
        let c = &t.class;
        let ty = t.value_type.as_str();
        let get = |this: &mut Self, name: &str, value_type: &str, default: f64| -> Result<DVec3> {
            match c.param(name) {
                None => Ok(DVec3::splat(default)),
                Some(p) => this.color_param(p, value_type, depth + 1),
            }
        };
        let varies = |why: &str| anyhow!("{}: Texture \"{}\" \"{}\": {why}; caustica's materials take constant values", c.at, t.name, c.kind);
        match c.kind.as_str() {
            "constant" => get(self, "value", ty, 1.0),
            "scale" => Ok(get(self, "tex", ty, 1.0)? * get(self, "scale", "float", 1.0)?.x),
            "mix" => {
                let (a, b) = (get(self, "tex1", ty, 0.0)?, get(self, "tex2", ty, 1.0)?);
                let amount = get(self, "amount", "float", 0.5)?.x;
                Ok(a + (b - a) * amount)
            }
            "checkerboard" => {
                let (a, b) = (get(self, "tex1", ty, 1.0)?, get(self, "tex2", ty, 0.0)?);
                if a != b {
                    return Err(varies("a checkerboard of two different values varies over the surface"));
                }
                // Where the squares lie does not matter when they are all the same.
                for name in ["mapping", "uscale", "vscale", "udelta", "vdelta", "dimension"] {
                    c.param(name);
                }
                Ok(a)
            }
            "imagemap" => Err(varies("an image map varies over the surface")),
            _ => Err(varies("this texture is not supported (constant, scale, mix, checkerboard of equal values)")),
        }
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
