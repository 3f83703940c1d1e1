// Flattened BVH traversal (layout in src/bvh): explicit stack, nearer child first.
// BVH_MAX_DEPTH is injected by the host from bvh::MAX_DEPTH, which the builder guarantees.

struct Hit {
    float t;
    uint prim;
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

// Closest hit along o + t d with 0 < t < t_max. With any_hit, returns at the first hit found (shadow rays).
bool trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, out Hit hit) {
    hit.t = t_max;
    hit.prim = 0xffffffffu;
    if (frame.env_size.w == 0u) return false;  // empty scene: no root node to test
    vec3 inv_d = safe_inverse(d);
    uint stack[BVH_MAX_DEPTH + 1];
    uint sp = 0u;
    uint node_index = 0u;
    while (true) {
        BvhNode node = nodes[node_index];
        if (ray_box(node.bmin, node.bmax, o, inv_d, hit.t)) {
            uint count = node.meta >> 2u;
            if (count == 0u) {
                // Interior: descend into the child on the ray's near side, keep the other.
                uint axis = node.meta & 3u;
                bool second_first = d[axis] < 0.0;
                stack[sp++] = second_first ? node_index + 1u : node.offset;
                node_index = second_first ? node.offset : node_index + 1u;
                continue;
            }
            for (uint i = node.offset; i < node.offset + count; ++i) {
                float t = intersect_primitive(prims[i], o, d, hit.t);
                if (t > 0.0) {
                    hit.t = t;
                    hit.prim = i;
                    if (any_hit) return true;
                }
            }
        }
        if (sp == 0u) break;
        node_index = stack[--sp];
    }
    return hit.prim != 0xffffffffu;
}

bool occluded(vec3 o, vec3 d, float t_max) {
    Hit ignored;
    return trace_ray(o, d, t_max, true, ignored);
}
