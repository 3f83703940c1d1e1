//! The wavefront split of the path loop (shaders/wavefront.glsl), an alternative to the megakernel
//! chosen by the `wavefront=1` kernel option (`CAUSTICA_WAVEFRONT=1`, kernel_options.rs) for an A/B of one
//! binary. A pass over a band runs in rounds of
//! three kernels, each over every pixel of the band: EXTEND (each path's ray to its hit), SHADOW
//! (each shadow ray the last vertex handed back) and SHADE (the vertex, and the next sample where
//! one ends), the paths' state kept between them in a buffer (`path_states`,
//! [`STATE_VEC4S`] uvec4s a pixel). The host records [`ROUNDS_PER_SUBMISSION`] rounds at a time
//! and reads how many paths are still in flight after the last; the band is done when none is.
//! The images are the megakernel's bit for bit (tests/wavefront.rs).
//!
//! Where it is compiled: devices whose loops run to their end (a round's kernels are short, but
//! the plain kernel's loop limit handling has no wavefront form). It is the default nowhere: on
//! lavapipe it lost to the megakernel on 2026-12-01 (`7a44715`) (docs/benchmarks/history.md: each kernel reloads and
//! stores every path's state through the lanes); on GPUs it is for the next GPU run to measure.

use super::layout::GpuStats;
use crate::gpu::{ComputeKernel, GpuContext};
use anyhow::{bail, Result};

/// uvec4s of a pixel's state in `path_states` (wavefront.glsl's layout, which fails to compile
/// with another count).
pub const STATE_VEC4S: u64 = 16;

/// Rounds recorded in one submission before the host reads how many paths are in flight. A
/// round past the band's end costs three dispatches over paths that are done; fewer rounds a
/// submission cost a fence wait each.
pub const ROUNDS_PER_SUBMISSION: u32 = 8;

/// One of a round's kernels: its `WAVEFRONT_STAGE` (wavefront.glsl).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum WavefrontStage {
    Extend = 1,
    Shadow = 2,
    Shade = 3,
}

impl WavefrontStage {
    pub const ALL: [WavefrontStage; 3] = [WavefrontStage::Extend, WavefrontStage::Shadow, WavefrontStage::Shade];

    /// The kernel's `#define`s for this stage, or for the megakernel (`None`).
    pub fn defines(stage: Option<WavefrontStage>) -> Vec<(&'static str, String)> {
        vec![
            ("WAVEFRONT", u32::from(stage.is_some()).to_string()),
            ("WAVEFRONT_STAGE", stage.map_or(0, |s| s as u32).to_string()),
            ("WAVEFRONT_STATE_VEC4S", format!("{STATE_VEC4S}u")),
        ]
    }
}

/// The three kernels of a round, in the order a round runs them.
pub struct WavefrontKernels {
    pub kernels: Vec<ComputeKernel>,
}

impl WavefrontKernels {
    /// Runs rounds over the band until no path is in flight: `push` makes each round's push
    /// constants from its number, `read_stats` reads the counters after a submission. Returns the
    /// device's seconds by its timestamps, where it has them. A band still in flight after
    /// `max_rounds` (more than its paths' vertices and shadow rays can take) is an error.
    pub fn run(
        &self,
        ctx: &GpuContext,
        groups: [u32; 3],
        max_rounds: u64,
        push: impl Fn(u32) -> Vec<u8>,
        read_stats: impl Fn() -> Result<GpuStats>,
    ) -> Result<Option<f64>> {
        let mut device_seconds = Some(0.0);
        let mut round = 0u32;
        loop {
            if round as u64 > max_rounds {
                bail!(
                    "{}: the wavefront's paths were still in flight after {round} rounds, more than they can take",
                    ctx.info.name
                );
            }
            let pushes: Vec<Vec<u8>> = (round..round + ROUNDS_PER_SUBMISSION).map(&push).collect();
            let steps: Vec<(&ComputeKernel, &[u8], [u32; 3])> =
                pushes.iter().flat_map(|p| self.kernels.iter().map(move |k| (k, &p[..], groups))).collect();
            let seconds = ComputeKernel::dispatch_sequence_timed(ctx, &steps)?;
            device_seconds = device_seconds.zip(seconds).map(|(sum, s)| sum + s);
            let last = round + ROUNDS_PER_SUBMISSION - 1;
            let stats = read_stats()?;
            let in_flight = if last.is_multiple_of(2) { stats.paths_in_flight_even } else { stats.paths_in_flight_odd };
            if in_flight == 0 {
                return Ok(device_seconds);
            }
            round += ROUNDS_PER_SUBMISSION;
        }
    }

    pub fn destroy(self, ctx: &GpuContext) {
        for k in self.kernels {
            k.destroy(ctx);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_state_count_is_the_one_the_kernel_lays_out() {
        let glsl = include_str!("../../shaders/wavefront.glsl");
        assert!(
            glsl.contains(&format!("const uint WAVEFRONT_STATE_LAYOUT_VEC4S = {STATE_VEC4S}u;")),
            "wavefront.glsl lays out another count"
        );
        for (stage, number) in [(WavefrontStage::Extend, 1), (WavefrontStage::Shadow, 2), (WavefrontStage::Shade, 3)] {
            assert_eq!(stage as u32, number);
            let define = format!("#define WAVEFRONT_{} {number}", format!("{stage:?}").to_uppercase());
            assert!(glsl.contains(&define), "wavefront.glsl lacks `{define}`");
        }
    }
}
