//! Host twins of the GPU structs in shaders/layout.glsl, and the blocks the kernel's GLSL is
//! generated from (FrameParams, GpuStats, PassParams: see glsl_block.rs). Field order, sizes and
//! the kind constants of the twins must match the GLSL; the tests below pin every offset.

use super::glsl_block::{glsl_block, GlslTexels, GlslType, Texel};
use crate::bvh::WideNode;
use bytemuck::{Pod, Zeroable};

pub const PRIM_SPHERE: u32 = 0;
pub const PRIM_QUAD: u32 = 1;
pub const PRIM_TRIANGLE: u32 = 2;
/// Set in a triangle light's a.w (its place in `mesh_triangles`) when vertices 1 and 2 were swapped.
pub const TRIANGLE_LIGHT_MIRRORED: u32 = 0x8000_0000;

pub const INSTANCE_PRIMITIVES: u32 = 0;
pub const INSTANCE_MESH: u32 = 1;
pub const INSTANCE_HAS_NORMALS: u32 = 1;
pub const INSTANCE_HAS_UVS: u32 = 2;
pub const INSTANCE_HAS_TANGENTS: u32 = 4;
pub const NO_TEXTURE: u32 = u32::MAX;
pub const TEXTURE_SRGB: u32 = 1;
/// A texture's wrap mode along u sits at this bit of its flags, along v at TEXTURE_WRAP_V_SHIFT.
pub const TEXTURE_WRAP_U_SHIFT: u32 = 1;
pub const TEXTURE_WRAP_V_SHIFT: u32 = 3;
pub const TEXTURE_WRAP_REPEAT: u32 = 0;
pub const TEXTURE_WRAP_CLAMP: u32 = 1;
pub const TEXTURE_WRAP_MIRROR: u32 = 2;

/// Material flags in `maps[3]` (u32 bits): Beckmann rather than GGX rough lobes and coat; a thin
/// sheet rather than a solid's surface for the T lobe; black from behind; a plastic whose coat
/// reflects light back down onto its base.
pub const MATERIAL_BECKMANN: u32 = 1;
pub const MATERIAL_THIN: u32 = 2;
pub const MATERIAL_ONE_SIDED: u32 = 4;
pub const MATERIAL_COAT_INTERNAL: u32 = 16;

pub const ALPHA_OPAQUE: u32 = 0;
pub const ALPHA_MASK: u32 = 1;
pub const ALPHA_BLEND: u32 = 2;

pub const CONDUCTOR_MIRROR: u32 = 0;
pub const CONDUCTOR_COMPLEX: u32 = 1;
pub const CONDUCTOR_ALBEDO: u32 = 2;

pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_SPOT: u32 = 1;
pub const LIGHT_DIRECTIONAL: u32 = 2;

pub const ENV_CONSTANT: u32 = 0;
pub const ENV_ANGULAR: u32 = 1;
pub const ENV_LATLONG: u32 = 2;

pub const FILTER_BOX: u32 = 0;
pub const FILTER_TENT: u32 = 1;
pub const FILTER_GAUSSIAN: u32 = 2;

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
    /// ior, two-sided (0/1), albedo texture (u32 bits), microfacet alpha (along u where anisotropic)
    pub params: [f32; 4],
    /// conductor eta, CONDUCTOR_* (u32 bits)
    pub conductor_eta: [f32; 4],
    /// conductor k, 1 / (1 - average coat Fresnel) for a plastic (0: plain diffuse base)
    pub conductor_k: [f32; 4],
    /// metallic-roughness texture (u32 bits), metallic, roughness and transmission factors
    pub metallic_roughness: [f32; 4],
    /// emission texture (u32 bits), normal map (u32 bits), normal map scale, MATERIAL_* flags (u32 bits)
    pub maps: [f32; 4],
    /// alpha texture (u32 bits), opacity factor, MASK cutoff, ALPHA_* mode (u32 bits)
    pub alpha: [f32; 4],
    /// clear coat factor (0: none), its perceptual roughness, their textures (u32 bits: R
    /// multiplies the factor, G the roughness)
    pub coat: [f32; 4],
    /// absorption coefficient sigma_a per world unit inside (0: clear), alpha along v of an
    /// anisotropic material (0: isotropic)
    pub volume: [f32; 4],
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

/// `struct PunctualLight`: a point, spot or directional light (see layout.glsl for its members).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuPunctualLight {
    /// Position (point, spot), LIGHT_* kind (u32 bits)
    pub position_kind: [f32; 4],
    /// Unit axis (spot) or direction of travel (directional), cos of the cone's half-angle
    pub axis_cos: [f32; 4],
    /// Intensity, irradiance or disk radiance; power for selection
    pub value_power: [f32; 4],
    /// Spot cone_angle and falloff_start (radians), 1 - cos of a disk's angular radius, unused
    pub shape: [f32; 4],
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

glsl_block! {
    /// The frame's parameters: the kernel's uniform block `frame` (std140), declared from this
    /// list (bindings.rs). Each vec3 is followed by a scalar in the rest of its 16 bytes, so std140
    /// places every member where `#[repr(C)]` does (the kernel's tests compare the offsets). The
    /// `pad` members fill rows and are zero.
    pub struct FrameParams {
        /// Camera position in world space.
        pub cam_origin: [f32; 3],
        pub pad0: f32,
        /// Unit viewing direction.
        pub cam_forward: [f32; 3],
        /// tan(vertical field of view / 2).
        pub tan_half_fov: f32,
        /// Unit vector along the image rows, to the right.
        pub cam_right: [f32; 3],
        /// Image width / height.
        pub aspect: f32,
        /// Unit vector up the image.
        pub cam_up: [f32; 3],
        pub pad1: f32,
        /// The constant environment's radiance, or the environment map's intensity multiplier.
        pub env_color: [f32; 3],
        pub pad2: f32,
        /// cos and sin of the environment map's rotation about +y.
        pub env_rotation: [f32; 2],
        /// Probability that next-event estimation samples the environment map rather than an area
        /// light (0: the map is not sampled).
        pub env_selection_probability: f32,
        pub pad3: f32,
        /// Image width in pixels.
        pub width: u32,
        /// Image height in pixels.
        pub height: u32,
        /// The render's random seed.
        pub seed: u32,
        /// Number of area lights: the entries of `lights`.
        pub light_count: u32,
        /// First bounce at which Russian roulette may end a path.
        pub rr_start: u32,
        /// 1: next-event estimation on, 0: off.
        pub nee: u32,
        /// The environment's ENV_* kind.
        pub env_kind: u32,
        /// Most bounces of a path (a safety cap).
        pub max_bounces: u32,
        /// Environment map width in texels (1 for a constant environment).
        pub env_width: u32,
        /// Environment map height in texels (1 for a constant environment).
        pub env_height: u32,
        /// Number of instances: the entries of `instances`.
        pub instance_count: u32,
        /// Number of BVH nodes (0: an empty scene, which has no root node).
        pub node_count: u32,
        /// Fixed probability that Russian roulette ends a path (< 0: derive it from the throughput).
        pub rr_absorption: f32,
        /// Least survival probability derived from the throughput.
        pub rr_survival_min: f32,
        /// Greatest survival probability derived from the throughput.
        pub rr_survival_max: f32,
        pub pad4: f32,
        /// Thin-lens radius (0: a pinhole).
        pub lens_radius: f32,
        /// Distance of the focal plane along the viewing axis.
        pub focus_distance: f32,
        /// Per-sample radiance clamp (0: off).
        pub radiance_clamp: f32,
        /// The FILTER_* pixel reconstruction filter.
        pub pixel_filter: u32,
        /// The SAMPLER_* random sequence (shaders/rng.glsl).
        pub sampler_kind: u32,
        /// Number of point, spot and directional lights: the entries of `punctual_lights`.
        pub punctual_light_count: u32,
        /// The instance of the scene's own shapes (`u32::MAX` where there are none): where the
        /// kernel's hits on its few shapes, tested apart from the walk, lie (SCENE_FEW_SHAPES).
        pub shape_instance: u32,
        pub pad7: u32,
        /// Total power of the lights (area and punctual) when they are picked by power (0: picked
        /// uniformly).
        pub light_total_power: f32,
        pub pad8: f32,
        pub pad9: f32,
        pub pad10: f32,
    }
}

glsl_block! {
    /// The kernel's storage block `stats`: per-dispatch counters, cleared and read by the host.
    pub struct GpuStats {
        /// Rays traced.
        pub ray_count: u32,
        /// Samples whose radiance was NaN or infinite, dropped.
        pub nonfinite_samples: u32,
        /// Pixels of the band holding the target sample count after the dispatch (the host checks
        /// that this is all of them).
        pub pixels_complete: u32,
        /// Samples added.
        pub samples_added: u32,
        /// Most loop iterations one subgroup ran (kernels built with COUNT_LOOP_ITERATIONS; else 0).
        pub max_loop_iterations: u32,
        /// The wavefront's paths still in flight after an even round (wavefront.glsl; else 0).
        pub paths_in_flight_even: u32,
        /// ... after an odd round: each round clears the other parity's count for the next.
        pub paths_in_flight_odd: u32,
        /// Tiles the subgroups took, the last take of each subgroup that found none left
        /// included (kernels with TAKE_TILES, tile_taking.rs; else 0).
        pub tiles_taken: u32,
    }
}

glsl_block! {
    /// The kernel's push constants `pass`: bring every pixel of rows `row_offset..row_offset +
    /// row_count` up to `target_samples` samples, a pixel holding `c` taking sample
    /// `stream_offset + c` next.
    pub struct PassParams {
        /// Index of the render's first sample.
        pub stream_offset: u32,
        /// Bring every pixel of the band up to this many samples.
        pub target_samples: u32,
        /// First image row of this dispatch's band.
        pub row_offset: u32,
        /// Rows in the band.
        pub row_count: u32,
        /// The trip count of loop_limit_intact()'s check loop (LOOP_CHECK_ITERATIONS).
        pub loop_check_iterations: u32,
        /// Stripes the band's rows of workgroups are dealt into (pathtrace.comp's
        /// `group_row_of`): 1 takes them in order; see [`crate::render::GroupOrder`].
        pub group_row_stripes: u32,
        /// The wavefront's round (wavefront.glsl): 0 starts the pass's paths. 0 in the megakernel.
        pub wavefront_round: u32,
    }
}

// The GLSL names of the twins, for the arrays of them that the kernel binds (bindings.rs).
impl GlslType for GpuPrimitive {
    const NAME: &'static str = "Primitive";
}
impl GlslType for GpuMaterial {
    const NAME: &'static str = "Material";
}
impl GlslType for GpuInstance {
    const NAME: &'static str = "Instance";
}
impl GlslType for GpuTexture {
    const NAME: &'static str = "TextureInfo";
}
impl GlslType for GpuPunctualLight {
    const NAME: &'static str = "PunctualLight";
}
impl GlslType for GpuAliasEntry {
    const NAME: &'static str = "LightAlias";
}
impl GlslType for WideNode {
    const NAME: &'static str = "WideNode";
}
impl GlslType for GpuMeshTriangle {
    const NAME: &'static str = "MeshTriangle";
}
// The walk's records, read as texels (bindings.rs): `origin`, `quantized_xy`, `quantized_z_kinds`,
// `links`; `v0`, `e1`, `e2`.
impl GlslTexels for WideNode {
    const TEXELS: &'static [Texel] = &[Texel::Vec4, Texel::Uvec4, Texel::Uvec4, Texel::Uvec4];
}
impl GlslTexels for GpuMaterial {
    const TEXELS: &'static [Texel] = &[Texel::Vec4; 10];
}
impl GlslTexels for GpuPrimitive {
    const TEXELS: &'static [Texel] = &[Texel::Vec4; 3];
}
impl GlslTexels for GpuMeshTriangle {
    const TEXELS: &'static [Texel] = &[Texel::Vec4; 3];
}
// `world_to_object`, `object_to_world`, `info`: read by each lane for its own ray's instance.
impl GlslTexels for GpuInstance {
    const TEXELS: &'static [Texel] = &[Texel::Vec4Array(3), Texel::Vec4Array(3), Texel::Uvec4];
}

/// Trip count of the kernel's check for loops cut short (shaders/loop_limit.glsl): it runs fewer
/// times exactly when the device's loop limit ran out in that invocation.
pub const LOOP_CHECK_ITERATIONS: u32 = 2;

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{offset_of, size_of};

    #[test]
    fn primitive_matches_glsl_std430() {
        assert_eq!(size_of::<GpuPrimitive>(), 48);
        assert_eq!(offset_of!(GpuPrimitive, b), 16);
        assert_eq!(offset_of!(GpuPrimitive, c), 32);
    }

    #[test]
    fn material_matches_glsl_std430() {
        assert_eq!(size_of::<GpuMaterial>(), 160);
        assert_eq!(offset_of!(GpuMaterial, emission_t), 16);
        assert_eq!(offset_of!(GpuMaterial, params), 32);
        assert_eq!(offset_of!(GpuMaterial, conductor_eta), 48);
        assert_eq!(offset_of!(GpuMaterial, conductor_k), 64);
        assert_eq!(offset_of!(GpuMaterial, metallic_roughness), 80);
        assert_eq!(offset_of!(GpuMaterial, maps), 96);
        assert_eq!(offset_of!(GpuMaterial, alpha), 112);
        assert_eq!(offset_of!(GpuMaterial, coat), 128);
        assert_eq!(offset_of!(GpuMaterial, volume), 144);
        let glsl = include_str!("../../shaders/layout.glsl");
        let members = "struct Material {\n    vec4 albedo_r;\n    vec4 emission_t;\n    vec4 params;\n    vec4 conductor_eta;\n    vec4 conductor_k;\n    vec4 metallic_roughness;\n    vec4 maps;\n    vec4 alpha;\n    vec4 coat;\n    vec4 volume;\n};";
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
        assert_eq!(size_of::<GpuTexture>(), 16);
        assert_eq!(offset_of!(GpuTexture, width), 4);
        assert_eq!(offset_of!(GpuTexture, height), 8);
        assert_eq!(offset_of!(GpuTexture, flags), 12);
        let glsl = include_str!("../../shaders/layout.glsl");
        let members = "struct TextureInfo {\n    uint offset;\n    uint width;\n    uint height;\n    uint flags;\n};";
        assert!(glsl.contains(members), "struct TextureInfo members differ from GpuTexture");
    }

    #[test]
    fn punctual_light_matches_glsl_std430() {
        assert_eq!(size_of::<GpuPunctualLight>(), 64);
        assert_eq!(offset_of!(GpuPunctualLight, axis_cos), 16);
        assert_eq!(offset_of!(GpuPunctualLight, value_power), 32);
        assert_eq!(offset_of!(GpuPunctualLight, shape), 48);
        let glsl = include_str!("../../shaders/layout.glsl");
        let members = "struct PunctualLight {\n    vec4 position_kind;\n    vec4 axis_cos;\n    vec4 value_power;\n    vec4 shape;\n};";
        assert!(glsl.contains(members), "struct PunctualLight members differ from GpuPunctualLight");
    }

    #[test]
    fn alias_entry_matches_glsl_std430() {
        assert_eq!(size_of::<GpuAliasEntry>(), 8);
        assert_eq!(offset_of!(GpuAliasEntry, alias), 4);
    }

    #[test]
    fn mesh_triangle_matches_glsl_std430() {
        assert_eq!(size_of::<GpuMeshTriangle>(), 48);
        assert_eq!(offset_of!(GpuMeshTriangle, e1), 16);
        assert_eq!(offset_of!(GpuMeshTriangle, e2), 32);
    }
    /// The kernel's own offsets are compared with these in bindings.rs's tests; here the sizes
    /// and each 16-byte row's first member are pinned, so that a reordering is a visible change
    /// (the scene hash covers these bytes).
    #[test]
    fn frame_params_rows_are_pinned() {
        assert_eq!(size_of::<FrameParams>(), 208);
        let offsets = [
            offset_of!(FrameParams, cam_origin),
            offset_of!(FrameParams, cam_forward),
            offset_of!(FrameParams, cam_right),
            offset_of!(FrameParams, cam_up),
            offset_of!(FrameParams, env_color),
            offset_of!(FrameParams, env_rotation),
            offset_of!(FrameParams, width),
            offset_of!(FrameParams, rr_start),
            offset_of!(FrameParams, env_width),
            offset_of!(FrameParams, rr_absorption),
            offset_of!(FrameParams, lens_radius),
            offset_of!(FrameParams, sampler_kind),
            offset_of!(FrameParams, light_total_power),
        ];
        assert_eq!(offsets, [0, 16, 32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192]);
    }

    #[test]
    fn stats_are_pinned() {
        assert_eq!(size_of::<GpuStats>(), 32);
        assert_eq!(offset_of!(GpuStats, nonfinite_samples), 4);
        assert_eq!(offset_of!(GpuStats, pixels_complete), 8);
        assert_eq!(offset_of!(GpuStats, samples_added), 12);
        assert_eq!(offset_of!(GpuStats, max_loop_iterations), 16);
        assert_eq!(offset_of!(GpuStats, paths_in_flight_even), 20);
        assert_eq!(offset_of!(GpuStats, paths_in_flight_odd), 24);
        assert_eq!(offset_of!(GpuStats, tiles_taken), 28);
    }

    #[test]
    fn pass_params_fit_the_push_constant_minimum() {
        assert_eq!(size_of::<PassParams>(), 28);
        assert!(size_of::<PassParams>() <= 128, "Vulkan guarantees only 128 bytes of push constants");
    }

    /// Every kernel function that dispatches on a primitive's kind is a `switch` with a case for
    /// each PRIM_* kind and a `default` (an unknown kind must not pass for another): a kind added
    /// here and forgotten in one of them fails.
    #[test]
    fn every_primitive_kind_has_a_case_in_each_kernel_dispatch() {
        let kinds = ["PRIM_SPHERE", "PRIM_QUAD", "PRIM_TRIANGLE"];
        assert_eq!([PRIM_SPHERE, PRIM_QUAD, PRIM_TRIANGLE], [0, 1, 2], "a kind was added: list it above");
        let mut switches = 0;
        for (file, glsl) in [
            ("intersect.glsl", include_str!("../../shaders/intersect.glsl")),
            ("lights.glsl", include_str!("../../shaders/lights.glsl")),
        ] {
            assert!(!glsl.contains("prim_kind(p) =="), "{file} compares a kind outside a switch");
            let starts = glsl.match_indices("switch (prim_kind(p)) {").chain(glsl.match_indices("switch (kind) {"));
            for (start, _) in starts {
                // The switch's body: up to the brace that closes it.
                let body = &glsl[start..];
                let mut depth = 0;
                let end = body.char_indices().find_map(|(i, c)| {
                    depth += match c {
                        '{' => 1,
                        '}' => -1,
                        _ => 0,
                    };
                    (c == '}' && depth == 0).then_some(i)
                });
                let body = &body[..end.expect("the switch closes")];
                for kind in kinds {
                    assert!(
                        body.contains(&format!("case {kind}:")),
                        "{file}: a switch at byte {start} has no case {kind}"
                    );
                }
                assert!(body.contains("default:"), "{file}: a switch at byte {start} has no default");
                switches += 1;
            }
        }
        assert!(switches >= 6, "found {switches} kind switches; the dispatches moved?");
    }

    /// The GLSL side declares the same kinds; a renumbering on one side only must fail here.
    #[test]
    fn kind_constants_match_glsl() {
        let glsl = concat!(include_str!("../../shaders/layout.glsl"), include_str!("../../shaders/rng.glsl"));
        for (name, value) in [
            ("PRIM_SPHERE", PRIM_SPHERE),
            ("PRIM_QUAD", PRIM_QUAD),
            ("PRIM_TRIANGLE", PRIM_TRIANGLE),
            ("TRIANGLE_LIGHT_MIRRORED", TRIANGLE_LIGHT_MIRRORED),
            ("INSTANCE_PRIMITIVES", INSTANCE_PRIMITIVES),
            ("INSTANCE_MESH", INSTANCE_MESH),
            ("INSTANCE_HAS_NORMALS", INSTANCE_HAS_NORMALS),
            ("INSTANCE_HAS_UVS", INSTANCE_HAS_UVS),
            ("INSTANCE_HAS_TANGENTS", INSTANCE_HAS_TANGENTS),
            ("NO_TEXTURE", NO_TEXTURE),
            ("TEXTURE_SRGB", TEXTURE_SRGB),
            ("MATERIAL_BECKMANN", MATERIAL_BECKMANN),
            ("MATERIAL_THIN", MATERIAL_THIN),
            ("MATERIAL_ONE_SIDED", MATERIAL_ONE_SIDED),
            ("MATERIAL_COAT_INTERNAL", MATERIAL_COAT_INTERNAL),
            ("CONDUCTOR_MIRROR", CONDUCTOR_MIRROR),
            ("CONDUCTOR_COMPLEX", CONDUCTOR_COMPLEX),
            ("CONDUCTOR_ALBEDO", CONDUCTOR_ALBEDO),
            ("LIGHT_POINT", LIGHT_POINT),
            ("LIGHT_SPOT", LIGHT_SPOT),
            ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
            ("ENV_CONSTANT", ENV_CONSTANT),
            ("ENV_ANGULAR", ENV_ANGULAR),
            ("ENV_LATLONG", ENV_LATLONG),
            ("FILTER_BOX", FILTER_BOX),
            ("FILTER_TENT", FILTER_TENT),
            ("FILTER_GAUSSIAN", FILTER_GAUSSIAN),
            ("SAMPLER_INDEPENDENT", SAMPLER_INDEPENDENT),
            ("SAMPLER_SOBOL", SAMPLER_SOBOL),
            ("WIDE_CHILD_INTERIOR", crate::bvh::CHILD_INTERIOR),
            ("WIDE_CHILD_NONE", crate::bvh::CHILD_NONE),
        ] {
            let literal = if value >= 1 << 31 { format!("{value:#x}u") } else { format!("{value}u") };
            assert!(
                glsl.contains(&format!("const uint {name} = {literal};")),
                "{name} = {literal} not found in layout.glsl or rng.glsl"
            );
        }
    }
}
