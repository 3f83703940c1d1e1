// Two-level BVH traversal (layout in src/bvh and src/render/acceleration.rs). Node 0 is the root of
// the top-level BVH, whose leaves list instances; each instance points at the root of its own
// bottom-level BVH in the same node array. One explicit stack serves both levels: a top-level leaf
// pushes its instances as tagged entries, and popping one transforms the ray into the instance's
// object space until the stack falls back below that entry. A scene with one instance skips the
// top level.
// Both levels are pair nodes (two children's boxes a node). The top level has one instance a leaf.
// BVH_MAX_DEPTH is injected by the host from the builder's bound.

const uint NO_INDEX = 0xffffffffu;
const uint INSTANCE_ENTRY = 0x80000000u;
const float MISSED_BOX = uintBitsToFloat(0x7f800000u);  // +infinity
// Each node visit leaves at most one entry behind (the farther child; at the top level the nearer
// is taken back at once): at most one a level of each BVH, plus the first entry and the nearer.
const uint STACK_SIZE = 2u * BVH_MAX_DEPTH + 2u;

struct Hit {
    float t;
    uint prim;      // index into prims (group instance) or mesh_triangles (mesh instance)
    uint instance;
    vec2 bary;      // barycentric (u, v) on a mesh triangle
};

// Where the ray enters [bmin, bmax] within (0, t_max), or +infinity when it misses the box.
float box_entry(vec3 bmin, vec3 bmax, vec3 o, vec3 inv_d, float t_max) {
    vec3 t0 = (bmin - o) * inv_d;
    vec3 t1 = (bmax - o) * inv_d;
    vec3 tn = min(t0, t1);
    vec3 tf = max(t0, t1);
    float enter = max(max(tn.x, tn.y), max(tn.z, 0.0));
    // The factor (1 + 2 gamma_3) keeps rounding from culling a box the ray grazes (pbrt-v4, 6.8).
    float leave = min(min(tf.x, tf.y), min(tf.z, t_max)) * 1.0000004;
    return enter <= leave ? enter : MISSED_BOX;
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
    stack[sp++] = SCENE_TOP_LEVEL == 0 || frame.instance_count == 1u ? INSTANCE_ENTRY : 0u;
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
            instance_kind = SCENE_MESHES == 0 ? INSTANCE_PRIMITIVES : SCENE_PRIMITIVES == 0 ? INSTANCE_MESH : info.x;
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
        // Walk down from this node: test both children, visit a leaf child at once, go on to the
        // nearer interior child and leave the farther one on the stack.
        while (true) {
            LOOP_ITERATION();
            PairNode node = load_nodes(node_index);
            float t_a = box_entry(node.a_min.xyz, node.a_max.xyz, ro, inv_d, hit.t);
            float t_b = box_entry(node.b_min.xyz, node.b_max.xyz, ro, inv_d, hit.t);
            uvec2 a = floatBitsToUint(vec2(node.a_min.w, node.a_max.w));  // link, primitive count
            uvec2 b = floatBitsToUint(vec2(node.b_min.w, node.b_max.w));
            if (t_b < t_a) {
                uvec2 c = a; a = b; b = c;
                float t = t_a; t_a = t_b; t_b = t;
            }
#if SCENE_TOP_LEVEL
            if (instance == NO_INDEX) {
                // Top level: every leaf is one instance (the host builds it so). Leave the farther
                // child, then the nearer, on the stack and take the nearer from there: entering an
                // instance happens when its entry is popped.
                if (t_b <= hit.t) stack[sp++] = b.y == 0u ? b.x : INSTANCE_ENTRY | b.x;
                if (t_a <= hit.t) stack[sp++] = a.y == 0u ? a.x : INSTANCE_ENTRY | a.x;
                break;
            }
#endif
            uint next = NO_INDEX;
            for (uint k = 0u; k < 2u; ++k) {
                LOOP_ITERATION();
                // A hit in the nearer child's leaf may put the farther child out of reach; a missed
                // box enters at +infinity, so the same test skips it.
                if ((k == 0u ? t_a : t_b) > hit.t) break;
                uvec2 child = k == 0u ? a : b;
                uint first = child.x;
                uint count = child.y;
                if (count == 0u) {
                    if (next == NO_INDEX) next = first; else stack[sp++] = first;
                } else if (SCENE_MESHES == 1 && (SCENE_PRIMITIVES == 0 || instance_kind == INSTANCE_MESH)) {
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
                } else if (SCENE_PRIMITIVES == 1) {
                    for (uint i = first; i < first + count; ++i) {
                        LOOP_ITERATION();
                        float t = intersect_primitive(prims[i], ro, rd, hit.t);
                        if (t > 0.0) {
                            hit = Hit(t, i, instance, vec2(0.0));
                            if (any_hit) return true;
                        }
                    }
                }
            }
            if (next == NO_INDEX) break;
            node_index = next;
        }
    }
    return hit.prim != NO_INDEX;
}

bool occluded(vec3 o, vec3 d, float t_max) {
    Hit ignored;
    return trace_ray(o, d, t_max, true, ignored);
}
