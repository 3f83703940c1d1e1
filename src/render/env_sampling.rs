//! Importance sampling of environment maps: a piecewise-constant 2D distribution over the map's
//! texel cells, proportional to radiance times the solid angle each cell covers, as a marginal CDF
//! over rows and one conditional CDF per row (pbrt-v4's PiecewiseConstant2D). The kernel samples
//! it in environment.glsl and evaluates its pdf there for MIS.

use super::luminance;
use crate::scene::{EnvironmentMap, MapProjection};
use std::f64::consts::PI;

/// `cdf` = [marginal over rows: height + 1 values][per row: width + 1 values] x height, each
/// running from 0 to 1. Empty when the map has no radiance (nothing to sample).
pub struct EnvDistribution {
    pub cdf: Vec<f32>,
}

/// Solid angle of texel cell (x, y) of a w x h map; zero where the map has no directions.
fn cell_solid_angle(projection: MapProjection, x: u32, y: u32, w: u32, h: u32) -> f64 {
    match projection {
        // Rows are bands of polar angle theta = pi v.
        MapProjection::LatLong => {
            let theta = |row: u32| PI * row as f64 / h as f64;
            2.0 * PI / w as f64 * (theta(y).cos() - theta(y + 1).cos())
        }
        // d(omega) = 4 pi sin(pi r) / r du dv, at the cell centre; none outside the unit disk.
        MapProjection::Angular => {
            let a = 2.0 * (x as f64 + 0.5) / w as f64 - 1.0;
            let b = 1.0 - 2.0 * (y as f64 + 0.5) / h as f64;
            let r = (a * a + b * b).sqrt();
            if r > 1.0 {
                return 0.0;
            }
            let sin_over_r = if r < 1e-6 { PI } else { (PI * r).sin() / r };
            4.0 * PI * sin_over_r / (w as f64 * h as f64)
        }
    }
}

/// Running sums of `weights` normalised to end at 1; uniform when they are all zero (such a row
/// has zero probability in the marginal, so its shape never matters).
fn cdf_of(weights: &[f64]) -> (Vec<f32>, f64) {
    let total: f64 = weights.iter().sum();
    let mut cdf = Vec::with_capacity(weights.len() + 1);
    let mut running = 0.0;
    cdf.push(0.0);
    for (i, w) in weights.iter().enumerate() {
        running += w;
        cdf.push(if total > 0.0 { (running / total) as f32 } else { (i + 1) as f32 / weights.len() as f32 });
    }
    *cdf.last_mut().expect("at least one entry") = 1.0;
    (cdf, total)
}

impl EnvDistribution {
    pub fn new(map: &EnvironmentMap) -> EnvDistribution {
        let (w, h) = (map.image.width, map.image.height);
        let lum = |x: i64, y: i64| -> f64 {
            // The kernel filters bilinearly, so a cell shows its neighbours' radiance too: weight
            // it by the brightest of them, so no direction with radiance gets zero probability.
            let x = if map.projection == MapProjection::LatLong {
                x.rem_euclid(w as i64)
            } else {
                x.clamp(0, w as i64 - 1)
            };
            luminance(&map.image.pixels[(y.clamp(0, h as i64 - 1) * w as i64 + x) as usize])
        };
        let mut rows = Vec::with_capacity(h as usize);
        let mut row_weights = Vec::with_capacity(h as usize);
        for y in 0..h {
            let weights: Vec<f64> = (0..w)
                .map(|x| {
                    let brightest = (-1..=1)
                        .flat_map(|dy| (-1..=1).map(move |dx| (dx, dy)))
                        .map(|(dx, dy)| lum(x as i64 + dx, y as i64 + dy))
                        .fold(0.0, f64::max);
                    brightest * cell_solid_angle(map.projection, x, y, w, h)
                })
                .collect();
            let (cdf, total) = cdf_of(&weights);
            rows.push(cdf);
            row_weights.push(total);
        }
        let (marginal, total) = cdf_of(&row_weights);
        if !(total > 0.0 && total.is_finite()) {
            return EnvDistribution { cdf: Vec::new() };
        }
        let mut cdf = marginal;
        cdf.extend(rows.into_iter().flatten());
        EnvDistribution { cdf }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::RgbImage;

    fn map(projection: MapProjection, w: u32, h: u32) -> EnvironmentMap {
        let mut image = RgbImage::new(w, h);
        image.pixels.iter_mut().for_each(|p| *p = [1.0; 3]);
        EnvironmentMap { projection, image, intensity: 1.0, rotation_deg: 0.0 }
    }

    #[test]
    fn cells_cover_the_sphere() {
        // Lat-long bands are exact; the angular map's midpoint rule converges as cells shrink.
        let total = |p: MapProjection, w: u32, h: u32| {
            (0..h).flat_map(|y| (0..w).map(move |x| cell_solid_angle(p, x, y, w, h))).sum::<f64>()
        };
        assert!((total(MapProjection::LatLong, 64, 32) - 4.0 * PI).abs() < 1e-9);
        assert!((total(MapProjection::Angular, 512, 512) / (4.0 * PI) - 1.0).abs() < 0.01);
    }

    #[test]
    fn a_uniform_lat_long_map_is_sampled_by_solid_angle() {
        let d = EnvDistribution::new(&map(MapProjection::LatLong, 8, 4));
        assert_eq!(d.cdf.len(), 5 + 4 * 9);
        // Rows get the solid angle of their band: (cos theta0 - cos theta1) / 2.
        let band = |y: f64| ((PI * y / 4.0).cos() - (PI * (y + 1.0) / 4.0).cos()) / 2.0;
        for y in 0..4 {
            let p = (d.cdf[y + 1] - d.cdf[y]) as f64;
            assert!((p - band(y as f64)).abs() < 1e-6, "row {y}: {p}");
        }
        // Within a row, every cell is equally likely.
        let row = &d.cdf[5 + 9..5 + 18];
        assert!(row.windows(2).all(|c| ((c[1] - c[0]) - 0.125).abs() < 1e-6), "{row:?}");
    }

    #[test]
    fn a_black_map_has_nothing_to_sample() {
        let mut m = map(MapProjection::Angular, 4, 4);
        m.image.pixels.iter_mut().for_each(|p| *p = [0.0; 3]);
        assert!(EnvDistribution::new(&m).cdf.is_empty());
    }
}
