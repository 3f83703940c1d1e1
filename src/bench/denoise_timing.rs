//! `bench --denoise`: how long Intel Open Image Denoise takes on an image of the bench's size on
//! the device a render there would use, with the guides a render gives it and the prefiltering of
//! the quality asked for. OIDN's cost depends on the pixel count, not on what the pixels hold, so a
//! fixed, noisy test image stands in for the render.

use crate::denoise::{Denoiser, Guides, Quality};
use crate::image::RgbImage;
use anyhow::Result;

/// Timed denoises after the first, which pays OIDN's one-time costs (loading the weights,
/// allocating its scratch memory) and is not counted.
const TIMED_RUNS: usize = 3;

/// The median of [`TIMED_RUNS`] denoises of one image size.
#[derive(Clone, Debug)]
pub struct DenoiseTiming {
    pub width: u32,
    pub height: u32,
    pub quality: Quality,
    /// What denoised: "Open Image Denoise 2.5.1 on CPU (...)".
    pub device: String,
    pub seconds: f64,
    /// Of which, copying the images into OIDN's buffers and the result back: device memory on a
    /// GPU (through the host, as caustica hands it host images), plain copies on the CPU.
    pub copy_seconds: f64,
}

/// Times denoising a `width` x `height` image at `quality` with albedo and normal guides.
pub fn time_denoise(denoiser: &Denoiser, width: u32, height: u32, quality: Quality) -> Result<DenoiseTiming> {
    let pixels = width as usize * height as usize;
    // A grey image with a hash's noise (deterministic), over a plain albedo and normal.
    let noise = |i: usize| (i.wrapping_mul(2654435761) % 1024) as f32 / 1024.0;
    let color =
        RgbImage { width, height, pixels: (0..pixels).map(|i| [noise(i), noise(i + 7), noise(i + 13)]).collect() };
    let albedo = vec![[0.5f32; 3]; pixels];
    let normal = vec![[0.0f32, 0.0, 1.0]; pixels];
    let guides = Guides { albedo: &albedo, normal: Some(&normal) };
    denoiser.denoise(&color, Some(guides), quality)?;
    let mut runs = Vec::with_capacity(TIMED_RUNS);
    for _ in 0..TIMED_RUNS {
        runs.push(denoiser.denoise(&color, Some(guides), quality)?.1);
    }
    runs.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    let median = runs[TIMED_RUNS / 2];
    Ok(DenoiseTiming {
        width,
        height,
        quality,
        device: denoiser.describe(),
        seconds: median.seconds,
        copy_seconds: median.copy_seconds,
    })
}

impl DenoiseTiming {
    /// "denoise:      256x256 in 0.052 s (copies 2 %), quality high, Open Image Denoise 2.5.1 on CPU (...)".
    pub fn line(&self) -> String {
        format!(
            "denoise:      {}x{} in {:.3} s ({:.3} Mpixels/s; copies {:.0} %), quality {}, {}",
            self.width,
            self.height,
            self.seconds,
            self.width as f64 * self.height as f64 / self.seconds / 1e6,
            100.0 * self.copy_seconds / self.seconds,
            self.quality.name(),
            self.device
        )
    }

    pub fn json(&self) -> serde_json::Value {
        serde_json::json!({
            "width": self.width,
            "height": self.height,
            "quality": self.quality.name(),
            "device": self.device,
            "seconds": self.seconds,
            "copy_seconds": self.copy_seconds,
        })
    }
}
