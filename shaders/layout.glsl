// GPU data layout: every struct here has a twin in src/render/layout.rs, pinned by size/offset tests.
// Only vec4/uvec4 members in the uniform block, so std140 and std430 agree.

// Primitive kinds (PRIM_* must match layout.rs).
const uint PRIM_SPHERE = 0u;
const uint PRIM_QUAD = 1u;
const uint PRIM_TRIANGLE = 2u;

// Sphere:   a.xyz = center, a.w = radius.
// Quad:     a.xyz = origin, b.xyz = edge u, c.xyz = edge v; the emitting side faces cross(u, v).
// Triangle: a.xyz = v0, b.xyz = v1 - v0, c.xyz = v2 - v0; the front side faces cross(e1, e2).
// b.w holds the kind and c.w the material index, as raw uint bits.
struct Primitive {
    vec4 a;
    vec4 b;
    vec4 c;
};

// Fresnel of the reflector (R) lobe (CONDUCTOR_* must match layout.rs): none (a perfect
// reflector), a complex IOR eta + ik, or Schlick's form with the albedo as F0 (glTF's metals).
const uint CONDUCTOR_MIRROR = 0u;
const uint CONDUCTOR_COMPLEX = 1u;
const uint CONDUCTOR_ALBEDO = 2u;

// albedo_r.w = reflectivity R, emission_t.w = transparency T, params.x = ior,
// params.y = 1 when the emitter radiates from both sides, params.z = albedo texture index (uint
// bits; NO_TEXTURE for none), params.w = GGX alpha of the R and T lobes and the coat.
// conductor_eta.rgb = eta and conductor_k.rgb = k of CONDUCTOR_COMPLEX, conductor_eta.w = the
// CONDUCTOR_* kind (uint bits), conductor_k.w = 1 / (1 - the coat's average Fresnel) for a
// plastic (a coated base), 0 for a plain diffuse base. metallic_roughness.x = glTF
// metallic-roughness texture index (uint bits; NO_TEXTURE for none), .y/.z/.w = the metallic,
// roughness and transmission factors that surface_material() turns into R, T and alpha per texel.
struct Material {
    vec4 albedo_r;
    vec4 emission_t;
    vec4 params;
    vec4 conductor_eta;
    vec4 conductor_k;
    vec4 metallic_roughness;
};

// One entry of the alias table that picks area lights by power (src/render/light_selection.rs):
// keep this entry's light with probability `threshold`, otherwise take `alias`.
struct LightAlias {
    float threshold;
    uint alias;
};

// BVH node (src/bvh/pair_node.rs): both children of an interior node of the binary BVH, so one
// load tests both boxes. Per child: xyz of *_min / *_max = its box; *_min.w = its link and
// *_max.w = its primitive count (uint bits). Count 0: an interior child, the link is its node;
// otherwise a leaf of primitives link..link + count. A missing child is a point box at +infinity.
struct PairNode {
    vec4 a_min;
    vec4 a_max;
    vec4 b_min;
    vec4 b_max;
};

// Instance kinds (INSTANCE_* must match layout.rs): the scene's own spheres, quads and triangles
// (one group, identity transform), or a placed triangle mesh.
const uint INSTANCE_PRIMITIVES = 0u;
const uint INSTANCE_MESH = 1u;
// Instance flags: the mesh has per-vertex normals / texture coordinates.
const uint INSTANCE_HAS_NORMALS = 1u;
const uint INSTANCE_HAS_UVS = 2u;
const uint NO_TEXTURE = 0xffffffffu;
// Texture flags: RGB is sRGB-encoded colour (else linear data, read as stored).
const uint TEXTURE_SRGB = 1u;

// One placement of a bottom-level BVH. Rows of the 3x4 affine maps; info.x = kind, info.y = root
// node of its BVH, info.z = flags.
struct Instance {
    vec4 world_to_object[3];
    vec4 object_to_world[3];
    uvec4 info;
};

// A mesh triangle by value, in its BVH's leaf order: v0.xyz = first vertex, e1.xyz / e2.xyz = the
// edges to the second / third; the w lanes hold the three global vertex indices (uint bits) for
// normals and texture coordinates. Intersection needs no index indirection (loads are what costs).
struct MeshTriangle {
    vec4 v0;
    vec4 e1;
    vec4 e2;
};

// Texture descriptor: texels offset..offset + width * height (RGBA8, top row first); flags =
// TEXTURE_* bits.
struct TextureInfo {
    uint offset;
    uint width;
    uint height;
    uint flags;
};

// Environment kinds (ENV_* must match layout.rs).
const uint ENV_CONSTANT = 0u;
const uint ENV_ANGULAR = 1u;
const uint ENV_LATLONG = 2u;

// Pixel reconstruction filters (FILTER_* must match layout.rs).
const uint FILTER_BOX = 0u;
const uint FILTER_TENT = 1u;
const uint FILTER_GAUSSIAN = 2u;

layout(std140, set = 0, binding = 0) uniform FrameParamsBlock {
    vec4 cam_origin;    // w unused
    vec4 cam_forward;   // w = tan(vertical fov / 2)
    vec4 cam_right;     // w = width / height
    vec4 cam_up;        // w unused
    vec4 env_color;     // constant radiance, or the map's intensity multiplier (rgb)
    vec4 env_rotation;  // x = cos, y = sin of the map's rotation about +y, z = probability that
                        // next-event estimation samples the map (0: it is not sampled)
    uvec4 image;        // width, height, seed, light count
    uvec4 integrator;   // rr_start, nee (0/1), env kind, max depth
    uvec4 env_size;     // map width, map height, instance count, node count
    vec4 roulette;      // x = fixed absorption (< 0: derive from throughput), y = q min, z = q max
    vec4 lens;          // x = lens radius (0: pinhole), y = focus distance along the viewing axis,
                        // z = per-sample radiance clamp (0: off), w = FILTER_* as raw uint bits
    uvec4 sampling;     // x = SAMPLER_* (rng.glsl), yzw unused
    vec4 lights;        // x = total power of the area lights when picked by power (0: uniformly)
} frame;

layout(push_constant) uniform PassBlock {
    uint stream_offset;         // index of the render's first sample: a pixel holding c samples
                                // takes sample stream_offset + c next
    uint target_samples;        // bring every pixel of the band up to this many samples
    uint row_offset;            // first image row of this dispatch's band
    uint row_count;             // rows in the band
    uint loop_check_iterations; // 2: the trip count of loop_limit_intact()'s loop
} pass;

// Arrays that can outgrow one storage binding (marked "binding N: type name[]") are declared in
// chunked_buffers.glsl, which src/render/chunks.rs generates for each scene and device; the kernel
// reads them with load_<name>(i) (and writes accum with store_accum).
// binding 1: PairNode nodes[]
layout(std430, set = 0, binding = 2) readonly buffer PrimitiveBuffer { Primitive prims[]; };
layout(std430, set = 0, binding = 3) readonly buffer MaterialBuffer { Material materials[]; };
// Every emitter in world space, in Primitive form (mesh triangles transformed by the host).
layout(std430, set = 0, binding = 4) readonly buffer LightBuffer { Primitive lights[]; };
// binding 5: vec4 env_texels[]
// Per pixel: rgb = sum of sample radiance, a = samples accumulated.
// binding 6: vec4 accum[]
// Per dispatch, cleared and read by the host: rays traced, non-finite samples dropped, pixels of the
// band that hold the target sample count afterwards (the host checks that this is all of them),
// samples added, and the most loop iterations one subgroup ran (with COUNT_LOOP_ITERATIONS).
layout(std430, set = 0, binding = 7) buffer StatsBuffer { uint ray_count; uint nonfinite_samples; uint pixels_complete; uint samples_added; uint max_loop_iterations; } stats;
// Top-level BVH leaves index instances; node 0 is the top-level root.
layout(std430, set = 0, binding = 8) readonly buffer InstanceBuffer { Instance instances[]; };
// Every mesh's triangles by value and their materials, in their BVH's leaf order.
// binding 9: MeshTriangle mesh_triangles[]
// binding 10: uint triangle_materials[]
// Vertex attributes of every mesh, indexed by global vertex index; normals octahedral snorm16x2.
// binding 11: uint vertex_normals[]
// binding 12: vec2 vertex_uvs[]
layout(std430, set = 0, binding = 13) readonly buffer TextureInfoBuffer { TextureInfo texture_infos[]; };
// binding 14: uint texels[]
// The environment map's sampling distribution: marginal CDF over rows (height + 1 values), then
// one CDF per row (width + 1 values each); see src/render/env_sampling.rs.
layout(std430, set = 0, binding = 15) readonly buffer EnvCdfBuffer { float env_cdf[]; };
// Alias table over `lights` for picking them by power; empty when they are picked uniformly.
layout(std430, set = 0, binding = 16) readonly buffer LightAliasBuffer { LightAlias light_alias[]; };

// Denoiser features (AOVs), per pixel, summed over samples like `accum`: rgb = albedo and
// xyz = camera-facing shading normal at the first non-specular vertex, and a = distance to the
// first hit summed over the samples that hit something, w = how many those were. Only the kernel
// variant built with AOVS 1 touches them, and only then are they bound.
// binding 20: vec4 aov_albedo_depth[]
// binding 21: vec4 aov_normal_hits[]

uint prim_kind(Primitive p) { return floatBitsToUint(p.b.w); }
uint prim_material(Primitive p) { return floatBitsToUint(p.c.w); }
