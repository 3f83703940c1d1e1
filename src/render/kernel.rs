//! The path tracing kernel's sources (embedded) and its compiled SPIR-V, built once per process.

use crate::gpu::{assemble_source, compile_compute, ShaderSources};
use anyhow::Result;
use std::sync::OnceLock;

pub const SHADERS: ShaderSources = &[
    ("pathtrace.comp", include_str!("../../shaders/pathtrace.comp")),
    ("layout.glsl", include_str!("../../shaders/layout.glsl")),
    ("rng.glsl", include_str!("../../shaders/rng.glsl")),
    ("sobol.glsl", include_str!("../../shaders/sobol.glsl")),
    ("sampling.glsl", include_str!("../../shaders/sampling.glsl")),
    ("intersect.glsl", include_str!("../../shaders/intersect.glsl")),
    ("bvh.glsl", include_str!("../../shaders/bvh.glsl")),
    ("textures.glsl", include_str!("../../shaders/textures.glsl")),
    ("surface.glsl", include_str!("../../shaders/surface.glsl")),
    ("materials.glsl", include_str!("../../shaders/materials.glsl")),
    ("lights.glsl", include_str!("../../shaders/lights.glsl")),
    ("environment.glsl", include_str!("../../shaders/environment.glsl")),
    ("camera.glsl", include_str!("../../shaders/camera.glsl")),
    ("integrator.glsl", include_str!("../../shaders/integrator.glsl")),
];

/// Workgroup edge of the kernel (`local_size_x/y` in pathtrace.comp).
pub const WORKGROUP: u32 = 8;

pub fn kernel_source() -> Result<String> {
    assemble_source(SHADERS, "pathtrace.comp", &[
            ("BVH_MAX_DEPTH", format!("{}u", crate::bvh::MAX_DEPTH)),
            ("BVH_MAX_LEAF_SIZE", format!("{}u", crate::bvh::MAX_LEAF_SIZE)),
        ],)
}

/// SPIR-V of the kernel; compiled on first use (glslang takes about a second the first time).
pub fn kernel_spirv() -> Result<&'static [u32]> {
    static SPIRV: OnceLock<Vec<u32>> = OnceLock::new();
    if let Some(s) = SPIRV.get() {
        return Ok(s);
    }
    let spirv = compile_compute(&kernel_source()?)?;
    Ok(SPIRV.get_or_init(|| spirv))
}

#[cfg(test)]
mod tests {
    #[test]
    fn kernel_compiles_to_spirv() {
        let spirv = super::kernel_spirv().expect("pathtrace.comp compiles");
        assert_eq!(spirv[0], 0x0723_0203, "SPIR-V magic number");
    }
}
