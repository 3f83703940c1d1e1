// Two-level BVH traversal (layout in src/bvh and src/render/acceleration.rs). Node 0 is the root of
// the top-level BVH, whose leaves list instances; each instance points at the root of its own
// bottom-level BVH in the same node array. Each instance the ray enters is walked to its end by
// walk_instance, in the instance's object space, before the top level goes on. The top level is
// compiled for the scene (src/render/features.rs): a scene of one instance has none
// (SCENE_TOP_LEVEL 0); a scene whose top level is its root alone tests the instances as that
// node's children and walks them in turn (SCENE_TOP_LEVEL_TREE 0); any other walks the top level
// with a stack of its own, its leaves' instances tagged.
// Both levels are wide nodes (up to four children's quantized boxes a node, layout.glsl), or with
// BVH_WIDTH 8 the bottom levels are eight-wide (bvh_eight_wide.glsl). The top level has one
// instance a leaf. BVH_MAX_DEPTH is injected by the host from the builder's bound on
// the binary tree; each wide level takes at least one binary level (src/bvh/wide_node.rs).
// A scene's few shapes (SCENE_FEW_SHAPES, at most FEW_PRIMITIVES of src/render/features.rs) are
// tested in turn, as straight-line code, before any walk: a scene of nothing else compiles no walk
// at all (SCENE_BVH 0), and a scene with meshes walks them alone (SCENE_WALKED_SHAPES 0), skipping
// the shapes' instance, with t_max already cut to the nearest shape.

const uint NO_INDEX = 0xffffffffu;
const uint INSTANCE_ENTRY = 0x80000000u;
const float MISSED_BOX = uintBitsToFloat(0x7f800000u);  // +infinity
// Each node visit leaves at most three entries behind (the children other than the nearest; at the
// top level the nearest is taken back at once): at most three a wide level of the BVH a stack
// walks, whose levels number at most BVH_MAX_DEPTH + 1, plus the first entry.
const uint STACK_SIZE = 3u * (BVH_MAX_DEPTH + 1u) + 1u;

// A walk's stack entry: a node's index in the low bits, as many as the scene's node count needs,
// and above them the top bits of the distance where the ray enters the node (a float of at least
// zero, whose sign bit is 0), which read back as a float no larger. A node popped after the walk
// found a hit nearer than that is left without loading it: the hit culls far siblings that a
// node's own visit would only have culled after loading it (bunny under a sky, Mesa 25: 1.068x,
// docs/benchmarks/history.md, 2026-12-06, `6bd217d`). Node arrays hold fewer than 2^31 nodes (64 bytes each), so at
// least one bit of the distance is kept. Only walks call these, and a scene walks only where it has
// a node (trace_ray and queue_ray return first where frame.node_count is 0).
uint entry_index_bits() {
    return min(uint(findMSB(frame.node_count)) + 1u, 31u);
}

uint stack_entry(uint node, float t_entry) {
    uint bits = entry_index_bits();
    return ((floatBitsToUint(t_entry) >> (bits - 1u)) << bits) | node;
}

uint entry_node(uint entry) {
    uint bits = entry_index_bits();
    return entry & ((1u << bits) - 1u);
}

// At most the distance the entry was made with.
float entry_bound(uint entry) {
    uint bits = entry_index_bits();
    return uintBitsToFloat((entry >> bits) << (bits - 1u));
}

struct Hit {
    float t;
    uint prim;      // index into prims (group instance) or mesh_triangles (mesh instance)
    uint instance;
    vec2 bary;      // barycentric (u, v) on a mesh triangle
};

// Each byte of `word` as a lane: child k's in lane k.
uvec4 child_bytes(uint word) {
    return (uvec4(word) >> uvec4(0u, 8u, 16u, 24u)) & 0xffu;
}

// Where the ray meets the four children's planes along one axis whose bounds `word` packs (steps
// from the node's origin), from = the origin's plane and per_step = one step, both in t.
vec4 child_planes(uint word, float from, float per_step) {
    return from + vec4(child_bytes(word)) * per_step;
}

// Where the ray enters each of the node's four children within (0, t_max), or +infinity for a
// child it misses and for an empty slot. The four boxes are decoded and tested side by side: one
// node's loads serve them all.
vec4 wide_child_entries(WideNode node, vec3 o, vec3 inv_d, float t_max) {
    uvec3 exponents = child_bytes(floatBitsToUint(node.origin.w)).xyz;
    vec3 quantum = uintBitsToFloat(exponents << 23u);
    // A child's plane at t = (origin + steps * quantum - o) * inv_d = from + steps * per_step: one
    // multiply-add a plane. Where the ray starts inside the node, from and steps * per_step cancel
    // and the sum is off by a few ulps of the node's size, not of the child's; the host keeps every
    // stored bound at least 1/64 quantum outside the exact one (src/bvh/wide_node.rs, MARGIN), a
    // thousand times more, and a bound at step 0 is the origin's plane, computed as exactly as the
    // float boxes' slab test was.
    vec3 from = (node.origin.xyz - o) * inv_d;
    vec3 per_step = quantum * inv_d;
    // Each axis's near and far planes picked by the direction's sign, before the bytes are
    // decoded: one select a word instead of a min and a max a child.
    uvec3 min_words = uvec3(node.quantized_xy.x, node.quantized_xy.z, node.quantized_z_kinds.x);
    uvec3 max_words = uvec3(node.quantized_xy.y, node.quantized_xy.w, node.quantized_z_kinds.y);
    bvec3 ascending = greaterThanEqual(inv_d, vec3(0.0));
    uvec3 near_words = mix(max_words, min_words, ascending);
    uvec3 far_words = mix(min_words, max_words, ascending);
    vec4 near_x = child_planes(near_words.x, from.x, per_step.x);
    vec4 near_y = child_planes(near_words.y, from.y, per_step.y);
    vec4 near_z = child_planes(near_words.z, from.z, per_step.z);
    vec4 far_x = child_planes(far_words.x, from.x, per_step.x);
    vec4 far_y = child_planes(far_words.y, from.y, per_step.y);
    vec4 far_z = child_planes(far_words.z, from.z, per_step.z);
    vec4 enter = max(max(near_x, near_y), max(near_z, vec4(0.0)));
    // The factor (1 + 2 gamma_3) keeps rounding from culling a box the ray grazes (pbrt-v4, 6.8).
    vec4 leave = min(min(far_x, far_y), min(far_z, vec4(t_max))) * 1.0000004;
    bvec4 present = notEqual(child_bytes(node.quantized_z_kinds.z), uvec4(WIDE_CHILD_NONE));
    bvec4 entered = bvec4(uvec4(lessThanEqual(enter, leave)) & uvec4(present));
    return mix(vec4(MISSED_BOX), enter, entered);
}

// Orders the pair (t_a, a), (t_b, b) by entry distance.
void order_children(inout float t_a, inout uvec2 a, inout float t_b, inout uvec2 b) {
    if (t_b < t_a) {
        float t = t_a; t_a = t_b; t_b = t;
        uvec2 c = a; a = b; b = c;
    }
}

// The k-th of four children (k from 1), by selects rather than an array a loop indexes.
uvec2 kth_child(uint k, uvec2 c0, uvec2 c1, uvec2 c2, uvec2 c3) {
    return k == 4u ? c3 : k == 3u ? c2 : k == 2u ? c1 : c0;
}

// The k-th of four children's entry distances (k from 1), as kth_child.
float kth_entry(uint k, float t0, float t1, float t2, float t3) {
    return k == 4u ? t3 : k == 3u ? t2 : k == 2u ? t1 : t0;
}

// Node `node_index`'s children as the ray enters them within (0, t_max), nearest first: their
// entries (+infinity for a child missed) and (link, kind) pairs, sorted by a sorting network.
// Returns how many are entered.
uint sorted_children(uint node_index, vec3 ro, vec3 inv_d, float t_max, out float t0, out float t1, out float t2, out float t3, out uvec2 c0, out uvec2 c1, out uvec2 c2, out uvec2 c3) {
    WideNode node = load_nodes(node_index);
    vec4 entries = wide_child_entries(node, ro, inv_d, t_max);
    uvec4 kinds = child_bytes(node.quantized_z_kinds.z);
    t0 = entries.x, t1 = entries.y, t2 = entries.z, t3 = entries.w;
    c0 = uvec2(node.links.x, kinds.x), c1 = uvec2(node.links.y, kinds.y);
    c2 = uvec2(node.links.z, kinds.z), c3 = uvec2(node.links.w, kinds.w);
    order_children(t0, c0, t1, c1);
    order_children(t2, c2, t3, c3);
    order_children(t0, c0, t2, c2);
    order_children(t1, c1, t3, c3);
    order_children(t1, c1, t2, c2);
    return uint(t0 != MISSED_BOX) + uint(t1 != MISSED_BOX) + uint(t2 != MISSED_BOX) + uint(t3 != MISSED_BOX);
}

// Node `node_index`'s children as sorted_children gives them, but in their stored order: entries
// (+infinity for a child missed or an empty slot) and (link, kind) pairs, for a shadow ray's walk
// with SHADOW_WALK_UNSORTED (src/render/shadow_walk.rs). Returns 4: a missed child is told by its
// entry, not by its place.
uint unsorted_children(uint node_index, vec3 ro, vec3 inv_d, float t_max, out float t0, out float t1, out float t2, out float t3, out uvec2 c0, out uvec2 c1, out uvec2 c2, out uvec2 c3) {
    WideNode node = load_nodes(node_index);
    vec4 entries = wide_child_entries(node, ro, inv_d, t_max);
    uvec4 kinds = child_bytes(node.quantized_z_kinds.z);
    t0 = entries.x, t1 = entries.y, t2 = entries.z, t3 = entries.w;
    c0 = uvec2(node.links.x, kinds.x), c1 = uvec2(node.links.y, kinds.y);
    c2 = uvec2(node.links.z, kinds.z), c3 = uvec2(node.links.w, kinds.w);
    return 4u;
}

// Zero direction components would make 0 * inf = NaN in the slab test; nudge them.
vec3 safe_inverse(vec3 d) {
    const float tiny = 1e-30;
    return 1.0 / vec3(abs(d.x) > tiny ? d.x : tiny, abs(d.y) > tiny ? d.y : tiny, abs(d.z) > tiny ? d.z : tiny);
}

vec3 affine_point(vec4 rows[3], vec3 p) {
    return vec3(dot(rows[0].xyz, p) + rows[0].w, dot(rows[1].xyz, p) + rows[1].w, dot(rows[2].xyz, p) + rows[2].w);
}

vec3 affine_vector(vec4 rows[3], vec3 v) {
    return vec3(dot(rows[0].xyz, v), dot(rows[1].xyz, v), dot(rows[2].xyz, v));
}

// Tests shape `i` (of `instance`, its kind `kind`) against the ray, keeping the nearest hit before
// hit.t. True when any_hit and it was hit: the caller returns at once.
bool intersect_shape(uint kind, Primitive p, uint i, uint instance, vec3 o, vec3 d, bool any_hit, inout Hit hit) {
    float t = intersect_primitive_as(kind, p, o, d, hit.t);
    if (t <= 0.0) return false;
    hit = Hit(t, i, instance, vec2(0.0));
    return any_hit;
}

// The scene's shapes first..first + count (of `instance`), as intersect_shape.
bool intersect_shapes(uint first, uint count, uint instance, vec3 o, vec3 d, bool any_hit, inout Hit hit) {
    for (uint i = first; i < first + count; ++i) {
        LOOP_ITERATION();
        Primitive p = prims[i];
        if (intersect_shape(prim_kind(p), p, i, instance, o, d, any_hit, hit)) return true;
    }
    return false;
}

// The host lists the scene's few shapes in SCENE_FEW_SHAPES, one FEW_SHAPE(index, kind) each in
// stored (leaf) order, so that each is straight-line code of its own kind's test: no loop, and no
// switch on the kind, every case of which Mesa 22.3 would run for each shape (docs/benchmarks/history.md,
// 2026-12-01 (`7e4cc16`)). Their hits are in the shapes' own instance.
#define FEW_SHAPE(i, kind) if (intersect_shape(kind, prims[i], i, frame.shape_instance, o, d, any_hit, hit)) return true;

// The scene's few shapes against the ray, as intersect_shape: true when any_hit and one was hit.
bool few_shapes_hit(vec3 o, vec3 d, bool any_hit, inout Hit hit) {
    SCENE_FEW_SHAPES
    return false;
}

#if SCENE_BVH == 0
// Closest hit along o + t d with 0 < t < t_max, in a scene of a few shapes and nothing else
// (src/render/features.rs, FEW_PRIMITIVES). With any_hit, returns at the first hit found. The
// shapes are tested one after another, all lanes of a subgroup on the same shape at once, which
// lavapipe loads once for all of them; a walk loads each lane's own node and leaves, and keeps a
// stack (docs/benchmarks/history.md, "few shapes").
bool trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, out Hit hit) {
    hit = Hit(t_max, NO_INDEX, NO_INDEX, vec2(0.0));
    SCENE_FEW_SHAPES
    return hit.prim != NO_INDEX;
}
#elif SCENE_RAY_QUERY == 1
// The device's ray queries in place of the walk below (src/gpu/traversal.rs).
#include "ray_query.glsl"
#else
// Intersects a leaf's `count` records from `first` (triangles of a placed mesh, or shapes), with
// the ray (ro, rd) in the instance's object space, keeping the nearest hit before hit.t. True
// when any_hit and one was hit: the walk ends there.
bool leaf_hit(uint first, uint count, uint instance, uint instance_kind, vec3 ro, vec3 rd, bool any_hit, inout Hit hit) {
    if (SCENE_MESHES == 1 && (SCENE_WALKED_SHAPES == 0 || instance_kind == INSTANCE_MESH)) {
        for (uint i = first; i < first + count; ++i) {
            LOOP_ITERATION();
            MeshTriangle tri = load_mesh_triangles(i);
            vec2 bary;
            float t = intersect_triangle(tri.v0.xyz, tri.e1.xyz, tri.e2.xyz, ro, rd, hit.t, bary);
            if (t > 0.0) {
                if (SCENE_ALPHA == 1 && !alpha_passes(tri, i, instance, bary, ro, rd)) continue;
                hit = Hit(t, i, instance, bary);
                if (any_hit) return true;
            }
        }
    } else if (SCENE_WALKED_SHAPES == 1) {
        return intersect_shapes(first, count, instance, ro, rd, any_hit, hit);
    }
    return false;
}

// Walks one instance's BVH from its root node `root`, with the ray (ro, rd) already in the
// instance's object space, keeping the nearest hit before hit.t. True when any_hit and it was
// hit: the caller returns at once. The walk knows nothing of instances, their transforms or the
// top level: every scene walks its meshes with this loop alone, and Mesa 22.3, which runs every
// block of a loop body taken or not (docs/benchmarks/history.md, 2026-12-01, `be8847b`), pays for nothing else in it.
bool walk_instance(uint root, uint instance, uint instance_kind, vec3 ro, vec3 rd, bool any_hit, inout Hit hit) {
    vec3 inv_d = safe_inverse(rd);
    uint stack[STACK_SIZE];
    uint sp = 0u;
    stack[sp++] = stack_entry(root, 0.0);
    while (true) {
        LOOP_ITERATION();
        if (sp == 0u) break;
        uint entry = stack[--sp];
        if (entry_bound(entry) > hit.t) continue;
        uint node_index = entry_node(entry);
        // Walk down from this node: test its children, intersect leaf children at once, go on to
        // the nearest interior child and leave the others on the stack, nearer on top.
        while (true) {
            LOOP_ITERATION();
            float t0, t1, t2, t3;
            uvec2 c0, c1, c2, c3;
#if SHADOW_WALK_UNSORTED
            // A shadow ray takes the children as stored (shadow_walk.rs); a missed child's entry
            // is +infinity, past its hit.t unless that is infinite too, where a missed child is
            // visited for nothing (its own boxes are missed in turn) but never gives a hit.
            uint entered = any_hit ? unsorted_children(node_index, ro, inv_d, hit.t, t0, t1, t2, t3, c0, c1, c2, c3)
                                   : sorted_children(node_index, ro, inv_d, hit.t, t0, t1, t2, t3, c0, c1, c2, c3);
#else
            uint entered = sorted_children(node_index, ro, inv_d, hit.t, t0, t1, t2, t3, c0, c1, c2, c3);
#endif
            // Children farthest first: leaves are intersected, interior children left on the
            // stack, so that the nearest becomes the next node and the nearer of the rest lie on
            // top. One loop over the children in this order measured faster on lavapipe than a
            // nearest-first pass over the leaves and a second, farthest-first, over the rest
            // (docs/benchmarks/history.md): a leaf's hit can no longer cull a farther sibling in the same
            // node, but fewer loops run in step.
            uint next = NO_INDEX;
            float t_next = 0.0;
            // Child k (from 1) of the entered, its entry t_k and (link, kind) c.
#define WALK_CHILD(k, t_k, c) \
            if (k <= entered && t_k <= hit.t) { \
                if (c.y == WIDE_CHILD_INTERIOR) { \
                    if (next != NO_INDEX) stack[sp++] = stack_entry(next, t_next); \
                    next = c.x; \
                    t_next = t_k; \
                } else if (leaf_hit(c.x, c.y, instance, instance_kind, ro, rd, any_hit, hit)) { \
                    return true; \
                } \
            }
#if WALK_CHILDREN_UNROLLED
            // Four straight-line steps, each its child's own variables: no loop and no selects of
            // kth_child (Mesa 25: 1.046x on the bunny under a sky, docs/benchmarks/history.md, 2026-12-06, `ee3ce82`).
            WALK_CHILD(4u, t3, c3)
            WALK_CHILD(3u, t2, c2)
            WALK_CHILD(2u, t1, c1)
            WALK_CHILD(1u, t0, c0)
#else
            // A loop: Mesa 22.3 runs every block of a loop body whether a lane takes it or not,
            // and would run four leaf tests a node (0.74-0.78x unrolled there).
            for (uint k = entered; k > 0u; --k) {
                LOOP_ITERATION();
                float t_k = kth_entry(k, t0, t1, t2, t3);
                uvec2 c = kth_child(k, c0, c1, c2, c3);
                WALK_CHILD(k, t_k, c)
            }
#endif
#undef WALK_CHILD
            if (next == NO_INDEX) break;
            node_index = next;
        }
    }
    return false;
}

#if BVH_WIDTH == 8
// The meshes' and shapes' own BVHs as eight-wide nodes (bvh-width=8): walk_instance_eight_wide.
#include "bvh_eight_wide.glsl"
#endif

// Walks instance `instance` with the world ray o + t d, as walk_instance: in its object space
// where it is a placed mesh (the object-space ray keeps the world parameter t: its direction is
// transformed, not renormalised). The scene's own shapes are placed by the identity and keep the
// world ray (loads are what costs, on lavapipe most of all); where they were tested before any
// walk, their instance is not walked again.
// Instance `instance`'s kind, and the world ray o + t d in its space (ro, rd), as walk_placed walks it.
uint placed_ray(uint instance, uvec4 info, vec3 o, vec3 d, out vec3 ro, out vec3 rd) {
    // Where the scene has meshes and no walked shapes every walked instance is a mesh, and where
    // it has no meshes none is: the kind is known when the kernel is compiled.
    uint instance_kind = SCENE_MESHES == 0 ? INSTANCE_PRIMITIVES : SCENE_WALKED_SHAPES == 0 ? INSTANCE_MESH : info.x;
    ro = o;
    rd = d;
    if (instance_kind == INSTANCE_MESH) {
        vec4 world_to_object[3] = load_instances(instance).world_to_object;
        ro = affine_point(world_to_object, o);
        rd = affine_vector(world_to_object, d);
    }
    return instance_kind;
}

// Whether a walk of `instance` (its `info`) can hit anything the few shapes' tests did not.
bool instance_walked(uvec4 info) {
    return !(SCENE_PRIMITIVES == 1 && SCENE_WALKED_SHAPES == 0 && info.x == INSTANCE_PRIMITIVES);
}

bool walk_placed(uint instance, vec3 o, vec3 d, bool any_hit, inout Hit hit) {
    uvec4 info = load_instances(instance).info;
    if (!instance_walked(info)) return false;
    vec3 ro, rd;
    uint instance_kind = placed_ray(instance, info, o, d, ro, rd);
#if BVH_WIDTH == 8
    return walk_instance_eight_wide(info.y, instance, instance_kind, ro, rd, any_hit, hit);
#else
    return walk_instance(info.y, instance, instance_kind, ro, rd, any_hit, hit);
#endif
}

// Closest hit along o + t d with 0 < t < t_max. With any_hit, returns at the first hit found
// (shadow rays). Each instance the ray enters is walked to the end before the next: the top level
// is walked apart from the instances' BVHs, by a loop of its own or none.
bool trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, out Hit hit) {
    hit = Hit(t_max, NO_INDEX, NO_INDEX, vec2(0.0));
    if (few_shapes_hit(o, d, any_hit, hit)) return true;
    if (frame.node_count == 0u) return hit.prim != NO_INDEX;  // empty scene: no root node to test
#if SCENE_TOP_LEVEL == 0
    // The scene's one instance (at the constant index 0, a load lavapipe makes once for all lanes).
    if (walk_placed(0u, o, d, any_hit, hit)) return true;
#elif SCENE_TOP_LEVEL_TREE == 0
    // The top level is its root alone, every child an instance (src/render/features.rs): the
    // instances the ray enters are walked in turn, nearest first, with no stack of their own,
    // and the rest are left once the hit is nearer than where the ray enters them.
    float t0, t1, t2, t3;
    uvec2 c0, c1, c2, c3;
    uint entered = sorted_children(0u, o, safe_inverse(d), hit.t, t0, t1, t2, t3, c0, c1, c2, c3);
    for (uint k = 1u; k <= entered; ++k) {
        LOOP_ITERATION();
        float t_k = kth_entry(k, t0, t1, t2, t3);
        if (t_k > hit.t) break;
        if (walk_placed(kth_child(k, c0, c1, c2, c3).x, o, d, any_hit, hit)) return true;
    }
#else
    // The top-level walk: its nodes' children go on its own stack, farthest first, instances
    // tagged; an instance is walked when its entry is popped. A scene of one instance (the
    // general kernel's, which serves any scene) starts in that instance.
    vec3 inv_d = safe_inverse(d);
    uint stack[STACK_SIZE];
    uint sp = 0u;
    stack[sp++] = frame.instance_count == 1u ? INSTANCE_ENTRY : 0u;
    while (true) {
        LOOP_ITERATION();
        if (sp == 0u) break;
        uint entry = stack[--sp];
        if ((entry & INSTANCE_ENTRY) != 0u) {
            if (walk_placed(entry & ~INSTANCE_ENTRY, o, d, any_hit, hit)) return true;
            continue;
        }
        float t0, t1, t2, t3;
        uvec2 c0, c1, c2, c3;
        uint entered = sorted_children(entry, o, inv_d, hit.t, t0, t1, t2, t3, c0, c1, c2, c3);
        for (uint k = entered; k > 0u; --k) {
            LOOP_ITERATION();
            uvec2 c = kth_child(k, c0, c1, c2, c3);
            stack[sp++] = c.y == WIDE_CHILD_INTERIOR ? c.x : INSTANCE_ENTRY | c.x;
        }
    }
#endif
    return hit.prim != NO_INDEX;
}
#endif

bool occluded(vec3 o, vec3 d, float t_max) {
    Hit ignored;
    return trace_ray(o, d, t_max, true, ignored);
}
