//! SAH split search: bins primitive centroids on all three axes in one pass, then sweeps the bin
//! boundaries for the cheapest split.

use glam::Vec3A;

use super::blocks;
use super::box_a::BoxA;

/// Most bins per axis. 16 is the usual point where more bins stop paying for the extra sweep.
pub(super) const BINS: usize = 16;

/// Maps (doubled) centroids to bin indices on each axis.
#[derive(Clone, Copy, Debug)]
pub(super) struct Binning {
    min: Vec3A,
    scale: Vec3A,
    /// bin_count - 1 on every axis, for clamping before the float-to-int conversion.
    last: Vec3A,
}

impl Binning {
    pub fn new(centroids: &BoxA, bin_count: usize) -> Binning {
        let extent = centroids.hi - centroids.lo;
        // A flat or non-finite extent gets scale 0: everything lands in bin 0 and the axis offers no split.
        let scale = Vec3A::from_array(std::array::from_fn(|axis| {
            if extent[axis] > 0.0 && extent[axis].is_finite() {
                bin_count as f32 / extent[axis]
            } else {
                0.0
            }
        }));
        Binning { min: centroids.lo, scale, last: Vec3A::splat((bin_count - 1) as f32) }
    }

    /// Clamping in SIMD first leaves the conversions nothing to saturate. `max` comes first and
    /// returns its operand 0 for a NaN lane, so even non-finite centroids land in a valid bin.
    fn bins(&self, centroid2: Vec3A) -> [usize; 3] {
        let f = ((centroid2 - self.min) * self.scale).max(Vec3A::ZERO).min(self.last);
        std::array::from_fn(|axis| f[axis] as u32 as usize)
    }

    /// `bins(centroid2)[axis]`, bit for bit: the partition must agree with the bins it was planned on.
    pub fn bin(&self, centroid2: Vec3A, axis: usize) -> usize {
        let f = ((centroid2[axis] - self.min[axis]) * self.scale[axis]).max(0.0).min(self.last[axis]);
        f as u32 as usize
    }
}

/// Per-axis bin boxes and counts. Only the first `bin_count` bins of each axis are used, so a
/// builder reuses one `Bins` and resets just those (small nodes would otherwise spend more time
/// clearing bins than filling them).
#[derive(Clone, Debug)]
pub(super) struct Bins {
    boxes: [[BoxA; BINS]; 3],
    counts: [[u32; BINS]; 3],
}

impl Bins {
    pub fn new() -> Bins {
        Bins { boxes: [[BoxA::EMPTY; BINS]; 3], counts: [[0; BINS]; 3] }
    }

    fn reset(&mut self, bin_count: usize) {
        for axis in 0..3 {
            self.boxes[axis][..bin_count].fill(BoxA::EMPTY);
            self.counts[axis][..bin_count].fill(0);
        }
    }

    fn add(&mut self, binning: &Binning, prims: &[BoxA]) {
        for p in prims {
            let bins = binning.bins(p.centroid2());
            for (axis, &bin) in bins.iter().enumerate() {
                self.boxes[axis][bin] = self.boxes[axis][bin].union(p);
                self.counts[axis][bin] += 1;
            }
        }
    }

    fn merge(&mut self, o: &Bins, bin_count: usize) {
        for axis in 0..3 {
            for bin in 0..bin_count {
                self.boxes[axis][bin] = self.boxes[axis][bin].union(&o.boxes[axis][bin]);
                self.counts[axis][bin] += o.counts[axis][bin];
            }
        }
    }
}

/// Bins `0..=last_left_bin` of `axis` go left. `cost` = area(L) * |L| + area(R) * |R|.
#[derive(Clone, Copy, Debug)]
pub(super) struct Split {
    pub axis: usize,
    pub binning: Binning,
    pub last_left_bin: usize,
    pub cost: f32,
    /// Bounds of the two sides, read off the bins.
    pub bounds: [BoxA; 2],
}

/// Cheapest bin boundary over all three axes that leaves both sides non-empty; None when every
/// centroid falls into one bin or every candidate cost is non-finite. `bins` is scratch space.
pub(super) fn best_split(prims: &[BoxA], centroids: &BoxA, bins: &mut Bins) -> Option<Split> {
    // Small nodes get one bin per primitive rather than sweeping mostly empty bins.
    let bin_count = prims.len().min(BINS);
    let binning = Binning::new(centroids, bin_count);
    bins.reset(bin_count);
    if prims.len() > blocks::BLOCK {
        *bins = blocks::map_merge(
            prims,
            |block| {
                let mut b = Bins::new();
                b.add(&binning, block);
                b
            },
            |acc, b| acc.merge(b, bin_count),
        );
    } else {
        bins.add(&binning, prims);
    }

    // Sweep with costs only; the winner's two boxes are unioned again afterwards.
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        let (boxes, counts) = (&bins.boxes[axis], &bins.counts[axis]);
        // right_cost[i]: area * count of bins i+1.. (the right side of a split after bin i).
        let mut right_cost = [0.0; BINS - 1];
        let (mut right_box, mut right_count) = (BoxA::EMPTY, 0);
        for i in (1..bin_count).rev() {
            right_box = right_box.union(&boxes[i]);
            right_count += counts[i];
            right_cost[i - 1] = right_box.surface_area() * right_count as f32;
        }
        let (mut left_box, mut left_count) = (BoxA::EMPTY, 0);
        for i in 0..bin_count - 1 {
            left_box = left_box.union(&boxes[i]);
            left_count += counts[i];
            if left_count == 0 || left_count as usize == prims.len() {
                continue;
            }
            let cost = left_box.surface_area() * left_count as f32 + right_cost[i];
            if cost < best.map_or(f32::INFINITY, |b| b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    let (cost, axis, last_left_bin) = best?;
    let side = |range: &[BoxA]| range.iter().fold(BoxA::EMPTY, |acc, b| acc.union(b));
    let boxes = &bins.boxes[axis][..bin_count];
    Some(Split {
        axis,
        binning,
        last_left_bin,
        cost,
        bounds: [side(&boxes[..=last_left_bin]), side(&boxes[last_left_bin + 1..])],
    })
}
