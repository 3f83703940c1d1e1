//! Portable Float Map: the simplest lossless HDR format, used for light probes
//! and reference renders. Header is three whitespace-separated ASCII tokens
//! (`PF`/`Pf`, `width height`, `scale`), then raw f32 rows stored bottom to top.

use std::io::Write;
use std::path::Path;

use super::atomic::write_atomically;
use super::{check_size, file_name, ImageError, RgbImage};
use crate::input_file::{InputFiles, InputKind};

/// Reads a PFM file through `files`. Non-finite pixels are kept; see [`check_finite`].
pub fn read(files: &InputFiles, path: &Path) -> Result<RgbImage, ImageError> {
    let bytes = files.read(path, InputKind::RadianceImage)?;
    decode(&bytes, &file_name(path))
}

/// Writes a little-endian RGB PFM file, atomically.
pub fn write(path: &Path, img: &RgbImage) -> Result<(), ImageError> {
    write_atomically(path, |out| {
        out.write_all(&encode(img)).map_err(|cause| ImageError::Io { file: file_name(path), cause })
    })
}

/// Encodes as `PF`, little-endian (scale -1.0), rows bottom to top.
pub fn encode(img: &RgbImage) -> Vec<u8> {
    let header = format!("PF\n{} {}\n-1.0\n", img.width, img.height);
    let mut out = Vec::with_capacity(header.len() + img.pixels.len() * 12);
    out.extend_from_slice(header.as_bytes());
    let width = img.width as usize;
    // chunks_exact(0) panics; an empty image is just the header.
    if width > 0 {
        for row in img.pixels.chunks_exact(width).rev() {
            for &channel in row.iter().flatten() {
                out.extend_from_slice(&channel.to_le_bytes());
            }
        }
    }
    out
}

/// Decodes a PFM image; `file` is only used in error messages.
///
/// Only the sign of the scale is used (endianness). Its magnitude is ignored:
/// writers practically always put 1.0 there and readers disagree on whether
/// to multiply by it, so the stored floats are taken as the radiance.
/// Bytes after the pixel data are tolerated, since some writers pad files.
pub fn decode(bytes: &[u8], file: &str) -> Result<RgbImage, ImageError> {
    let bad = |reason: String| ImageError::PfmHeader { file: file.to_owned(), reason };
    let mut header = Header { bytes, pos: 0 };

    let channels = match header.token() {
        Some(b"PF") => 3,
        Some(b"Pf") => 1,
        found => return Err(bad(format!("expected 'PF' or 'Pf', found {}", describe(found)))),
    };
    // A header written in lines (the usual form) keeps the scale on the line after the size: a third
    // number beside the width and height is not the scale, whose line would then be taken as pixels.
    let in_lines = header.newline_before_token();
    let width = header.dimension("width").map_err(bad)?;
    let height = header.dimension("height").map_err(bad)?;
    // Before the scale and before allocating: a huge header fails fast.
    check_size(file, width, height)?;

    if in_lines && !header.newline_before_token() {
        let stray = header.token();
        return Err(bad(format!(
            "expected the scale on the line after the width and height, found {} beside them",
            describe(stray)
        )));
    }
    let scale_token = header.token();
    let scale = scale_token
        .and_then(|t| std::str::from_utf8(t).ok())
        .and_then(|t| t.parse::<f32>().ok())
        .filter(|s| s.is_finite() && *s != 0.0)
        .ok_or_else(|| bad(format!("expected a non-zero finite scale, found {}", describe(scale_token))))?;
    let little_endian = scale < 0.0;
    header.skip_separator();

    // check_size bounds both dimensions by 2^28, so these cannot truncate
    // or overflow.
    let (width, height) = (width as u32, height as u32);
    let pixel_count = width as usize * height as usize;
    let expected = pixel_count * channels * 4;
    let data = &bytes[header.pos..];
    if data.len() < expected {
        return Err(ImageError::Truncated { file: file.to_owned(), expected, found: data.len() });
    }

    let sample = |b: &[u8]| {
        let b = [b[0], b[1], b[2], b[3]];
        if little_endian {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        }
    };
    let mut pixels = Vec::with_capacity(pixel_count);
    for row in data[..expected].chunks_exact(width as usize * channels * 4).rev() {
        for px in row.chunks_exact(channels * 4) {
            pixels.push(if channels == 3 {
                [sample(&px[0..4]), sample(&px[4..8]), sample(&px[8..12])]
            } else {
                [sample(px); 3]
            });
        }
    }
    Ok(RgbImage { width, height, pixels })
}

/// Fails on the first NaN or infinite pixel (scanning rows top to bottom), so
/// light-probe loaders can reject files that would poison importance sampling.
pub fn check_finite(img: &RgbImage, file: &str) -> Result<(), ImageError> {
    let width = img.width as usize;
    match img.pixels.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
        None => Ok(()),
        Some(i) => Err(ImageError::NonFinite {
            file: file.to_owned(),
            x: (i % width) as u32,
            y: (i / width) as u32,
            value: img.pixels[i],
        }),
    }
}

/// Cursor over the ASCII header.
struct Header<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Header<'a> {
    /// Next whitespace-delimited token, or `None` at end of input.
    fn token(&mut self) -> Option<&'a [u8]> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        (self.pos > start).then(|| &self.bytes[start..self.pos])
    }

    /// Whether the whitespace before the next token holds a line break (true at end of input).
    fn newline_before_token(&self) -> bool {
        let rest = &self.bytes[self.pos..];
        let gap = rest.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(rest.len());
        gap == rest.len() || rest[..gap].iter().any(|&b| b == b'\n' || b == b'\r')
    }

    /// A positive decimal integer. Parsed as u64 so that values beyond u32
    /// still reach the size check and get the "too large" message.
    fn dimension(&mut self, what: &str) -> Result<u64, String> {
        let token = self.token();
        token
            .filter(|t| t.iter().all(u8::is_ascii_digit))
            .and_then(|t| std::str::from_utf8(t).ok()?.parse::<u64>().ok())
            .filter(|&n| n > 0)
            .ok_or_else(|| format!("expected a positive integer {what}, found {}", describe(token)))
    }

    /// Skips the single whitespace character that ends the header. "\r\n"
    /// counts as one because Windows tools write it; a lone '\r' followed by
    /// pixel data starting with 0x0A is far less likely than that.
    fn skip_separator(&mut self) {
        if self.bytes[self.pos..].starts_with(b"\r\n") {
            self.pos += 2;
        } else if self.pos < self.bytes.len() {
            self.pos += 1;
        }
    }
}

/// A token for an error message, quoted and cut short in case it is binary.
fn describe(token: Option<&[u8]>) -> String {
    match token {
        None => "end of file".to_owned(),
        Some(t) => {
            let shown = String::from_utf8_lossy(&t[..t.len().min(16)]);
            let more = if t.len() > 16 { "..." } else { "" };
            format!("'{shown}{more}'")
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 3 x 2 image with every channel distinct, so any transposition,
    /// row flip or channel swap changes the result.
    fn asymmetric() -> RgbImage {
        let mut img = RgbImage::new(3, 2);
        for y in 0..2 {
            for x in 0..3 {
                let base = (y * 3 + x) as f32;
                img.set(x, y, [base, base + 0.25, -base - 0.5]);
            }
        }
        img
    }

    fn err(bytes: &[u8]) -> String {
        decode(bytes, "probe.pfm").unwrap_err().to_string()
    }

    fn le(values: &[f32]) -> Vec<u8> {
        values.iter().flat_map(|v| v.to_le_bytes()).collect()
    }

    #[test]
    fn round_trip_is_exact() {
        let mut img = asymmetric();
        img.set(0, 0, [f32::MIN_POSITIVE, 1e30, f32::NAN]);
        let back = decode(&encode(&img), "t.pfm").unwrap();
        assert_eq!((back.width, back.height), (3, 2));
        // Compare bits: NaN != NaN but must survive unchanged.
        let bits = |i: &RgbImage| -> Vec<u32> { i.pixels.iter().flatten().map(|v| v.to_bits()).collect() };
        assert_eq!(bits(&back), bits(&img));
    }

    #[test]
    fn round_trip_through_file() {
        let dir = crate::test_files::temp_dir("pfm");
        let path = dir.join("image.pfm");
        let img = asymmetric();
        write(&path, &img).unwrap();
        let back = read(&InputFiles::anywhere(), &path);
        assert_eq!(back.unwrap(), img);
    }

    #[test]
    fn header_is_exact() {
        let bytes = encode(&asymmetric());
        let header = b"PF\n3 2\n-1.0\n";
        assert_eq!(&bytes[..header.len()], header);
        assert_eq!(bytes.len(), header.len() + 3 * 2 * 12);
    }

    #[test]
    fn first_stored_row_is_bottom_row() {
        let img = asymmetric();
        let bytes = encode(&img);
        let data = &bytes[b"PF\n3 2\n-1.0\n".len()..];
        let bottom: Vec<f32> = (0..3).flat_map(|x| img.get(x, 1)).collect();
        assert_eq!(&data[..36], le(&bottom).as_slice());
    }

    #[test]
    fn decodes_big_endian() {
        let mut bytes = b"PF\n2 1\n1.0\n".to_vec();
        for v in [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0] {
            bytes.extend_from_slice(&v.to_be_bytes());
        }
        let img = decode(&bytes, "be.pfm").unwrap();
        assert_eq!(img.pixels, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    }

    #[test]
    fn scale_magnitude_is_not_applied() {
        let mut bytes = b"PF\n1 1\n-4.0\n".to_vec();
        bytes.extend(le(&[1.0, 2.0, 3.0]));
        assert_eq!(decode(&bytes, "s.pfm").unwrap().pixels, vec![[1.0, 2.0, 3.0]]);
    }

    #[test]
    fn decodes_greyscale_bottom_to_top() {
        let mut bytes = b"Pf\n2 2\n-1\n".to_vec();
        bytes.extend(le(&[1.0, 2.0, 3.0, 4.0]));
        let img = decode(&bytes, "g.pfm").unwrap();
        assert_eq!(img.pixels, vec![[3.0; 3], [4.0; 3], [1.0; 3], [2.0; 3]]);
    }

    #[test]
    fn accepts_any_header_whitespace_and_crlf() {
        let mut bytes = b"PF\r\n1\t1\r\n-1.0\r\n".to_vec();
        bytes.extend(le(&[1.0, 2.0, 3.0]));
        bytes.extend_from_slice(b"trailing");
        assert_eq!(decode(&bytes, "w.pfm").unwrap().pixels, vec![[1.0, 2.0, 3.0]]);

        // A single whitespace ends the header even if data starts with a
        // whitespace byte (0x20 is the low byte of this value).
        let value = f32::from_le_bytes([0x20, 0, 0x80, 0x3f]);
        let mut bytes = b"Pf 1 1 -1.0 ".to_vec();
        bytes.extend(le(&[value]));
        assert_eq!(decode(&bytes, "w.pfm").unwrap().pixels, vec![[value; 3]]);
    }

    #[test]
    fn rejects_empty_file() {
        assert_eq!(err(b""), "probe.pfm: bad PFM header: expected 'PF' or 'Pf', found end of file");
    }

    #[test]
    fn rejects_bad_magic() {
        assert_eq!(err(b"P6\n1 1\n255\n"), "probe.pfm: bad PFM header: expected 'PF' or 'Pf', found 'P6'");
    }

    #[test]
    fn rejects_missing_height() {
        assert_eq!(err(b"PF\n4"), "probe.pfm: bad PFM header: expected a positive integer height, found end of file");
    }

    #[test]
    fn rejects_bad_sizes() {
        assert_eq!(
            err(b"PF\n-4 4\n-1.0\n"),
            "probe.pfm: bad PFM header: expected a positive integer width, found '-4'"
        );
        assert!(err(b"PF\n0 4\n-1.0\n").contains("positive integer width, found '0'"));
        assert!(err(b"PF\n4 x\n-1.0\n").contains("positive integer height, found 'x'"));
        assert!(err(b"PF\n4.5 4\n-1.0\n").contains("width, found '4.5'"));
    }

    #[test]
    fn rejects_huge_dimensions_without_allocating() {
        // No pixel data at all: if decode tried to allocate or read 12 EB it
        // would abort or report truncation instead.
        assert_eq!(
            err(b"PF\n1000000000 1000000000\n-1.0\n"),
            "probe.pfm: image of 1000000000 x 1000000000 pixels is too large (limit 2^28 pixels)"
        );
        // Overflowing u64 multiplication is also "too large", not a panic.
        assert!(err(b"PF\n18446744073709551615 3\n-1.0\n").contains("too large"));
        // Exactly at the limit passes the size check and fails on data.
        assert!(err(b"Pf\n16384 16384\n-1.0\n").contains("truncated"));
    }

    #[test]
    fn rejects_truncated_data() {
        let mut bytes = b"PF\n256 256\n-1.0\n".to_vec();
        bytes.extend(vec![0u8; 1000]);
        assert_eq!(err(&bytes), "probe.pfm: truncated: expected 786432 bytes of pixel data, found 1000");
    }

    #[test]
    fn rejects_bad_scale() {
        assert_eq!(
            err(b"PF\n2 2 3\n-1.0\n"),
            "probe.pfm: bad PFM header: expected the scale on the line after the width and height, found '3' beside them"
        );
        assert_eq!(err(b"PF\n1 1\n0\n"), "probe.pfm: bad PFM header: expected a non-zero finite scale, found '0'");
        assert!(err(b"PF\n1 1\n-0.0\n").contains("scale, found '-0.0'"));
        assert!(err(b"PF\n1 1\nnan\n").contains("scale, found 'nan'"));
        assert!(err(b"PF\n1 1\ninf\n").contains("scale, found 'inf'"));
        assert!(err(b"PF\n1 1\n").contains("scale, found end of file"));
    }

    #[test]
    fn check_finite_reports_first_bad_pixel() {
        let mut img = asymmetric();
        assert!(check_finite(&img, "p.pfm").is_ok());
        img.set(2, 1, [0.0, f32::INFINITY, 0.0]);
        img.set(1, 0, [f32::NAN, 0.0, 0.0]);
        let msg = check_finite(&img, "p.pfm").unwrap_err().to_string();
        assert!(msg.starts_with("p.pfm: pixel (1, 0) is not finite: [NaN"), "{msg}");
    }
}
