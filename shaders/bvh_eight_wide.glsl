// The eight-wide walk of a placed mesh's or the shapes' own BVH (BVH_WIDTH 8, bvh-width=8,
// src/render/bvh_width.rs): compressed nodes of up to eight children (src/bvh/eight_wide.rs,
// Ylitie, Karras and Laine 2017), whose children are visited in the order of the ray's octant
// instead of sorted by entry distance. Included by bvh.glsl after leaf_hit, in place of
// walk_instance's four-wide loop; the top level stays four-wide.
//
// A node is 80 bytes, five texels, stored in two 64-byte records of the node array: the first
// record's four texels, then the second record's first (its origin, read as bits), which is all
// of the second record the walk uses, so the other three texels are never fetched.
// - texel 0: the node's min corner, and (w's bytes 0-2) the biased exponent of each axis's quantum;
// - texel 1: x the record of the first interior child (the others follow, two records each, in
//   slot order), y the first primitive of the first leaf child (the others' follow in slot order),
//   z each leaf slot's primitive count (nibble k), w the interior slots (bits 0-7) and the slots
//   that hold a child (bits 8-15);
// - texels 2, 3, 4 (x, y, z): the min bounds of slots 0-3 and 4-7, then the max bounds of slots
//   0-3 and 4-7, a byte a slot, in quanta from the min corner.

const uint EIGHT_WIDE_RECORDS = 2u;

// Each node visit leaves at most seven entries behind; levels as in STACK_SIZE (bvh.glsl).
const uint EIGHT_WIDE_STACK_SIZE = 7u * (BVH_MAX_DEPTH + 1u) + 1u;

struct EightWideNode {
    vec4 origin;
    uvec4 links;
    uvec4 quantized_x;
    uvec4 quantized_y;
    uvec4 quantized_z;
};

EightWideNode load_eight_wide_node(uint record) {
    WideNode first = load_nodes(record);
    uvec4 z = floatBitsToUint(load_nodes(record + 1u).origin);
    return EightWideNode(first.origin, first.quantized_xy, first.quantized_z_kinds, first.links, z);
}

// Where the ray enters slots 0-3 (low) and 4-7 (high) within (0, t_max), or +infinity for a slot
// it misses and an empty one; the planes as wide_child_entries computes them (bvh.glsl), whose
// comments say why they never cull a child the ray meets.
void eight_wide_entries(EightWideNode node, vec3 o, vec3 inv_d, float t_max, out vec4 low, out vec4 high) {
    uvec3 exponents = child_bytes(floatBitsToUint(node.origin.w)).xyz;
    vec3 from = (node.origin.xyz - o) * inv_d;
    vec3 per_step = uintBitsToFloat(exponents << 23u) * inv_d;
    bvec3 ascending = greaterThanEqual(inv_d, vec3(0.0));
    // Per axis the near bounds' words (low slots, high slots), then the far bounds'.
    uvec4 x = ascending.x ? node.quantized_x : node.quantized_x.zwxy;
    uvec4 y = ascending.y ? node.quantized_y : node.quantized_y.zwxy;
    uvec4 z = ascending.z ? node.quantized_z : node.quantized_z.zwxy;
    vec4 enter_low = max(max(child_planes(x.x, from.x, per_step.x), child_planes(y.x, from.y, per_step.y)),
                         max(child_planes(z.x, from.z, per_step.z), vec4(0.0)));
    vec4 enter_high = max(max(child_planes(x.y, from.x, per_step.x), child_planes(y.y, from.y, per_step.y)),
                          max(child_planes(z.y, from.z, per_step.z), vec4(0.0)));
    vec4 leave_low = min(min(child_planes(x.z, from.x, per_step.x), child_planes(y.z, from.y, per_step.y)),
                         min(child_planes(z.z, from.z, per_step.z), vec4(t_max))) * 1.0000004;
    vec4 leave_high = min(min(child_planes(x.w, from.x, per_step.x), child_planes(y.w, from.y, per_step.y)),
                          min(child_planes(z.w, from.z, per_step.z), vec4(t_max))) * 1.0000004;
    uint present = node.links.w >> 8u;
    bvec4 present_low = notEqual((uvec4(present) >> uvec4(0u, 1u, 2u, 3u)) & 1u, uvec4(0u));
    bvec4 present_high = notEqual((uvec4(present) >> uvec4(4u, 5u, 6u, 7u)) & 1u, uvec4(0u));
    bvec4 entered_low = bvec4(uvec4(lessThanEqual(enter_low, leave_low)) & uvec4(present_low));
    bvec4 entered_high = bvec4(uvec4(lessThanEqual(enter_high, leave_high)) & uvec4(present_high));
    low = mix(vec4(MISSED_BOX), enter_low, entered_low);
    high = mix(vec4(MISSED_BOX), enter_high, entered_high);
}

// The primitives of the leaf slots before `slot`: the sum of the nibbles of `counts` below it.
uint leaf_offset(uint counts, uint slot) {
    uint below = slot == 0u ? 0u : counts & (0xffffffffu >> (32u - 4u * slot));
    uint pairs = (below & 0x0f0f0f0fu) + ((below >> 4u) & 0x0f0f0f0fu);
    return (pairs * 0x01010101u) >> 24u;
}

// As walk_instance (bvh.glsl), over eight-wide nodes: from the root record `root`, with the ray
// (ro, rd) in the instance's object space, keeping the nearest hit before hit.t; true when any_hit
// and it was hit. Each node's children are taken farthest first in the ray's octant order: slot
// k ^ octant is the k-th nearest, roughly (eight_wide.rs, octant_slots), with no sorting. Leaf
// children are intersected at once, the nearest interior child is the next node and the others go
// on the stack with where the ray enters them, which culls them once a nearer hit is found: the
// order only changes the speed, never the hit.
bool walk_instance_eight_wide(uint root, uint instance, uint instance_kind, vec3 ro, vec3 rd, bool any_hit, inout Hit hit) {
    vec3 inv_d = safe_inverse(rd);
    // Bit a set where the ray goes toward -a: the slots' sides are numbered so (eight_wide.rs).
    uint octant = uint(inv_d.x < 0.0) | (uint(inv_d.y < 0.0) << 1u) | (uint(inv_d.z < 0.0) << 2u);
    uint stack[EIGHT_WIDE_STACK_SIZE];
    uint sp = 0u;
    stack[sp++] = stack_entry(root, 0.0);
    while (true) {
        LOOP_ITERATION();
        if (sp == 0u) break;
        uint entry = stack[--sp];
        if (entry_bound(entry) > hit.t) continue;
        uint node_index = entry_node(entry);
        while (true) {
            LOOP_ITERATION();
            EightWideNode node = load_eight_wide_node(node_index);
            vec4 low, high;
            eight_wide_entries(node, ro, inv_d, hit.t, low, high);
            uint interior = node.links.w & 0xffu;
            uint next = NO_INDEX;
            float t_next = 0.0;
            for (uint k = 8u; k > 0u; --k) {
                LOOP_ITERATION();
                uint slot = (k - 1u) ^ octant;
                float t_slot = slot < 4u ? low[slot] : high[slot - 4u];
                if (t_slot == MISSED_BOX || t_slot > hit.t) continue;
                if ((interior & (1u << slot)) != 0u) {
                    if (next != NO_INDEX) stack[sp++] = stack_entry(next, t_next);
                    next = node.links.x + EIGHT_WIDE_RECORDS * uint(bitCount(interior & ((1u << slot) - 1u)));
                    t_next = t_slot;
                } else {
                    uint first = node.links.y + leaf_offset(node.links.z, slot);
                    uint count = (node.links.z >> (4u * slot)) & 0xfu;
                    if (leaf_hit(first, count, instance, instance_kind, ro, rd, any_hit, hit)) return true;
                }
            }
            if (next == NO_INDEX) break;
            node_index = next;
        }
    }
    return false;
}
