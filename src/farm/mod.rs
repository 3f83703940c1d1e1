//! Rendering on farms and under deadlines: time budgets, checkpoints and resuming, partial renders
//! of separate sample ranges, and merging them into one image (see docs/farm.md).

// Sample ranges are lists of ranges, and one range is the common case: `vec![0..64]` is meant.
#![allow(clippy::single_range_in_vec_init)]

mod denoised;
mod duration;
mod merge;
mod outputs;
mod partial;
mod rate;
mod session;
mod watch;

pub use denoised::{denoise, write_denoised, Denoised};
pub use duration::parse_duration;
pub use merge::{merge, merge_files};
pub use outputs::{check_render_files, is_exr, remove_leftovers, same_file};
pub use partial::{
    format_ranges, parse_ranges, PartialRender, DENOISED, HEIGHT, NOISY_LAYER, SAMPLES, SAMPLE_RANGES, SCENE_HASH,
    SEED, WIDTH,
};
pub use rate::per_second;
pub use session::{check_sample_range, resumable_range, resume, run, snapshot, Outcome, RenderJob, SAMPLE_INDEX_END};
pub use watch::{pick as pick_watched, Picked, Skipped};
