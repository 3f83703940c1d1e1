//! A TOML material's data textures: `opacity` with `opacity_texture` (Mitsuba's `mask`) and
//! `normal_texture` (Mitsuba's `normalmap`), onto the same `TextureMaps` glTF and MTL materials
//! fill, and the one `to_uv` map all of a material's textures share (the kernel keeps one set of
//! texture coordinates per vertex, so two textures of a material cannot be read through two maps).

use super::albedo_texture;
use super::asset::{load_texture, srgb_to_linear};
use super::format::{Encoding, ImageTextureFile, MaterialFile};
use super::{Alpha, AlphaMode, Material, NormalMap, Texture};
use crate::input_file::InputFiles;
use anyhow::{bail, Result};
use glam::Affine2;
use std::path::Path;

/// Loads `m`'s textures (albedo, opacity, normals) into `textures`, points `material` at them and
/// sets its opacity; the texture-coordinate map they share, if it has any texture.
pub fn attach(
    mname: &str,
    m: &MaterialFile,
    material: &mut Material,
    textures: &mut Vec<Texture>,
    base: &Path,
    files: &InputFiles,
) -> Result<Option<Affine2>> {
    let key = |field: &str| format!("materials.{mname}.{field}");
    let mut shared = SharedMap::default();
    if let Some(t) = &m.albedo_texture {
        let (texture, to_uv) = albedo_texture::load(t, &key("albedo_texture"), base, files)?;
        shared.add(key("albedo_texture"), to_uv)?;
        material.albedo_texture = Some(push(textures, texture));
    }
    let opacity_texture = match &m.opacity_texture {
        Some(t) => {
            let mut texture = load(t, &key("opacity_texture"), base, files, &mut shared)?;
            luminance_to_alpha(&mut texture, t.encoding.unwrap_or(Encoding::Srgb));
            Some(push(textures, texture))
        }
        None => None,
    };
    let opacity = super::unit_interval(&key("opacity"), m.opacity.unwrap_or(1.0))?;
    if opacity < 1.0 || opacity_texture.is_some() {
        material.maps.alpha = Some(Alpha { factor: opacity, texture: opacity_texture, mode: AlphaMode::Blend });
    }
    if let Some(t) = &m.normal_texture {
        let mut texture = load(t, &key("normal_texture"), base, files, &mut shared)?;
        texture.srgb = t.encoding == Some(Encoding::Srgb);
        material.maps.normal = Some(NormalMap { texture: push(textures, texture), scale: 1.0 });
    }
    Ok(shared.map)
}

/// Does a shape need a mesh's texture coordinates (or triangles) to wear `m`? Opacity is tested
/// on mesh triangles only (shaders/alpha.glsl).
pub fn needs_mesh(m: &MaterialFile) -> Option<&'static str> {
    [
        (m.albedo_texture.is_some(), "albedo_texture"),
        (m.opacity_texture.is_some(), "opacity_texture"),
        (m.opacity.is_some_and(|o| o < 1.0), "opacity"),
        (m.normal_texture.is_some(), "normal_texture"),
    ]
    .into_iter()
    .find_map(|(used, key)| used.then_some(key))
}

/// The first texture's `to_uv`, which every other texture of the material must repeat.
#[derive(Default)]
struct SharedMap {
    first_key: String,
    map: Option<Affine2>,
}

impl SharedMap {
    fn add(&mut self, key: String, to_uv: Affine2) -> Result<()> {
        match self.map {
            None => (self.first_key, self.map) = (key, Some(to_uv)),
            Some(first) if first == to_uv => {}
            Some(first) => bail!(
                "{key}.to_uv differs from {}.to_uv ({to_uv:?} against {first:?}): a material's textures share one texture-coordinate map",
                self.first_key
            ),
        }
        Ok(())
    }
}

fn load(t: &ImageTextureFile, key: &str, base: &Path, files: &InputFiles, shared: &mut SharedMap) -> Result<Texture> {
    let texture = load_texture(files, &super::resolve(base, &t.file))?;
    shared.add(key.to_owned(), albedo_texture::to_uv(t.to_uv, key)?)?;
    Ok(texture)
}

fn push(textures: &mut Vec<Texture>, texture: Texture) -> u32 {
    textures.push(texture);
    textures.len() as u32 - 1
}

/// Stores each texel's luminance (Rec. 709, of the decoded colour) in its A channel, where the
/// kernel reads opacity; Mitsuba's `mask` reads a colour bitmap's luminance, never its alpha.
fn luminance_to_alpha(texture: &mut Texture, encoding: Encoding) {
    let decode = |b: u8| match encoding {
        Encoding::Srgb => srgb_to_linear(b),
        Encoding::Linear => f32::from(b) / 255.0,
    };
    for texel in &mut texture.texels {
        let luminance = 0.2126 * decode(texel[0]) + 0.7152 * decode(texel[1]) + 0.0722 * decode(texel[2]);
        texel[3] = (luminance.clamp(0.0, 1.0) * 255.0).round() as u8;
    }
}
