//! In what order a dispatch's workgroups take the rows of the band it renders.
//!
//! lavapipe splits a dispatch among its threads up front: each takes one contiguous run of
//! workgroup indices (Mesa's `lp_cs_tpool`, `iter_per_thread`). Taken in order, a run is a
//! horizontal slab of the image, and slabs differ in cost (a sky above, a mesh below), so one
//! thread idles while the other finishes: on the 2-core machine of docs/benchmarks/history.md a bunny
//! under a sky kept 1.5 of 2 cores busy. Dealing the rows of workgroups into stripes gives every
//! run rows from the whole band. GPUs hand out workgroups as their units free up, so they keep
//! the image's order and the locality it has. Where loops run to their end (Mesa 24 and newer),
//! lavapipe's subgroups also take their tiles from a counter (tile_taking.rs), which evens the
//! threads out dispatch by dispatch; the stripes then only order the tiles, and they remain what
//! balances Debian 12's Mesa 22.3.

use crate::gpu::DeviceType;
use clap::ValueEnum;

/// See the module documentation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum GroupOrder {
    /// Rows of workgroups top to bottom.
    InOrder,
    /// Rows dealt into about sqrt(rows) stripes: a contiguous run of workgroups spans the band.
    Interleaved,
}

impl GroupOrder {
    /// The order that keeps `kind`'s threads busy: interleaved on CPU implementations.
    pub fn for_device(kind: DeviceType) -> Self {
        if kind == DeviceType::Cpu {
            Self::Interleaved
        } else {
            Self::InOrder
        }
    }

    /// `pass.group_row_stripes` for a band of `group_rows` rows of workgroups (at least 1).
    pub fn stripes(self, group_rows: u32) -> u32 {
        match self {
            Self::InOrder => 1,
            // About as many stripes as rows per stripe: any number of threads up to sqrt(rows)
            // gets whole stripes, each spanning the band.
            Self::Interleaved => (group_rows as f64).sqrt().floor().max(1.0) as u32,
        }
    }

    /// The name `caustica bench --group-order` takes and reports.
    pub fn label(self) -> &'static str {
        match self {
            Self::InOrder => "in-order",
            Self::Interleaved => "interleaved",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// pathtrace.comp's `group_row_of`, transcribed: which band row workgroup row `r` renders.
    fn group_row_of(r: u32, n: u32, stripes: u32) -> u32 {
        let per_stripe = n / stripes;
        let longer = n % stripes;
        if r < longer * (per_stripe + 1) {
            return (r % (per_stripe + 1)) * stripes + r / (per_stripe + 1);
        }
        let rest = r - longer * (per_stripe + 1);
        (rest % per_stripe) * stripes + longer + rest / per_stripe
    }

    #[test]
    fn every_order_renders_every_row_once() {
        for order in [GroupOrder::InOrder, GroupOrder::Interleaved] {
            for n in 1..600 {
                let stripes = order.stripes(n);
                let mut rows: Vec<u32> = (0..n).map(|r| group_row_of(r, n, stripes)).collect();
                rows.sort_unstable();
                assert!(rows.iter().copied().eq(0..n), "{order:?}, {n} rows: not a permutation");
            }
        }
    }

    #[test]
    fn in_order_is_the_identity_and_interleaved_spans_the_band() {
        assert!((0..90).all(|r| group_row_of(r, 90, GroupOrder::InOrder.stripes(90)) == r));
        // 15 rows (a 120-pixel band) in 3 stripes: each half of the run reaches both ends.
        let rows: Vec<u32> = (0..15).map(|r| group_row_of(r, 15, GroupOrder::Interleaved.stripes(15))).collect();
        assert_eq!(rows, [0, 3, 6, 9, 12, 1, 4, 7, 10, 13, 2, 5, 8, 11, 14]);
    }

    #[test]
    fn the_kernel_deals_rows_as_transcribed_here() {
        let kernel = include_str!("../../shaders/pathtrace.comp");
        for line in [
            "    if (r < longer * (per_stripe + 1u)) return (r % (per_stripe + 1u)) * stripes + r / (per_stripe + 1u);",
            "    return (rest % per_stripe) * stripes + longer + rest / per_stripe;",
        ] {
            assert!(
                kernel.contains(line),
                "pathtrace.comp's group_row_of changed: update the transcription in group_order.rs"
            );
        }
    }
}
