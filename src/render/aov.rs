//! Arbitrary output variables (AOVs): which ones a render produces, and their per-pixel sums as the
//! kernel accumulates them (`aov_albedo_depth` and `aov_normal_hits` in bindings.rs), turned into
//! per-pixel means. Albedo and normal are the features denoisers such as Intel Open Image Denoise
//! take.

use anyhow::{bail, Result};
use std::fmt;

/// The AOVs of a render, besides the beauty.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AovSet {
    /// Albedo of the first non-specular vertex (mirror and glass bounces are followed).
    pub albedo: bool,
    /// World-space shading normal there, turned towards the side the ray came from.
    pub normal: bool,
    /// Distance along the camera ray to the first hit.
    pub depth: bool,
    /// Samples accumulated in the pixel.
    pub samples: bool,
}

impl AovSet {
    pub const NAMES: [&'static str; 4] = ["albedo", "normal", "depth", "samples"];

    pub const ALL: AovSet = AovSet { albedo: true, normal: true, depth: true, samples: true };

    /// Parses a comma-separated list of [`Self::NAMES`], or "all".
    pub fn parse(text: &str) -> Result<Self> {
        let mut set = AovSet::default();
        for name in text.split(',').map(str::trim) {
            match name {
                "all" => set = Self::ALL,
                "albedo" => set.albedo = true,
                "normal" => set.normal = true,
                "depth" => set.depth = true,
                "samples" => set.samples = true,
                other => bail!(
                    "unknown AOV '{other}': expected a comma-separated list of {}, or all",
                    Self::NAMES.join(", ")
                ),
            }
        }
        Ok(set)
    }

    pub fn is_empty(&self) -> bool {
        *self == AovSet::default()
    }

    /// Whether the kernel has to accumulate features (the sample count it keeps anyway).
    pub fn needs_kernel(&self) -> bool {
        self.albedo || self.normal || self.depth
    }

    fn flags(&self) -> [bool; 4] {
        [self.albedo, self.normal, self.depth, self.samples]
    }
}

/// "albedo,normal", or "none": the form [`AovSet::parse`] reads (but for "none").
impl fmt::Display for AovSet {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let names: Vec<&str> = Self::NAMES.iter().zip(self.flags()).filter(|&(_, on)| on).map(|(&n, _)| n).collect();
        if names.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&names.join(","))
        }
    }
}

/// Per-pixel sums over samples, top row first, exactly as the kernel keeps them.
#[derive(Clone, Debug, PartialEq)]
pub struct AovSums {
    /// rgb = sum of albedo, a = sum of first-hit distance over the samples that hit.
    pub albedo_depth: Vec<[f32; 4]>,
    /// xyz = sum of shading normal, w = samples whose camera ray hit something.
    pub normal_hits: Vec<[f32; 4]>,
}

impl AovSums {
    pub fn zeroed(pixels: usize) -> Self {
        Self { albedo_depth: vec![[0.0; 4]; pixels], normal_hits: vec![[0.0; 4]; pixels] }
    }

    pub fn pixels(&self) -> usize {
        self.albedo_depth.len()
    }

    /// Adds `other`'s sums (a partial render of other samples of the same image).
    pub fn add(&mut self, other: &AovSums) {
        let pairs = self
            .albedo_depth
            .iter_mut()
            .zip(&other.albedo_depth)
            .chain(self.normal_hits.iter_mut().zip(&other.normal_hits));
        for (sum, add) in pairs {
            for c in 0..4 {
                sum[c] += add[c];
            }
        }
    }

    /// Mean albedo per pixel over its `counts` samples (the beauty's sample counts).
    pub fn albedo(&self, counts: &[f32]) -> Vec<[f32; 3]> {
        self.albedo_depth.iter().zip(counts).map(|(a, &n)| mean3(a, n)).collect()
    }

    /// Mean shading normal per pixel, not renormalised (denoisers take it as it is): shorter than
    /// 1 where the pixel straddles an edge or some samples escaped.
    pub fn normal(&self, counts: &[f32]) -> Vec<[f32; 3]> {
        self.normal_hits.iter().zip(counts).map(|(a, &n)| mean3(a, n)).collect()
    }

    /// Mean distance to the first hit over the samples that hit; +infinity where none did.
    pub fn depth(&self) -> Vec<f32> {
        self.albedo_depth
            .iter()
            .zip(&self.normal_hits)
            .map(|(a, h)| if h[3] > 0.0 { a[3] / h[3] } else { f32::INFINITY })
            .collect()
    }
}

fn mean3(sum: &[f32; 4], count: f32) -> [f32; 3] {
    let n = count.max(1.0);
    [sum[0] / n, sum[1] / n, sum[2] / n]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_parse_and_print() {
        assert_eq!(AovSet::parse("all").unwrap(), AovSet::ALL);
        let set = AovSet::parse("depth, albedo").unwrap();
        assert_eq!(set, AovSet { albedo: true, depth: true, ..AovSet::default() });
        assert_eq!(set.to_string(), "albedo,depth");
        assert_eq!(AovSet::parse(&AovSet::ALL.to_string()).unwrap(), AovSet::ALL);
        assert_eq!(AovSet::default().to_string(), "none");
        assert!(!AovSet::parse("samples").unwrap().needs_kernel());
        let err = AovSet::parse("albedo,variance").unwrap_err().to_string();
        assert!(err.contains("unknown AOV 'variance'") && err.contains("albedo, normal, depth, samples"), "{err}");
        assert!(AovSet::parse("").is_err());
    }

    #[test]
    fn means_divide_by_samples_and_depth_by_hits() {
        let sums = AovSums {
            albedo_depth: vec![[1.0, 2.0, 3.0, 6.0], [0.5, 0.5, 0.5, 0.0]],
            normal_hits: vec![[0.0, 4.0, 0.0, 3.0], [0.0; 4]],
        };
        let counts = [4.0, 2.0];
        assert_eq!(sums.albedo(&counts), vec![[0.25, 0.5, 0.75], [0.25, 0.25, 0.25]]);
        assert_eq!(sums.normal(&counts), vec![[0.0, 1.0, 0.0], [0.0; 3]]);
        assert_eq!(sums.depth(), vec![2.0, f32::INFINITY], "depth averages hits only; no hit is infinitely far");
        let mut twice = sums.clone();
        twice.add(&sums);
        assert_eq!(twice.normal_hits[0], [0.0, 8.0, 0.0, 6.0]);
    }
}
