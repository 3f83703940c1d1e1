//! GLSL to SPIR-V with the glslang crate. The kernel's sources are embedded in the binary; their
//! `#include "x.glsl"` lines are resolved here, each file once, so no file system is needed at run time.

use anyhow::{anyhow, Result};
use glslang::{
    Compiler, CompilerOptions, ShaderInput, ShaderSource, ShaderStage, SourceLanguage, SpirvVersion, Target,
    VulkanVersion,
};

/// (file name, contents) of every shader file the kernel may include.
pub type ShaderSources<'a> = &'a [(&'a str, &'a str)];

/// Inlines `#include "name"` lines (depth-first, each file once) and inserts `defines` right after
/// the `#version` line.
pub fn assemble_source(sources: ShaderSources<'_>, main: &str, defines: &[(&str, String)]) -> Result<String> {
    fn inline(sources: ShaderSources<'_>, name: &str, seen: &mut Vec<String>, out: &mut String) -> Result<()> {
        if seen.iter().any(|s| s == name) {
            return Ok(());
        }
        seen.push(name.to_string());
        let text = sources
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| *t)
            .ok_or_else(|| anyhow!("shader include '{name}' not found"))?;
        for line in text.lines() {
            let trimmed = line.trim();
            if let Some(rest) = trimmed.strip_prefix("#include") {
                let included = rest.trim().trim_matches('"');
                out.push_str(&format!("// begin {included}\n"));
                inline(sources, included, seen, out)?;
                out.push_str(&format!("// end {included}\n"));
            } else {
                out.push_str(line);
                out.push('\n');
            }
        }
        Ok(())
    }
    let mut body = String::new();
    inline(sources, main, &mut vec![], &mut body)?;
    let (version, rest) = body.split_once('\n').ok_or_else(|| anyhow!("shader '{main}' is empty"))?;
    let mut out = format!("{version}\n");
    for (name, value) in defines {
        out.push_str(&format!("#define {name} {value}\n"));
    }
    out.push_str(rest);
    Ok(out)
}

/// Compiles a complete compute shader for Vulkan 1.2 / SPIR-V 1.5.
pub fn compile_compute(source: &str) -> Result<Vec<u32>> {
    let compiler = Compiler::acquire().ok_or_else(|| anyhow!("glslang failed to initialise"))?;
    let options = CompilerOptions {
        source_language: SourceLanguage::GLSL,
        target: Target::Vulkan { version: VulkanVersion::Vulkan1_2, spirv_version: SpirvVersion::SPIRV1_5 },
        ..Default::default()
    };
    let source = ShaderSource::from(source.to_string());
    let input = ShaderInput::new(&source, ShaderStage::Compute, &options, None::<&[(&str, Option<&str>)]>, None)
        .map_err(|e| anyhow!("shader input: {e}"))?;
    let shader = compiler.create_shader(input).map_err(|e| anyhow!("compiling the kernel: {e}"))?;
    shader.compile().map_err(|e| anyhow!("compiling the kernel to SPIR-V: {e}"))
}
