//! How the kernel reads the records its BVH walk visits (the nodes and the mesh triangles): as
//! texels of uniform texel buffers, which lavapipe fetches for a whole subgroup as straight-line
//! code (docs/benchmarks.md, stops 21 and 22), or as arrays of storage buffers, which a GPU loads
//! through its L1 cache, not its texture path. The records and the sums are the same either way,
//! bit for bit; only the bindings differ (bindings.rs, [`super::bindings::bindings_of`]).
//! `CAUSTICA_WALK_READS=texels|storage` overrides the device's choice, for an A/B of one binary.

use crate::gpu::DeviceInfo;
use anyhow::{bail, Result};

/// Names the environment variable that overrides the choice (`texels` or `storage`).
pub const WALK_READS_VAR: &str = "CAUSTICA_WALK_READS";

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WalkReads {
    /// Uniform texel buffers.
    #[default]
    Texels,
    /// Storage buffers.
    Storage,
}

impl WalkReads {
    /// The reads for `device`: [`WALK_READS_VAR`]'s where it is set, else the device's own.
    pub fn for_device(_device: &DeviceInfo) -> Result<WalkReads> {
        match std::env::var(WALK_READS_VAR) {
            Ok(text) => WalkReads::parse(&text).map_err(|e| anyhow::anyhow!("{WALK_READS_VAR}={text}: {e}")),
            Err(_) => Ok(WalkReads::Texels),
        }
    }

    pub fn parse(text: &str) -> Result<WalkReads> {
        match text.trim() {
            "texels" => Ok(WalkReads::Texels),
            "storage" => Ok(WalkReads::Storage),
            _ => bail!("expected texels or storage"),
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            WalkReads::Texels => "texels",
            WalkReads::Storage => "storage",
        }
    }
}
