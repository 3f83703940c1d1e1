//! Linear radiance to display-ready sRGB: exposure, a tone curve, then the
//! exact sRGB transfer function, quantized to 8 or 16 bits.

use std::fmt;
use std::str::FromStr;

use clap::ValueEnum;

use super::RgbImage;

/// Tone curve from exposed linear radiance to display-linear [0, 1], applied
/// per channel. The names ("clamp", "reinhard", "aces") are the CLI values
/// and what `Display`/`FromStr` use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, ValueEnum)]
pub enum Tonemap {
    /// Clip to [0, 1]: exact for values in range, highlights burn out.
    #[default]
    Clamp,
    /// x / (1 + x) on each channel (the simple global operator of Reinhard
    /// et al. 2002, applied to R, G and B rather than luminance). Per channel
    /// it never exceeds 1, so no clipping is needed, and very bright colours
    /// drift towards white, as on film; the luminance form keeps hue but
    /// needs clipping again.
    Reinhard,
    /// Krzysztof Narkowicz's fit of the ACES filmic reference curve
    /// (<https://knarkowicz.wordpress.com/2016/01/06/aces-filmic-tone-mapping-curve/>):
    /// (x (2.51 x + 0.03)) / (x (2.43 x + 0.59) + 0.14), saturated to [0, 1].
    /// Used without the post's 0.6 pre-scale: exposure is the knob for that.
    #[value(name = "aces")]
    AcesFilmic,
}

impl Tonemap {
    /// Maps one exposed linear value to display-linear [0, 1]. NaN maps to 0
    /// so a single bad sample shows as a black pixel rather than poisoning
    /// the image; negative values are clipped to 0.
    pub fn apply(self, linear: f32) -> f32 {
        // `clamp` alone would pass NaN through. Bounding by f32::MAX keeps
        // the curves finite for +inf (inf / inf is NaN); f64 keeps the ACES
        // squares from overflowing near f32::MAX.
        let x = if linear.is_nan() { 0.0 } else { linear.clamp(0.0, f32::MAX) };
        match self {
            Self::Clamp => x.min(1.0),
            Self::Reinhard => {
                let x = f64::from(x);
                (x / (1.0 + x)) as f32
            }
            Self::AcesFilmic => {
                let x = f64::from(x);
                let y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14);
                y.min(1.0) as f32
            }
        }
    }
}

impl fmt::Display for Tonemap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Only variants marked #[value(skip)] have no name; none are.
        let value = self.to_possible_value().ok_or(fmt::Error)?;
        f.write_str(value.get_name())
    }
}

impl FromStr for Tonemap {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        <Self as ValueEnum>::from_str(s, false)
    }
}

/// The exact piecewise sRGB transfer function (IEC 61966-2-1), for linear
/// values in [0, 1]. Not a 2.2 gamma: the linear toe matters for dark pixels.
pub fn srgb_oetf(linear: f32) -> f32 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// Scales by 2^`exposure`, applies `tonemap` and sRGB-encodes: values in
/// [0, 1], channel by channel, rows top to bottom.
fn display_values(img: &RgbImage, exposure: f32, tonemap: Tonemap) -> impl Iterator<Item = f32> + '_ {
    let scale = exposure.exp2();
    img.pixels.iter().flatten().map(move |&v| srgb_oetf(tonemap.apply(v * scale)))
}

/// Display values rounded to 8 bits: tightly packed RGB rows, top to bottom.
pub fn tonemap_srgb8(img: &RgbImage, exposure: f32, tonemap: Tonemap) -> Vec<u8> {
    display_values(img, exposure, tonemap).map(|v| (v * 255.0).round() as u8).collect()
}

/// Display values rounded to 16 bits: tightly packed RGB rows, top to bottom.
pub fn tonemap_srgb16(img: &RgbImage, exposure: f32, tonemap: Tonemap) -> Vec<u16> {
    display_values(img, exposure, tonemap).map(|v| (v * 65535.0).round() as u16).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const ALL: [Tonemap; 3] = [Tonemap::Clamp, Tonemap::Reinhard, Tonemap::AcesFilmic];

    fn one(v: f32, exposure: f32) -> u8 {
        let mut img = RgbImage::new(1, 1);
        img.set(0, 0, [v; 3]);
        tonemap_srgb8(&img, exposure, Tonemap::Clamp)[0]
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
        assert_eq!(tonemap_srgb8(&img, 0.0, Tonemap::Clamp), vec![0, 188, 255, 255, 0, 188]);
    }

    #[test]
    fn clamp_keeps_values_in_range() {
        assert_eq!(Tonemap::Clamp.apply(0.5), 0.5);
        assert_eq!(Tonemap::Clamp.apply(0.0), 0.0);
        assert_eq!(Tonemap::Clamp.apply(3.0), 1.0);
    }

    #[test]
    fn reinhard_known_values() {
        assert_eq!(Tonemap::Reinhard.apply(1.0), 0.5);
        assert_eq!(Tonemap::Reinhard.apply(3.0), 0.75);
        assert_eq!(Tonemap::Reinhard.apply(0.0), 0.0);
        assert_eq!(Tonemap::Reinhard.apply(f32::INFINITY), 1.0);
        // Small values pass almost unchanged (slope 1 at 0).
        let tiny = Tonemap::Reinhard.apply(1e-6);
        assert!((tiny - 1e-6).abs() < 1e-11, "{tiny}");
    }

    #[test]
    fn aces_known_values() {
        assert_eq!(Tonemap::AcesFilmic.apply(0.0), 0.0);
        // 2.54 / 3.16 at 1; 0.18 (mid grey) lands near 0.27.
        let at_one = Tonemap::AcesFilmic.apply(1.0);
        assert!((at_one - 2.54 / 3.16).abs() < 1e-6, "{at_one}");
        let grey = Tonemap::AcesFilmic.apply(0.18);
        assert!((grey - 0.2669).abs() < 1e-3, "{grey}");
        // The fit crosses 1 near 7.24 and is saturated from there on.
        assert!(Tonemap::AcesFilmic.apply(7.0) < 1.0);
        assert_eq!(Tonemap::AcesFilmic.apply(8.0), 1.0);
        assert_eq!(Tonemap::AcesFilmic.apply(f32::INFINITY), 1.0);
    }

    #[test]
    fn curves_are_monotone_and_bounded() {
        for tonemap in ALL {
            let mut previous = 0.0;
            for i in 0..=4000 {
                let x = i as f32 * 0.005;
                let y = tonemap.apply(x);
                assert!((0.0..=1.0).contains(&y), "{tonemap}({x}) = {y}");
                assert!(y >= previous, "{tonemap} decreases at {x}");
                previous = y;
            }
            assert_eq!(tonemap.apply(f32::NAN), 0.0, "{tonemap}");
            assert_eq!(tonemap.apply(-2.0), 0.0, "{tonemap}");
            assert_eq!(tonemap.apply(f32::MAX), 1.0, "{tonemap}");
        }
    }

    #[test]
    fn exposure_comes_before_the_curve() {
        let mut img = RgbImage::new(1, 1);
        img.set(0, 0, [0.5, 0.5, 0.5]);
        // 0.5 * 2 = 1 -> Reinhard 0.5 -> sRGB 188.
        assert_eq!(tonemap_srgb8(&img, 1.0, Tonemap::Reinhard), vec![188; 3]);
    }

    #[test]
    fn sixteen_bit_uses_the_full_range() {
        let mut img = RgbImage::new(2, 1);
        img.set(0, 0, [0.0, 1.0, 0.5]);
        img.set(1, 0, [0.001, 2.0, f32::NAN]);
        let expected_half = (srgb_oetf(0.5) * 65535.0).round() as u16;
        assert_eq!(tonemap_srgb16(&img, 0.0, Tonemap::Clamp), vec![0, 65535, expected_half, 847, 65535, 0]);
    }

    #[test]
    fn names_round_trip() {
        let names: Vec<String> = ALL.iter().map(Tonemap::to_string).collect();
        assert_eq!(names, ["clamp", "reinhard", "aces"]);
        for tonemap in ALL {
            assert_eq!(tonemap.to_string().parse::<Tonemap>(), Ok(tonemap));
        }
        assert!("filmic".parse::<Tonemap>().is_err());
        assert_eq!(Tonemap::default(), Tonemap::Clamp);
    }
}
