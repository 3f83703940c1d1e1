//! Linear radiance to display-ready 8-bit sRGB.

use super::RgbImage;

/// The exact piecewise sRGB transfer function (IEC 61966-2-1), for linear
/// values in [0, 1]. Not a 2.2 gamma: the linear toe matters for dark pixels.
pub fn srgb_oetf(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// Scales by 2^`exposure`, clamps to [0, 1], encodes to sRGB and rounds to
/// 8 bits. Returns tightly packed RGB rows, top to bottom. NaN maps to 0 so a
/// single bad sample shows as a black pixel rather than poisoning the image.
pub fn tonemap_srgb8(img: &RgbImage, exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    img.pixels
        .iter()
        .flatten()
        .map(|&v| {
            let scaled = v * scale;
            // clamp alone would pass NaN through (and `as u8` would hide it).
            let linear = if scaled.is_nan() {
                0.0
            } else {
                scaled.clamp(0.0, 1.0)
            };
            (srgb_oetf(linear) * 255.0).round() as u8
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn one(v: f32, exposure: f32) -> u8 {
        let mut img = RgbImage::new(1, 1);
        img.set(0, 0, [v; 3]);
        tonemap_srgb8(&img, exposure)[0]
    }

    #[test]
    fn known_values() {
        assert_eq!(one(0.0, 0.0), 0);
        assert_eq!(one(1.0, 0.0), 255);
        assert_eq!(one(0.5, 0.0), 188);
        assert_eq!(one(0.18, 0.0), 118);
    }

    #[test]
    fn linear_segment_ends_at_threshold() {
        assert_eq!(srgb_oetf(0.003_130_8), 12.92 * 0.003_130_8);
        let above = srgb_oetf(0.003_130_9);
        assert!((above - 12.92 * 0.003_130_8).abs() < 1e-5, "{above}");
        assert_eq!(one(0.003_130_8, 0.0), 10);
        assert_eq!(one(0.001, 0.0), 3);
    }

    #[test]
    fn exposure_is_in_stops() {
        assert_eq!(one(0.25, 1.0), one(0.5, 0.0));
        assert_eq!(one(1.0, -1.0), one(0.5, 0.0));
        assert_eq!(one(0.125, 2.0), 188);
    }

    #[test]
    fn out_of_range_and_nan_are_clamped() {
        assert_eq!(one(-3.0, 0.0), 0);
        assert_eq!(one(f32::NAN, 0.0), 0);
        assert_eq!(one(f32::INFINITY, 0.0), 255);
        assert_eq!(one(7.0, 0.0), 255);
    }

    #[test]
    fn channels_and_pixels_keep_their_order() {
        let mut img = RgbImage::new(2, 1);
        img.set(0, 0, [0.0, 0.5, 1.0]);
        img.set(1, 0, [1.0, 0.0, 0.5]);
        assert_eq!(tonemap_srgb8(&img, 0.0), vec![0, 188, 255, 255, 0, 188]);
    }
}
