//! Whether a device ends shader loops early. llvmpipe (lavapipe) before Mesa 24 stops every loop of
//! an invocation once 65,535 iterations have run in total (gallivm's `LP_MAX_TGSI_LOOP_ITERATIONS`),
//! silently, so a kernel that loops longer loses work without an error. Rather than guess from
//! driver versions, a one-invocation kernel counts to more than that, storing its count as it goes:
//! where it stops is the limit.

use super::buffer::{Buffer, BufferKind};
use super::compute::{Binding, ComputeKernel};
use super::context::GpuContext;
use super::shader::compile_compute;
use anyhow::{Context as _, Result};

/// Iterations the probe asks for: above every limit known, and quick on any device.
const PROBE_ITERATIONS: u32 = 1 << 20;

const PROBE_SOURCE: &str = "#version 460
layout(local_size_x = 1) in;
layout(push_constant) uniform Probe { uint iterations; } probe;
layout(std430, set = 0, binding = 0) buffer Completed { uint iterations; } completed;
void main() {
    // A store per iteration: no compiler can replace the loop by its result.
    for (uint i = 0u; i < probe.iterations; ++i) completed.iterations = i + 1u;
}
";

impl GpuContext {
    /// The most loop iterations a shader invocation runs on this device before its loops are
    /// ended early without an error (llvmpipe before Mesa 24: 65,535), or `None` where loops run
    /// to their end. Probed once, by the tiny kernel below.
    pub fn loop_limit(&self) -> Result<Option<u32>> {
        if let Some(&limit) = self.loop_limit.get() {
            return Ok(limit);
        }
        let limit = probe_loop_limit(self).with_context(|| format!("probing {} for a loop limit", self.info.name))?;
        Ok(*self.loop_limit.get_or_init(|| limit))
    }
}

/// The most loop iterations one invocation of this device runs before its loops are ended, or
/// `None` when it ran the probe's 2^20 to the end.
fn probe_loop_limit(ctx: &GpuContext) -> Result<Option<u32>> {
    let counter = Buffer::with_data(ctx, "loop limit probe", BufferKind::HostStorage, &0u32.to_le_bytes())?;
    let result = (|| {
        let kernel = ComputeKernel::new(ctx, &compile_compute(PROBE_SOURCE)?, &[Binding::whole(0, &counter)], 4)?;
        let dispatched = kernel.dispatch(ctx, &PROBE_ITERATIONS.to_le_bytes(), [1, 1, 1]);
        kernel.destroy(ctx);
        dispatched?;
        let completed = u32::from_le_bytes(counter.read()?[..4].try_into().expect("four bytes"));
        Ok((completed < PROBE_ITERATIONS).then_some(completed))
    })();
    counter.destroy(ctx);
    result
}
