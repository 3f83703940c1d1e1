//! The partial-render file: a layered EXR holding an accumulation and what it is an accumulation of.
//! Checkpoints, farm partials, merged images and EXR render outputs are all this one format, so any
//! of them can be resumed or merged.
//!
//! Layers: the top-level "R", "G", "B" is the mean radiance (what viewers and `read_image` show);
//! "accumulation.R/G/B" is the raw per-pixel sum of sample radiance and "accumulation.count" the
//! number of samples in it, exactly as the kernel keeps them, so resuming is bit for bit. Text
//! attributes ([`SCENE_HASH`] and the rest) say which scene, seed and samples it holds.
//!
//! A denoised render ([`PartialRender::write_denoised`]) has the denoised image as the top-level
//! "R", "G", "B", the noisy mean as "noisy.R/G/B" and the attribute [`DENOISED`] saying how; the
//! accumulation is the same, so it still resumes and merges (the denoised image is made anew).
//!
//! AOVs ([`AOVS`] lists them) add, as means: "albedo.R/G/B", "normal.X/Y/Z", the depth as the
//! top-level "Z" (OpenEXR's name for depth) and the sample count as "samples.Y"; and, as the
//! kernel's raw sums, "accumulation.albedo.R/G/B", "accumulation.normal.X/Y/Z" and
//! "accumulation.depth.Z/hits", so AOVs resume and merge exactly like the beauty.

use crate::image::mean_image;
use crate::image::{read_exr_document, write_exr_document, ExrDocument, ExrLayer, ImageError, RgbImage};
use crate::input_file::{InputFiles, InputKind};
use crate::render::{AovSet, AovSums};
use anyhow::{anyhow, bail, ensure, Context as _, Result};
use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;

/// Hex BLAKE3 of the scene as uploaded (see `Renderer::scene_hash`).
pub const SCENE_HASH: &str = "caustica.scene_hash";
/// The seed of the random streams, decimal.
pub const SEED: &str = "caustica.seed";
/// The sample indices accumulated, as half-open ranges: "0..64", or "0..16,32..48" after a merge.
pub const SAMPLE_RANGES: &str = "caustica.sample_ranges";
/// Samples per pixel accumulated (the total length of the ranges), for people and scripts.
pub const SAMPLES: &str = "caustica.samples";
/// Image size, also in the EXR header; kept for scripts reading attributes only.
pub const WIDTH: &str = "caustica.width";
pub const HEIGHT: &str = "caustica.height";
/// The AOVs the file carries, as `--aov` takes them ("albedo,normal,depth,samples"); absent: none.
pub const AOVS: &str = "caustica.aovs";
/// How the top-level image was denoised, e.g. "Open Image Denoise 2.5.1, quality high, guides
/// albedo and normal"; absent: the top-level image is the noisy mean.
pub const DENOISED: &str = "caustica.denoised";
/// The layer that keeps the noisy mean of a denoised render.
pub const NOISY_LAYER: &str = "noisy";

const ACCUMULATION: &str = "accumulation";
const ACCUMULATION_ALBEDO: &str = "accumulation.albedo";
const ACCUMULATION_NORMAL: &str = "accumulation.normal";
const ACCUMULATION_DEPTH: &str = "accumulation.depth";

/// A layer of per-pixel values, one array element a channel.
fn layer<const N: usize>(name: &str, channels: &[&str; N], pixels: impl IntoIterator<Item = [f32; N]>) -> ExrLayer {
    ExrLayer {
        name: name.to_owned(),
        channels: channels.map(String::from).to_vec(),
        data: pixels.into_iter().flatten().collect(),
    }
}

/// Per pixel, the values of `channels` of `layer` in that order.
fn read_channels<const N: usize>(doc: &ExrDocument, layer: &str, channels: [&str; N]) -> Result<Vec<[f32; N]>> {
    let found = doc.layer(layer).ok_or_else(|| anyhow!("layer '{layer}' is missing"))?;
    let mut order = [0; N];
    for (slot, name) in order.iter_mut().zip(channels) {
        *slot = found
            .channels
            .iter()
            .position(|c| c == name)
            .ok_or_else(|| anyhow!("channel {layer}.{name} is missing"))?;
    }
    Ok(found.data.chunks_exact(found.channels.len()).map(|px| order.map(|c| px[c])).collect())
}

/// An accumulation of the samples in `ranges` of one scene and seed.
#[derive(Clone, Debug, PartialEq)]
pub struct PartialRender {
    pub scene_hash: String,
    pub seed: u32,
    pub width: u32,
    pub height: u32,
    /// Sorted, disjoint, non-empty half-open ranges of sample indices.
    pub ranges: Vec<Range<u32>>,
    /// Per pixel, top row first: sum of radiance (RGB) and the number of samples summed.
    pub accumulation: Vec<[f32; 4]>,
    /// AOV layers the file carries.
    pub aovs: AovSet,
    /// Their raw sums: present exactly when `aovs` needs the kernel's features.
    pub aov_sums: Option<AovSums>,
}

impl PartialRender {
    /// Samples per pixel.
    pub fn samples(&self) -> u32 {
        self.ranges.iter().map(|r| r.end - r.start).sum()
    }

    /// The mean radiance per pixel.
    pub fn image(&self) -> RgbImage {
        mean_image(self.width, self.height, &self.accumulation)
    }

    /// Writes the file atomically (a temporary file renamed over `path`), so a crash leaves either
    /// the previous file or this one.
    pub fn write(&self, path: &Path) -> Result<()> {
        self.write_with(path, None)
    }

    /// Writes the file as [`Self::write`] with `denoised` as the top-level image and the noisy
    /// mean as the layer [`NOISY_LAYER`]; `how` is the [`DENOISED`] attribute.
    pub fn write_denoised(&self, path: &Path, denoised: &RgbImage, how: &str) -> Result<()> {
        ensure!(
            (denoised.width, denoised.height) == (self.width, self.height),
            "the denoised image is {}x{}, the render {}x{}",
            denoised.width,
            denoised.height,
            self.width,
            self.height
        );
        self.write_with(path, Some((denoised, how)))
    }

    fn write_with(&self, path: &Path, denoised: Option<(&RgbImage, &str)>) -> Result<()> {
        let mut attributes = BTreeMap::from([
            (SCENE_HASH.to_owned(), self.scene_hash.clone()),
            (SEED.to_owned(), self.seed.to_string()),
            (SAMPLE_RANGES.to_owned(), format_ranges(&self.ranges)),
            (SAMPLES.to_owned(), self.samples().to_string()),
            (WIDTH.to_owned(), self.width.to_string()),
            (HEIGHT.to_owned(), self.height.to_string()),
        ]);
        if !self.aovs.is_empty() {
            attributes.insert(AOVS.to_owned(), self.aovs.to_string());
        }
        let accumulation = ExrLayer {
            name: ACCUMULATION.to_owned(),
            channels: ["R", "G", "B", "count"].map(String::from).to_vec(),
            data: self.accumulation.iter().flatten().copied().collect(),
        };
        let mut layers = match denoised {
            Some((image, how)) => {
                attributes.insert(DENOISED.to_owned(), how.to_owned());
                vec![ExrLayer::rgb("", image), ExrLayer::rgb(NOISY_LAYER, &self.image())]
            }
            None => vec![ExrLayer::rgb("", &self.image())],
        };
        layers.push(accumulation);
        layers.extend(self.aov_layers());
        let doc = ExrDocument { width: self.width, height: self.height, layers, attributes };
        Ok(write_exr_document(path, &doc)?)
    }

    /// The AOV layers: means for people and denoisers, raw sums for resuming and merging.
    fn aov_layers(&self) -> Vec<ExrLayer> {
        let counts: Vec<f32> = self.accumulation.iter().map(|a| a[3]).collect();
        let mut layers = vec![];
        if self.aovs.samples {
            layers.push(layer("samples", &["Y"], counts.iter().map(|&n| [n])));
        }
        let Some(sums) = &self.aov_sums else { return layers };
        if self.aovs.albedo {
            layers.push(layer("albedo", &["R", "G", "B"], sums.albedo(&counts)));
        }
        if self.aovs.normal {
            layers.push(layer("normal", &["X", "Y", "Z"], sums.normal(&counts)));
        }
        if self.aovs.depth {
            layers.push(layer("", &["Z"], sums.depth().into_iter().map(|z| [z])));
        }
        layers.push(layer(ACCUMULATION_ALBEDO, &["R", "G", "B"], sums.albedo_depth.iter().map(|a| [a[0], a[1], a[2]])));
        layers.push(layer(ACCUMULATION_NORMAL, &["X", "Y", "Z"], sums.normal_hits.iter().map(|a| [a[0], a[1], a[2]])));
        layers.push(layer(
            ACCUMULATION_DEPTH,
            &["Z", "hits"],
            sums.albedo_depth.iter().zip(&sums.normal_hits).map(|(a, n)| [a[3], n[3]]),
        ));
        layers
    }

    /// Reads a file written by [`Self::write`], checking that it is consistent; names the file and
    /// what is wrong otherwise.
    pub fn read(path: &Path) -> Result<Self> {
        let not_ours =
            |reason: String| anyhow!("{} is not a caustica EXR checkpoint/partial ({reason})", path.display());
        if !starts_like_exr(path)? {
            return Err(not_ours(
                "not an OpenEXR file; checkpoints and partial renders are the .exr files caustica writes".to_owned(),
            ));
        }
        // A failure to read is the file system's to report; anything else is the file's content.
        let doc = read_exr_document(path).map_err(|e| match e {
            e @ (ImageError::Io { .. } | ImageError::Exr { cause: ::exr::error::Error::Io(_), .. }) => {
                anyhow::Error::from(e)
            }
            e => not_ours(without_file_name(&e.to_string(), path)),
        })?;
        let partial = Self::from_document(doc).map_err(|e| not_ours(format!("{e:#}")))?;
        partial.check_consistent().map_err(|e| not_ours(format!("{e:#}")))?;
        partial.check_sums().map_err(|e| not_ours(format!("{e:#}")))?;
        Ok(partial)
    }

    fn from_document(doc: ExrDocument) -> Result<Self> {
        let attr = |name: &str| doc.attributes.get(name).ok_or_else(|| anyhow!("attribute {name} is missing"));
        let accumulation = read_channels(&doc, ACCUMULATION, ["R", "G", "B", "count"])?;
        let aovs = match doc.attributes.get(AOVS) {
            Some(text) => AovSet::parse(text).with_context(|| AOVS.to_owned())?,
            None => AovSet::default(),
        };
        let aov_sums = if aovs.needs_kernel() {
            let albedo = read_channels(&doc, ACCUMULATION_ALBEDO, ["R", "G", "B"])?;
            let normal = read_channels(&doc, ACCUMULATION_NORMAL, ["X", "Y", "Z"])?;
            let depth = read_channels(&doc, ACCUMULATION_DEPTH, ["Z", "hits"])?;
            let albedo_depth = albedo.iter().zip(&depth).map(|(a, d)| [a[0], a[1], a[2], d[0]]).collect();
            let normal_hits = normal.iter().zip(&depth).map(|(n, d)| [n[0], n[1], n[2], d[1]]).collect();
            Some(AovSums { albedo_depth, normal_hits })
        } else {
            None
        };
        let partial = Self {
            scene_hash: attr(SCENE_HASH)?.clone(),
            seed: attr(SEED)?.parse().map_err(|e| anyhow!("{SEED}: {e}"))?,
            width: doc.width,
            height: doc.height,
            ranges: parse_ranges(attr(SAMPLE_RANGES)?).with_context(|| SAMPLE_RANGES.to_owned())?,
            accumulation,
            aovs,
            aov_sums,
        };
        ensure!(partial.samples() > 0, "{SAMPLE_RANGES} is empty");
        let recorded: u32 = attr(SAMPLES)?.parse().map_err(|e| anyhow!("{SAMPLES}: {e}"))?;
        ensure!(
            recorded == partial.samples(),
            "{SAMPLES} says {recorded} samples per pixel, but {SAMPLE_RANGES} {} hold {}",
            format_ranges(&partial.ranges),
            partial.samples()
        );
        Ok(partial)
    }

    /// Fails unless every pixel's sample count is the number of samples in the ranges: what the
    /// kernel and merges keep, and what resuming and merging rely on (the mean divides by it).
    pub fn check_consistent(&self) -> Result<()> {
        let samples = self.samples();
        let wrong = |a: &&[f32; 4]| !count_matches(a[3], samples);
        let Some(first) = self.accumulation.iter().position(|a| wrong(&a)) else { return Ok(()) };
        let others = self.accumulation.iter().filter(wrong).count() - 1;
        let (x, y) = (first % self.width as usize, first / self.width as usize);
        bail!(
            "pixel ({x}, {y}) holds {} samples{}, but its sample ranges {} hold {samples}",
            self.accumulation[first][3],
            match others {
                0 => String::new(),
                n => format!(" (and {n} more pixels disagree)"),
            },
            format_ranges(&self.ranges)
        )
    }

    /// Fails unless every sum is finite and no radiance sum is negative: the kernel drops
    /// non-finite samples and radiance is never negative, so anything else would resume or merge
    /// into a wrong image. Names the first such pixel.
    pub fn check_sums(&self) -> Result<()> {
        let radiance = self.accumulation.iter().position(|a| a[..3].iter().any(|c| !c.is_finite() || *c < 0.0));
        if let Some(i) = radiance {
            let (x, y) = self.pixel_at(i);
            let [r, g, b, _] = self.accumulation[i];
            bail!("pixel ({x}, {y}) holds the radiance sums ({r}, {g}, {b}); they must be finite and not negative");
        }
        let Some(sums) = &self.aov_sums else { return Ok(()) };
        let non_finite = |a: &[f32; 4]| a.iter().any(|c| !c.is_finite());
        let aov = sums.albedo_depth.iter().zip(&sums.normal_hits).position(|(a, n)| non_finite(a) || non_finite(n));
        if let Some(i) = aov {
            let (x, y) = self.pixel_at(i);
            bail!("pixel ({x}, {y}) holds a non-finite AOV sum");
        }
        Ok(())
    }

    /// The (x, y) of the pixel at `index`, top row first.
    pub fn pixel_at(&self, index: usize) -> (usize, usize) {
        (index % self.width as usize, index / self.width as usize)
    }

    /// Fails unless `other` is of the same size, seed and scene, naming the first difference (size
    /// first: the scene hash covers the size too).
    pub fn check_same_render(&self, other: &PartialRender) -> Result<()> {
        if (self.width, self.height) != (other.width, other.height) {
            bail!("different size ({}x{}, not {}x{})", other.width, other.height, self.width, self.height);
        }
        if self.seed != other.seed {
            bail!("different seed ({}, not {})", other.seed, self.seed);
        }
        if self.scene_hash != other.scene_hash {
            bail!("different scene (scene hash {}, not {})", other.scene_hash, self.scene_hash);
        }
        if self.aovs != other.aovs {
            bail!("different AOVs ({}, not {})", other.aovs, self.aovs);
        }
        Ok(())
    }
}

/// Whether a pixel's sample count `count` is right for `samples` samples. The kernel counts in an
/// f32, which is exact up to 2^24 and stays there beyond (adding 1 no longer changes it), while a
/// merge adds counts: past 2^24 a count is only known to lie between 2^24 and the samples.
fn count_matches(count: f32, samples: u32) -> bool {
    const EXACT: u32 = 1 << 24;
    if samples <= EXACT {
        count == samples as f32
    } else {
        count >= EXACT as f32 && count as f64 <= samples as f64 * (1.0 + 1e-6)
    }
}

/// Whether the file begins with OpenEXR's magic number: anything else (a PFM, a PNG) is not a
/// partial render, which is worth saying before the EXR reader finds fault with it.
fn starts_like_exr(path: &Path) -> Result<bool> {
    use std::io::Read as _;
    let mut start = Vec::with_capacity(4);
    let file = InputFiles::anywhere().open(path, InputKind::PartialRender)?;
    file.take(4).read_to_end(&mut start).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    Ok(start == [0x76, 0x2f, 0x31, 0x01])
}

/// An image error's message without the "{file}: " it starts with, for messages that name the file
/// their own way.
fn without_file_name(message: &str, path: &Path) -> String {
    let prefix = format!("{}: ", path.display());
    message.strip_prefix(&prefix).unwrap_or(message).to_owned()
}

pub fn format_ranges(ranges: &[Range<u32>]) -> String {
    ranges.iter().map(|r| format!("{}..{}", r.start, r.end)).collect::<Vec<_>>().join(",")
}

/// Parses "a..b,c..d": each range non-empty, sorted and apart from the next.
pub fn parse_ranges(text: &str) -> Result<Vec<Range<u32>>> {
    let mut ranges: Vec<Range<u32>> = Vec::new();
    for part in text.split(',') {
        let (start, end) = part.trim().split_once("..").ok_or_else(|| anyhow!("'{part}' is not a range like 0..64"))?;
        let range = start.parse()?..end.parse()?;
        ensure!(range.start < range.end, "empty range {part}");
        if let Some(last) = ranges.last() {
            ensure!(last.end < range.start, "ranges out of order or touching at {part}");
        }
        ranges.push(range);
    }
    Ok(ranges)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_round_trip_and_reject_overlap() {
        let ranges = parse_ranges("0..16,32..48").unwrap();
        assert_eq!(ranges, vec![0..16, 32..48]);
        assert_eq!(format_ranges(&ranges), "0..16,32..48");
        for bad in ["", "5..5", "0..8,4..12", "8..16,0..4", "0..8,8..9", "x..3", "3"] {
            assert!(parse_ranges(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn file_round_trips_bit_exact() {
        let partial = PartialRender {
            scene_hash: "ab12".into(),
            seed: 7,
            width: 2,
            height: 1,
            ranges: vec![4..6],
            accumulation: vec![[0.1, 1e-30, 3.5e7, 2.0], [f32::MIN_POSITIVE, 0.0, 1.0 / 3.0, 2.0]],
            aovs: AovSet::default(),
            aov_sums: None,
        };
        let dir = crate::test_files::temp_dir("partial");
        let path = dir.join("part.exr");
        partial.write(&path).unwrap();
        let back = PartialRender::read(&path).unwrap();
        assert_eq!(back, partial);
        assert_eq!(crate::image::read_image(&path).unwrap(), partial.image());
    }

    #[test]
    fn inconsistent_ranges_samples_or_counts_are_refused_naming_the_file() {
        let dir = crate::test_files::temp_dir("partial-consistency");
        let path = dir.join("part.exr");
        let good = PartialRender {
            scene_hash: "ab12".into(),
            seed: 7,
            width: 2,
            height: 2,
            ranges: vec![0..2, 4..6],
            accumulation: vec![[1.0, 1.0, 1.0, 4.0]; 4],
            aovs: AovSet::default(),
            aov_sums: None,
        };
        let refusal = |partial: &PartialRender, attribute: Option<(&str, &str)>| {
            partial.write(&path).unwrap();
            if let Some((name, value)) = attribute {
                let mut doc = read_exr_document(&path).unwrap();
                doc.attributes.insert(name.to_owned(), value.to_owned());
                write_exr_document(&path, &doc).unwrap();
            }
            PartialRender::read(&path).err().map(|e| format!("{e:#}"))
        };
        let not_ours = format!("{} is not a caustica EXR checkpoint/partial (", path.display());
        assert_eq!(refusal(&good, None), None);
        let samples = refusal(&good, Some((SAMPLES, "5"))).expect("samples 5 with ranges of 4");
        assert!(
            samples.starts_with(&not_ours)
                && samples
                    .contains("caustica.samples says 5 samples per pixel, but caustica.sample_ranges 0..2,4..6 hold 4"),
            "{samples}"
        );
        let ranges = refusal(&good, Some((SAMPLE_RANGES, "0..5"))).expect("ranges of 5 with samples 4");
        assert!(ranges.contains("caustica.samples says 4"), "{ranges}");
        let mut counts = good.clone();
        counts.accumulation[3][3] = 3.0;
        counts.accumulation[1][3] = 5.0;
        let counts = refusal(&counts, None).expect("pixels with 3 and 5 samples of 4");
        assert!(
            counts.starts_with(&not_ours)
                && counts.contains(
                    "pixel (1, 0) holds 5 samples (and 1 more pixels disagree), but its sample ranges 0..2,4..6 hold 4"
                ),
            "{counts}"
        );
        std::fs::write(&path, b"PF\n1 1\n-1.0\n\0\0\0\0\0\0\0\0\0\0\0\0").unwrap();
        let pfm = PartialRender::read(&path).unwrap_err().to_string();
        assert!(pfm.starts_with(&not_ours) && pfm.contains("not an OpenEXR file"), "{pfm}");
        good.write(&path).unwrap();
        let mut plain = read_exr_document(&path).unwrap();
        plain.attributes.clear();
        write_exr_document(&path, &plain).unwrap();
        let plain = PartialRender::read(&path).unwrap_err().to_string();
        assert!(plain.starts_with(&not_ours) && plain.contains("is missing"), "{plain}");
    }

    #[test]
    fn non_finite_or_negative_sums_are_refused_naming_the_file() {
        let dir = crate::test_files::temp_dir("partial-sums");
        let path = dir.join("part.exr");
        let not_ours = format!("{} is not a caustica EXR checkpoint/partial (", path.display());
        for (value, shown) in [(f32::NAN, "NaN"), (f32::INFINITY, "inf"), (-1.0, "-1")] {
            let mut partial = PartialRender {
                scene_hash: "ab12".into(),
                seed: 7,
                width: 2,
                height: 1,
                ranges: vec![0..2],
                accumulation: vec![[1.0, 1.0, 1.0, 2.0]; 2],
                aovs: AovSet::default(),
                aov_sums: None,
            };
            partial.accumulation[1][1] = value;
            partial.write(&path).unwrap();
            let error = format!("{:#}", PartialRender::read(&path).unwrap_err());
            let expected = format!("pixel (1, 0) holds the radiance sums (1, {shown}, 1); they must be finite");
            assert!(error.starts_with(&not_ours) && error.contains(&expected), "{error}");
        }
        let partial = PartialRender {
            scene_hash: "ab12".into(),
            seed: 7,
            width: 1,
            height: 1,
            ranges: vec![0..1],
            accumulation: vec![[1.0, 1.0, 1.0, 1.0]],
            aovs: AovSet { depth: true, ..AovSet::default() },
            aov_sums: Some(AovSums { albedo_depth: vec![[0.5, 0.5, 0.5, f32::INFINITY]], normal_hits: vec![[0.0; 4]] }),
        };
        partial.write(&path).unwrap();
        let error = format!("{:#}", PartialRender::read(&path).unwrap_err());
        assert!(error.starts_with(&not_ours) && error.contains("pixel (0, 0) holds a non-finite AOV sum"), "{error}");
    }

    #[test]
    fn counts_past_two_to_the_24_are_taken_as_f32_keeps_them() {
        assert!(count_matches(16777216.0, 16777216));
        assert!(count_matches(16777216.0, 20_000_000), "the kernel's f32 count stops at 2^24");
        assert!(count_matches(20_000_000.0, 20_000_000), "a merge adds counts past it");
        assert!(!count_matches(16777215.0, 20_000_000));
        assert!(!count_matches(3.0, 4));
    }

    #[test]
    fn aov_sums_round_trip_bit_exact_and_means_are_written() {
        let sums = AovSums {
            albedo_depth: vec![[0.5, 0.25, 1e-30, 7.0], [0.0, 1.0, 2.0, 0.0]],
            normal_hits: vec![[-1.0, 0.5, 1.0 / 3.0, 2.0], [0.0; 4]],
        };
        let partial = PartialRender {
            scene_hash: "ab12".into(),
            seed: 7,
            width: 2,
            height: 1,
            ranges: vec![0..2],
            accumulation: vec![[1.0, 1.0, 1.0, 2.0], [0.0, 0.0, 0.0, 2.0]],
            aovs: AovSet { albedo: true, depth: true, ..AovSet::default() },
            aov_sums: Some(sums),
        };
        let dir = crate::test_files::temp_dir("partial-aov");
        let path = dir.join("part.exr");
        partial.write(&path).unwrap();
        let back = PartialRender::read(&path);
        let doc = read_exr_document(&path);
        assert_eq!(back.unwrap(), partial);
        let doc = doc.unwrap();
        assert_eq!(doc.attributes[AOVS], "albedo,depth");
        assert_eq!(doc.layer("albedo").unwrap().data, [0.25, 0.125, 0.5e-30, 0.0, 0.5, 1.0]);
        let top = doc.layer("").unwrap();
        assert_eq!(top.channels, ["R", "G", "B", "Z"]);
        assert_eq!([top.data[3], top.data[7]], [3.5, f32::INFINITY], "depth: mean over hits, infinite without");
        assert!(doc.layer("normal").is_none() && doc.layer("samples").is_none(), "only the AOVs asked for");
    }
}
