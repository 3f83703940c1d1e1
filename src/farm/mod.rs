//! Rendering on farms and under deadlines: time budgets, checkpoints and resuming, partial renders
//! of separate sample ranges, and merging them into one image (see docs/farm.md).

// Sample ranges are lists of ranges, and one range is the common case: `vec![0..64]` is meant.
#![allow(clippy::single_range_in_vec_init)]

mod duration;
mod merge;
mod partial;
mod session;

pub use duration::parse_duration;
pub use merge::{merge, merge_files};
pub use partial::{format_ranges, parse_ranges, PartialRender, HEIGHT, SAMPLES, SAMPLE_RANGES, SCENE_HASH, SEED, WIDTH};
pub use session::{resume, run, snapshot, Outcome, RenderJob};
