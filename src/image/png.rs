//! Tonemapped 8-bit sRGB PNG output for viewing renders.

use std::io::Write;
use std::path::Path;

use super::tonemap::tonemap_srgb8;
use super::{file_name, ImageError, RgbImage};

/// Writes `img` tonemapped with `exposure` (in stops) as 8-bit RGB PNG.
pub fn write(path: &Path, img: &RgbImage, exposure: f32) -> Result<(), ImageError> {
    let file = std::fs::File::create(path).map_err(|source| ImageError::Io {
        file: file_name(path),
        source,
    })?;
    encode(std::io::BufWriter::new(file), img, exposure).map_err(|source| ImageError::Png {
        file: file_name(path),
        source,
    })
}

/// Encodes into any writer. The sRGB chunk tells viewers the bytes are
/// already sRGB-encoded so they do not apply another gamma.
pub fn encode(out: impl Write, img: &RgbImage, exposure: f32) -> Result<(), ::png::EncodingError> {
    let mut encoder = ::png::Encoder::new(out, img.width, img.height);
    encoder.set_color(::png::ColorType::Rgb);
    encoder.set_depth(::png::BitDepth::Eight);
    encoder.set_source_srgb(::png::SrgbRenderingIntent::Perceptual);
    let mut writer = encoder.write_header()?;
    writer.write_image_data(&tonemap_srgb8(img, exposure))?;
    writer.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    #[test]
    fn decodes_to_tonemapped_bytes_with_srgb_chunk() {
        let mut img = RgbImage::new(2, 2);
        img.set(0, 0, [1.0, 0.0, 0.5]);
        img.set(1, 0, [0.25, 0.25, 0.25]);
        img.set(0, 1, [f32::NAN, 2.0, 0.003_130_8]);
        let mut bytes = Vec::new();
        encode(&mut bytes, &img, 1.0).unwrap();

        let mut reader = ::png::Decoder::new(Cursor::new(bytes)).read_info().unwrap();
        let info = reader.info();
        assert_eq!((info.width, info.height), (2, 2));
        assert_eq!(info.srgb, Some(::png::SrgbRenderingIntent::Perceptual));
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let frame = reader.next_frame(&mut buf).unwrap();
        assert_eq!(
            (frame.color_type, frame.bit_depth),
            (::png::ColorType::Rgb, ::png::BitDepth::Eight)
        );
        // Exposure +1 doubles: 0.25 -> 0.5 -> 188, 2 * 0.0031308 is on the
        // power segment (0.0724 -> 18), NaN -> 0, the unset pixel stays 0.
        assert_eq!(
            &buf[..frame.buffer_size()],
            &[255, 0, 255, 188, 188, 188, 0, 255, 18, 0, 0, 0]
        );
    }

    #[test]
    fn write_creates_file_and_reports_bad_path() {
        let path = std::env::temp_dir().join(format!("caustica-png-{}.png", std::process::id()));
        write(&path, &RgbImage::new(3, 1), 0.0).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"));

        let err = write(
            Path::new("/nonexistent/caustica/out.png"),
            &RgbImage::new(1, 1),
            0.0,
        )
        .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("/nonexistent/caustica/out.png: "),
            "{err}"
        );
    }
}
