//! How the kernel reads the BVH walk's records (the nodes and the mesh triangles): as texels of
//! uniform texel buffers, or from storage buffers. Both are declared by bindings.rs's table and
//! read by the same generated `load_nodes(i)` and `load_mesh_triangles(i)`; the images are the
//! same bit for bit (tests/walk_records.rs). Only the speed differs, and it differs by CPU:
//!
//! - Mesa 25's lavapipe makes every texel fetch an indirect call into a function of the
//!   descriptor's, which fetches the lanes' texels one by one and transposes them; the caller
//!   spills its live vector registers around each call (docs/benchmarks/history.md, 2026-12-06, `273e196`). A storage
//!   load at a per-lane index is a loop over the lanes instead, each behind its own branch and
//!   bounds check, inlined in the kernel.
//! - With Mesa 25.0 on an AMD EPYC (Zen 4) the storage loads measured 1.09x on the mesh box and
//!   1.43x on the bunny under a sky; on an Intel Xeon (Sapphire Rapids) the nodes as storage
//!   measured 0.91x on the mesh box (docs/benchmarks/history.md, 2026-12-06, `273e196`, `b968832`). With Mesa 26.2
//!   (LLVM 22) on the same AMD EPYC the storage loads lost on the mesh box (0.90x, sky 1.03x). On Mesa
//!   22.3 the texels measured 1.2-2x faster (2026-12-02, `093d897`), and on an NVIDIA GPU the two are level
//!   (2026-12-04, `3e96a5c`).
//!
//! So the storage buffers are the default on Mesa 25's lavapipe running on an AMD CPU, and texels
//! everywhere else (kernel_options.rs's table). The `walk-records` kernel option
//! (`CAUSTICA_WALK_RECORDS`: `texels` or `storage`) overrides the choice on any device, for an A/B
//! of one binary.

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WalkRecords {
    /// Uniform texel buffers (the table's own shape for them).
    #[default]
    Texels,
    /// Storage buffers, split into windows like any chunked array.
    Storage,
}

impl WalkRecords {
    pub fn label(self) -> &'static str {
        match self {
            WalkRecords::Texels => "texels",
            WalkRecords::Storage => "storage",
        }
    }
}
