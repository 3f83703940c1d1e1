//! The path tracing kernel's sources (embedded) and its compiled SPIR-V, built once per process
//! for each way of splitting the large arrays (see chunks.rs).

use super::chunks::{self, ChunkPlan, CHUNKED_ARRAYS};
use crate::gpu::{assemble_source, compile_compute, ShaderSources};
use anyhow::Result;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

pub const SHADERS: ShaderSources<'static> = &[
    ("pathtrace.comp", include_str!("../../shaders/pathtrace.comp")),
    ("layout.glsl", include_str!("../../shaders/layout.glsl")),
    ("loop_limit.glsl", include_str!("../../shaders/loop_limit.glsl")),
    ("rng.glsl", include_str!("../../shaders/rng.glsl")),
    ("sobol.glsl", include_str!("../../shaders/sobol.glsl")),
    ("sampling.glsl", include_str!("../../shaders/sampling.glsl")),
    ("intersect.glsl", include_str!("../../shaders/intersect.glsl")),
    ("bvh.glsl", include_str!("../../shaders/bvh.glsl")),
    ("textures.glsl", include_str!("../../shaders/textures.glsl")),
    ("surface.glsl", include_str!("../../shaders/surface.glsl")),
    ("fresnel.glsl", include_str!("../../shaders/fresnel.glsl")),
    ("microfacet.glsl", include_str!("../../shaders/microfacet.glsl")),
    ("materials.glsl", include_str!("../../shaders/materials.glsl")),
    ("lights.glsl", include_str!("../../shaders/lights.glsl")),
    ("environment.glsl", include_str!("../../shaders/environment.glsl")),
    ("camera.glsl", include_str!("../../shaders/camera.glsl")),
    ("integrator.glsl", include_str!("../../shaders/integrator.glsl")),
];

/// Workgroup edge of the kernel (`local_size_x/y` in pathtrace.comp).
pub const WORKGROUP: u32 = 8;

/// Every large array in one binding: the layout of any scene that fits the device's limits unsplit.
pub const UNSPLIT: [ChunkPlan; CHUNKED_ARRAYS.len()] = [ChunkPlan { shift: 31, chunks: 1 }; CHUNKED_ARRAYS.len()];

/// What a kernel is compiled with besides the split of the arrays: work that only some renders or
/// devices need, so that the others pay nothing for it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct KernelVariant {
    /// Also accumulate the denoiser features (bindings 20 and 21).
    pub aovs: bool,
    /// Count loop iterations per subgroup, for devices that end loops early (loop_limit.glsl).
    pub count_loop_iterations: bool,
}

/// The kernel's GLSL for this split of the arrays and variant.
pub fn kernel_source(plans: &[ChunkPlan; CHUNKED_ARRAYS.len()], variant: KernelVariant) -> Result<String> {
    let generated = chunks::glsl(plans);
    let mut sources = SHADERS.to_vec();
    sources.push(("chunked_buffers.glsl", &generated));
    assemble_source(&sources, "pathtrace.comp", &[
            ("BVH_MAX_DEPTH", format!("{}u", crate::bvh::MAX_DEPTH)),
            ("BVH_MAX_LEAF_SIZE", format!("{}u", crate::bvh::MAX_LEAF_SIZE)),
            ("AOVS", u32::from(variant.aovs).to_string()),
            ("COUNT_LOOP_ITERATIONS", u32::from(variant.count_loop_iterations).to_string()),
        ],)
}

/// SPIR-V of the kernel for this split of the arrays and variant; compiled on first use (glslang
/// takes about a second the first time, 20 ms later) and kept for the process.
pub fn kernel_spirv(plans: &[ChunkPlan; CHUNKED_ARRAYS.len()], variant: KernelVariant) -> Result<&'static [u32]> {
    type Key = ([ChunkPlan; CHUNKED_ARRAYS.len()], KernelVariant);
    static CACHE: OnceLock<Mutex<HashMap<Key, &'static [u32]>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(spirv) = cache.lock().unwrap().get(&(*plans, variant)) {
        return Ok(spirv);
    }
    // Leaked on purpose: one per split layout and variant a process meets, which is one or two.
    let spirv: &'static [u32] = Vec::leak(compile_compute(&kernel_source(plans, variant)?)?);
    cache.lock().unwrap().insert((*plans, variant), spirv);
    Ok(spirv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_compiles_to_spirv() {
        for aovs in [false, true] {
            for count_loop_iterations in [false, true] {
                let spirv = kernel_spirv(&UNSPLIT, KernelVariant { aovs, count_loop_iterations }).expect("pathtrace.comp compiles");
                assert_eq!(spirv[0], 0x0723_0203, "SPIR-V magic number");
            }
        }
    }

    #[test]
    fn kernel_compiles_with_every_array_split() {
        let split = [ChunkPlan { shift: 10, chunks: chunks::MAX_CHUNKS }; CHUNKED_ARRAYS.len()];
        let spirv = kernel_spirv(&split, KernelVariant { aovs: true, count_loop_iterations: true }).expect("pathtrace.comp compiles split");
        assert_eq!(spirv[0], 0x0723_0203, "SPIR-V magic number");
    }
}
