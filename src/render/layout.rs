//! Everything the kernel reads whose layout the host decides, declared once here: the kind and flag
//! constants, the record structs of the kernel's arrays (written into the kernel as `records.glsl`
//! by [`records_glsl`]) and the blocks its `interface.glsl` declares (FrameParams, GpuStats,
//! PassParams: see glsl_block.rs and interface.rs). The BVH's WideNode (bvh/wide_node.rs) is the
//! one record declared by hand in layout.glsl, as four 16-byte loads rather than its host fields;
//! the tests below pin every offset, and bindings.rs's compare the compiled kernel's.

use super::glsl_block::{glsl_block, glsl_struct, GlslBlock, GlslTexels, GlslType, Texel};
use crate::bvh::WideNode;

/// Declares `pub const NAME: u32 = value;` for each constant, in documented groups, and
/// `GLSL_CONSTANT_GROUPS`, from which [`records_glsl`] writes them into the kernel.
macro_rules! glsl_constants {
    ($($(#[doc = $doc:literal])* $group:ident { $($name:ident = $value:expr),* $(,)? })*) => {
        $($(pub const $name: u32 = $value;)*)*
        /// Every constant group: its doc comment and its (name, value) pairs.
        pub const GLSL_CONSTANT_GROUPS: &[(&[&str], &[(&str, u32)])] =
            &[$((&[$($doc),*], &[$((stringify!($name), $name)),*])),*];
    };
}

glsl_constants! {
    /// Primitive kinds.
    PRIMITIVE_KINDS { PRIM_SPHERE = 0, PRIM_QUAD = 1, PRIM_TRIANGLE = 2 }
    /// Set in a triangle light's a.w (its place in `mesh_triangles`) when vertices 1 and 2 were
    /// swapped to keep the front side of a placement that mirrors it.
    TRIANGLE_LIGHT { TRIANGLE_LIGHT_MIRRORED = 0x8000_0000 }
    /// Instance kinds: the scene's own spheres, quads and triangles (one group, identity
    /// transform), or a placed triangle mesh.
    INSTANCE_KINDS { INSTANCE_PRIMITIVES = 0, INSTANCE_MESH = 1 }
    /// Instance flags: the mesh has per-vertex normals / texture coordinates / tangents (for
    /// normal maps; a mesh with tangents has the other two) / colours (glTF COLOR_0).
    INSTANCE_FLAGS { INSTANCE_HAS_NORMALS = 1, INSTANCE_HAS_UVS = 2, INSTANCE_HAS_TANGENTS = 4, INSTANCE_HAS_COLORS = 8 }
    /// A texture index that names no texture.
    NO_TEXTURES { NO_TEXTURE = u32::MAX }
    /// Texture flags: RGB is sRGB-encoded colour (else linear data, read as stored); the
    /// TEXTURE_WRAP_* mode along u at bit TEXTURE_WRAP_U_SHIFT and along v at TEXTURE_WRAP_V_SHIFT
    /// (glTF samplers).
    TEXTURE_FLAGS {
        TEXTURE_SRGB = 1,
        TEXTURE_WRAP_U_SHIFT = 1,
        TEXTURE_WRAP_V_SHIFT = 3,
        TEXTURE_WRAP_REPEAT = 0,
        TEXTURE_WRAP_CLAMP = 1,
        TEXTURE_WRAP_MIRROR = 2,
    }
    /// Material flags in `maps.w`: the rough lobes and the coat are Beckmann rather than GGX; the
    /// T lobe is a thin sheet rather than the surface of a solid; the surface scatters on its
    /// front side only and is black from behind (Mitsuba's BSDFs); a plastic whose coat reflects
    /// light back down onto its base.
    MATERIAL_FLAGS { MATERIAL_BECKMANN = 1, MATERIAL_THIN = 2, MATERIAL_ONE_SIDED = 4, MATERIAL_COAT_INTERNAL = 16, MATERIAL_NULL = 32 }
    /// Participating media (shaders/medium.glsl). A medium is named by an 8-bit code: its index in
    /// `media` + 1, MEDIUM_VACUUM for empty space, MEDIUM_STACK_EMPTY for no entry. A material's
    /// interior medium's code sits in its flags from bit MATERIAL_INTERIOR_SHIFT (MEDIUM_STACK_EMPTY:
    /// none given, the inside is empty space). A path keeps the media it entered in a stack of
    /// MEDIUM_STACK_DEPTH codes, the innermost in the low byte.
    MEDIUM_CODES { MATERIAL_INTERIOR_SHIFT = 24, MEDIUM_STACK_EMPTY = 0, MEDIUM_VACUUM = 255, MEDIUM_STACK_DEPTH = 4 }
    /// Medium kinds.
    MEDIUM_KINDS { MEDIUM_HOMOGENEOUS = 0, MEDIUM_HETEROGENEOUS = 1 }
    /// Alpha modes: always there; there where the opacity reaches the cutoff (glTF MASK); met
    /// with probability equal to the opacity (glTF BLEND, MTL d).
    ALPHA_MODES { ALPHA_OPAQUE = 0, ALPHA_MASK = 1, ALPHA_BLEND = 2 }
    /// Fresnel of the reflector (R) lobe: none (a perfect reflector), a complex IOR eta + ik, or
    /// Schlick's form with the albedo as F0 (glTF's metals).
    CONDUCTORS { CONDUCTOR_MIRROR = 0, CONDUCTOR_COMPLEX = 1, CONDUCTOR_ALBEDO = 2 }
    /// Lights without a surface (src/scene/light.rs).
    LIGHT_KINDS { LIGHT_POINT = 0, LIGHT_SPOT = 1, LIGHT_DIRECTIONAL = 2 }
    /// The light tree (light_tree.rs): flags in a node's links.z (a leaf, whose links.x is its
    /// light; bounds of a two-sided emitter), and the index that names no node or light.
    LIGHT_TREE { LIGHT_TREE_LEAF = 1, LIGHT_TREE_TWO_SIDED = 2, LIGHT_TREE_NONE = u32::MAX }
    /// Environment kinds.
    ENV_KINDS { ENV_CONSTANT = 0, ENV_ANGULAR = 1, ENV_LATLONG = 2 }
    /// Pixel reconstruction filters.
    FILTERS { FILTER_BOX = 0, FILTER_TENT = 1, FILTER_GAUSSIAN = 2 }
}

/// The random sequences (FrameParams::sampler_kind), declared in rng.glsl beside the samplers.
pub const SAMPLER_INDEPENDENT: u32 = 0;
pub const SAMPLER_SOBOL: u32 = 1;

glsl_block! {
    /// `struct Primitive`: a sphere, quad or triangle (area lights and the scene's own shapes).
    pub struct GpuPrimitive as "Primitive" {
        /// Sphere: xyz = center, w = radius. Quad: xyz = origin. Triangle: xyz = v0. A light made
        /// of a mesh triangle (in `lights`, or built at a hit by world_primitive): w = its place
        /// in `mesh_triangles` (uint bits), with TRIANGLE_LIGHT_MIRRORED set where its placement
        /// mirrors it and vertices 1 and 2 were swapped to keep its front side.
        pub a: [f32; 4],
        /// Quad: xyz = edge u. Triangle: xyz = v1 - v0. w = the PRIM_* kind (uint bits).
        pub b: [f32; 4],
        /// Quad: xyz = edge v (the emitting side faces cross(u, v)). Triangle: xyz = v2 - v0 (the
        /// front side faces cross(e1, e2)). w = the material index (uint bits).
        pub c: [f32; 4],
    }
}

glsl_block! {
    /// `struct Material`: a base (diffuse, or a plastic) replaced per bounce with probability R
    /// by a reflector and with probability T by a Fresnel dielectric (scene::Material).
    pub struct GpuMaterial as "Material" {
        /// rgb = albedo, w = reflectivity R.
        pub albedo_r: [f32; 4],
        /// rgb = emitted radiance, w = transparency T.
        pub emission_t: [f32; 4],
        /// x = ior, y = 1 when the emitter radiates from both sides, z = albedo texture index
        /// (uint bits; NO_TEXTURE for none), w = GGX alpha of the R and T lobes and the coat
        /// (along u where anisotropic).
        pub params: [f32; 4],
        /// rgb = eta of CONDUCTOR_COMPLEX, w = the CONDUCTOR_* kind (uint bits).
        pub conductor_eta: [f32; 4],
        /// rgb = k of CONDUCTOR_COMPLEX, w = 1 / (1 - the coat's average Fresnel) for a plastic (a
        /// coated base), 0 for a plain diffuse base.
        pub conductor_k: [f32; 4],
        /// x = glTF metallic-roughness texture index (uint bits; NO_TEXTURE for none), y / z / w =
        /// the metallic, roughness and transmission factors that surface_material() turns into R,
        /// T and alpha per texel.
        pub metallic_roughness: [f32; 4],
        /// x = emission texture index (uint bits; NO_TEXTURE for none), which multiplies
        /// emission_t.rgb per texel; y = tangent-space normal map index (uint bits; NO_TEXTURE for
        /// none), z = its scale (of the normal's x and y); w = MATERIAL_* flags (uint bits).
        pub maps: [f32; 4],
        /// Tested in traversal (alpha.glsl): x = an RGBA texture whose A channel is the opacity
        /// (uint bits; NO_TEXTURE for none), y = the opacity factor it multiplies, z = the cutoff
        /// of ALPHA_MASK, w = the ALPHA_* mode (uint bits).
        pub alpha: [f32; 4],
        /// glTF KHR_materials_clearcoat (pick_lobe): x = the clear coat's factor (0: none), y its
        /// perceptual roughness (GGX alpha is its square), z / w = textures whose R / G channel
        /// multiplies x / y per texel (uint bits; NO_TEXTURE for none).
        pub coat: [f32; 4],
        /// rgb = the absorption coefficient sigma_a per world unit inside (Beer-Lambert,
        /// path_step; 0: clear); w = the alpha along v of an anisotropic material's R and T lobes
        /// and coat, params.w being the one along u (0: isotropic, params.w along both).
        pub volume: [f32; 4],
    }
}

glsl_block! {
    /// `struct Medium`: a participating medium (scene::Medium), coefficients per world unit.
    pub struct GpuMedium as "Medium" {
        /// rgb = extinction sigma_t per channel; w = Henyey-Greenstein's g (0: isotropic).
        pub sigma_t_g: [f32; 4],
        /// rgb = single-scattering albedo sigma_s / sigma_t; w = the MEDIUM_* kind (uint bits).
        pub albedo_kind: [f32; 4],
        /// MEDIUM_HETEROGENEOUS: x = its density grid's first value in `medium_densities`, y / z /
        /// w = its cells along x, y and z (values x fastest, at the cells' centres).
        pub grid: [u32; 4],
        /// xyz = the world box's min corner the grid fills; w = the majorant: the largest
        /// sigma_t of any channel anywhere in the grid, the rate of delta and ratio tracking.
        pub box_min_majorant: [f32; 4],
        /// xyz = the world box's max corner; w unused.
        pub box_max: [f32; 4],
    }
}

glsl_block! {
    /// `struct Instance`: one placement of a bottom-level BVH.
    pub struct GpuInstance as "Instance" {
        /// Rows of the 3x4 affine map from world to object space.
        pub world_to_object: [[f32; 4]; 3],
        /// Rows of the 3x4 affine map from object to world space.
        pub object_to_world: [[f32; 4]; 3],
        /// x = the INSTANCE_* kind, y = the root node of its BVH, z = INSTANCE_HAS_* flags.
        pub info: [u32; 4],
    }
}

glsl_block! {
    /// `struct MeshTriangle`: a mesh triangle by value, in its BVH's leaf order, so intersecting
    /// it is three vec4 loads with no index indirection.
    pub struct GpuMeshTriangle as "MeshTriangle" {
        /// xyz = the first vertex; w = its global vertex index (uint bits), for normals and
        /// texture coordinates.
        pub v0: [f32; 4],
        /// xyz = the edge to the second vertex; w = the second's global vertex index (uint bits).
        pub e1: [f32; 4],
        /// xyz = the edge to the third vertex; w = the third's global vertex index (uint bits).
        pub e2: [f32; 4],
    }
}

glsl_block! {
    /// `struct TextureInfo`: texels offset..offset + width * height of `texels` (RGBA8, top row
    /// first).
    pub struct GpuTexture as "TextureInfo" {
        pub offset: u32,
        pub width: u32,
        pub height: u32,
        /// TEXTURE_* bits.
        pub flags: u32,
    }
}

glsl_block! {
    /// `struct PunctualLight`: a point, spot or directional light.
    pub struct GpuPunctualLight as "PunctualLight" {
        /// xyz = position (point, spot), w = the LIGHT_* kind (uint bits).
        pub position_kind: [f32; 4],
        /// xyz = the spot's unit axis, or the unit direction a directional light travels; w = cos
        /// of the angular radius of a directional light's disk (1 for a delta light).
        pub axis_cos: [f32; 4],
        /// rgb = radiant intensity W/sr (point; spot on its axis), irradiance W/m^2 (delta
        /// directional) or radiance (a disk); w = the power light selection weighs it by
        /// (light_selection.rs).
        pub value_power: [f32; 4],
        /// x / y = the spot's cone_angle / falloff_start in radians; z = 1 - cos of a disk's
        /// angular radius, to full precision for sun-sized disks (0: a delta light); w = a
        /// directional light's probability of being picked beside the light tree (light_tree.rs;
        /// 0 without one).
        pub shape: [f32; 4],
    }
}

glsl_block! {
    /// `struct LightAlias`: one entry of the alias table that picks area lights by power
    /// (light_selection.rs).
    pub struct GpuAliasEntry as "LightAlias" {
        /// Probability of keeping this entry's own light rather than taking `alias`.
        pub threshold: f32,
        pub alias: u32,
    }
}

glsl_block! {
    /// `struct LightTreeNode`: a node of the light tree (light_tree.rs), what its lights offer the
    /// importance estimate. An interior node's first child is the next node.
    pub struct GpuLightTreeNode as "LightTreeNode" {
        /// xyz = the min corner of the box around the lights, w = their total power.
        pub min_phi: [f32; 4],
        /// xyz = the max corner, w = cos of the half-angle of the cone around their normals.
        pub max_cos_theta_o: [f32; 4],
        /// xyz = that cone's unit axis, w = cos of how far past a normal they still emit.
        pub axis_cos_theta_e: [f32; 4],
        /// x = the second child (interior) or the light (leaf), y = the parent (LIGHT_TREE_NONE
        /// at the root), z = LIGHT_TREE_* flags, w unused.
        pub links: [u32; 4],
    }
}

/// The kernel's generated `records.glsl`, which layout.glsl includes: every constant and record
/// struct above, declared from these Rust definitions so that the two cannot drift.
pub fn records_glsl() -> String {
    let mut out = String::from("// Generated by src/render/layout.rs from its constants and record structs.\n");
    for (doc, constants) in GLSL_CONSTANT_GROUPS {
        out += "\n";
        for line in *doc {
            out += &format!("//{line}\n");
        }
        for (name, value) in *constants {
            let literal = if *value >= 1 << 31 { format!("{value:#x}u") } else { format!("{value}u") };
            out += &format!("const uint {name} = {literal};\n");
        }
    }
    for declaration in [
        glsl_struct::<GpuPrimitive>(),
        glsl_struct::<GpuMaterial>(),
        glsl_struct::<GpuInstance>(),
        glsl_struct::<GpuMeshTriangle>(),
        glsl_struct::<GpuTexture>(),
        glsl_struct::<GpuPunctualLight>(),
        glsl_struct::<GpuAliasEntry>(),
        glsl_struct::<GpuLightTreeNode>(),
        glsl_struct::<GpuMedium>(),
    ] {
        out += "\n";
        out += &declaration;
    }
    out
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
        /// The code of the medium the camera is in (MEDIUM_CODES): MEDIUM_VACUUM for none.
        pub camera_medium: u32,
        /// Total power of the lights (area and punctual) when they are picked by power (0: picked
        /// uniformly).
        pub light_total_power: f32,
        /// Probability that next-event estimation descends the light tree rather than picking a
        /// directional light beside it (light_tree.rs; the environment map's share not counted);
        /// 0 without a tree.
        pub light_tree_share: f32,
        /// 1: next-event estimation picks by the light tree (the scene's `light_tree`), 0: by
        /// the alias table or uniformly. A kernel built for one scene knows it (SCENE_LIGHT_TREE);
        /// the general kernel, which has the tree walk compiled in, reads it here.
        pub light_tree: u32,
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
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for GpuMaterial {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for GpuInstance {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for GpuTexture {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for GpuPunctualLight {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for GpuAliasEntry {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for GpuLightTreeNode {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for GpuMedium {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
}
impl GlslType for WideNode {
    const NAME: &'static str = "WideNode";
}
impl GlslType for GpuMeshTriangle {
    const NAME: &'static str = <Self as GlslBlock>::NAME;
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
    }

    #[test]
    fn punctual_light_matches_glsl_std430() {
        assert_eq!(size_of::<GpuPunctualLight>(), 64);
        assert_eq!(offset_of!(GpuPunctualLight, axis_cos), 16);
        assert_eq!(offset_of!(GpuPunctualLight, value_power), 32);
        assert_eq!(offset_of!(GpuPunctualLight, shape), 48);
    }

    #[test]
    fn medium_matches_glsl_std430() {
        assert_eq!(size_of::<GpuMedium>(), 80);
        assert_eq!(offset_of!(GpuMedium, albedo_kind), 16);
        assert_eq!(offset_of!(GpuMedium, grid), 32);
        assert_eq!(offset_of!(GpuMedium, box_min_majorant), 48);
        assert_eq!(offset_of!(GpuMedium, box_max), 64);
    }

    #[test]
    fn alias_entry_matches_glsl_std430() {
        assert_eq!(size_of::<GpuAliasEntry>(), 8);
        assert_eq!(offset_of!(GpuAliasEntry, alias), 4);
    }

    #[test]
    fn light_tree_node_matches_glsl_std430() {
        assert_eq!(size_of::<GpuLightTreeNode>(), 64);
        assert_eq!(offset_of!(GpuLightTreeNode, max_cos_theta_o), 16);
        assert_eq!(offset_of!(GpuLightTreeNode, axis_cos_theta_e), 32);
        assert_eq!(offset_of!(GpuLightTreeNode, links), 48);
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
        let glsl = records_glsl() + include_str!("../../shaders/layout.glsl") + include_str!("../../shaders/rng.glsl");
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
            ("MATERIAL_NULL", MATERIAL_NULL),
            ("MEDIUM_VACUUM", MEDIUM_VACUUM),
            ("MEDIUM_HOMOGENEOUS", MEDIUM_HOMOGENEOUS),
            ("MEDIUM_HETEROGENEOUS", MEDIUM_HETEROGENEOUS),
            ("CONDUCTOR_MIRROR", CONDUCTOR_MIRROR),
            ("CONDUCTOR_COMPLEX", CONDUCTOR_COMPLEX),
            ("CONDUCTOR_ALBEDO", CONDUCTOR_ALBEDO),
            ("LIGHT_POINT", LIGHT_POINT),
            ("LIGHT_SPOT", LIGHT_SPOT),
            ("LIGHT_DIRECTIONAL", LIGHT_DIRECTIONAL),
            ("LIGHT_TREE_LEAF", LIGHT_TREE_LEAF),
            ("LIGHT_TREE_TWO_SIDED", LIGHT_TREE_TWO_SIDED),
            ("LIGHT_TREE_NONE", LIGHT_TREE_NONE),
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
                "{name} = {literal} not found in records.glsl, layout.glsl or rng.glsl"
            );
        }
    }

    /// records.glsl is what the kernel compiles (the bindings' tests read its offsets back from
    /// the SPIR-V); here: every record and constant group is in it, with its members' comments,
    /// and layout.glsl no longer declares any of them by hand.
    #[test]
    fn records_glsl_declares_every_record_and_constant_once() {
        let records = records_glsl();
        let layout = include_str!("../../shaders/layout.glsl");
        for name in [
            "Primitive",
            "Material",
            "Instance",
            "MeshTriangle",
            "TextureInfo",
            "PunctualLight",
            "LightAlias",
            "LightTreeNode",
            "Medium",
        ] {
            assert_eq!(records.matches(&format!("struct {name} {{")).count(), 1, "{name}");
            assert!(!layout.contains(&format!("struct {name} {{")), "layout.glsl declares {name} by hand");
        }
        assert!(records.contains("    vec4 world_to_object[3];"), "{records}");
        assert!(records.contains("    // x = ior, y = 1 when the emitter radiates from both sides"), "{records}");
        for (_, constants) in GLSL_CONSTANT_GROUPS {
            for (name, _) in *constants {
                assert!(!layout.contains(&format!("const uint {name} ")), "layout.glsl declares {name} by hand");
            }
        }
    }
}
