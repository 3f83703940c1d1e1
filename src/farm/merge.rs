//! Combining partial renders of one image, each holding its own range of samples.

use super::partial::{format_ranges, PartialRender};
use crate::render::AovSums;
use anyhow::{bail, Context as _, Result};
use std::path::{Path, PathBuf};

/// Reads `inputs` and adds their accumulations. Fails, naming the file, on a different scene, seed
/// or size, and on overlapping sample ranges (those samples would count twice).
pub fn merge_files(inputs: &[PathBuf]) -> Result<PartialRender> {
    let partials =
        inputs.iter().map(|path| Ok((path.as_path(), PartialRender::read(path)?))).collect::<Result<Vec<_>>>()?;
    merge(partials)
}

/// Adds accumulations (AOV sums too) in the order of their first sample, starting from zero: partials
/// of one sample each sum exactly as the kernel would have, others to float rounding.
pub fn merge(mut partials: Vec<(&Path, PartialRender)>) -> Result<PartialRender> {
    let Some(((first_path, first), rest)) = partials.split_first() else { bail!("nothing to merge") };
    for (path, partial) in rest {
        first
            .check_same_render(partial)
            .with_context(|| format!("{}: cannot merge with {}", path.display(), first_path.display()))?;
    }
    partials.sort_by_key(|(_, p)| p.ranges[0].start);
    let first = &partials[0].1;
    let mut ranges: Vec<_> =
        partials.iter().flat_map(|(path, p)| p.ranges.iter().map(move |r| (*path, r.clone()))).collect();
    ranges.sort_by_key(|(_, r)| r.start);
    for pair in ranges.windows(2) {
        let ((a_path, a), (b_path, b)) = (&pair[0], &pair[1]);
        if b.start < a.end {
            bail!(
                "{}: samples {} overlap samples {} of {}",
                b_path.display(),
                format_ranges(std::slice::from_ref(b)),
                format_ranges(std::slice::from_ref(a)),
                a_path.display()
            );
        }
    }
    let pixels = first.accumulation.len();
    let mut merged = PartialRender {
        ranges: union(ranges.into_iter().map(|(_, r)| r)),
        accumulation: vec![[0.0; 4]; pixels],
        aov_sums: first.aov_sums.as_ref().map(|_| AovSums::zeroed(pixels)),
        ..first.clone()
    };
    for (added, (path, partial)) in partials.iter().enumerate() {
        for (sum, add) in merged.accumulation.iter_mut().zip(&partial.accumulation) {
            for c in 0..4 {
                sum[c] += add[c];
            }
        }
        // check_same_render made the AOV sets equal, so both have sums or neither has.
        if let (Some(sum), Some(add)) = (&mut merged.aov_sums, &partial.aov_sums) {
            sum.add(add);
        }
        // Each part's sums are finite (PartialRender::read checks), but two can add to infinity.
        if let Err(e) = merged.check_sums() {
            let before: Vec<String> = partials[..added].iter().map(|(p, _)| p.display().to_string()).collect();
            match before.is_empty() {
                true => bail!("{}: {e:#}", path.display()),
                false => {
                    bail!("{}: its sums overflow when added to those of {}: {e:#}", path.display(), before.join(", "))
                }
            }
        }
    }
    Ok(merged)
}

/// Sorted, disjoint ranges with touching neighbours joined: 0..2 and 2..4 become 0..4.
fn union(sorted: impl Iterator<Item = std::ops::Range<u32>>) -> Vec<std::ops::Range<u32>> {
    let mut out: Vec<std::ops::Range<u32>> = Vec::new();
    for r in sorted {
        match out.last_mut() {
            Some(last) if last.end == r.start => last.end = r.end,
            _ => out.push(r),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn partial(ranges: Vec<std::ops::Range<u32>>, value: f32) -> PartialRender {
        let n: u32 = ranges.iter().map(|r| r.end - r.start).sum();
        PartialRender {
            scene_hash: "h".into(),
            seed: 1,
            width: 1,
            height: 1,
            ranges,
            accumulation: vec![[value, 0.0, 0.0, n as f32]],
            aovs: Default::default(),
            aov_sums: None,
        }
    }

    #[test]
    fn sums_accumulations_and_joins_ranges() {
        let merged = merge(vec![
            (Path::new("b"), partial(vec![2..4], 2.0)),
            (Path::new("a"), partial(vec![0..2], 1.0)),
            (Path::new("c"), partial(vec![6..8], 4.0)),
        ])
        .unwrap();
        assert_eq!(merged.ranges, vec![0..4, 6..8]);
        assert_eq!(merged.accumulation, vec![[7.0, 0.0, 0.0, 6.0]]);
    }

    #[test]
    fn refuses_overlap_and_other_renders() {
        let err =
            merge(vec![(Path::new("a.exr"), partial(vec![0..4], 1.0)), (Path::new("b.exr"), partial(vec![2..6], 1.0))])
                .unwrap_err();
        assert_eq!(format!("{err:#}"), "b.exr: samples 2..6 overlap samples 0..4 of a.exr");
        let mut other = partial(vec![4..6], 1.0);
        other.seed = 2;
        let err = merge(vec![(Path::new("a.exr"), partial(vec![0..4], 1.0)), (Path::new("b.exr"), other)]).unwrap_err();
        assert_eq!(format!("{err:#}"), "b.exr: cannot merge with a.exr: different seed (2, not 1)");
    }

    #[test]
    fn sums_that_overflow_when_added_are_refused_naming_both_parts() {
        let err = merge(vec![
            (Path::new("a.exr"), partial(vec![0..2], 3e38)),
            (Path::new("b.exr"), partial(vec![2..4], 3e38)),
        ])
        .unwrap_err();
        let message = format!("{err:#}");
        assert!(
            message.starts_with("b.exr: its sums overflow when added to those of a.exr: pixel (0, 0)"),
            "{message}"
        );
    }
}
