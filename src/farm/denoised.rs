//! A render's image denoised (src/denoise/): the mean of its accumulation as the beauty, with the
//! albedo and normal guides from its AOV sums where it has them (a render made with `--denoise`
//! always does; a checkpoint or partial from a render without AOVs is denoised on its colour
//! alone, which OIDN supports at lower quality).

use super::partial::PartialRender;
use crate::denoise::{Denoiser, Guides, Quality};
use crate::image::RgbImage;
use anyhow::Result;

/// The denoised image of a render and how it was made.
pub struct Denoised {
    pub image: RgbImage,
    /// For the EXR attribute and messages: "Open Image Denoise 2.5.1 on CPU (...), quality high,
    /// guides albedo and normal".
    pub how: String,
    /// Whether the albedo and normal guides were used.
    pub guided: bool,
    pub seconds: f64,
}

/// Denoises `partial`'s mean with its guides, where it has them.
pub fn denoise(denoiser: &Denoiser, partial: &PartialRender, quality: Quality) -> Result<Denoised> {
    let counts: Vec<f32> = partial.accumulation.iter().map(|a| a[3]).collect();
    let guides = partial.aov_sums.as_ref().map(|sums| (sums.albedo(&counts), sums.normal(&counts)));
    let (image, timing) = denoiser.denoise(
        &partial.image(),
        guides.as_ref().map(|(albedo, normal)| Guides { albedo, normal: Some(normal) }),
        quality,
    )?;
    let guided = guides.is_some();
    let how = format!(
        "{}, quality {}, {}",
        denoiser.describe(),
        quality.name(),
        if guided { "guides albedo and normal" } else { "no guides (the render has no AOVs)" }
    );
    Ok(Denoised { image, how, guided, seconds: timing.seconds })
}

/// Writes a denoised render: an EXR keeps the noisy mean and the AOVs beside the denoised image
/// (see [`PartialRender::write_denoised`]); other formats get the denoised image.
pub fn write_denoised(
    output: &std::path::Path,
    partial: &PartialRender,
    denoised: &Denoised,
    options: &crate::image::OutputOptions,
) -> Result<()> {
    if super::is_exr(output) {
        partial.write_denoised(output, &denoised.image, &denoised.how)
    } else {
        Ok(crate::image::write_image_with(output, &denoised.image, options)?)
    }
}
