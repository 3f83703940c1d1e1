//! Radiance RGBE (`.hdr`, `.pic`): the most common format of HDRI environment maps. A text header
//! (`#?RADIANCE` or `#?RGBE`, lines of `NAME=value`, a blank line, then `-Y height +X width`), and
//! rows top to bottom of 4-byte pixels: an 8-bit mantissa per channel and a shared exponent, value =
//! (mantissa + 0.5) / 256 x 2^(exponent - 128) (Greg Ward's `colr_color`; exponent 0 is black).
//! Rows are flat, or run-length encoded per channel ("new" RLE: a row starts 2, 2, width high,
//! width low). The old RLE (repeat markers 1, 1, 1) and orientations other than `-Y +X` are refused
//! by name: the writers of HDRIs today do not use them.
//!
//! Every read is bounds-checked: a header that claims more pixels than [`check_size`] allows, a
//! run that passes its row's end, or data that ends early is an error naming the file, before any
//! allocation the file's size does not back.

use std::path::Path;

use super::{check_size, file_name, ImageError, RgbImage};
use crate::input_file::{InputFiles, InputKind};

/// Reads an RGBE file through `files`.
pub fn read(files: &InputFiles, path: &Path) -> Result<RgbImage, ImageError> {
    let bytes = files.read(path, InputKind::RadianceImage)?;
    decode(&bytes, &file_name(path))
}

/// Header lines longer than this are not a Radiance header (a binary file read by mistake).
const MAX_HEADER_LINE: usize = 4096;

/// Decodes RGBE bytes; `file` is only used in error messages.
pub fn decode(bytes: &[u8], file: &str) -> Result<RgbImage, ImageError> {
    let bad = |reason: String| ImageError::RgbeHeader { file: file.to_owned(), reason };
    let mut pos = 0;
    let mut line = || -> Option<&[u8]> {
        let rest = bytes.get(pos..)?;
        let end = rest.iter().take(MAX_HEADER_LINE).position(|&b| b == b'\n')?;
        pos += end + 1;
        Some(&rest[..end])
    };
    let magic = line().ok_or_else(|| bad("no header line".to_owned()))?;
    if !(magic.starts_with(b"#?RADIANCE") || magic.starts_with(b"#?RGBE")) {
        return Err(bad("expected '#?RADIANCE' or '#?RGBE' on the first line".to_owned()));
    }
    loop {
        let header = line().ok_or_else(|| bad("the header ends without a blank line and a size".to_owned()))?;
        if header.is_empty() {
            break;
        }
        if let Some(format) = header.strip_prefix(b"FORMAT=") {
            if format != b"32-bit_rle_rgbe" {
                return Err(bad(format!(
                    "FORMAT={} is not supported (only 32-bit_rle_rgbe)",
                    String::from_utf8_lossy(format)
                )));
            }
        }
    }
    let size = line().ok_or_else(|| bad("no size line after the header".to_owned()))?;
    let size = std::str::from_utf8(size).map_err(|_| bad("the size line is not text".to_owned()))?;
    let tokens: Vec<&str> = size.split_whitespace().collect();
    let (height, width) = match tokens.as_slice() {
        ["-Y", h, "+X", w] => (h.parse::<u64>().ok(), w.parse::<u64>().ok()),
        _ => {
            return Err(bad(format!("size line '{size}': only '-Y height +X width' (rows top to bottom) is supported")))
        }
    };
    let (Some(height), Some(width)) = (height, width) else {
        return Err(bad(format!("size line '{size}': width and height must be whole numbers")));
    };
    if width == 0 || height == 0 {
        return Err(bad(format!("size line '{size}': the image is empty")));
    }
    check_size(file, width, height)?;
    let (width, height) = (width as usize, height as usize);
    // Each pixel takes at least one byte even run-length encoded (two per run of up to 127): a
    // file far smaller than its claimed size is refused before allocating for it.
    let data = &bytes[pos..];
    if data.len().saturating_mul(128) < width * height {
        return Err(ImageError::Truncated { file: file.to_owned(), expected: width * height / 128, found: data.len() });
    }
    let truncated = |at: usize| ImageError::Truncated { file: file.to_owned(), expected: at + 1, found: data.len() };
    let mut image = RgbImage::new(width as u32, height as u32);
    let mut at = 0;
    let mut row = vec![[0u8; 4]; width];
    for y in 0..height {
        let start = data.get(at..at + 4);
        let rle = (8..=0x7fff).contains(&width)
            && start.is_some_and(|s| s[0] == 2 && s[1] == 2 && s[2] & 0x80 == 0)
            && start.is_some_and(|s| ((s[2] as usize) << 8 | s[3] as usize) == width);
        if rle {
            at += 4;
            for channel in 0..4 {
                let mut x = 0;
                while x < width {
                    let &count = data.get(at).ok_or_else(|| truncated(at))?;
                    at += 1;
                    let (count, run) = if count > 128 { (count as usize - 128, true) } else { (count as usize, false) };
                    if count == 0 || x + count > width {
                        return Err(bad(format!("row {y}: a run of {count} pixels passes the row's end or is empty")));
                    }
                    if run {
                        let &value = data.get(at).ok_or_else(|| truncated(at))?;
                        at += 1;
                        row[x..x + count].iter_mut().for_each(|p| p[channel] = value);
                    } else {
                        let values = data.get(at..at + count).ok_or_else(|| truncated(at + count - 1))?;
                        at += count;
                        row[x..x + count].iter_mut().zip(values).for_each(|(p, &v)| p[channel] = v);
                    }
                    x += count;
                }
            }
        } else {
            let flat = data.get(at..at + 4 * width).ok_or_else(|| truncated(at + 4 * width - 1))?;
            at += 4 * width;
            for (p, bytes) in row.iter_mut().zip(flat.chunks_exact(4)) {
                if bytes[..3] == [1, 1, 1] {
                    return Err(bad(format!("row {y}: old-style run-length encoding is not supported")));
                }
                p.copy_from_slice(bytes);
            }
        }
        for (x, p) in row.iter().enumerate() {
            image.set(x as u32, y as u32, rgbe_to_rgb(*p));
        }
    }
    Ok(image)
}

/// One RGBE pixel as linear RGB: (mantissa + 0.5) / 256 x 2^(exponent - 128), black for exponent 0.
fn rgbe_to_rgb([r, g, b, e]: [u8; 4]) -> [f32; 3] {
    if e == 0 {
        return [0.0; 3];
    }
    let scale = 2f32.powi(e as i32 - 136);
    [r, g, b].map(|m| (m as f32 + 0.5) * scale)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn header(width: usize, height: usize) -> Vec<u8> {
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y {height} +X {width}\n").into_bytes()
    }

    /// Flat rows: the decoded values are (m + 0.5) / 256 x 2^(e - 128), rows top to bottom.
    #[test]
    fn flat_pixels_decode_to_their_values() {
        let mut file = header(2, 2);
        file.extend([128, 64, 32, 129, 0, 0, 0, 0, 255, 255, 255, 128, 128, 128, 128, 130]);
        let image = decode(&file, "flat.hdr").unwrap();
        assert_eq!(image.get(0, 0), [128.5 / 128.0, 64.5 / 128.0, 32.5 / 128.0]);
        assert_eq!(image.get(1, 0), [0.0; 3]);
        assert_eq!(image.get(0, 1), [255.5 / 256.0; 3]);
        assert_eq!(image.get(1, 1), [128.5 / 64.0; 3]);
    }

    /// Run-length encoded rows (each channel in runs and literal spans) decode like flat ones.
    #[test]
    fn run_length_encoded_rows_decode_like_flat_ones() {
        let width = 10;
        let mut file = header(width, 1);
        file.extend([2, 2, 0, width as u8]);
        // Red: a run of 10 x 100. Green: 3 literals, then a run of 7 x 50. Blue: 10 literals.
        // Exponent: a run of 10 x 128.
        file.extend([128 + 10, 100]);
        file.extend([3, 1, 2, 3, 128 + 7, 50]);
        file.push(10);
        file.extend(0..10u8);
        file.extend([128 + 10, 128]);
        let image = decode(&file, "rle.hdr").unwrap();
        for x in 0..width as u32 {
            let g = if x < 3 { x as f32 + 1.0 } else { 50.0 };
            let expected = [100.5 / 256.0, (g + 0.5) / 256.0, (x as f32 + 0.5) / 256.0];
            assert_eq!(image.get(x, 0), expected, "pixel {x}");
        }
    }

    /// Truncated data, a run past the row's end, a lying size, a missing magic line, another
    /// orientation, and a size far beyond the file: each an error naming the file, no panic.
    #[test]
    fn truncated_and_lying_files_are_errors() {
        let mut flat = header(2, 2);
        flat.extend([128u8; 12]);
        let mut rle_overrun = header(8, 1);
        rle_overrun.extend([2, 2, 0, 8, 128 + 9, 1]);
        let mut rle_cut = header(8, 1);
        rle_cut.extend([2, 2, 0, 8, 5, 1, 2]);
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (flat, "truncated"),
            (rle_overrun, "passes the row's end"),
            (rle_cut, "truncated"),
            (b"P6\n2 2\n255\n".to_vec(), "#?RADIANCE"),
            (b"#?RADIANCE\n\n+Y 2 +X 2\n".to_vec(), "-Y height +X width"),
            (b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\0\0\0\0".to_vec(), "32-bit_rle_xyze"),
            (b"#?RADIANCE\n\n-Y 100000 +X 100000\n".to_vec(), "too large"),
            (b"#?RADIANCE\n\n-Y 10000 +X 10000\n\0\0\0\0".to_vec(), "truncated"),
            (b"#?RADIANCE\nno blank line".to_vec(), "blank line"),
        ];
        for (bytes, needle) in cases {
            let err = decode(&bytes, "bad.hdr").unwrap_err().to_string();
            assert!(err.contains("bad.hdr") && err.contains(needle), "expected '{needle}': {err}");
        }
    }
}
