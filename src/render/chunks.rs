//! Large arrays split across several bindings. A device limits what one storage binding can see
//! (`maxStorageBufferRange`: 128 MiB on lavapipe and some integrated GPUs, 4 GiB on most discrete
//! ones) and how many texels one texel buffer holds (`maxTexelBufferElements`), not how large a
//! buffer can be. Each array that can outgrow one binding (marked `chunked` in bindings.rs's
//! table, and every array read as texels) lives in one buffer and is bound as consecutive windows
//! of a power-of-two number of elements; the kernel reads it through a generated `load_<name>(i)`
//! that picks the window by `i >> shift`. Lavapipe cannot index an array of bindings by a
//! non-uniform index, so the windows are separate bindings chosen by a `switch`; with one window
//! (the usual case) the accessor is a plain load.

use super::bindings::{BufferBinding, Element, KernelBuffer, EXTRA_BINDING_BASE};
use super::glsl_block::Texel;
use anyhow::{bail, Result};
use std::ops::{Index, IndexMut};

/// Most windows one array may have.
pub const MAX_CHUNKS: u32 = 8;

/// How one array is split: `chunks` windows of `1 << shift` elements (the last one shorter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChunkPlan {
    pub shift: u32,
    pub chunks: u32,
}

impl ChunkPlan {
    /// One window: the plan of every buffer that is not split.
    pub const WHOLE: ChunkPlan = ChunkPlan { shift: 31, chunks: 1 };

    pub fn window_bytes(&self, element_bytes: u64) -> u64 {
        element_bytes << self.shift
    }

    /// (offset, size) in bytes of each window of a buffer of `total_bytes`.
    pub fn windows(&self, element_bytes: u64, total_bytes: u64) -> Vec<(u64, u64)> {
        let window = self.window_bytes(element_bytes);
        (0..self.chunks as u64).map(|c| (c * window, window.min(total_bytes - c * window))).collect()
    }
}

/// How every buffer of the kernel is split, indexed by [`KernelBuffer`]: only the chunked arrays
/// of bindings.rs may have more than one window.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SplitPlans(pub [ChunkPlan; KernelBuffer::COUNT]);

/// Every buffer in one binding: the layout of any scene that fits the device's limits unsplit.
pub const UNSPLIT: SplitPlans = SplitPlans([ChunkPlan::WHOLE; KernelBuffer::COUNT]);

impl Index<KernelBuffer> for SplitPlans {
    type Output = ChunkPlan;
    fn index(&self, buffer: KernelBuffer) -> &ChunkPlan {
        &self.0[buffer as usize]
    }
}

impl IndexMut<KernelBuffer> for SplitPlans {
    fn index_mut(&mut self, buffer: KernelBuffer) -> &mut ChunkPlan {
        &mut self.0[buffer as usize]
    }
}

/// As few windows of [`capacity_bytes`]'s size as `total_bytes` of `element_bytes` elements need;
/// at most [`MAX_CHUNKS`]. `offset_alignment` is the device's `minStorageBufferOffsetAlignment`,
/// which every window's offset must meet.
pub fn plan(element_bytes: u64, total_bytes: u64, max_range: u64, offset_alignment: u64) -> Result<ChunkPlan> {
    let window = capacity_bytes(element_bytes, max_range) / MAX_CHUNKS as u64;
    let shift = (window / element_bytes).trailing_zeros();
    let chunks = total_bytes.div_ceil(window).max(1);
    if chunks > 1 && !window.is_multiple_of(offset_alignment.max(1)) {
        bail!("{} bytes windows do not meet the device's storage offset alignment of {offset_alignment} bytes", window);
    }
    if chunks > MAX_CHUNKS as u64 {
        bail!("at most {MAX_CHUNKS} bindings of {:.1} MiB", window as f64 / 1048576.0);
    }
    Ok(ChunkPlan { shift, chunks: chunks as u32 })
}

/// Most bytes an array of `element_bytes` elements can hold on a device whose bindings see
/// `max_range` bytes: windows of the largest power-of-two element count one binding can see
/// (indices are 32-bit in the kernel, so never more than 2^31 elements a window).
pub fn capacity_bytes(element_bytes: u64, max_range: u64) -> u64 {
    let shift = (63 - (max_range / element_bytes).max(1).leading_zeros()).min(31);
    (element_bytes << shift) * MAX_CHUNKS as u64
}

/// Binding of window `chunk` of `array`: window 0 has the array's own binding.
pub fn window_binding(array: &BufferBinding, chunk: u32) -> u32 {
    if chunk == 0 {
        array.binding
    } else {
        EXTRA_BINDING_BASE + MAX_CHUNKS * array.buffer as u32 + chunk - 1
    }
}

/// GLSL declarations of the windows of `array` (of `element`s) and its accessors `load_<name>(i)`,
/// and `store_<name>(i, v)` when the kernel writes it.
pub fn glsl(array: &BufferBinding, element: Element, plan: ChunkPlan) -> String {
    let (name, ty) = (array.name, element.glsl_type);
    let writable = array.is_written();
    let access = if writable { "" } else { "readonly " };
    let mut out = String::new();
    for c in 0..plan.chunks {
        out += &format!(
            "layout(std430, set = 0, binding = {}) {access}buffer {name}_window{c} {{ {ty} {name}_{c}[]; }};\n",
            window_binding(array, c)
        );
    }
    if plan.chunks == 1 {
        out += &format!("{ty} load_{name}(uint i) {{ return {name}_0[i]; }}\n");
        if writable {
            out += &format!("void store_{name}(uint i, {ty} v) {{ {name}_0[i] = v; }}\n");
        }
        return out;
    }
    out += &format!("{ty} load_{name}(uint i) {{\n{}}}\n", window_switch(plan, &|c| format!("return {name}_{c}[j];")));
    if writable {
        out += &format!(
            "void store_{name}(uint i, {ty} v) {{\n{}}}\n",
            window_switch(plan, &|c| format!("{name}_{c}[j] = v; break;"))
        );
    }
    out
}

/// A function body that runs `body(c)` for element `i`'s window c, where it is element `j`.
fn window_switch(plan: ChunkPlan, body: &dyn Fn(u32) -> String) -> String {
    let cases: String = (0..plan.chunks)
        .map(|c| {
            let label = if c + 1 == plan.chunks { "default:".to_string() } else { format!("case {c}u:") };
            format!("    {label} {}\n", body(c))
        })
        .collect();
    format!("    uint j = i & {:#x}u;\n    switch (i >> {}u) {{\n{cases}    }}\n", (1u64 << plan.shift) - 1, plan.shift)
}

/// GLSL declarations of the windows of `array`, read as texels (bindings.rs, `Shape::TexelBuffer`):
/// one uniform texel buffer of unsigned texels a window (as wide as the record's texels), a
/// function a window that builds its record j from texels `texels.len()` j on, and the accessor
/// `load_<name>(i)`.
pub fn glsl_texels(array: &BufferBinding, element: Element, texels: &[Texel], plan: ChunkPlan) -> String {
    let (name, ty) = (array.name, element.glsl_type);
    let mut out = String::new();
    for c in 0..plan.chunks {
        out += &format!("layout(set = 0, binding = {}) uniform utextureBuffer {name}_{c};\n", window_binding(array, c));
    }
    // One function a window, each fetching from its own binding.
    for c in 0..plan.chunks {
        let fetch = |k: usize| format!("texelFetch({name}_{c}, t + {k})");
        let mut first = 0;
        let mut members = Vec::new();
        for texel in texels {
            members.push(match texel {
                Texel::Vec4 => format!("uintBitsToFloat({})", fetch(first)),
                Texel::Uvec4 => fetch(first),
                Texel::Vec2 => format!("uintBitsToFloat({}.xy)", fetch(first)),
                Texel::Float => format!("uintBitsToFloat({}.x)", fetch(first)),
                Texel::Uint => format!("{}.x", fetch(first)),
                Texel::Vec4Array(n) => {
                    let rows: Vec<String> =
                        (first..first + n).map(|row| format!("uintBitsToFloat({})", fetch(row))).collect();
                    format!("vec4[{n}]({})", rows.join(", "))
                }
            });
            first += texel.count();
        }
        out += &format!(
            "{ty} {name}_{c}_record(uint j) {{\n    int t = int(j * {first}u);\n    return {ty}({});\n}}\n",
            members.join(", ")
        );
    }
    if plan.chunks == 1 {
        out += &format!("{ty} load_{name}(uint i) {{ return {name}_0_record(i); }}\n");
        return out;
    }
    out += &format!(
        "{ty} load_{name}(uint i) {{\n{}}}\n",
        window_switch(plan, &|c| format!("return {name}_{c}_record(j);"))
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::bindings::{Shape, BINDINGS};

    /// BVH nodes: 64 bytes each.
    const NODE_BYTES: u64 = 64;

    #[test]
    fn small_arrays_take_one_window() {
        let p = plan(NODE_BYTES, 1000 * 64, 128 << 20, 16).unwrap();
        assert_eq!(p, ChunkPlan { shift: 21, chunks: 1 });
        assert_eq!(p.windows(64, 1000 * 64), vec![(0, 64000)]);
    }

    #[test]
    fn large_arrays_are_split_into_power_of_two_windows() {
        // 3.5M 64-byte nodes (224 MB; about 20M triangles' worth of wide nodes) under lavapipe's 128 MiB.
        let bytes = 3_500_000 * 64;
        let p = plan(NODE_BYTES, bytes, 128 << 20, 16).unwrap();
        assert_eq!(p, ChunkPlan { shift: 21, chunks: 2 });
        let w = p.windows(64, bytes);
        assert_eq!(w, vec![(0, 128 << 20), (128 << 20, bytes - (128 << 20))]);
        // A range that is not a power of two of elements rounds down.
        let p = plan(4, 100, 30, 4).unwrap();
        assert_eq!(p, ChunkPlan { shift: 2, chunks: 7 });
    }

    #[test]
    fn too_many_windows_or_misaligned_windows_are_refused() {
        assert!(plan(NODE_BYTES, 9 << 20, 1 << 20, 16).unwrap_err().to_string().contains("at most 8 bindings"));
        assert!(plan(NODE_BYTES, 4096, 64, 256).unwrap_err().to_string().contains("alignment"));
        // One window needs no alignment: its offset is 0.
        assert!(plan(NODE_BYTES, 32, 64, 256).is_ok());
    }

    #[test]
    fn extra_windows_bind_clear_of_the_table_and_of_each_other() {
        let mut seen: std::collections::HashSet<u32> = BINDINGS.iter().map(|b| b.binding).collect();
        for array in BINDINGS.iter().filter(|b| b.chunked_element().is_some()) {
            for c in 1..MAX_CHUNKS {
                let b = window_binding(array, c);
                assert!(seen.insert(b), "binding {b} used twice");
                assert!(b >= EXTRA_BINDING_BASE);
            }
        }
    }

    #[test]
    fn accessors_select_the_window_by_the_high_bits() {
        let accum = KernelBuffer::Accum.entry();
        let src = glsl(accum, accum.chunked_element().unwrap(), ChunkPlan { shift: 4, chunks: 3 });
        let window1 = format!("binding = {}) buffer accum_window1 {{ vec4 accum_1[]; }}", window_binding(accum, 1));
        assert!(src.contains(&window1), "{src}");
        assert!(src.contains("uint j = i & 0xfu;\n    switch (i >> 4u) {\n    case 0u: accum_0[j] = v; break;\n    case 1u: accum_1[j] = v; break;\n    default: accum_2[j] = v; break;"), "{src}");
    }

    #[test]
    fn records_read_as_texels_are_built_from_their_texels() {
        let nodes = KernelBuffer::Nodes.entry();
        let Shape::TexelBuffer { element, texels } = nodes.shape else { panic!("the nodes are read as texels") };
        let src = glsl_texels(nodes, element, texels, ChunkPlan::WHOLE);
        assert!(src.contains(&format!("binding = {}) uniform utextureBuffer nodes_0;", nodes.binding)), "{src}");
        assert!(src.contains("    int t = int(j * 4u);\n    return WideNode(uintBitsToFloat(texelFetch(nodes_0, t + 0)), texelFetch(nodes_0, t + 1), texelFetch(nodes_0, t + 2), texelFetch(nodes_0, t + 3));"), "{src}");
        assert!(src.contains("WideNode load_nodes(uint i) { return nodes_0_record(i); }"), "{src}");
        let src = glsl_texels(nodes, element, texels, ChunkPlan { shift: 4, chunks: 2 });
        assert!(
            src.contains(&format!("binding = {}) uniform utextureBuffer nodes_1;", window_binding(nodes, 1))),
            "{src}"
        );
        assert!(
            src.contains("    case 0u: return nodes_0_record(j);\n    default: return nodes_1_record(j);"),
            "{src}"
        );
    }

    #[test]
    fn single_words_are_read_as_narrow_texels() {
        let cdf = KernelBuffer::EnvCdf.entry();
        let Shape::TexelBuffer { element, texels } = cdf.shape else { panic!("the environment CDF is read as texels") };
        assert_eq!(cdf.texel_words(), Some(crate::gpu::TexelWords::One));
        let src = glsl_texels(cdf, element, texels, ChunkPlan::WHOLE);
        assert!(src.contains("float env_cdf_0_record(uint j) {\n    int t = int(j * 1u);\n    return float(uintBitsToFloat(texelFetch(env_cdf_0, t + 0).x));"), "{src}");
        let uvs = KernelBuffer::VertexUvs.entry();
        let Shape::TexelBuffer { element, texels } = uvs.shape else {
            panic!("the texture coordinates are read as texels")
        };
        assert_eq!(uvs.texel_words(), Some(crate::gpu::TexelWords::Two));
        let src = glsl_texels(uvs, element, texels, ChunkPlan::WHOLE);
        assert!(src.contains("return vec2(uintBitsToFloat(texelFetch(vertex_uvs_0, t + 0).xy));"), "{src}");
    }
}
