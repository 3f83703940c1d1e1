//! Spectra given as wavelength:value pairs (and black bodies), reduced to the linear sRGB triple caustica renders
//! with, as Mitsuba 3's RGB modes do: the spectrum (linear between its samples, zero outside
//! them) is integrated against the CIE 1931 colour matching functions, normalised by the integral
//! of y-bar (so that a constant spectrum of 1 has Y = 1, an equal-energy white), and converted from
//! XYZ to linear sRGB; a reflectance is weighted by the D65 illuminant first (its colour under
//! sRGB's white light). The matching functions are the multi-lobe Gaussian fit of Wyman, Sloan and
//! Shirley (JCGT 2013), within about 1% of the tabulated curves: the one approximation here.

use glam::DVec3;

/// Visible range the matching functions are integrated over, nm.
const LAMBDA_MIN: f64 = 360.0;
const LAMBDA_MAX: f64 = 830.0;
const STEPS: usize = 4700;

/// Piecewise Gaussian with different widths left and right of its peak.
fn lobe(lambda: f64, mu: f64, sigma_left: f64, sigma_right: f64) -> f64 {
    let t = (lambda - mu) / if lambda < mu { sigma_left } else { sigma_right };
    (-0.5 * t * t).exp()
}

/// CIE 1931 2-degree matching functions (x-bar, y-bar, z-bar) at `lambda` nm.
fn cie_xyz(lambda: f64) -> DVec3 {
    DVec3::new(
        1.056 * lobe(lambda, 599.8, 37.9, 31.0) + 0.362 * lobe(lambda, 442.0, 16.0, 26.7)
            - 0.065 * lobe(lambda, 501.1, 20.4, 26.2),
        0.821 * lobe(lambda, 568.8, 46.9, 40.5) + 0.286 * lobe(lambda, 530.9, 16.3, 31.1),
        1.217 * lobe(lambda, 437.0, 11.8, 36.0) + 0.681 * lobe(lambda, 459.0, 26.0, 13.8),
    )
}

/// CIE standard illuminant D65 from 360 to 830 nm in steps of 5 nm (relative, 100 at 560 nm).
const D65: [f64; 95] = [
    46.6383, 49.3637, 52.0891, 51.0323, 49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589, 93.4318,
    90.057, 86.6823, 95.7736, 104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392, 115.923, 112.367,
    108.811, 109.082, 109.354, 108.578, 107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046,
    102.023, 100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489,
    87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281, 78.2842,
    74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398,
    63.5927, 55.0054, 46.4182, 56.6118, 66.8054, 65.0941, 63.3828, 63.8434, 64.304, 61.8779, 59.4519, 55.7054, 51.959,
    54.6998, 57.4406, 58.8765, 60.3125,
];

/// D65 at `lambda` nm, linear between the table's samples.
fn d65(lambda: f64) -> f64 {
    let t = ((lambda - LAMBDA_MIN) / 5.0).clamp(0.0, (D65.len() - 1) as f64);
    let i = (t as usize).min(D65.len() - 2);
    D65[i] + (D65[i + 1] - D65[i]) * (t - i as f64)
}

/// Linear sRGB of an emitted spectrum: (wavelength nm, value) pairs, wavelengths increasing.
pub fn to_rgb(samples: &[(f64, f64)]) -> DVec3 {
    weighted_rgb(samples, &|_| 1.0)
}

/// Linear sRGB of a reflectance spectrum, as Mitsuba 3's RGB modes read one (outside emitters):
/// its colour under D65, the illuminant whose white is sRGB's (1, 1, 1), normalised so that a
/// reflectance of 1 everywhere is that white, and clamped to [0, 1] as Mitsuba clamps it.
pub fn reflectance_to_rgb(samples: &[(f64, f64)]) -> DVec3 {
    weighted_rgb(samples, &d65).clamp(DVec3::ZERO, DVec3::ONE)
}

/// The spectrum's XYZ under `weight` (an illuminant), relative to the illuminant's own Y, in
/// linear sRGB.
fn weighted_rgb(samples: &[(f64, f64)], weight: &dyn Fn(f64) -> f64) -> DVec3 {
    let value = |lambda: f64| -> f64 {
        let k = samples.partition_point(|&(l, _)| l < lambda);
        match (k.checked_sub(1).map(|j| samples[j]), samples.get(k)) {
            (_, Some(&(l, v))) if l == lambda => v,
            (Some((l0, v0)), Some(&(l1, v1))) => v0 + (v1 - v0) * (lambda - l0) / (l1 - l0),
            _ => 0.0,
        }
    };
    let h = (LAMBDA_MAX - LAMBDA_MIN) / STEPS as f64;
    let (mut xyz, mut y_integral) = (DVec3::ZERO, 0.0);
    for i in 0..STEPS {
        let lambda = LAMBDA_MIN + (i as f64 + 0.5) * h;
        let cmf = cie_xyz(lambda) * weight(lambda);
        xyz += cmf * value(lambda);
        y_integral += cmf.y;
    }
    xyz_to_linear_srgb(xyz / y_integral)
}

/// Relative luminance (Y) of a linear sRGB colour.
pub fn luminance(c: DVec3) -> f64 {
    0.212671 * c.x + 0.715160 * c.y + 0.072169 * c.z
}

/// Linear sRGB of a black body at `kelvin`, scaled to luminance 1: pbrt-v4 normalises an
/// emitter's spectrum to unit luminance before its `scale`, so only the colour is left.
pub fn blackbody_rgb(kelvin: f64) -> DVec3 {
    // Planck's law with the constants in SI units; wavelengths in nm.
    let (h, c, k) = (6.62606957e-34, 299792458.0, 1.3806488e-23);
    let planck = |nm: f64| {
        let l = nm * 1e-9;
        2.0 * h * c * c / (l.powi(5) * ((h * c / (l * k * kelvin)).exp() - 1.0))
    };
    let samples: Vec<(f64, f64)> = (360..=830).map(|nm| (nm as f64, planck(nm as f64))).collect();
    let rgb = to_rgb(&samples);
    rgb / luminance(rgb)
}

fn xyz_to_linear_srgb(c: DVec3) -> DVec3 {
    DVec3::new(
        3.240479 * c.x - 1.537150 * c.y - 0.498535 * c.z,
        -0.969256 * c.x + 1.875991 * c.y + 0.041556 * c.z,
        0.055648 * c.x - 0.204043 * c.y + 1.057311 * c.z,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The red wall of mitsuba-data's scenes/cbox/cbox.xml.
    const RED_WALL: &str = "400:0.04, 404:0.046, 408:0.048, 412:0.053, 416:0.049, 420:0.05, 424:0.053, 428:0.055, 432:0.057, 436:0.056, 440:0.059, 444:0.057, 448:0.061, 452:0.061, 456:0.06, 460:0.062, 464:0.062, 468:0.062, 472:0.061, 476:0.062, 480:0.06, 484:0.059, 488:0.057, 492:0.058, 496:0.058, 500:0.058, 504:0.056, 508:0.055, 512:0.056, 516:0.059, 520:0.057, 524:0.055, 528:0.059, 532:0.059, 536:0.058, 540:0.059, 544:0.061, 548:0.061, 552:0.063, 556:0.063, 560:0.067, 564:0.068, 568:0.072, 572:0.08, 576:0.09, 580:0.099, 584:0.124, 588:0.154, 592:0.192, 596:0.255, 600:0.287, 604:0.349, 608:0.402, 612:0.443, 616:0.487, 620:0.513, 624:0.558, 628:0.584, 632:0.62, 636:0.606, 640:0.609, 644:0.651, 648:0.612, 652:0.61, 656:0.65, 660:0.638, 664:0.627, 668:0.62, 672:0.63, 676:0.628, 680:0.642, 684:0.639, 688:0.657, 692:0.639, 696:0.635, 700:0.642";

    fn close(a: DVec3, b: DVec3, tolerance: f64) -> bool {
        (a - b).abs().max_element() <= tolerance * b.max_element()
    }

    #[test]
    fn the_red_wall_of_mitsubas_cornell_box_gets_mitsubas_own_rgb() {
        // scenes/cbox of mitsuba-data gives the box both as spectra and as RGB (cbox-rgb.xml).
        // The light's RGB there is not this conversion of its spectrum (red 18.4 where this
        // gives 20.6); docs/importers.md says so.
        let red: Vec<(f64, f64)> = RED_WALL
            .split(", ")
            .map(|pair| {
                let (l, v) = pair.split_once(':').unwrap();
                (l.parse().unwrap(), v.parse().unwrap())
            })
            .collect();
        let rgb = to_rgb(&red);
        assert!(close(rgb, DVec3::new(0.570068, 0.0430135, 0.0443706), 0.02), "{rgb:?}");
        // Mitsuba 3.9 itself reads the spectrum as a reflectance, under D65 (what
        // mi.traverse shows of scenes/cbox/cbox.xml in llvm_ad_rgb).
        let rgb = reflectance_to_rgb(&red);
        assert!(close(rgb, DVec3::new(0.49132, 0.0492281, 0.0509219), 0.02), "{rgb:?}");
    }

    #[test]
    fn a_flat_reflectance_is_grey() {
        let grey = reflectance_to_rgb(&[(400.0, 0.78), (700.0, 0.78)]);
        assert!(close(grey, DVec3::splat(0.78), 0.01), "{grey:?}");
    }

    #[test]
    fn an_equal_energy_spectrum_has_unit_luminance() {
        let flat = to_rgb(&[(LAMBDA_MIN, 1.0), (LAMBDA_MAX, 1.0)]);
        assert!((luminance(flat) - 1.0).abs() < 1e-3, "{flat:?}");
        assert_eq!(to_rgb(&[(400.0, 0.0), (700.0, 0.0)]), DVec3::ZERO);
    }
}

#[cfg(test)]
mod blackbody_tests {
    use super::*;

    #[test]
    fn a_cool_black_body_is_red_a_hot_one_blue_and_6500k_near_white() {
        let (cool, white, hot) = (blackbody_rgb(2700.0), blackbody_rgb(6500.0), blackbody_rgb(12000.0));
        assert!(cool.x > cool.y && cool.y > cool.z, "{cool:?}");
        assert!(hot.z > hot.x, "{hot:?}");
        assert!((white - DVec3::ONE).abs().max_element() < 0.1, "{white:?}");
        assert!((luminance(cool) - 1.0).abs() < 1e-9);
    }
}
