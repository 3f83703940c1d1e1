//! Density grids of heterogeneous media in Mitsuba's `.vol` format (Mitsuba 0.6's and 3's
//! `gridvolume`): a 48-byte header, "VOL", version 3, encoding 1 (float32), the resolution along
//! x, y and z, the channel count (1: a density) and the bounding box (min x, y, z, max x, y, z),
//! little-endian, then the values with x fastest, z slowest. Read strictly: the file's length must
//! be exactly what the header says, checked before any value is copied, so a header that lies
//! allocates nothing beyond the file; NaN, infinite and negative densities are refused by index.

use anyhow::{bail, Result};
use glam::Vec3;

const HEADER_BYTES: usize = 48;

/// A grid of densities, values at the centres of its cells, filling `bounds` in its own space.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityGrid {
    /// Cells along x, y and z, each at least 1.
    pub resolution: [u32; 3],
    /// x fastest, then y, then z; finite and >= 0.
    pub values: Vec<f32>,
    /// The box the file says the grid fills (min, max), min < max on every axis.
    pub bounds: (Vec3, Vec3),
}

impl DensityGrid {
    /// The largest value: the majorant of a medium scaled by it.
    pub fn max_value(&self) -> f32 {
        self.values.iter().copied().fold(0.0, f32::max)
    }
}

/// Parses a `.vol` file's bytes; errors name the problem (the caller adds the file).
pub fn parse_vol(bytes: &[u8]) -> Result<DensityGrid> {
    if bytes.len() < HEADER_BYTES {
        bail!("a Mitsuba .vol file has a {HEADER_BYTES}-byte header; this file has {} bytes", bytes.len());
    }
    if &bytes[..3] != b"VOL" {
        bail!("not a Mitsuba .vol file (it does not start with \"VOL\")");
    }
    if bytes[3] != 3 {
        bail!(".vol version {} (only version 3 is read)", bytes[3]);
    }
    let int = |at: usize| i32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let float = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().expect("4 bytes"));
    let encoding = int(4);
    if encoding != 1 {
        bail!(".vol encoding {encoding} (only 1, float32, is read)");
    }
    let dims = [int(8), int(12), int(16)];
    if dims.iter().any(|&d| d < 1) {
        bail!(".vol resolution {dims:?}: every axis needs at least one cell");
    }
    let channels = int(20);
    if channels != 1 {
        bail!(".vol with {channels} channels (a density grid has 1)");
    }
    let min = Vec3::new(float(24), float(28), float(32));
    let max = Vec3::new(float(36), float(40), float(44));
    if !min.is_finite() || !max.is_finite() || min.cmpge(max).any() {
        bail!(".vol bounding box {:?} to {:?}: it must be finite with min < max on every axis", min, max);
    }
    let cells = dims.iter().try_fold(1u64, |n, &d| n.checked_mul(d as u64));
    let expected = cells.and_then(|n| n.checked_mul(4)).and_then(|n| n.checked_add(HEADER_BYTES as u64));
    if expected != Some(bytes.len() as u64) {
        bail!(
            ".vol header says {} x {} x {} cells ({} bytes of values), but the file holds {} bytes after its header",
            dims[0],
            dims[1],
            dims[2],
            cells.and_then(|n| n.checked_mul(4)).map_or("too many".to_owned(), |b| b.to_string()),
            bytes.len() - HEADER_BYTES
        );
    }
    let values: Vec<f32> =
        bytes[HEADER_BYTES..].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes"))).collect();
    if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite() || **v < 0.0) {
        bail!(".vol value {i} is {v}: densities must be finite and >= 0");
    }
    Ok(DensityGrid { resolution: dims.map(|d| d as u32), values, bounds: (min, max) })
}

/// A `.vol` file of these values (for tests and examples).
pub fn vol_bytes(resolution: [u32; 3], bounds: (Vec3, Vec3), values: &[f32]) -> Vec<u8> {
    let mut out = b"VOL\x03".to_vec();
    out.extend(1i32.to_le_bytes());
    for d in resolution {
        out.extend((d as i32).to_le_bytes());
    }
    out.extend(1i32.to_le_bytes());
    for v in bounds.0.to_array().into_iter().chain(bounds.1.to_array()) {
        out.extend(v.to_le_bytes());
    }
    for v in values {
        out.extend(v.to_le_bytes());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> (Vec3, Vec3) {
        (Vec3::ZERO, Vec3::ONE)
    }

    #[test]
    fn a_grid_reads_back() {
        let values: Vec<f32> = (0..24).map(|i| i as f32 * 0.5).collect();
        let grid = parse_vol(&vol_bytes([2, 3, 4], unit(), &values)).unwrap();
        assert_eq!(grid.resolution, [2, 3, 4]);
        assert_eq!(grid.values, values);
        assert_eq!(grid.max_value(), 11.5);
    }

    #[test]
    fn truncated_lying_and_bad_values_are_refused() {
        let good = vol_bytes([2, 2, 2], unit(), &[1.0; 8]);
        let message = |bytes: &[u8]| format!("{:#}", parse_vol(bytes).unwrap_err());
        assert!(message(&good[..good.len() - 1]).contains("file holds 31 bytes"), "{}", message(&good[..47]));
        assert!(message(&good[..20]).contains("48-byte header"));
        // A header claiming 2^31 cells on each axis: refused by its length, nothing allocated.
        let mut lying = good.clone();
        lying[8..12].copy_from_slice(&i32::MAX.to_le_bytes());
        assert!(message(&lying).contains("header says 2147483647 x 2 x 2"), "{}", message(&lying));
        let mut huge = good.clone();
        for at in [8, 12, 16] {
            huge[at..at + 4].copy_from_slice(&i32::MAX.to_le_bytes());
        }
        assert!(message(&huge).contains("too many"), "{}", message(&huge));
        let mut zero = good.clone();
        zero[12..16].copy_from_slice(&0i32.to_le_bytes());
        assert!(message(&zero).contains("at least one cell"));
        assert!(message(&vol_bytes([2, 2, 2], unit(), &[1.0, 1.0, f32::NAN, 1.0, 1.0, 1.0, 1.0, 1.0]))
            .contains("value 2 is NaN"));
        assert!(message(&vol_bytes([2, 2, 2], unit(), &[1.0, 1.0, 1.0, -1.0, 1.0, 1.0, 1.0, 1.0]))
            .contains("value 3 is -1"));
        assert!(message(&vol_bytes([1, 1, 1], (Vec3::ONE, Vec3::ZERO), &[1.0])).contains("min < max"));
        let mut channels = good.clone();
        channels[20..24].copy_from_slice(&3i32.to_le_bytes());
        assert!(message(&channels).contains("3 channels"));
        assert!(message(b"VOX\x03 and more bytes to pass the header length check.....").contains("not a Mitsuba"));
    }
}
