//! PNG output's 8-bit tonemap as a table a GPU can apply exactly.
//!
//! The viewer tonemaps on the GPU and must show what `render -o FILE.png` writes, pixel for pixel.
//! A shader cannot recompute [`tonemap_srgb8`]: GPU `pow`, `exp2` and division are not correctly
//! rounded the way Rust's are, so an 8-bit code would now and then differ by one. But the code of a
//! channel is a non-decreasing function of its accumulated radiance sum (for a given sample count,
//! exposure and curve): every step (division by the count, the exposure scale, the curve, the sRGB
//! transfer, the rounding) is monotone. So it is fully described by 255 thresholds: the smallest
//! sum whose code is at least k, for k = 1..=255. They are found here by bisection over the f32
//! bit patterns of non-negative sums, evaluating the very functions PNG output uses
//! ([`mean_image`] and [`tonemap_srgb8`]); the shader only compares a sum's bits with them, which
//! every device does exactly. Non-negative floats order as their bit patterns do, so the
//! comparison is an integer one, free of any denormal flushing.

use super::mean_image;
use super::tonemap::{tonemap_srgb8, Tonemap};

/// Entries of a table: entry k (1..=255) is the threshold of code k; entry 0, the threshold of
/// code 0, is 0 (every non-negative sum has a code of at least 0).
pub const CODES: usize = 256;

/// Bit pattern of +infinity, the largest non-negative, non-NaN f32.
const INFINITY_BITS: u32 = 0x7f80_0000;

/// Above every non-NaN sum: the threshold of a code no sum reaches.
pub const UNREACHED: u32 = INFINITY_BITS + 1;

/// The code PNG output gives a channel whose accumulation holds `sum` over `count` samples.
pub fn png_code(sum: f32, count: f32, exposure: f32, tonemap: Tonemap) -> u8 {
    let mean = mean_image(1, 1, &[[sum, sum, sum, count]]);
    tonemap_srgb8(&mean, exposure, tonemap)[0]
}

/// The thresholds of the 8-bit codes of a channel whose accumulation holds `count` samples, as f32
/// bit patterns: the code of a sum `s >= 0` is the largest k with `table[k] <= s.to_bits()`.
pub fn code_thresholds(count: f32, exposure: f32, tonemap: Tonemap) -> [u32; CODES] {
    let code = |bits: u32| png_code(f32::from_bits(bits), count, exposure, tonemap);
    let mut table = [0u32; CODES];
    // Each threshold is at least the previous one, so each search starts there.
    let mut low = 0u32;
    for (k, entry) in table.iter_mut().enumerate().skip(1) {
        if code(INFINITY_BITS) < k as u8 {
            *entry = UNREACHED;
            continue;
        }
        // Invariant: code(high) >= k, and every pattern below `low` has a code below k.
        let mut high = INFINITY_BITS;
        while low < high {
            let mid = low + (high - low) / 2;
            if code(mid) >= k as u8 {
                high = mid;
            } else {
                low = mid + 1;
            }
        }
        *entry = low;
    }
    table
}

/// What the GPU computes from a table: the code of an accumulated `sum`. NaN and negative sums
/// (PNG output clamps them to black) are 0.
pub fn code_from_table(table: &[u32; CODES], sum: f32) -> u8 {
    let bits = sum.to_bits();
    if bits > INFINITY_BITS {
        return 0;
    }
    table.partition_point(|&threshold| threshold <= bits).saturating_sub(1) as u8
}

/// The reference the tables are checked against in the tests: PNG output of a whole image.
#[cfg(test)]
fn png_codes(sums: &[f32], count: f32, exposure: f32, tonemap: Tonemap) -> Vec<u8> {
    let accumulation: Vec<[f32; 4]> = sums.iter().map(|&s| [s, s, s, count]).collect();
    let image: super::RgbImage = mean_image(sums.len() as u32, 1, &accumulation);
    tonemap_srgb8(&image, exposure, tonemap).into_iter().step_by(3).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const CURVES: [Tonemap; 3] = [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::AcesFilmic];

    /// Sums spread over every exponent (every 4099th bit pattern), each threshold and its
    /// neighbours, and the special values.
    fn probe_sums(table: &[u32; CODES]) -> Vec<f32> {
        let mut bits: Vec<u32> = (0..INFINITY_BITS).step_by(4099).collect();
        for &t in table.iter().filter(|&&t| t < UNREACHED) {
            bits.extend([t.saturating_sub(1), t, t + 1]);
        }
        let mut sums: Vec<f32> = bits.into_iter().filter(|&b| b <= INFINITY_BITS).map(f32::from_bits).collect();
        sums.extend([
            f32::NAN,
            -f32::NAN,
            -0.0,
            -1.0,
            f32::NEG_INFINITY,
            f32::INFINITY,
            f32::MAX,
            f32::MIN_POSITIVE,
            1e-45,
        ]);
        sums
    }

    #[test]
    fn tables_give_png_output_codes_exactly() {
        for tonemap in CURVES {
            for (count, exposure) in [
                (1.0, 0.0),
                (7.0, 0.0),
                (64.0, 1.5),
                (3.0, -2.25),
                (1000.0, 0.3),
                (0.0, 0.0),
                (5.0, 126.0),
                (2.0, -126.0),
            ] {
                let table = code_thresholds(count, exposure, tonemap);
                let sums = probe_sums(&table);
                let expected = png_codes(&sums, count, exposure, tonemap);
                for (&sum, &want) in sums.iter().zip(&expected) {
                    assert_eq!(
                        code_from_table(&table, sum),
                        want,
                        "{tonemap} count {count} exposure {exposure}: sum {sum:e} ({:#x})",
                        sum.to_bits()
                    );
                }
            }
        }
    }

    #[test]
    fn thresholds_are_sorted_and_start_at_zero() {
        let table = code_thresholds(16.0, 0.0, Tonemap::Reinhard);
        assert_eq!(table[0], 0);
        assert!(table.windows(2).all(|w| w[0] <= w[1]), "{table:?}");
        // Code 255 of Reinhard needs x / (1 + x) >= 254.5 / 255 in sRGB: reached, and far up.
        assert!(table[255] < UNREACHED && f32::from_bits(table[255]) > 16.0 * 100.0);
    }

    #[test]
    fn a_very_dark_exposure_leaves_bright_codes_unreached_but_infinity_is_white() {
        // Infinity stays infinite whatever the exposure and clamps to white: every code is reached.
        let table = code_thresholds(1.0, -126.0, Tonemap::Clamp);
        assert_eq!(code_from_table(&table, f32::INFINITY), 255);
        assert_eq!(code_from_table(&table, f32::MAX), png_code(f32::MAX, 1.0, -126.0, Tonemap::Clamp));
    }
}
