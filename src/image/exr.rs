//! OpenEXR via the `exr` crate: 32-bit float RGB out, first RGB(A) layer in.

use std::path::Path;

use std::io::BufReader;

use ::exr::meta::MetaData;
use ::exr::prelude::{Image, ReadChannels as _, ReadLayers as _, SpecificChannels, Vec2, WritableImage};

use super::atomic::write_atomically;
use super::{check_size, file_name, ImageError, RgbImage};
use crate::input_file::{InputFiles, InputKind};

/// Writes full-precision f32 RGB with the crate's default lossless
/// compression, atomically.
pub fn write(path: &Path, img: &RgbImage) -> Result<(), ImageError> {
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let [r, g, b] = img.get(x as u32, y as u32);
        (r, g, b)
    });
    let image = Image::from_channels((img.width as usize, img.height as usize), channels);
    write_atomically(path, |out| image.write().to_buffered(out).map_err(|e| exr_error(path, e)))
}

/// Reads the first layer that has R, G and B channels; alpha is dropped and
/// half or u32 samples are converted to f32. In a layered file written by
/// [`super::write_exr_document`] that is the top-level (beauty) layer. The
/// file is read through `files` (as the crate's `read_first_rgba_layer_from_file`
/// would, but never opening it itself).
pub fn read(files: &InputFiles, path: &Path) -> Result<RgbImage, ImageError> {
    let kind = InputKind::RadianceImage;
    check_header_sizes(files, path, kind)?;
    let image = ::exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            // Sizes fit in u32: check_header_sizes bounded them by 2^28.
            |size: Vec2<usize>, _| RgbImage::new(size.0 as u32, size.1 as u32),
            |img: &mut RgbImage, pos: Vec2<usize>, (r, g, b, _): (f32, f32, f32, f32)| {
                img.set(pos.0 as u32, pos.1 as u32, [r, g, b])
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(BufReader::new(files.open(path, kind)?))
        .map_err(|e| exr_error(path, e))?;
    Ok(image.layer_data.channel_data.pixels)
}

/// The pixel readers allocate from the header without asking us, so this
/// checks sizes from the headers alone first. Any oversized layer rejects the
/// file, which is stricter than needed but avoids duplicating the crate's
/// choice of "first valid layer".
pub(crate) fn check_header_sizes(files: &InputFiles, path: &Path, kind: InputKind) -> Result<(), ImageError> {
    let meta = MetaData::read_from_unbuffered(files.open(path, kind)?, false).map_err(|e| exr_error(path, e))?;
    for header in &meta.headers {
        let Vec2(width, height) = header.layer_size;
        check_size(&file_name(path), width as u64, height as u64)?;
    }
    Ok(())
}

pub(crate) fn exr_error(path: &Path, cause: ::exr::error::Error) -> ImageError {
    ImageError::Exr { file: file_name(path), cause }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_is_exact() {
        let mut img = RgbImage::new(5, 3);
        for y in 0..3 {
            for x in 0..5 {
                // Values that f16 could not hold, to prove f32 storage.
                let v = 1.0 + (y * 5 + x) as f32 * 1e-6;
                img.set(x, y, [v, -v * 3.0, v * 1e20]);
            }
        }
        let dir = crate::test_files::temp_dir("exr-roundtrip");
        let path = dir.join("image.exr");
        write(&path, &img).unwrap();
        let back = read(&InputFiles::anywhere(), &path);
        assert_eq!(back.unwrap(), img);
    }

    #[test]
    fn garbage_is_rejected_with_file_name() {
        let path = crate::test_files::write_file("exr-garbage", "garbage.exr", b"not an exr file at all");
        let err = read(&InputFiles::anywhere(), &path).unwrap_err().to_string();
        assert!(err.starts_with(&format!("{}: EXR: ", path.display())), "{err}");
    }
}
