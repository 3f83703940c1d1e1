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
//! everywhere else. `CAUSTICA_WALK_RECORDS` (`texels` or `storage`) overrides the choice on any
//! device, for an A/B of one binary.

use crate::gpu::DeviceInfo;
use anyhow::{bail, Result};

/// Names the environment variable that picks the form on any device.
pub const WALK_RECORDS_VAR: &str = "CAUSTICA_WALK_RECORDS";

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WalkRecords {
    /// Uniform texel buffers (the table's own shape for them).
    #[default]
    Texels,
    /// Storage buffers, split into windows like any chunked array.
    Storage,
}

impl WalkRecords {
    /// The form for `device`; an error where [`WALK_RECORDS_VAR`] holds anything but `texels` or
    /// `storage`.
    pub fn for_device(device: &DeviceInfo) -> Result<WalkRecords> {
        let lavapipe = device.is_lavapipe();
        let storage_faster = lavapipe && mesa_major(&device.driver_info) == Some(25) && cpu_is_amd();
        decide(std::env::var(WALK_RECORDS_VAR).ok().as_deref(), storage_faster)
    }

    pub fn label(self) -> &'static str {
        match self {
            WalkRecords::Texels => "texels",
            WalkRecords::Storage => "storage",
        }
    }
}

/// [`WalkRecords::for_device`] for the variable's value `request`, on a device where storage
/// buffers are the faster form (`storage_faster`).
fn decide(request: Option<&str>, storage_faster: bool) -> Result<WalkRecords> {
    match request {
        None if storage_faster => Ok(WalkRecords::Storage),
        None => Ok(WalkRecords::Texels),
        Some("texels") => Ok(WalkRecords::Texels),
        Some("storage") => Ok(WalkRecords::Storage),
        Some(other) => {
            bail!("{WALK_RECORDS_VAR}={other}: expected texels (uniform texel buffers) or storage (storage buffers)")
        }
    }
}

/// Mesa's major version in a driver's info string ("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)").
fn mesa_major(driver_info: &str) -> Option<u32> {
    let version = driver_info.split("Mesa ").nth(1)?;
    version.split('.').next()?.parse().ok()
}

/// Whether this process runs on an AMD CPU (CPUID's vendor string), where lavapipe runs its
/// kernels.
fn cpu_is_amd() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        // CPUID leaf 0 holds the vendor string in EBX, EDX, ECX.
        #[allow(unused_unsafe)]
        // SAFETY: every x86_64 processor has CPUID and its leaf 0; the instruction only reads registers.
        let leaf = unsafe { std::arch::x86_64::__cpuid(0) };
        let vendor: Vec<u8> = [leaf.ebx, leaf.edx, leaf.ecx].iter().flat_map(|r| r.to_le_bytes()).collect();
        vendor == b"AuthenticAMD"
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn storage_where_faster_and_the_variable_overrides_the_device() {
        assert_eq!(decide(None, true).unwrap(), WalkRecords::Storage);
        assert_eq!(decide(None, false).unwrap(), WalkRecords::Texels);
        assert_eq!(decide(Some("texels"), true).unwrap(), WalkRecords::Texels);
        assert_eq!(decide(Some("storage"), false).unwrap(), WalkRecords::Storage);
        let bad = decide(Some("ssbo"), false).unwrap_err().to_string();
        assert!(bad.contains("CAUSTICA_WALK_RECORDS=ssbo") && bad.contains("expected texels"), "{bad}");
    }

    #[test]
    fn mesa_s_major_version_is_read_from_the_driver_info() {
        assert_eq!(mesa_major("Mesa 25.0.7-2~bpo12+1 (LLVM 15.0.6)"), Some(25));
        assert_eq!(mesa_major("Mesa 26.2.6-1 (LLVM 22.1.8)"), Some(26));
        assert_eq!(mesa_major("Mesa 22.3.6 (LLVM 15.0.6)"), Some(22));
        assert_eq!(mesa_major("580.159.04"), None);
        assert_eq!(mesa_major(""), None);
    }

    #[test]
    fn the_cpu_vendor_matches_proc_cpuinfo() {
        // Linux names the vendor in /proc/cpuinfo; elsewhere there is nothing to check against.
        let Ok(info) = std::fs::read_to_string("/proc/cpuinfo") else { return };
        let Some(line) = info.lines().find(|l| l.starts_with("vendor_id")) else { return };
        assert_eq!(cpu_is_amd(), line.contains("AuthenticAMD"), "{line}");
    }
}
