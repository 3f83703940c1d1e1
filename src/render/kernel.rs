//! The path tracing kernel's sources (embedded, or read from `$CAUSTICA_SHADER_DIR`) and its
//! compiled SPIR-V, built once per process for each way of splitting the large arrays (see
//! chunks.rs) and each variant.

use super::chunks::{self, ChunkPlan, CHUNKED_ARRAYS};
use crate::gpu::{assemble_source, compile_compute, ShaderSources};
use crate::input_file::{InputFiles, InputKind};
use anyhow::{anyhow, Context as _, Result};
use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;
use std::sync::{Mutex, OnceLock};

/// Names a folder whose shader files replace the embedded ones at run time: shader work and
/// mutation testing (scripts/mutate.py) without rebuilding the crate.
pub const SHADER_DIR_VAR: &str = "CAUSTICA_SHADER_DIR";

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

/// The text of the kernel's shader file `name`: from `$CAUSTICA_SHADER_DIR` when it is set, else as
/// embedded in the binary.
pub fn shader_file(name: &str) -> Result<Cow<'static, str>> {
    let embedded = SHADERS.iter().find(|(n, _)| *n == name).map(|(_, text)| *text).ok_or_else(|| anyhow!("no shader file named {name}"))?;
    match std::env::var_os(SHADER_DIR_VAR) {
        Some(dir) => {
            let path = Path::new(&dir).join(name);
            let text = InputFiles::anywhere().read_to_string(&path, InputKind::Shader).with_context(|| format!("{SHADER_DIR_VAR} is set"))?;
            Ok(Cow::Owned(text))
        }
        None => Ok(Cow::Borrowed(embedded)),
    }
}

/// The shader `main` assembled from `extra` files and every shader file of the kernel, as
/// [`shader_file`] reads them, with `defines`.
fn assemble_with(extra: &[(&str, &str)], main: &str, defines: &[(&str, String)]) -> Result<String> {
    let files = SHADERS.iter().map(|&(name, _)| Ok((name, shader_file(name)?))).collect::<Result<Vec<_>>>()?;
    let sources: Vec<(&str, &str)> = extra.iter().copied().chain(files.iter().map(|(name, text)| (*name, text.as_ref()))).collect();
    assemble_source(&sources, main, defines)
}

/// A compute shader of `main` (GLSL whose `#include`s name the kernel's shader files) with those
/// files as [`shader_file`] reads them: test kernels run the kernel's own code, mutations included.
pub fn assemble_with_kernel_files(main: &str) -> Result<String> {
    assemble_with(&[("main.comp", main)], "main.comp", &[])
}

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
    assemble_with(&[("chunked_buffers.glsl", &generated)], "pathtrace.comp", &[
            ("BVH_MAX_DEPTH", format!("{}u", crate::bvh::MAX_DEPTH)),
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
