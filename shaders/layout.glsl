// GPU data layout. The kind and flag constants and the record structs of the kernel's arrays
// (Primitive, Material, Instance, MeshTriangle, TextureInfo, PunctualLight, LightAlias) are
// declared once, in src/render/layout.rs, which writes them into records.glsl with what each
// member's lanes hold; the BVH's node is declared here as the four 16-byte loads the walk makes.
#include "records.glsl"

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

uint material_flags(Material m) {
    return floatBitsToUint(m.maps.w);
}

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
