//! One render run under farm rules: stop at a sample count, a time budget or a stop request, write
//! checkpoints on the way, resume from one, and save what was rendered when the device fails.

use super::partial::PartialRender;
use crate::gpu::DeviceFailure;
use crate::render::{Renderer, MAX_SAMPLES_PER_PIXEL};
use anyhow::{bail, Context as _, Result};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// When to stop and where to keep checkpoints.
pub struct RenderJob<'a> {
    /// Samples per pixel the image should hold in all (resumed samples included); `None`: no limit.
    pub spp: Option<u32>,
    /// Stop after the pass that uses this up.
    pub time: Option<Duration>,
    /// Where checkpoints go, and where a failed device's samples are saved.
    pub checkpoint: PathBuf,
    /// Write a checkpoint whenever this much time has passed since the last one.
    pub checkpoint_every: Option<Duration>,
    /// Set from a signal handler: stop after the pass in flight.
    pub stop: &'a AtomicBool,
}

/// Why a run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The sample count was reached.
    Done,
    /// The time budget was spent.
    TimeUp,
    /// A stop was requested (SIGINT or SIGTERM).
    Interrupted,
}

/// The renderer's accumulation with its scene, seed and sample range; `None` before any sample.
pub fn snapshot(renderer: &Renderer) -> Result<Option<PartialRender>> {
    if renderer.samples_done == 0 {
        return Ok(None);
    }
    // Empty after a camera change until recomputed: a file must never carry a hash of another view.
    anyhow::ensure!(
        !renderer.scene_hash.is_empty(),
        "the scene hash is unknown after a camera change (Renderer::refresh_scene_hash)"
    );
    let (width, height) = renderer.size();
    let start = renderer.sample_offset();
    Ok(Some(PartialRender {
        scene_hash: renderer.scene_hash.clone(),
        seed: renderer.seed(),
        width,
        height,
        ranges: vec![start..start + renderer.samples_done],
        accumulation: renderer.accumulation()?,
        aovs: renderer.aovs(),
        aov_sums: renderer.aov_sums()?,
    }))
}

/// The one sample range a checkpoint holds, which resuming continues; refuses a merge of separate
/// ranges. `path` is the checkpoint's file, for messages.
pub fn resumable_range(checkpoint: &PartialRender, path: &Path) -> Result<Range<u32>> {
    let [range] = &checkpoint.ranges[..] else {
        bail!(
            "{}: cannot resume: it holds separate sample ranges (a merge); render more as another partial",
            path.display()
        );
    };
    Ok(range.clone())
}

/// Loads `checkpoint` (read from `path`) into a fresh renderer, which then continues its sample
/// stream. Refuses a checkpoint of another scene, seed, size or AOV set, or a merge of separate
/// ranges.
pub fn resume(renderer: &mut Renderer, checkpoint: &PartialRender, path: &Path) -> Result<()> {
    let (width, height) = renderer.size();
    let this = PartialRender {
        scene_hash: renderer.scene_hash.clone(),
        seed: renderer.seed(),
        width,
        height,
        ranges: vec![],
        accumulation: vec![],
        aovs: renderer.aovs(),
        aov_sums: None,
    };
    this.check_same_render(checkpoint).with_context(|| format!("{}: cannot resume", path.display()))?;
    let range = resumable_range(checkpoint, path)?;
    renderer.set_sample_offset(range.start);
    renderer.restore(&checkpoint.accumulation, range.end - range.start)?;
    if let Some(sums) = &checkpoint.aov_sums {
        renderer.restore_aovs(sums)?;
    }
    Ok(())
}

/// One past the last sample index: the kernel numbers samples with 32-bit integers.
pub const SAMPLE_INDEX_END: u64 = u32::MAX as u64;

/// Fails unless a render whose stream starts at sample `first` can hold `spp` samples per pixel:
/// indices past [`SAMPLE_INDEX_END`] do not exist, and rendering would stop short of `spp` there.
pub fn check_sample_range(first: u32, spp: u32) -> Result<()> {
    let end = first as u64 + spp as u64;
    if end > SAMPLE_INDEX_END {
        bail!(
            "samples {first}..{end} run past the last sample index ({}): from sample {first}, at most {} samples per pixel can be rendered",
            SAMPLE_INDEX_END - 1,
            SAMPLE_INDEX_END - first as u64
        );
    }
    if spp > MAX_SAMPLES_PER_PIXEL {
        bail!("{spp} samples per pixel asked; a render holds at most {MAX_SAMPLES_PER_PIXEL} (pixel counts are 32-bit floats, exact that far): render partials and merge them");
    }
    Ok(())
}

/// Renders until `job` says stop, calling `progress(samples_done)` after every pass. On a lost
/// device or exhausted memory, saves what it can to the checkpoint path and fails saying so.
pub fn run(renderer: &mut Renderer, job: &RenderJob, mut progress: impl FnMut(u32)) -> Result<Outcome> {
    let started = Instant::now();
    let mut last_checkpoint = started;
    let mut checkpointed = false;
    let target = job.spp.unwrap_or(u32::MAX);
    loop {
        let mut outcome = Outcome::Done;
        let mut checkpoint_due = false;
        let remaining = target.saturating_sub(renderer.samples_done);
        let rendered = renderer.render_while(remaining, |done| {
            progress(done);
            if job.stop.load(Ordering::SeqCst) {
                outcome = Outcome::Interrupted;
            } else if job.time.is_some_and(|t| started.elapsed() >= t) {
                outcome = Outcome::TimeUp;
            }
            checkpoint_due = job.checkpoint_every.is_some_and(|every| last_checkpoint.elapsed() >= every);
            outcome == Outcome::Done && !checkpoint_due
        });
        if let Err(e) = rendered {
            return Err(salvage(renderer, job, checkpointed, e));
        }
        if checkpoint_due && outcome == Outcome::Done {
            if let Some(partial) = snapshot(renderer)? {
                partial.write(&job.checkpoint)?;
                checkpointed = true;
            }
            last_checkpoint = Instant::now();
        }
        // render_while also ends where the render can hold no more samples.
        let finished = renderer.samples_done >= target || renderer.samples_left() == 0;
        if outcome != Outcome::Done || finished {
            return Ok(outcome);
        }
    }
}

/// After `error`: for a device failure, writes the accumulation if it can still be read and every
/// pixel holds the same samples (a pass cut short leaves some rows ahead), and says where the samples
/// are; other errors pass through.
fn salvage(renderer: &Renderer, job: &RenderJob, checkpointed: bool, error: anyhow::Error) -> anyhow::Error {
    if DeviceFailure::of(&error).is_none() {
        return error;
    }
    let done = renderer.samples_done;
    let consistent = snapshot(renderer).ok().flatten().filter(|p| p.check_consistent().is_ok());
    let path = job.checkpoint.display();
    let saved = match consistent.map(|p| p.write(&job.checkpoint)) {
        Some(Ok(())) => format!("wrote the {done} samples per pixel rendered so far to {path}"),
        _ if checkpointed => format!("the device could not be read back; the last checkpoint is {path}"),
        _ => "the device could not be read back and there is no checkpoint (use --checkpoint-every)".to_owned(),
    };
    error.context(format!("rendering stopped after {done} samples per pixel; {saved}"))
}
