//! Large arrays split across several storage-buffer bindings. A device limits what one storage
//! binding can see (`maxStorageBufferRange`: 128 MiB on lavapipe and some integrated GPUs, 4 GiB
//! on most discrete ones), not how large a buffer can be. Each array that can outgrow one binding
//! lives in one buffer and is bound as consecutive windows of a power-of-two number of elements;
//! the kernel reads it through a generated `load_<name>(i)` that picks the window by `i >> shift`.
//! Lavapipe cannot index an array of bindings by a non-uniform index, so the windows are separate
//! bindings chosen by a `switch`; with one window (the usual case) the accessor is a plain load.

use super::layout::AOV_BINDINGS;
use anyhow::{bail, Result};

/// An array of the kernel that may span several bindings.
#[derive(Clone, Copy, Debug)]
pub struct ChunkedArray {
    /// Array name in the kernel; the accessors are `load_<name>` (and `store_<name>`).
    pub name: &'static str,
    /// Element type in GLSL (declared in layout.glsl when it is a struct).
    pub glsl_type: &'static str,
    pub element_bytes: u64,
    /// Binding of the first window (the array's place in the binding order of layout.glsl).
    pub binding: u32,
    pub writable: bool,
}

/// Most windows one array may have.
pub const MAX_CHUNKS: u32 = 8;
/// Bindings of windows past the first: array `k` of [`CHUNKED_ARRAYS`] uses
/// `EXTRA_BINDING_BASE + MAX_CHUNKS * k + (window - 1)`, clear of layout.glsl's fixed bindings.
pub const EXTRA_BINDING_BASE: u32 = 64;

/// Every array the renderer may split, in no particular order (bindings say where they go).
pub const CHUNKED_ARRAYS: [ChunkedArray; 10] = [
    ChunkedArray { name: "nodes", glsl_type: "PairNode", element_bytes: 64, binding: 1, writable: false },
    ChunkedArray { name: "env_texels", glsl_type: "vec4", element_bytes: 16, binding: 5, writable: false },
    ChunkedArray { name: "accum", glsl_type: "vec4", element_bytes: 16, binding: 6, writable: true },
    ChunkedArray { name: "mesh_triangles", glsl_type: "MeshTriangle", element_bytes: 48, binding: 9, writable: false },
    ChunkedArray { name: "triangle_materials", glsl_type: "uint", element_bytes: 4, binding: 10, writable: false },
    ChunkedArray { name: "vertex_normals", glsl_type: "uint", element_bytes: 4, binding: 11, writable: false },
    ChunkedArray { name: "vertex_uvs", glsl_type: "vec2", element_bytes: 8, binding: 12, writable: false },
    ChunkedArray { name: "texels", glsl_type: "uint", element_bytes: 4, binding: 14, writable: false },
    // The AOV sums, as large as the accumulation; bound only when a render asks for them.
    ChunkedArray { name: "aov_albedo_depth", glsl_type: "vec4", element_bytes: 16, binding: AOV_BINDINGS[0], writable: true },
    ChunkedArray { name: "aov_normal_hits", glsl_type: "vec4", element_bytes: 16, binding: AOV_BINDINGS[1], writable: true },
];

/// The chunked array bound at `binding`, if any.
pub fn chunked_array_at(binding: u32) -> Option<(usize, &'static ChunkedArray)> {
    CHUNKED_ARRAYS.iter().enumerate().find(|(_, a)| a.binding == binding)
}

/// How one array is split: `chunks` windows of `1 << shift` elements (the last one shorter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChunkPlan {
    pub shift: u32,
    pub chunks: u32,
}

impl ChunkPlan {
    pub fn window_bytes(&self, element_bytes: u64) -> u64 {
        element_bytes << self.shift
    }

    /// (offset, size) in bytes of each window of a buffer of `total_bytes`.
    pub fn windows(&self, element_bytes: u64, total_bytes: u64) -> Vec<(u64, u64)> {
        let window = self.window_bytes(element_bytes);
        (0..self.chunks as u64).map(|c| (c * window, window.min(total_bytes - c * window))).collect()
    }
}

/// As few windows of [`capacity_bytes`]'s size as `total_bytes` needs; at most [`MAX_CHUNKS`]. `offset_alignment` is the device's
/// `minStorageBufferOffsetAlignment`, which every window's offset must meet.
pub fn plan(array: &ChunkedArray, total_bytes: u64, max_range: u64, offset_alignment: u64) -> Result<ChunkPlan> {
    let window = capacity_bytes(array, max_range) / MAX_CHUNKS as u64;
    let shift = (window / array.element_bytes).trailing_zeros();
    let chunks = total_bytes.div_ceil(window).max(1);
    if chunks > 1 && !window.is_multiple_of(offset_alignment.max(1)) {
        bail!("{} bytes windows do not meet the device's storage offset alignment of {offset_alignment} bytes", window);
    }
    if chunks > MAX_CHUNKS as u64 {
        bail!("at most {MAX_CHUNKS} bindings of {:.1} MiB", window as f64 / 1048576.0);
    }
    Ok(ChunkPlan { shift, chunks: chunks as u32 })
}

/// Most bytes `array` can hold on a device whose bindings see `max_range` bytes: windows of the
/// largest power-of-two element count one binding can see (indices are 32-bit in the kernel, so
/// never more than 2^31 elements a window).
pub fn capacity_bytes(array: &ChunkedArray, max_range: u64) -> u64 {
    let shift = (63 - (max_range / array.element_bytes).max(1).leading_zeros()).min(31);
    (array.element_bytes << shift) * MAX_CHUNKS as u64
}

/// Binding of window `chunk` of array number `index` in [`CHUNKED_ARRAYS`].
pub fn window_binding(index: usize, chunk: u32) -> u32 {
    if chunk == 0 {
        CHUNKED_ARRAYS[index].binding
    } else {
        EXTRA_BINDING_BASE + MAX_CHUNKS * index as u32 + chunk - 1
    }
}

/// GLSL declarations and accessors of every chunked array (the kernel's `chunked_buffers.glsl`).
pub fn glsl(plans: &[ChunkPlan; CHUNKED_ARRAYS.len()]) -> String {
    let mut out = String::from("// Generated by src/render/chunks.rs for this scene and device.\n");
    for (k, (array, plan)) in CHUNKED_ARRAYS.iter().zip(plans).enumerate() {
        let ChunkedArray { name, glsl_type: ty, .. } = *array;
        let access = if array.writable { "" } else { "readonly " };
        for c in 0..plan.chunks {
            out += &format!(
                "layout(std430, set = 0, binding = {}) {access}buffer {name}_window{c} {{ {ty} {name}_{c}[]; }};\n",
                window_binding(k, c)
            );
        }
        if plan.chunks == 1 {
            out += &format!("{ty} load_{name}(uint i) {{ return {name}_0[i]; }}\n");
            if array.writable {
                out += &format!("void store_{name}(uint i, {ty} v) {{ {name}_0[i] = v; }}\n");
            }
            continue;
        }
        let mask = (1u64 << plan.shift) - 1;
        let shift = plan.shift;
        let cases = |body: &dyn Fn(u32) -> String| -> String {
            (0..plan.chunks)
                .map(|c| {
                    let label = if c + 1 == plan.chunks { "default:".to_string() } else { format!("case {c}u:") };
                    format!("    {label} {}\n", body(c))
                })
                .collect()
        };
        out += &format!(
            "{ty} load_{name}(uint i) {{\n    uint j = i & {mask:#x}u;\n    switch (i >> {shift}u) {{\n{}    }}\n}}\n",
            cases(&|c| format!("return {name}_{c}[j];"))
        );
        if array.writable {
            out += &format!(
                "void store_{name}(uint i, {ty} v) {{\n    uint j = i & {mask:#x}u;\n    switch (i >> {shift}u) {{\n{}    }}\n}}\n",
                cases(&|c| format!("{name}_{c}[j] = v; break;"))
            );
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const NODES: ChunkedArray = CHUNKED_ARRAYS[0];

    #[test]
    fn small_arrays_take_one_window() {
        let p = plan(&NODES, 1000 * 64, 128 << 20, 16).unwrap();
        assert_eq!(p, ChunkPlan { shift: 21, chunks: 1 });
        assert_eq!(p.windows(64, 1000 * 64), vec![(0, 64000)]);
    }

    #[test]
    fn large_arrays_are_split_into_power_of_two_windows() {
        // 10M triangles' worth of nodes (3.5M pair nodes, 224 MB) under lavapipe's 128 MiB.
        let bytes = 3_500_000 * 64;
        let p = plan(&NODES, bytes, 128 << 20, 16).unwrap();
        assert_eq!(p, ChunkPlan { shift: 21, chunks: 2 });
        let w = p.windows(64, bytes);
        assert_eq!(w, vec![(0, 128 << 20), (128 << 20, bytes - (128 << 20))]);
        // A range that is not a power of two of elements rounds down.
        let p = plan(&CHUNKED_ARRAYS[4], 100, 30, 4).unwrap();
        assert_eq!(p, ChunkPlan { shift: 2, chunks: 7 });
    }

    #[test]
    fn too_many_windows_or_misaligned_windows_are_refused() {
        assert!(plan(&NODES, 9 << 20, 1 << 20, 16).unwrap_err().to_string().contains("at most 8 bindings"));
        assert!(plan(&NODES, 4096, 64, 256).unwrap_err().to_string().contains("alignment"));
        // One window needs no alignment: its offset is 0.
        assert!(plan(&NODES, 32, 64, 256).is_ok());
    }

    #[test]
    fn extra_windows_bind_clear_of_the_fixed_bindings_and_of_each_other() {
        let mut seen = std::collections::HashSet::new();
        for k in 0..CHUNKED_ARRAYS.len() {
            for c in 0..MAX_CHUNKS {
                let b = window_binding(k, c);
                assert!(seen.insert(b), "binding {b} used twice");
                assert!(c == 0 || b >= EXTRA_BINDING_BASE);
            }
        }
    }

    #[test]
    fn accessors_select_the_window_by_the_high_bits() {
        let mut plans = [ChunkPlan { shift: 31, chunks: 1 }; CHUNKED_ARRAYS.len()];
        plans[2] = ChunkPlan { shift: 4, chunks: 3 };
        let src = glsl(&plans);
        assert!(src.contains("PairNode load_nodes(uint i) { return nodes_0[i]; }"));
        assert!(src.contains("binding = 80) buffer accum_window1 { vec4 accum_1[]; }"));
        assert!(src.contains("uint j = i & 0xfu;\n    switch (i >> 4u) {\n    case 0u: accum_0[j] = v; break;\n    case 1u: accum_1[j] = v; break;\n    default: accum_2[j] = v; break;"));
    }
}
