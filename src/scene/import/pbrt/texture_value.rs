//! What a pbrt-v4 texture evaluates to for caustica: a constant, or caustica's one albedo texture
//! times a factor (textures.rs evaluates them; the mapper keeps each texture's value).

use super::super::scene_parts::f32x3;
use crate::scene::format::{AlbedoTextureFile, Array};
use glam::DVec3;

/// A texture's value over the surface.
#[derive(Clone, Debug)]
pub(super) enum TextureValue {
    Constant(DVec3),
    /// `texture` times `factor` (a checkerboard carries its scaled colours, with factor 1).
    Varying {
        texture: AlbedoTextureFile,
        factor: DVec3,
    },
}

impl TextureValue {
    pub(super) fn scaled(self, s: DVec3) -> TextureValue {
        match self {
            TextureValue::Constant(c) => TextureValue::Constant(c * s),
            TextureValue::Varying { mut texture, factor } => match &mut texture.checkerboard {
                Some(Array(colors)) => {
                    for c in colors.iter_mut() {
                        *c = f32x3(DVec3::from(c.0.map(f64::from)) * s);
                    }
                    TextureValue::Varying { texture, factor }
                }
                None => TextureValue::Varying { texture, factor: factor * s },
            },
        }
    }
}
