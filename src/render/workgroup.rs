//! The path-tracing kernel's workgroup shape (`local_size_x/y` of pathtrace.comp), a kernel
//! variant. Every device measured runs best at 8x8: lavapipe runs a subgroup of 8 lanes as one
//! SIMD thread and a workgroup of 8x8 as eight of them (its walk queue is laid out for that), and
//! on an NVIDIA H200 no other shape gained more than 3 % (docs/benchmarks/history.md, 2026-12-04, `3e96a5c`). A device
//! found to want another shape would get its own here. The `workgroup=WxH` kernel option
//! (`CAUSTICA_WORKGROUP`, kernel_options.rs) overrides the shape, for an A/B of one binary on one device.

use anyhow::{bail, Result};

/// Most invocations in a workgroup: the least `maxComputeWorkGroupInvocations` Vulkan allows.
const MAX_INVOCATIONS: u32 = 128;

/// Pixels one workgroup covers: `width` x `height` invocations, one pixel each.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Workgroup {
    pub width: u32,
    pub height: u32,
}

impl Default for Workgroup {
    fn default() -> Self {
        Workgroup::EIGHT_BY_EIGHT
    }
}

impl Workgroup {
    /// The shape every device ran before shapes were chosen per device, and lavapipe's.
    pub const EIGHT_BY_EIGHT: Workgroup = Workgroup { width: 8, height: 8 };

    /// `WxH`, each a power of two, at most [`MAX_INVOCATIONS`] in all.
    pub fn parse(text: &str) -> Result<Workgroup> {
        let Some((w, h)) = text.split_once('x') else {
            bail!("expected WIDTHxHEIGHT, e.g. 16x8");
        };
        let (width, height): (u32, u32) = (w.trim().parse()?, h.trim().parse()?);
        if !width.is_power_of_two() || !height.is_power_of_two() {
            bail!("the width and height must be powers of two");
        }
        if width * height > MAX_INVOCATIONS {
            bail!("{} invocations; at most {MAX_INVOCATIONS}", width * height);
        }
        Ok(Workgroup { width, height })
    }

    pub fn invocations(self) -> u32 {
        self.width * self.height
    }

    /// The kernel's defines for `local_size_x/y`.
    pub fn defines(self) -> [(&'static str, String); 2] {
        [("WORKGROUP_WIDTH", self.width.to_string()), ("WORKGROUP_HEIGHT", self.height.to_string())]
    }

    pub fn label(self) -> String {
        format!("{}x{}", self.width, self.height)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_shapes_and_refuses_others() {
        assert_eq!(Workgroup::parse("16x8").unwrap(), Workgroup { width: 16, height: 8 });
        assert_eq!(Workgroup::parse("32x1").unwrap(), Workgroup { width: 32, height: 1 });
        for bad in ["16", "12x8", "16x16", "0x8", "x8", "8xeight"] {
            assert!(Workgroup::parse(bad).is_err(), "{bad} accepted");
        }
    }
}
