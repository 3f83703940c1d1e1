//! Denoising with Intel Open Image Denoise 2 (OIDN), loaded at run time: caustica builds and runs
//! without it, and only `--denoise` (and `caustica denoise`) need it. `locate` finds and loads the
//! library, `ffi` binds the C functions used, `device` picks the device (CUDA for the NVIDIA
//! device caustica renders on where OIDN has it, else the CPU), `filter` runs OIDN's "RT" filter.
//!
//! How an image is denoised follows OIDN's documentation for final frames: the beauty as HDR
//! colour, with the albedo and normal guides of the first non-delta vertex (the kernel follows
//! mirrors and glass to it, shaders/integrator.glsl `FirstHit`); for quality high and balanced the
//! guides, noisy themselves at low sample counts (depth of field, motion, rough surfaces seen
//! through glass), are first denoised by the RT filter on their own and then marked clean
//! (`cleanAux`), so that their noise is not kept as detail.

mod device;
mod ffi;
mod filter;
mod locate;

use crate::image::RgbImage;
use anyhow::{ensure, Result};
use device::Device;
use filter::{Buffer, Filter};
use std::sync::Arc;
use std::time::Instant;

pub use device::{DeviceChoice, DeviceKind};
pub use locate::{Origin, INSTALL_SCRIPT, LIBRARY_NAME, VARIABLE};

/// OIDN's quality setting (`--denoise fast|balanced|high`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Quality {
    /// Quickest, for interactive previews (the viewer while the camera moves).
    Fast,
    /// Between the two, for interactive rendering.
    Balanced,
    /// Final frames.
    #[default]
    High,
}

impl Quality {
    pub fn name(self) -> &'static str {
        match self {
            Quality::Fast => "fast",
            Quality::Balanced => "balanced",
            Quality::High => "high",
        }
    }

    fn oidn(self) -> i32 {
        match self {
            Quality::Fast => ffi::QUALITY_FAST,
            Quality::Balanced => ffi::QUALITY_BALANCED,
            Quality::High => ffi::QUALITY_HIGH,
        }
    }

    /// Whether the guides are denoised first (`cleanAux`): for the two slower settings, as OIDN
    /// recommends for final frames; `fast` takes them as they are.
    fn prefilters_guides(self) -> bool {
        self != Quality::Fast
    }
}

/// The guide images (per pixel, top row first, as the beauty): albedo in [0, 1] and the shading
/// normal (any length up to 1), each of the first non-delta vertex. OIDN takes a normal only with
/// an albedo.
#[derive(Clone, Copy, Debug)]
pub struct Guides<'a> {
    pub albedo: &'a [[f32; 3]],
    pub normal: Option<&'a [[f32; 3]]>,
}

/// OIDN loaded, with a device to denoise on.
pub struct Denoiser {
    device: Device,
    pub origin: Origin,
}

/// OIDN's library, loaded and checked, before a device is chosen: what `--denoise` gets before
/// rendering starts, so that a missing or wrong library fails first.
pub struct Library {
    oidn: Arc<ffi::Oidn>,
    pub origin: Origin,
}

impl Library {
    /// Finds and loads OIDN (see `locate`): errors name `CAUSTICA_OIDN`'s value when it is wrong,
    /// or the install script when OIDN is nowhere.
    pub fn load() -> Result<Self> {
        let (oidn, origin) = locate::load()?;
        let oidn = Arc::new(oidn);
        Device::check_version(&oidn).map_err(|e| anyhow::anyhow!("{origin}: {e:#}"))?;
        Ok(Self { oidn, origin })
    }

    /// A denoiser on the OIDN device `choice` asks for, the CPU where OIDN has none such. Fails,
    /// naming the library, where it is not OIDN 2.
    pub fn denoiser(&self, choice: DeviceChoice) -> Result<Denoiser> {
        let device = Device::new(self.oidn.clone(), choice).map_err(|e| anyhow::anyhow!("{}: {e:#}", self.origin))?;
        Ok(Denoiser { device, origin: self.origin.clone() })
    }
}

/// What a denoise took.
#[derive(Clone, Copy, Debug)]
pub struct Timing {
    pub seconds: f64,
    /// Of which, copying the images into OIDN's buffers and the result back (device memory on a
    /// GPU device, reached through the host).
    pub copy_seconds: f64,
}

impl Denoiser {
    /// Loads OIDN and takes the device `choice` asks for, as [`Library::load`] then
    /// [`Library::denoiser`].
    pub fn new(choice: DeviceChoice) -> Result<Self> {
        Library::load()?.denoiser(choice)
    }

    pub fn device_kind(&self) -> DeviceKind {
        self.device.kind
    }

    /// "Open Image Denoise 2.5.1 on CPU (AMD EPYC 9B14)".
    pub fn describe(&self) -> String {
        format!("Open Image Denoise {} on {}", self.device.version_text(), self.device.describe())
    }

    /// The beauty `color` (linear HDR radiance) denoised, with `guides` where there are any.
    pub fn denoise(&self, color: &RgbImage, guides: Option<Guides>, quality: Quality) -> Result<(RgbImage, Timing)> {
        let started = Instant::now();
        let pixels = color.pixels.len();
        if let Some(g) = guides {
            ensure!(g.albedo.len() == pixels, "the albedo guide has {} pixels, the image {pixels}", g.albedo.len());
            if let Some(n) = g.normal {
                ensure!(n.len() == pixels, "the normal guide has {} pixels, the image {pixels}", n.len());
            }
        }
        let device = &self.device;
        let (w, h) = (color.width, color.height);
        let uploads = Instant::now();
        let color_buffer = Buffer::with(device, &color.pixels)?;
        let output = Buffer::with(device, &color.pixels)?;
        let albedo = guides.map(|g| Buffer::with(device, g.albedo)).transpose()?;
        let normal = guides.and_then(|g| g.normal).map(|n| Buffer::with(device, n)).transpose()?;
        let mut copy_seconds = uploads.elapsed().as_secs_f64();
        let clean_guides = albedo.is_some() && quality.prefilters_guides();
        if clean_guides {
            // Each guide through the RT filter on its own, in place (OIDN's documented prefilter).
            for (name, buffer) in [("albedo", albedo.as_ref()), ("normal", normal.as_ref())] {
                let Some(buffer) = buffer else { continue };
                let prefilter = Filter::new(device, w, h)?;
                prefilter.image(name, buffer);
                prefilter.image("output", buffer);
                prefilter.set_int("quality", quality.oidn());
                prefilter.run(&format!("the {name} guide's prefilter"))?;
            }
        }
        let beauty = Filter::new(device, w, h)?;
        beauty.image("color", &color_buffer);
        if let Some(albedo) = &albedo {
            beauty.image("albedo", albedo);
        }
        if let Some(normal) = &normal {
            beauty.image("normal", normal);
        }
        beauty.image("output", &output);
        beauty.set_bool("hdr", true);
        beauty.set_bool("cleanAux", clean_guides);
        beauty.set_int("quality", quality.oidn());
        beauty.run("the denoising filter")?;
        let download = Instant::now();
        let denoised = RgbImage { width: w, height: h, pixels: output.read()? };
        copy_seconds += download.elapsed().as_secs_f64();
        Ok((denoised, Timing { seconds: started.elapsed().as_secs_f64(), copy_seconds }))
    }
}
