//! caustica: a physically based path tracer with a Rust host and a GLSL compute kernel on Vulkan.
//!
//! Rooms: `scene` (TOML scenes, meshes, environment maps), `bvh` (build, flatten, CPU traversal),
//! `image` (PFM/EXR/PNG), `input_file` (how every input file is read: regular files only, size
//! caps, `--confine`), `denoise` (Intel Open Image Denoise, loaded at run time), `gpu` (all Vulkan), `render` (the kernel and progressive passes), `farm`
//! (time budgets, checkpoints, partial renders and merging them), `bench` (throughput of one scene
//! or of the suite of checked-in scenes), `view` (the interactive viewer's window, input and frames).

pub mod bench;
pub mod bvh;
pub mod denoise;
pub mod farm;
pub mod gpu;
pub mod image;
pub mod input_file;
pub mod process_time;
pub mod render;
pub mod scene;
#[cfg(test)]
mod test_files;
pub mod view;
