//! Error metrics between a rendered image and a reference, for convergence studies and tests.

use super::{ImageError, RgbImage};

/// How far `image` is from `reference`, over every pixel and channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    /// Mean of (a - b)^2 / (b^2 + 0.01): squared error relative to the reference's brightness, the
    /// usual convergence metric for HDR renders (the 0.01 keeps black pixels from dominating).
    pub relative_mse: f64,
    /// Mean of |a - b|.
    pub mean_absolute_error: f64,
    /// Mean of `image` over mean of `reference`: 1 for an unbiased render of the same scene; `None`
    /// when the reference is black (mean 0), where there is no ratio.
    pub mean_ratio: Option<f64>,
}

/// Fails, naming the file, when `image` holds NaN or infinite values: they would make every figure
/// NaN or infinite. Says how many pixels and which is the first.
fn check_finite(image: &RgbImage, file: &str) -> Result<(), ImageError> {
    let finite = |p: &[f32; 3]| p.iter().all(|c| c.is_finite());
    let Some(first) = image.pixels.iter().position(|p| !finite(p)) else { return Ok(()) };
    let count = image.pixels.iter().filter(|p| !finite(p)).count();
    let (x, y) = (first % image.width as usize, first / image.width as usize);
    Err(ImageError::Incomparable {
        file: file.to_string(),
        reason: format!(
            "holds {count} non-finite pixel{} (NaN or infinity; the first at ({x}, {y}): {:?}); only finite images can be compared",
            if count == 1 { "" } else { "s" },
            image.pixels[first]
        ),
    })
}

pub fn compare(image: &RgbImage, reference: &RgbImage, names: (&str, &str)) -> Result<Comparison, ImageError> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(ImageError::Incomparable {
            file: names.0.to_string(),
            reason: format!(
                "is {}x{} but {} is {}x{}; only images of the same size can be compared",
                image.width, image.height, names.1, reference.width, reference.height
            ),
        });
    }
    check_finite(image, names.0)?;
    check_finite(reference, names.1)?;
    let (mut rel, mut abs, mut sum_a, mut sum_b) = (0.0, 0.0, 0.0, 0.0);
    for (a, b) in image.pixels.iter().flatten().zip(reference.pixels.iter().flatten()) {
        let (a, b) = (*a as f64, *b as f64);
        rel += (a - b).powi(2) / (b * b + 0.01);
        abs += (a - b).abs();
        sum_a += a;
        sum_b += b;
    }
    let n = (image.pixels.len() * 3) as f64;
    let mean_ratio = (sum_b != 0.0).then(|| sum_a / sum_b);
    Ok(Comparison { relative_mse: rel / n, mean_absolute_error: abs / n, mean_ratio })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(values: &[f32]) -> RgbImage {
        let mut img = RgbImage::new(values.len() as u32, 1);
        for (p, &v) in img.pixels.iter_mut().zip(values) {
            *p = [v; 3];
        }
        img
    }

    #[test]
    fn known_differences() {
        let c = compare(&image(&[1.1, 0.0]), &image(&[1.0, 0.1]), ("a", "b")).unwrap();
        let expected_rel = (0.01 / 1.01 + 0.01 / 0.02) / 2.0;
        assert!((c.relative_mse - expected_rel).abs() < 1e-6, "{c:?}");
        assert!((c.mean_absolute_error - 0.1).abs() < 1e-6);
        assert!((c.mean_ratio.unwrap() - 1.0).abs() < 1e-6);
        assert_eq!(
            compare(&image(&[1.0]), &image(&[0.0]), ("a", "b")).unwrap().mean_ratio,
            None,
            "no ratio to a black reference"
        );
        assert_eq!(compare(&image(&[2.0]), &image(&[2.0]), ("a", "b")).unwrap().relative_mse, 0.0);
    }

    #[test]
    fn non_finite_pixels_are_an_error_naming_the_image_and_counting_them() {
        let e =
            compare(&image(&[1.0, f32::NAN, f32::INFINITY]), &image(&[1.0, 1.0, 1.0]), ("render.pfm", "reference.exr"))
                .unwrap_err()
                .to_string();
        assert!(e.starts_with("render.pfm holds 2 non-finite pixels") && e.contains("(1, 0)"), "{e}");
        let e = compare(&image(&[1.0]), &image(&[f32::NAN]), ("render.pfm", "reference.exr")).unwrap_err().to_string();
        assert!(e.starts_with("reference.exr holds 1 non-finite pixel "), "{e}");
    }

    #[test]
    fn different_sizes_are_an_error_naming_both() {
        let e = compare(&image(&[1.0, 2.0]), &image(&[1.0]), ("render.pfm", "reference.exr")).unwrap_err().to_string();
        assert!(e.contains("render.pfm") && e.contains("reference.exr") && e.contains("2x1"), "{e}");
    }
}
