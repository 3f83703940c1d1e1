//! pbrt-v4 textures as caustica values: a texture that does not vary (`constant`, and `scale`,
//! `mix` and `checkerboard` of values that do not) is a constant; an `imagemap` (times a
//! constant) or a 2D `checkerboard` of two constants is caustica's `albedo_texture`, which
//! materials take as a diffuse reflectance. docs/importers.md ("pbrt-v4") lists each mapping.
//!
//! Texture coordinates: caustica turns a PLY's (u, v) into (u, 1 - v) as it reads it, with
//! (0, 0) the image's top-left corner; pbrt keeps (u, v), maps it to (s, t) = (uscale u + udelta,
//! vscale v + vdelta) and reads an image at (s, 1 - t) from its top-left. The `to_uv` of each
//! texture below is that map written in caustica's coordinates.

use super::super::scene_parts::{f32x3, relative_to};
use super::mapping::Mapper;
use super::params::{Directive, Param};
use super::parser::TextureDef;
use super::texture_value::TextureValue;
use crate::scene::format::{AlbedoTextureFile, Array};
use anyhow::{anyhow, Result};
use glam::DVec3;
use std::path::PathBuf;

/// Texture references deeper than this are a cycle.
const MAX_TEXTURE_DEPTH: usize = 32;

impl Mapper<'_> {
    /// The value of `p` (of `value_type`, spectrum or float): a constant as written, or a texture's.
    pub(super) fn texture_param(&mut self, p: &Param, value_type: &str, depth: usize) -> Result<TextureValue> {
        match (p.ty.as_str(), p.strings()) {
            ("texture", [name]) => self.texture(value_type, name, p, depth),
            ("texture", _) => Err(p.error("names one texture")),
            _ => Ok(TextureValue::Constant(self.color_param(p, value_type, depth)?)),
        }
    }

    /// The value of the texture `name` of `value_type`, which `used_by` refers to.
    pub(super) fn texture(
        &mut self,
        value_type: &str,
        name: &str,
        used_by: &Param,
        depth: usize,
    ) -> Result<TextureValue> {
        if depth > MAX_TEXTURE_DEPTH {
            return Err(
                used_by.error(format!("textures refer to each other more than {MAX_TEXTURE_DEPTH} deep (a cycle?)"))
            );
        }
        let model = self.model;
        let key = (value_type.to_owned(), name.to_owned());
        if let Some(value) = self.textures_evaluated.get(&key) {
            return Ok(value.clone());
        }
        let Some(t) = model.textures.get(&key) else {
            return Err(used_by.error(format!("no {value_type} texture named \"{name}\"")));
        };
        let value = self.texture_value(t, depth)?;
        t.class.check_all_used()?;
        self.textures_evaluated.insert(key, value.clone());
        Ok(value)
    }

    fn texture_value(&mut self, t: &TextureDef, depth: usize) -> Result<TextureValue> {
        let c = &t.class;
        let ty = t.value_type.as_str();
        let get = |this: &mut Self, name: &str, value_type: &str, default: f64| -> Result<TextureValue> {
            match c.param(name) {
                None => Ok(TextureValue::Constant(DVec3::splat(default))),
                Some(p) => this.texture_param(p, value_type, depth + 1),
            }
        };
        let varies = |why: &str| anyhow!("{}: Texture \"{}\" \"{}\": {why}", c.at, t.name, c.kind);
        // A part that must be constant (a scale, an amount, a checkerboard's squares).
        let constant = |value: TextureValue, name: &str| match value {
            TextureValue::Constant(v) => Ok(v),
            TextureValue::Varying { .. } => {
                Err(varies(&format!("its {name} varies over the surface; caustica takes it constant here")))
            }
        };
        match c.kind.as_str() {
            "constant" => get(self, "value", ty, 1.0),
            "scale" => {
                let s = get(self, "scale", "float", 1.0)?;
                let s = constant(s, "scale")?;
                Ok(get(self, "tex", ty, 1.0)?.scaled(s))
            }
            "mix" => {
                let amount = get(self, "amount", "float", 0.5)?;
                let amount = constant(amount, "amount")?.x;
                match (get(self, "tex1", ty, 0.0)?, get(self, "tex2", ty, 1.0)?) {
                    (TextureValue::Constant(a), TextureValue::Constant(b)) => Ok(TextureValue::Constant(a + (b - a) * amount)),
                    // Only one of them shows.
                    (a, _) if amount == 0.0 => Ok(a),
                    (_, b) if amount == 1.0 => Ok(b),
                    _ => Err(varies("a mix with a varying texture is supported only where the amount is 0 or 1 (caustica's albedo_texture is one texture)")),
                }
            }
            "checkerboard" => {
                let dimension = c.integer("dimension")?.unwrap_or(2);
                let a = get(self, "tex1", ty, 1.0)?;
                let a = constant(a, "tex1")?;
                let b = get(self, "tex2", ty, 0.0)?;
                let b = constant(b, "tex2")?;
                if a == b {
                    // Where the squares lie does not matter when they are all the same.
                    for name in ["mapping", "uscale", "vscale", "udelta", "vdelta"] {
                        c.param(name);
                    }
                    return Ok(TextureValue::Constant(a));
                }
                if dimension != 2 {
                    return Err(varies("only the 2D checkerboard (dimension 2) is supported"));
                }
                if ty != "spectrum" {
                    return Err(varies("a float checkerboard of two different values varies over the surface; caustica takes float parameters constant"));
                }
                // pbrt's squares are one unit of (s, t) wide, tex1 where floor(s) + floor(t) is
                // even; caustica's (Mitsuba's) checkerboard has its first colour where the
                // halves of (x, y) agree. x = s / 2 and y = t / 2 put the same colours in
                // the same squares: floor(s) is even exactly where frac(s / 2) < 1/2.
                let (su, sv, du, dv) = uv_mapping(c)?;
                let to_uv = [[su / 2.0, 0.0, du / 2.0], [0.0, -sv / 2.0, (sv + dv) / 2.0]];
                let texture = AlbedoTextureFile {
                    file: None,
                    checkerboard: Some(Array([f32x3(a), f32x3(b)])),
                    to_uv: Some(Array(to_uv.map(|r| Array(r.map(|x| x as f32))))),
                };
                Ok(TextureValue::Varying { texture, factor: DVec3::ONE })
            }
            "imagemap" if ty == "spectrum" => self.imagemap(c),
            "imagemap" => {
                Err(varies("a float image map varies over the surface; caustica takes float parameters constant"))
            }
            _ => Err(varies("this texture is not supported (constant, scale, mix, checkerboard, imagemap)")),
        }
    }

    /// An `imagemap`: its image read at pbrt's (s, 1 - t), times its `scale`.
    /// An `imagemap` texture's image, and the factor that scales it.
    pub(super) fn imagemap_file(&mut self, c: &Directive) -> Result<(AlbedoTextureFile, DVec3)> {
        match self.imagemap(c)? {
            TextureValue::Varying { texture, factor } => Ok((texture, factor)),
            TextureValue::Constant(_) => unreachable!("an imagemap varies"),
        }
    }

    pub(super) fn imagemap(&mut self, c: &Directive) -> Result<TextureValue> {
        let Some(name) = c.string("filename")?.map(str::to_owned) else { return Err(c.error("needs a filename")) };
        let (path, extension) = self.texture_image(c, &name)?;
        // pbrt reads a PNG as sRGB and any other image as linear unless told.
        let encoding = c.string("encoding")?.unwrap_or(if extension == "png" { "sRGB" } else { "linear" });
        if encoding != "sRGB" {
            return Err(c.error(format!("\"{name}\": the encoding \"{encoding}\" is not supported: caustica reads texture images as sRGB (pbrt's default for PNG; a JPEG needs \"string encoding\" \"sRGB\")")));
        }
        if c.boolean("invert", false)? {
            return Err(c.error("invert is not supported"));
        }
        if let Some(wrap) = c.string("wrap")?.filter(|w| *w != "repeat") {
            return Err(c.error(format!("wrap \"{wrap}\" is not supported (caustica's textures repeat)")));
        }
        match c.string("filter")?.unwrap_or("bilinear") {
            "bilinear" => {}
            f @ ("point" | "trilinear" | "ewa" | "EWA") => {
                let at = c.at.clone();
                self.warn("texture filter", || format!("{at}: the texture filter \"{f}\" becomes caustica's bilinear lookup without MIP maps (the same where a texel covers several pixels, more aliased where it covers less than one)"));
            }
            f => return Err(c.error(format!("the filter \"{f}\" is unknown (point, bilinear, trilinear, ewa)"))),
        }
        // Only pbrt's MIP-mapped filters use it.
        c.float("maxanisotropy")?;
        let scale = c.float_or("scale", 1.0)?;
        let (su, sv, du, dv) = uv_mapping(c)?;
        // Read at (s, 1 - t) = (su u + du, 1 - sv (1 - w) - dv) where caustica's w is 1 - v.
        let to_uv = [[su, 0.0, du], [0.0, sv, 1.0 - sv - dv]];
        let identity = to_uv == [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let texture = AlbedoTextureFile {
            file: Some(relative_to(&path, self.base)),
            checkerboard: None,
            to_uv: (!identity).then(|| Array(to_uv.map(|r| Array(r.map(|x| x as f32))))),
        };
        Ok(TextureValue::Varying { texture, factor: DVec3::splat(scale) })
    }
}

impl Mapper<'_> {
    /// The image file `name` that `d` names, with its extension in lower case: caustica reads PNG
    /// and JPEG textures only.
    pub(super) fn texture_image(&self, d: &Directive, name: &str) -> Result<(PathBuf, String)> {
        let path = self.scene_file(name);
        let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
        if !matches!(extension.as_str(), "png" | "jpg" | "jpeg") {
            return Err(d.error(format!("\"{name}\": only PNG and JPEG images are supported as textures")));
        }
        Ok((path, extension))
    }
}

/// pbrt's 2D texture mapping: only `uv`, as (uscale, vscale, udelta, vdelta).
fn uv_mapping(c: &Directive) -> Result<(f64, f64, f64, f64)> {
    if let Some(mapping) = c.string("mapping")?.filter(|m| *m != "uv") {
        return Err(c.error(format!("the mapping \"{mapping}\" is not supported (uv)")));
    }
    Ok((c.float_or("uscale", 1.0)?, c.float_or("vscale", 1.0)?, c.float_or("udelta", 0.0)?, c.float_or("vdelta", 0.0)?))
}
