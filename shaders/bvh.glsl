// Two-level BVH traversal (layout in src/bvh and src/render/acceleration.rs). Node 0 is the root of
// the top-level BVH, whose leaves list instances; each instance points at the root of its own
// bottom-level BVH in the same node array. One explicit stack serves both levels: a top-level leaf
// pushes its instances as tagged entries, and popping one transforms the ray into the instance's
// object space until the stack falls back below that entry. A scene with one instance skips the
// top level.
// BVH_MAX_DEPTH and BVH_MAX_LEAF_SIZE are injected by the host from the builder's bounds.

const uint NO_INDEX = 0xffffffffu;
const uint INSTANCE_ENTRY = 0x80000000u;
// The first entry, pending far children of the top level, one leaf's instances, then the bottom level's.
const uint STACK_SIZE = 2u * BVH_MAX_DEPTH + BVH_MAX_LEAF_SIZE + 2u;

struct Hit {
    float t;
    uint prim;      // index into prims (group instance) or mesh_triangles (mesh instance)
    uint instance;
    vec2 bary;      // barycentric (u, v) on a mesh triangle
};

// Slab test against [bmin, bmax]; true when the box overlaps (0, t_max).
bool ray_box(vec3 bmin, vec3 bmax, vec3 o, vec3 inv_d, float t_max) {
    vec3 t0 = (bmin - o) * inv_d;
    vec3 t1 = (bmax - o) * inv_d;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    // The factor (1 + 2 gamma_3) keeps rounding from culling a box the ray grazes (pbrt-v4, 6.8).
    float leave = min(min(tf.x, tf.y), min(tf.z, t_max)) * 1.0000004;
    return enter <= leave;
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

vec3 vertex_position(uint v) {
    return vec3(load_vertex_positions(3u * v), load_vertex_positions(3u * v + 1u), load_vertex_positions(3u * v + 2u));
}

// Closest hit along o + t d with 0 < t < t_max. With any_hit, returns at the first hit found (shadow rays).
// The object-space ray keeps the world parameter t: its direction is transformed, not renormalised.
bool trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, out Hit hit) {
    hit.t = t_max;
    hit.prim = NO_INDEX;
    hit.instance = NO_INDEX;
    hit.bary = vec2(0.0);
    if (frame.node_count == 0u) return false;  // empty scene: no root node to test
    vec3 ro = o;
    vec3 rd = d;
    vec3 world_inv_d = safe_inverse(d);
    vec3 inv_d = world_inv_d;
    uint stack[STACK_SIZE];
    uint sp = 0u;
    uint instance = NO_INDEX;  // the instance whose bottom level is being walked
    uint instance_kind = INSTANCE_PRIMITIVES;
    uint instance_sp = 0u;     // stack height when it was entered
    // Start at the top-level root, or with a single instance, in that instance right away.
    stack[sp++] = frame.instance_count == 1u ? INSTANCE_ENTRY : 0u;
    while (true) {
        LOOP_ITERATION();
        // Next entry: leave the instance once its part of the stack is used up.
        if (instance != NO_INDEX && sp == instance_sp) {
            if (instance_kind == INSTANCE_MESH) {
                ro = o;
                rd = d;
                inv_d = world_inv_d;
            }
            instance = NO_INDEX;
        }
        if (sp == 0u) break;
        uint entry = stack[--sp];
        uint node_index = entry;
        if ((entry & INSTANCE_ENTRY) != 0u) {
            instance = entry & ~INSTANCE_ENTRY;
            uvec4 info = instances[instance].info;
            instance_kind = info.x;
            instance_sp = sp;
            // The scene's own shapes are placed by the identity: keep the world ray (loads are
            // what costs, on lavapipe most of all).
            if (instance_kind == INSTANCE_MESH) {
                vec4 world_to_object[3] = instances[instance].world_to_object;
                ro = affine_point(world_to_object, o);
                rd = affine_vector(world_to_object, d);
                inv_d = safe_inverse(rd);
            }
            node_index = info.y;
        }
        // Walk down from this node, nearer child first, until a leaf or a miss.
        while (true) {
            LOOP_ITERATION();
            BvhNode node = load_nodes(node_index);
            if (!ray_box(node.bmin, node.bmax, ro, inv_d, hit.t)) break;
            uint count = node.meta >> 2u;
            if (count == 0u) {
                uint axis = node.meta & 3u;
                bool second_first = rd[axis] < 0.0;
                stack[sp++] = second_first ? node_index + 1u : node.offset;
                node_index = second_first ? node.offset : node_index + 1u;
                continue;
            }
            if (instance == NO_INDEX) {
                for (uint i = 0u; i < count; ++i) {
                    LOOP_ITERATION();
                    stack[sp++] = INSTANCE_ENTRY | (node.offset + i);
                }
            } else if (instance_kind == INSTANCE_MESH) {
                for (uint i = node.offset; i < node.offset + count; ++i) {
                    LOOP_ITERATION();
                    uvec4 tri = load_mesh_triangles(i);
                    vec3 v0 = vertex_position(tri.x);
                    vec2 bary;
                    float t = intersect_triangle(v0, vertex_position(tri.y) - v0, vertex_position(tri.z) - v0, ro, rd, hit.t, bary);
                    if (t > 0.0) {
                        hit = Hit(t, i, instance, bary);
                        if (any_hit) return true;
                    }
                }
            } else {
                for (uint i = node.offset; i < node.offset + count; ++i) {
                    LOOP_ITERATION();
                    float t = intersect_primitive(prims[i], ro, rd, hit.t);
                    if (t > 0.0) {
                        hit = Hit(t, i, instance, vec2(0.0));
                        if (any_hit) return true;
                    }
                }
            }
            break;
        }
    }
    return hit.prim != NO_INDEX;
}

bool occluded(vec3 o, vec3 d, float t_max) {
    Hit ignored;
    return trace_ray(o, d, t_max, true, ignored);
}
