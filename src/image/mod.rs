//! Linear RGB float images and the file formats the renderer reads and writes:
//! PFM and EXR for radiance (light probes in, renders out), PNG for viewing.
//! Every writer replaces its target atomically (see `atomic`).

mod atomic;
pub mod compare;
pub mod display_codes;
pub mod exr;
mod exr_header_order;
pub mod exr_layers;
pub mod pfm;
pub mod png;
pub mod rgbe;
pub mod tonemap;

use std::path::Path;

pub use atomic::{check_writable, remove_stale_temp_files, remove_temp_files_in_flight};

use crate::input_file::{InputError, InputFiles};

pub use compare::{compare, Comparison};
pub use exr_layers::{read_exr_document, write_exr_document, ExrDocument, ExrLayer};
pub use png::PngDepth;
pub use tonemap::Tonemap;

/// Largest accepted image, in pixels. Checked against header sizes before any
/// pixel buffer is allocated, so a corrupt or hostile header cannot make a
/// loader reserve gigabytes (2^28 RGB f32 pixels is already 3 GiB).
pub const MAX_PIXELS: u64 = 1 << 28;

/// Mean radiance from an accumulation of (sum, count) pixels, the kernel's accumulation buffer and
/// a farm part's sums alike; pixels without samples are black.
pub fn mean_image(width: u32, height: u32, accumulation: &[[f32; 4]]) -> RgbImage {
    let mut image = RgbImage::new(width, height);
    for (dst, a) in image.pixels.iter_mut().zip(accumulation) {
        let n = a[3].max(1.0);
        *dst = [a[0] / n, a[1] / n, a[2] / n];
    }
    image
}

/// Linear RGB float image, rows top to bottom, row-major.
#[derive(Clone, Debug, PartialEq)]
pub struct RgbImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, pixels: vec![[0.0; 3]; width as usize * height as usize] }
    }

    /// Pixel at column `x`, row `y` (row 0 is the top). Panics out of bounds.
    pub fn get(&self, x: u32, y: u32) -> [f32; 3] {
        self.pixels[self.index(x, y)]
    }

    /// Sets the pixel at column `x`, row `y`. Panics out of bounds.
    pub fn set(&mut self, x: u32, y: u32, rgb: [f32; 3]) {
        let i = self.index(x, y);
        self.pixels[i] = rgb;
    }

    fn index(&self, x: u32, y: u32) -> usize {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {} x {} image", self.width, self.height);
        y as usize * self.width as usize + x as usize
    }
}

/// Every variant names the file first so a failed load of one of many inputs
/// (scene, probes, outputs) is traceable from the message alone.
///
/// Each message is complete, with the underlying error's text in it, so these
/// errors report no `source()`: printers of error chains (`{:#}`) would print
/// that text a second time. (The `exr` crate's I/O errors even report
/// themselves as their own source.)
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// Not a readable regular file within its size cap (or outside `--confine`).
    #[error(transparent)]
    Input(#[from] InputError),
    #[error("{file}: {cause}")]
    Io { file: String, cause: std::io::Error },
    #[error("{file}: cannot be written: {reason}")]
    Unwritable { file: String, reason: String },
    #[error("{file}: unsupported image format: expected extension {expected}")]
    UnsupportedExtension { file: String, expected: &'static str },
    #[error("{file}: bad PFM header: {reason}")]
    PfmHeader { file: String, reason: String },
    #[error("{file}: bad Radiance RGBE (.hdr) file: {reason}")]
    RgbeHeader { file: String, reason: String },
    #[error("{file}: truncated: expected {expected} bytes of pixel data, found {found}")]
    Truncated { file: String, expected: usize, found: usize },
    #[error("{file}: image of {width} x {height} pixels is too large (limit 2^28 pixels)")]
    TooLarge { file: String, width: u64, height: u64 },
    #[error("{file}: pixel ({x}, {y}) is not finite: {value:?}")]
    NonFinite { file: String, x: u32, y: u32, value: [f32; 3] },
    #[error("{file}: EXR: {cause}")]
    Exr { file: String, cause: ::exr::error::Error },
    #[error("{file}: invalid EXR layers: {reason}")]
    ExrLayout { file: String, reason: String },
    #[error("{file} {reason}")]
    Incomparable { file: String, reason: String },
    #[error("{file}: PNG: {cause}")]
    Png { file: String, cause: ::png::EncodingError },
}

/// Rejects images whose pixel count overflows or exceeds [`MAX_PIXELS`].
pub(crate) fn check_size(file: &str, width: u64, height: u64) -> Result<(), ImageError> {
    match width.checked_mul(height) {
        Some(n) if n <= MAX_PIXELS => Ok(()),
        _ => Err(ImageError::TooLarge { file: file.to_owned(), width, height }),
    }
}

/// The path as it appears in error messages.
pub(crate) fn file_name(path: &Path) -> String {
    path.display().to_string()
}

fn extension(path: &Path) -> Option<String> {
    path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase)
}

/// Reads a radiance image from anywhere (the command line's images), choosing the format by
/// extension (case-insensitive).
pub fn read_image(path: &Path) -> Result<RgbImage, ImageError> {
    read_image_from(&InputFiles::anywhere(), path)
}

/// Reads a radiance image through `files` (a scene's environment map, under the scene's
/// confinement), choosing the format by extension (case-insensitive).
pub fn read_image_from(files: &InputFiles, path: &Path) -> Result<RgbImage, ImageError> {
    match extension(path).as_deref() {
        Some("pfm") => pfm::read(files, path),
        Some("exr") => exr::read(files, path),
        Some("hdr") => rgbe::read(files, path),
        _ => Err(ImageError::UnsupportedExtension { file: file_name(path), expected: ".pfm, .exr or .hdr" }),
    }
}

/// Checks, before any work is done, that `write_image` can take this path: a
/// known extension, an existing directory, and a place where a file can be
/// written (see [`check_writable`]).
pub fn check_output_path(path: &Path) -> Result<(), ImageError> {
    if !matches!(extension(path).as_deref(), Some("pfm" | "exr" | "png")) {
        return Err(ImageError::UnsupportedExtension { file: file_name(path), expected: ".pfm, .exr or .png" });
    }
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !dir.is_dir() {
        let problem = if dir.exists() { "is not a directory" } else { "does not exist" };
        return Err(ImageError::Unwritable {
            file: file_name(path),
            reason: format!("directory {} {problem}", dir.display()),
        });
    }
    check_writable(path)
}

/// How to turn radiance into display values. Only PNG uses these: the float
/// formats keep the raw radiance so that no information is lost. The default
/// (no exposure change, clamp, 8 bits) is what `write_image` has always done.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OutputOptions {
    /// In stops: values are scaled by 2^exposure before the tone curve.
    pub exposure: f32,
    pub tonemap: Tonemap,
    pub png_depth: PngDepth,
}

/// Writes an image with default [`OutputOptions`] except `exposure`.
pub fn write_image(path: &Path, img: &RgbImage, exposure: f32) -> Result<(), ImageError> {
    let options = OutputOptions { exposure, ..OutputOptions::default() };
    write_image_with(path, img, &options)
}

/// Writes an image atomically, choosing the format by extension
/// (case-insensitive).
pub fn write_image_with(path: &Path, img: &RgbImage, options: &OutputOptions) -> Result<(), ImageError> {
    match extension(path).as_deref() {
        Some("pfm") => pfm::write(path, img),
        Some("exr") => exr::write(path, img),
        Some("png") => png::write(path, img, options),
        _ => Err(ImageError::UnsupportedExtension { file: file_name(path), expected: ".pfm, .exr or .png" }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn get_set_are_row_major_top_down() {
        let mut img = RgbImage::new(3, 2);
        img.set(2, 1, [1.0, 2.0, 3.0]);
        assert_eq!(img.pixels[5], [1.0, 2.0, 3.0]);
        assert_eq!(img.get(2, 1), [1.0, 2.0, 3.0]);
        assert_eq!(img.get(1, 1), [0.0; 3]);
    }

    #[test]
    #[should_panic(expected = "outside 3 x 2 image")]
    fn get_out_of_bounds_panics() {
        RgbImage::new(3, 2).get(3, 0);
    }

    #[test]
    fn unknown_extension_is_rejected_with_file_name() {
        let img = RgbImage::new(1, 1);
        let err = write_image(Path::new("out.tga"), &img, 0.0).unwrap_err();
        assert_eq!(err.to_string(), "out.tga: unsupported image format: expected extension .pfm, .exr or .png");
        let err = read_image(Path::new("probe.png")).unwrap_err();
        assert!(err.to_string().starts_with("probe.png: unsupported"), "{err}");
    }

    #[test]
    fn read_dispatch_is_case_insensitive() {
        let dir = crate::test_files::temp_dir("dispatch");
        let path = dir.join("image.PFM");
        let mut img = RgbImage::new(2, 1);
        img.set(1, 0, [0.5, 1.5, 2.5]);
        write_image(&path, &img, 0.0).unwrap();
        let back = read_image(&path);
        assert_eq!(back.unwrap(), img);
    }

    #[test]
    fn every_format_leaves_only_the_target() {
        let dir = crate::test_files::temp_dir("formats");
        let mut img = RgbImage::new(2, 1);
        img.set(0, 0, [0.5, 1.5, 2.5]);
        let options = OutputOptions { exposure: -1.0, tonemap: Tonemap::AcesFilmic, png_depth: PngDepth::Sixteen };
        for name in ["a.pfm", "b.exr", "c.png"] {
            write_image_with(&dir.join(name), &img, &options).unwrap();
        }
        let mut names: Vec<String> =
            std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        names.sort();
        let exr = read_image(&dir.join("b.exr"));
        assert_eq!(names, ["a.pfm", "b.exr", "c.png"]);
        assert_eq!(exr.unwrap(), img);
    }

    #[test]
    fn writing_into_missing_directory_names_the_file() {
        for name in ["out.pfm", "out.exr", "out.png"] {
            let path = Path::new("/nonexistent/caustica").join(name);
            let err = write_image(&path, &RgbImage::new(1, 1), 0.0).unwrap_err();
            let expected = format!("{}: ", path.display());
            assert!(err.to_string().starts_with(&expected), "{err}");
        }
    }

    #[test]
    fn missing_file_error_names_the_file() {
        let err = read_image(Path::new("/nonexistent/caustica/probe.exr")).unwrap_err();
        assert!(err.to_string().starts_with("/nonexistent/caustica/probe.exr: "), "{err}");
    }
}
