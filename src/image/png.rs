//! Tonemapped sRGB PNG output, 8 or 16 bits per channel, for viewing renders.

use std::fmt;
use std::io::Write;
use std::path::Path;
use std::str::FromStr;

use clap::ValueEnum;

use super::atomic::write_atomically;
use super::tonemap::{tonemap_srgb16, tonemap_srgb8};
use super::{file_name, ImageError, OutputOptions, RgbImage};

/// Bits per PNG channel. The names ("8", "16") are the CLI values and what
/// `Display`/`FromStr` use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum PngDepth {
    #[default]
    #[value(name = "8")]
    Eight,
    /// For grading or compositing afterwards: no banding in smooth gradients.
    #[value(name = "16")]
    Sixteen,
}

impl fmt::Display for PngDepth {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Only variants marked #[value(skip)] have no name; none are.
        let value = self.to_possible_value().ok_or(fmt::Error)?;
        f.write_str(value.get_name())
    }
}

impl FromStr for PngDepth {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as ValueEnum>::from_str(s, false)
    }
}

/// Writes `img` tonemapped as `options` say, atomically.
pub fn write(path: &Path, img: &RgbImage, options: &OutputOptions) -> Result<(), ImageError> {
    write_atomically(path, |out| {
        encode(out, img, options).map_err(|cause| ImageError::Png { file: file_name(path), cause })
    })
}

/// Encodes into any writer. The sRGB chunk tells viewers the samples are
/// already sRGB-encoded so they do not apply another gamma.
pub fn encode(out: impl Write, img: &RgbImage, options: &OutputOptions) -> Result<(), ::png::EncodingError> {
    let OutputOptions { exposure, tonemap, png_depth } = *options;
    let data = match png_depth {
        PngDepth::Eight => tonemap_srgb8(img, exposure, tonemap),
        // PNG stores 16-bit samples big-endian, and the png crate takes
        // them as they are stored.
        PngDepth::Sixteen => tonemap_srgb16(img, exposure, tonemap).into_iter().flat_map(u16::to_be_bytes).collect(),
    };
    encode_srgb(out, img.width, img.height, png_depth, &data)
}

/// Encodes display-ready sRGB samples (RGB rows, top to bottom, as PNG
/// stores them) with the sRGB chunk.
fn encode_srgb(
    out: impl Write,
    width: u32,
    height: u32,
    depth: PngDepth,
    samples: &[u8],
) -> Result<(), ::png::EncodingError> {
    let mut encoder = ::png::Encoder::new(out, width, height);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
    encoder.set_depth(match depth {
        PngDepth::Eight => ::png::BitDepth::Eight,
        PngDepth::Sixteen => ::png::BitDepth::Sixteen,
    });
    let mut writer = encoder.write_header()?;
    writer.write_image_data(samples)?;
    writer.finish()
}

/// Writes 8-bit sRGB samples tonemapped elsewhere (tightly packed RGB rows,
/// top to bottom: the viewer's screen) atomically, as [`write`] writes a
/// tonemapped image.
pub fn write_srgb8(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), ImageError> {
    assert_eq!(rgb.len(), width as usize * height as usize * 3, "RGB samples of {width}x{height}");
    write_atomically(path, |out| {
        encode_srgb(out, width, height, PngDepth::Eight, rgb)
            .map_err(|cause| ImageError::Png { file: file_name(path), cause })
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::tonemap::{srgb_oetf, Tonemap};
    use std::io::Cursor;

    /// Decodes without transformations: (color type, bit depth, sRGB intent,
    /// raw sample bytes).
    fn decode(bytes: Vec<u8>) -> (::png::ColorType, ::png::BitDepth, Option<::png::SrgbRenderingIntent>, Vec<u8>) {
        let mut decoder = ::png::Decoder::new(Cursor::new(bytes));
        decoder.set_transformations(::png::Transformations::IDENTITY);
        let mut reader = decoder.read_info().unwrap();
        let srgb = reader.info().srgb;
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut buf).unwrap();
        buf.truncate(frame.buffer_size());
        (frame.color_type, frame.bit_depth, srgb, buf)
    }

    #[test]
    fn decodes_to_tonemapped_bytes_with_srgb_chunk() {
        let mut img = RgbImage::new(2, 2);
        img.set(0, 0, [1.0, 0.0, 0.5]);
        img.set(1, 0, [0.25, 0.25, 0.25]);
        img.set(0, 1, [f32::NAN, 2.0, 0.003_130_8]);
        let mut bytes = Vec::new();
        let options = OutputOptions { exposure: 1.0, ..OutputOptions::default() };
        encode(&mut bytes, &img, &options).unwrap();

        let (color, depth, srgb, samples) = decode(bytes);
        assert_eq!((color, depth), (::png::ColorType::Rgb, ::png::BitDepth::Eight));
        assert_eq!(srgb, Some(::png::SrgbRenderingIntent::Perceptual));
        // Exposure +1 doubles: 0.25 -> 0.5 -> 188, 2 * 0.0031308 is on the
        // power segment (0.0724 -> 18), NaN -> 0, the unset pixel stays 0.
        assert_eq!(samples, [255, 0, 255, 188, 188, 188, 0, 255, 18, 0, 0, 0]);
    }

    #[test]
    fn sixteen_bit_round_trips_big_endian() {
        let mut img = RgbImage::new(2, 1);
        img.set(0, 0, [0.5, 1.0, 0.0]);
        img.set(1, 0, [3.0, 0.001, 0.18]);
        let options = OutputOptions { exposure: 0.0, tonemap: Tonemap::Reinhard, png_depth: PngDepth::Sixteen };
        let mut bytes = Vec::new();
        encode(&mut bytes, &img, &options).unwrap();

        let (color, depth, srgb, samples) = decode(bytes);
        assert_eq!((color, depth), (::png::ColorType::Rgb, ::png::BitDepth::Sixteen));
        assert_eq!(srgb, Some(::png::SrgbRenderingIntent::Perceptual));
        let values: Vec<u16> = samples.chunks_exact(2).map(|b| u16::from_be_bytes([b[0], b[1]])).collect();
        let expected: Vec<u16> = [0.5f32, 1.0, 0.0, 3.0, 0.001, 0.18]
            .iter()
            .map(|&v| (srgb_oetf(v / (1.0 + v)) * 65535.0).round() as u16)
            .collect();
        assert_eq!(values, expected);
        // Reinhard(3) = 0.75 and Reinhard(1) = 0.5, both exact before sRGB.
        assert_eq!(values[3], (srgb_oetf(0.75) * 65535.0).round() as u16);
        assert_eq!(values[1], (srgb_oetf(0.5) * 65535.0).round() as u16);
    }

    #[test]
    fn write_creates_file_and_reports_bad_path() {
        let dir = crate::test_files::temp_dir("png");
        let path = dir.join("out.png");
        write(&path, &RgbImage::new(3, 1), &OutputOptions::default()).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));

        let err = write(Path::new("/nonexistent/caustica/out.png"), &RgbImage::new(1, 1), &OutputOptions::default())
            .unwrap_err();
        assert!(err.to_string().starts_with("/nonexistent/caustica/out.png: "), "{err}");
    }

    #[test]
    fn depth_names_round_trip() {
        assert_eq!(PngDepth::Eight.to_string(), "8");
        assert_eq!(PngDepth::Sixteen.to_string(), "16");
        assert_eq!("16".parse::<PngDepth>(), Ok(PngDepth::Sixteen));
        assert_eq!("8".parse::<PngDepth>(), Ok(PngDepth::Eight));
        assert!("12".parse::<PngDepth>().is_err());
    }
}
