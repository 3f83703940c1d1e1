//! Host twins of the GPU structs in shaders/layout.glsl. Field order, sizes and the kind constants
//! must match the GLSL; the tests below pin every offset.

use bytemuck::{Pod, Zeroable};

pub const PRIM_SPHERE: u32 = 0;
pub const PRIM_QUAD: u32 = 1;
pub const PRIM_TRIANGLE: u32 = 2;

pub const INSTANCE_PRIMITIVES: u32 = 0;
pub const INSTANCE_MESH: u32 = 1;
pub const INSTANCE_HAS_NORMALS: u32 = 1;
pub const INSTANCE_HAS_UVS: u32 = 2;
pub const NO_TEXTURE: u32 = u32::MAX;
pub const TEXTURE_SRGB: u32 = 1;

pub const CONDUCTOR_MIRROR: u32 = 0;
pub const CONDUCTOR_COMPLEX: u32 = 1;
pub const CONDUCTOR_ALBEDO: u32 = 2;

pub const ENV_CONSTANT: u32 = 0;
pub const ENV_ANGULAR: u32 = 1;
pub const ENV_LATLONG: u32 = 2;

pub const FILTER_BOX: u32 = 0;
pub const FILTER_TENT: u32 = 1;
pub const FILTER_GAUSSIAN: u32 = 2;

/// Bindings of the AOV sums (`aov_albedo_depth`, `aov_normal_hits`, split like the accumulation
/// by chunks.rs): one `vec4` a pixel each, so `[f32; 4]` on the host.
pub const AOV_BINDINGS: [u32; 2] = [20, 21];

pub const SAMPLER_INDEPENDENT: u32 = 0;
pub const SAMPLER_SOBOL: u32 = 1;

/// `struct Primitive`: see layout.glsl for what a, b and c hold per kind.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuPrimitive {
    pub a: [f32; 4],
    pub b: [f32; 4],
    pub c: [f32; 4],
}

/// `struct Material`: see layout.glsl for what each member holds.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuMaterial {
    pub albedo_r: [f32; 4],
    pub emission_t: [f32; 4],
    /// ior, two-sided (0/1), albedo texture (u32 bits), GGX alpha
    pub params: [f32; 4],
    /// conductor eta, CONDUCTOR_* (u32 bits)
    pub conductor_eta: [f32; 4],
    /// conductor k, 1 / (1 - average coat Fresnel) for a plastic (0: plain diffuse base)
    pub conductor_k: [f32; 4],
    /// metallic-roughness texture (u32 bits), metallic, roughness and transmission factors
    pub metallic_roughness: [f32; 4],
}

/// `struct Instance`: rows of the two 3x4 affine maps, then kind, BVH root node and flags.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuInstance {
    pub world_to_object: [[f32; 4]; 3],
    pub object_to_world: [[f32; 4]; 3],
    pub info: [u32; 4],
}

/// `struct MeshTriangle`: a mesh triangle by value, in its BVH's leaf order, so intersecting it is
/// three vec4 loads with no index indirection. `v0.xyz` is the first vertex, `e1.xyz` and `e2.xyz`
/// the edges to the second and third; the w lanes hold the three global vertex indices (u32 bits)
/// that shading uses for normals and texture coordinates.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuMeshTriangle {
    pub v0: [f32; 4],
    pub e1: [f32; 4],
    pub e2: [f32; 4],
}

/// `struct TextureInfo`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuTexture {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    /// TEXTURE_* bits
    pub flags: u32,
}

/// `struct LightAlias`: one entry of the alias table that picks area lights by power
/// (light_selection.rs).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuAliasEntry {
    /// Probability of keeping this entry's own light rather than taking `alias`.
    pub threshold: f32,
    pub alias: u32,
}

/// `uniform FrameParamsBlock` (std140; only 16-byte members, so it equals std430).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct FrameParams {
    pub cam_origin: [f32; 4],
    pub cam_forward: [f32; 4],
    pub cam_right: [f32; 4],
    pub cam_up: [f32; 4],
    pub env_color: [f32; 4],
    /// cos and sin of the map's rotation about +y, probability that NEE samples the map, unused
    pub env_rotation: [f32; 4],
    /// width, height, seed, light count
    pub image: [u32; 4],
    /// rr_start, nee, env kind, max bounces (safety cap)
    pub integrator: [u32; 4],
    /// map width, map height, instance count, node count (0: empty scene)
    pub env_size: [u32; 4],
    /// fixed absorption (< 0: derive from throughput), q min, q max, unused
    pub roulette: [f32; 4],
    /// lens radius (0: pinhole), focus distance along the viewing axis, radiance clamp (0: off),
    /// FILTER_* as raw u32 bits
    pub lens: [f32; 4],
    /// SAMPLER_* (shaders/rng.glsl), unused, unused, unused
    pub sampling: [u32; 4],
    /// total power of the area lights when they are picked by power (0: picked uniformly), unused x3
    pub lights: [f32; 4],
}

/// `buffer StatsBuffer`: per-dispatch counters, cleared and read by the host.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuStats {
    pub ray_count: u32,
    pub nonfinite_samples: u32,
    /// Pixels of the band holding the target sample count after the dispatch.
    pub pixels_complete: u32,
    pub samples_added: u32,
    /// Most loop iterations one subgroup ran (kernels built with COUNT_LOOP_ITERATIONS; else 0).
    pub max_loop_iterations: u32,
}

/// `push_constant PassBlock`: bring every pixel of rows `row_offset..row_offset + row_count` up to
/// `target_samples` samples, a pixel holding `c` taking sample `stream_offset + c` next.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct PassParams {
    pub stream_offset: u32,
    pub target_samples: u32,
    pub row_offset: u32,
    pub row_count: u32,
    /// The trip count of loop_limit_intact()'s check loop (LOOP_CHECK_ITERATIONS).
    pub loop_check_iterations: u32,
}

/// Trip count of the kernel's check for loops cut short (shaders/loop_limit.glsl): it runs fewer
/// times exactly when the device's loop limit ran out in that invocation.
pub const LOOP_CHECK_ITERATIONS: u32 = 2;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{ChildBox, PairNode};
    use std::mem::{offset_of, size_of};

    #[test]
    fn primitive_matches_glsl_std430() {
        assert_eq!(size_of::<GpuPrimitive>(), 48);
        assert_eq!(offset_of!(GpuPrimitive, b), 16);
        assert_eq!(offset_of!(GpuPrimitive, c), 32);
    }

    #[test]
    fn material_matches_glsl_std430() {
        assert_eq!(size_of::<GpuMaterial>(), 96);
        assert_eq!(offset_of!(GpuMaterial, emission_t), 16);
        assert_eq!(offset_of!(GpuMaterial, params), 32);
        assert_eq!(offset_of!(GpuMaterial, conductor_eta), 48);
        assert_eq!(offset_of!(GpuMaterial, conductor_k), 64);
        assert_eq!(offset_of!(GpuMaterial, metallic_roughness), 80);
        let glsl = include_str!("../../shaders/layout.glsl");
        let members = "struct Material {\n    vec4 albedo_r;\n    vec4 emission_t;\n    vec4 params;\n    vec4 conductor_eta;\n    vec4 conductor_k;\n    vec4 metallic_roughness;\n};";
        assert!(glsl.contains(members), "struct Material members differ from GpuMaterial");
    }

    #[test]
    fn instance_matches_glsl_std430() {
        assert_eq!(size_of::<GpuInstance>(), 112);
        assert_eq!(offset_of!(GpuInstance, object_to_world), 48);
        assert_eq!(offset_of!(GpuInstance, info), 96);
    }

    #[test]
    fn texture_info_matches_glsl_std430() {
        assert_eq!(size_of::<GpuMeshTriangle>(), 48);
        assert_eq!(offset_of!(GpuMeshTriangle, e1), 16);
        assert_eq!(offset_of!(GpuMeshTriangle, e2), 32);
        assert_eq!(size_of::<GpuTexture>(), 16);
        assert_eq!(offset_of!(GpuTexture, width), 4);
        assert_eq!(offset_of!(GpuTexture, height), 8);
        assert_eq!(offset_of!(GpuTexture, flags), 12);
        let glsl = include_str!("../../shaders/layout.glsl");
        let members = "struct TextureInfo {\n    uint offset;\n    uint width;\n    uint height;\n    uint flags;\n};";
        assert!(glsl.contains(members), "struct TextureInfo members differ from GpuTexture");
    }

    #[test]
    fn alias_entry_matches_glsl_std430() {
        assert_eq!(size_of::<GpuAliasEntry>(), 8);
        assert_eq!(offset_of!(GpuAliasEntry, alias), 4);
    }

    #[test]
    fn pair_node_matches_glsl_std430() {
        assert_eq!(size_of::<PairNode>(), 64);
        assert_eq!(offset_of!(PairNode, children) + size_of::<ChildBox>(), 32);
        assert_eq!(offset_of!(ChildBox, link), 12);
        assert_eq!(offset_of!(ChildBox, max), 16);
        assert_eq!(offset_of!(ChildBox, prim_count), 28);
    }

    #[test]
    fn frame_params_match_glsl_std140() {
        assert_eq!(size_of::<FrameParams>(), 208);
        let offsets = [
            offset_of!(FrameParams, cam_origin),
            offset_of!(FrameParams, cam_forward),
            offset_of!(FrameParams, cam_right),
            offset_of!(FrameParams, cam_up),
            offset_of!(FrameParams, env_color),
            offset_of!(FrameParams, env_rotation),
            offset_of!(FrameParams, image),
            offset_of!(FrameParams, integrator),
            offset_of!(FrameParams, env_size),
            offset_of!(FrameParams, roulette),
            offset_of!(FrameParams, lens),
            offset_of!(FrameParams, sampling),
            offset_of!(FrameParams, lights),
        ];
        assert_eq!(offsets, [0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192]);
    }

    #[test]
    fn stats_match_glsl_std430() {
        assert_eq!(size_of::<GpuStats>(), 20);
        assert_eq!(offset_of!(GpuStats, nonfinite_samples), 4);
        assert_eq!(offset_of!(GpuStats, pixels_complete), 8);
        assert_eq!(offset_of!(GpuStats, samples_added), 12);
        assert_eq!(offset_of!(GpuStats, max_loop_iterations), 16);
        let glsl = include_str!("../../shaders/layout.glsl");
        let members = "buffer StatsBuffer { uint ray_count; uint nonfinite_samples; uint pixels_complete; uint samples_added; uint max_loop_iterations; } stats;";
        assert!(glsl.contains(members), "StatsBuffer members differ from GpuStats");
    }

    #[test]
    fn aov_buffers_match_glsl() {
        let glsl = include_str!("../../shaders/layout.glsl");
        for (binding, name) in AOV_BINDINGS.iter().zip(["aov_albedo_depth", "aov_normal_hits"]) {
            let line = format!("// binding {binding}: vec4 {name}[]");
            assert!(glsl.contains(&line), "layout.glsl lacks {line}");
        }
    }

    #[test]
    fn pass_params_fit_the_push_constant_minimum() {
        assert_eq!(size_of::<PassParams>(), 20);
        let glsl = include_str!("../../shaders/layout.glsl");
        let block = glsl.split("uniform PassBlock {").nth(1).and_then(|b| b.split("} pass;").next()).expect("layout.glsl declares PassBlock");
        let members: Vec<&str> = block.lines().filter_map(|l| l.trim().strip_prefix("uint ")?.split(';').next()).collect();
        assert_eq!(members, ["stream_offset", "target_samples", "row_offset", "row_count", "loop_check_iterations"], "PassBlock members differ from PassParams");
        assert!(size_of::<PassParams>() <= 128, "Vulkan guarantees only 128 bytes of push constants");
    }

    /// The GLSL side declares the same kinds; a renumbering on one side only must fail here.
    #[test]
    fn kind_constants_match_glsl() {
        let glsl = concat!(include_str!("../../shaders/layout.glsl"), include_str!("../../shaders/rng.glsl"));
        for (name, value) in [
            ("PRIM_SPHERE", PRIM_SPHERE),
            ("PRIM_QUAD", PRIM_QUAD),
            ("PRIM_TRIANGLE", PRIM_TRIANGLE),
            ("INSTANCE_PRIMITIVES", INSTANCE_PRIMITIVES),
            ("INSTANCE_MESH", INSTANCE_MESH),
            ("INSTANCE_HAS_NORMALS", INSTANCE_HAS_NORMALS),
            ("INSTANCE_HAS_UVS", INSTANCE_HAS_UVS),
            ("NO_TEXTURE", NO_TEXTURE),
            ("TEXTURE_SRGB", TEXTURE_SRGB),
            ("CONDUCTOR_MIRROR", CONDUCTOR_MIRROR),
            ("CONDUCTOR_COMPLEX", CONDUCTOR_COMPLEX),
            ("CONDUCTOR_ALBEDO", CONDUCTOR_ALBEDO),
            ("ENV_CONSTANT", ENV_CONSTANT),
            ("ENV_ANGULAR", ENV_ANGULAR),
            ("ENV_LATLONG", ENV_LATLONG),
            ("FILTER_BOX", FILTER_BOX),
            ("FILTER_TENT", FILTER_TENT),
            ("FILTER_GAUSSIAN", FILTER_GAUSSIAN),
            ("SAMPLER_INDEPENDENT", SAMPLER_INDEPENDENT),
            ("SAMPLER_SOBOL", SAMPLER_SOBOL),
        ] {
            let literal = if value == u32::MAX { "0xffffffffu".to_string() } else { format!("{value}u") };
            assert!(glsl.contains(&format!("const uint {name} = {literal};")), "{name} = {literal} not found in layout.glsl or rng.glsl");
        }
    }
}
