// GPU data layout: every struct here has a twin in src/render/layout.rs, pinned by size/offset tests.

// Primitive kinds (PRIM_* must match layout.rs).
const uint PRIM_SPHERE = 0u;
const uint PRIM_QUAD = 1u;
const uint PRIM_TRIANGLE = 2u;

// Sphere:   a.xyz = center, a.w = radius.
// Quad:     a.xyz = origin, b.xyz = edge u, c.xyz = edge v; the emitting side faces cross(u, v).
// Triangle: a.xyz = v0, b.xyz = v1 - v0, c.xyz = v2 - v0; the front side faces cross(e1, e2).
// b.w holds the kind and c.w the material index, as raw uint bits. A light made of a mesh triangle
// (in `lights`, or built at a hit by world_primitive) has in a.w its place in `mesh_triangles`
// (uint bits), with TRIANGLE_LIGHT_MIRRORED set where its placement mirrors it and vertices 1 and
// 2 were swapped to keep its front side: a textured emitter's texture coordinates and mean
// luminance are found through it.
const uint TRIANGLE_LIGHT_MIRRORED = 0x80000000u;
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
// maps.x = emission texture index (uint bits; NO_TEXTURE for none), which multiplies emission_t.rgb
// per texel; maps.y = tangent-space normal map index (uint bits; NO_TEXTURE for none), maps.z its
// scale (of the normal's x and y); maps.w = MATERIAL_* flags (uint bits). alpha (tested in traversal, alpha.glsl): .x = an
// RGBA texture whose A channel is the opacity (uint bits; NO_TEXTURE for none), .y = the opacity
// factor it multiplies, .z = the cutoff of ALPHA_MASK, .w = the ALPHA_* mode (uint bits).
// coat (glTF KHR_materials_clearcoat, pick_lobe): .x = the clear coat's factor (0: none), .y its
// perceptual roughness (GGX alpha is its square), .z / .w = textures whose R / G channel multiplies
// .x / .y per texel (uint bits; NO_TEXTURE for none). volume.rgb = the absorption coefficient
// sigma_a per world unit inside the material (Beer-Lambert, path_step; 0: clear); volume.w = the
// alpha along v of an anisotropic material's R and T lobes and coat, params.w being the one along
// u (0: isotropic, params.w along both).
struct Material {
    vec4 albedo_r;
    vec4 emission_t;
    vec4 params;
    vec4 conductor_eta;
    vec4 conductor_k;
    vec4 metallic_roughness;
    vec4 maps;
    vec4 alpha;
    vec4 coat;
    vec4 volume;
};

// Material flags in maps.w (MATERIAL_* must match layout.rs): the rough lobes and the coat are
// Beckmann rather than GGX; the T lobe is a thin sheet rather than the surface of a solid; the
// surface scatters on its front side only and is black from behind (Mitsuba's BSDFs).
const uint MATERIAL_BECKMANN = 1u;
const uint MATERIAL_THIN = 2u;
const uint MATERIAL_ONE_SIDED = 4u;
const uint MATERIAL_COAT_INTERNAL = 16u;

uint material_flags(Material m) {
    return floatBitsToUint(m.maps.w);
}

// Alpha modes (ALPHA_* must match layout.rs): always there; there where the opacity reaches the
// cutoff (glTF MASK); met with probability equal to the opacity (glTF BLEND, MTL d).
const uint ALPHA_OPAQUE = 0u;
const uint ALPHA_MASK = 1u;
const uint ALPHA_BLEND = 2u;

// Lights without a surface (LIGHT_* must match layout.rs; src/scene/light.rs).
const uint LIGHT_POINT = 0u;
const uint LIGHT_SPOT = 1u;
const uint LIGHT_DIRECTIONAL = 2u;

// position_kind.xyz = position (point, spot), .w = LIGHT_* kind (uint bits). axis_cos.xyz = the
// spot's unit axis, or the unit direction a directional light travels; axis_cos.w = cos of the
// angular radius of a directional light's disk (1 for a delta light). value_power.rgb = radiant
// intensity W/sr (point; spot on its axis), irradiance W/m^2 (delta directional) or radiance (a
// disk); value_power.w = the power light selection weighs it by (light_selection.rs).
// shape.x / .y = the spot's cone_angle / falloff_start in radians; shape.z = 1 - cos of a disk's
// angular radius, to full precision for sun-sized disks (0: a delta light).
struct PunctualLight {
    vec4 position_kind;
    vec4 axis_cos;
    vec4 value_power;
    vec4 shape;
};

// One entry of the alias table that picks area lights by power (src/render/light_selection.rs):
// keep this entry's light with probability `threshold`, otherwise take `alias`.
struct LightAlias {
    float threshold;
    uint alias;
};

// BVH node (src/bvh/wide_node.rs): up to four children, their boxes quantized to 8 bits against
// the node's own. Byte k of each packed word belongs to child k.
// - origin.xyz: the node's box's min corner; origin.w (uint bits): per axis (bytes 0, 1, 2) the
//   biased exponent of the quantum, so the quantum is uintBitsToFloat(byte << 23);
// - quantized_xy: each child's min x, max x, min y, max y in quanta from the origin (mins rounded
//   down, maxes up); quantized_z_kinds.xy: min z, max z;
// - quantized_z_kinds.z: each child's kind: WIDE_CHILD_INTERIOR, a leaf's primitive count, or
//   WIDE_CHILD_NONE; quantized_z_kinds.w is unused;
// - links: an interior child's node, or a leaf's first primitive.
struct WideNode {
    vec4 origin;
    uvec4 quantized_xy;
    uvec4 quantized_z_kinds;
    uvec4 links;
};
const uint WIDE_CHILD_INTERIOR = 0u;
const uint WIDE_CHILD_NONE = 255u;

// Instance kinds (INSTANCE_* must match layout.rs): the scene's own spheres, quads and triangles
// (one group, identity transform), or a placed triangle mesh.
const uint INSTANCE_PRIMITIVES = 0u;
const uint INSTANCE_MESH = 1u;
// Instance flags: the mesh has per-vertex normals / texture coordinates / tangents (for normal
// maps; a mesh with tangents has the other two).
const uint INSTANCE_HAS_NORMALS = 1u;
const uint INSTANCE_HAS_UVS = 2u;
const uint INSTANCE_HAS_TANGENTS = 4u;
const uint NO_TEXTURE = 0xffffffffu;
// Texture flags: RGB is sRGB-encoded colour (else linear data, read as stored); the TEXTURE_WRAP_*
// mode along u at bit TEXTURE_WRAP_U_SHIFT and along v at TEXTURE_WRAP_V_SHIFT (glTF samplers).
const uint TEXTURE_SRGB = 1u;
const uint TEXTURE_WRAP_U_SHIFT = 1u;
const uint TEXTURE_WRAP_V_SHIFT = 3u;
const uint TEXTURE_WRAP_REPEAT = 0u;
const uint TEXTURE_WRAP_CLAMP = 1u;
const uint TEXTURE_WRAP_MIRROR = 2u;

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

// The kernel's inputs: the frame's uniform block `frame` (FrameParams in src/render/layout.rs), the
// pass's push constants `pass` (PassParams) and every storage buffer, each described beside its
// entry in the table of src/render/bindings.rs, which generates interface.glsl from it for each
// kernel variant, scene and device. Arrays that can outgrow one storage binding are read with
// load_<name>(i) (and accum and the AOV sums written with store_<name>); the others by name. The
// arrays read at a per-lane index (BVH nodes, mesh triangles, instances, materials, area lights,
// vertex attributes, textures, the environment map and its CDF) are texel buffers of 1, 2 or 4
// words a texel, their records built texel by texel by load_<name> (src/render/bindings.rs,
// Shape::TexelBuffer); a kernel that includes this file enables GL_EXT_samplerless_texture_functions
// for their texelFetch.
#include "interface.glsl"

uint prim_kind(Primitive p) { return floatBitsToUint(p.b.w); }
uint prim_material(Primitive p) { return floatBitsToUint(p.c.w); }
uint light_mesh_triangle(Primitive p) { return floatBitsToUint(p.a.w) & ~TRIANGLE_LIGHT_MIRRORED; }
uint punctual_kind(PunctualLight l) { return floatBitsToUint(l.position_kind.w); }
