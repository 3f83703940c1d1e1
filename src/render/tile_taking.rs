//! Whether the kernel's subgroups take their pixels from a counter (pathtrace.comp, `TAKE_TILES`).
//!
//! lavapipe splits a dispatch among its threads up front, one contiguous run of workgroups each
//! (group_order.rs). Dealing rows into stripes evens the runs' costs out on average, but not
//! dispatch by dispatch: on the mesh box at 256x256 (bunny + Lucy) the two threads of a 2-core
//! machine still kept only 1.82 cores busy. With `TAKE_TILES` each subgroup takes the next tile
//! (a subgroup's share of a workgroup: eight pixels of a row on lavapipe) from a counter in
//! the statistics buffer as soon as it has finished one, until none is left, so the thread that
//! finishes its tiles first takes more of them: 1.99 cores busy and 1.10x the samples per
//! second (docs/benchmarks/history.md, 2026-12-05, `36b0b8f`). Every tile is one workgroup's subgroup's pixels as
//! before, whichever subgroup renders it, so the images are the same bit for bit
//! (tests/tile_taking.rs).
//!
//! By default it is compiled where all of these hold:
//! - **a CPU device**: a GPU hands out its workgroups as its units free up already;
//! - **loops run to their end**: on a device with a loop limit (Mesa 22.3) a subgroup that takes
//!   tile after tile would reach it at once;
//! - **the megakernel**: the wavefront's kernels each take one step of every pixel's path;
//! - **whole subgroups**: the workgroup's invocations are a multiple of the subgroup size, so the
//!   tiles cover the workgroup.
//!
//! The `take-tiles` kernel option (`CAUSTICA_TAKE_TILES`, kernel_options.rs) changes the first condition, for an A/B of one binary: `0` compiles no
//! counter, `1` compiles it on any device that meets the others.

use super::workgroup::Workgroup;
use crate::gpu::DeviceInfo;
use anyhow::{bail, Result};

/// Whether the kernel for `device` (whose loops are cut short where `loop_limit`), the wavefront's
/// kernels where `wavefront`, in workgroups of `workgroup`, takes its tiles from the counter: as
/// the `take-tiles` option `asked` says, else as the device class's `default`. An error where the
/// option asks for what cannot run.
pub fn takes_tiles(
    asked: Option<bool>,
    default: bool,
    device: &DeviceInfo,
    loop_limit: bool,
    wavefront: bool,
    workgroup: Workgroup,
) -> Result<bool> {
    let whole_subgroups = device.subgroup_size > 0 && workgroup.invocations().is_multiple_of(device.subgroup_size);
    let possible = !loop_limit && !wavefront && whole_subgroups;
    decide(asked, default, possible).map_err(|why| {
        anyhow::anyhow!(
            "{why} ({}: loop limit {loop_limit}, wavefront {wavefront}, {} invocations a workgroup, subgroups of {})",
            device.name,
            workgroup.invocations(),
            device.subgroup_size
        )
    })
}

/// [`takes_tiles`] where taking tiles is `possible`.
fn decide(asked: Option<bool>, default: bool, possible: bool) -> Result<bool> {
    match (asked.unwrap_or(default), possible) {
        (true, true) => Ok(true),
        (true, false) if asked.is_some() => bail!("take-tiles=1: tiles are taken only by the megakernel, on a device whose loops run to their end, in workgroups of whole subgroups"),
        _ => Ok(false),
    }
}

/// The kernel's `#define` for it.
pub fn defines(take_tiles: bool) -> Vec<(&'static str, String)> {
    vec![("TAKE_TILES", u32::from(take_tiles).to_string())]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_are_taken_where_wanted_and_possible_and_asking_for_the_impossible_fails() {
        assert!(decide(None, true, true).unwrap());
        assert!(!decide(None, true, false).unwrap(), "a default took tiles where it cannot");
        assert!(!decide(Some(false), true, true).unwrap());
        let impossible = decide(Some(true), false, false).unwrap_err().to_string();
        assert!(impossible.contains("loops run to their end"), "{impossible}");
    }
}
