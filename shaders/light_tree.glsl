// The light tree (src/render/light_tree.rs; `light_selection = "bvh"`): next-event estimation
// picks a light by descending a binary BVH over the lights with one random number, at each node
// taking a child in proportion to its importance at the shading point (power over squared
// distance, zero where the point is outside every direction its lights emit into); directional
// lights are picked beside the tree, each with the share the host stored in its record
// (shape.w), the tree with frame.light_tree_share. The probability of a light is the product of
// the choices on its path; light_tree_pmf recomputes it from the light's leaf up through parent
// links for an emitter hit by BSDF sampling, so that the MIS weights of both strategies come from
// the same pdf. The host's reference (LightTree::pick, LightTree::pmf) runs the same arithmetic;
// tests/light_tree.rs compares the two.
//
// Compiled in only where SCENE_LIGHT_TREE: a scene with one light, or that picks by power or
// uniformly, has no tree walk (but the general kernel, which asks light_tree_picks()). Needs layout.glsl (the `light_tree` and `light_tree_index` arrays,
// `punctual_lights`, `frame`) and loop_limit.glsl.

#if SCENE_LIGHT_TREE

// Whether this scene picks by the tree: always in a kernel built for a scene that does; the
// general kernel, compiled with every feature, asks the frame.
bool light_tree_picks() {
    return frame.light_tree != 0u;
}

// The largest float below 1 (light_tree.rs ONE_MINUS_EPSILON).
const float LIGHT_TREE_ONE_MINUS_EPSILON = 0.99999994;

// Importance of node `n`'s lights at `p` (light_tree.rs `importance`, the same operations):
// power x the cosine bound of the angle between the lights' emission cone and the direction to
// `p`, over the squared distance to the box's centre (at least half its diagonal).
float light_importance(LightTreeNode n, vec3 p) {
    vec3 lo = n.min_phi.xyz, hi = n.max_cos_theta_o.xyz;
    vec3 center = 0.5 * (lo + hi);
    vec3 to_p = p - center;
    float distance2 = dot(to_p, to_p);
    float radius2 = dot(hi - center, hi - center);
    float cos_theta_p = 1.0;
    // Inside the bounding sphere every direction may reach p: no angular bound.
    if (distance2 > radius2) {
        float cos_theta_b = sqrt(max(1.0 - radius2 / distance2, 0.0));
        float sin_theta_b = sqrt(min(radius2 / distance2, 1.0));
        float cos_theta_w = dot(n.axis_cos_theta_e.xyz, to_p / sqrt(distance2));
        if ((n.links.z & LIGHT_TREE_TWO_SIDED) != 0u) cos_theta_w = abs(cos_theta_w);
        float sin_theta_w = sqrt(max(1.0 - cos_theta_w * cos_theta_w, 0.0));
        float cos_theta_o = n.max_cos_theta_o.w;
        float sin_theta_o = sqrt(max(1.0 - cos_theta_o * cos_theta_o, 0.0));
        // theta_x = max(0, theta_w - theta_o), then theta' = max(0, theta_x - theta_b).
        float cos_theta_x = 1.0, sin_theta_x = 0.0;
        if (!(cos_theta_w > cos_theta_o)) {
            cos_theta_x = cos_theta_w * cos_theta_o + sin_theta_w * sin_theta_o;
            sin_theta_x = sin_theta_w * cos_theta_o - cos_theta_w * sin_theta_o;
        }
        cos_theta_p = cos_theta_x > cos_theta_b ? 1.0 : cos_theta_x * cos_theta_b + sin_theta_x * sin_theta_b;
    }
    if (cos_theta_p <= n.axis_cos_theta_e.w) return 0.0;
    vec3 diagonal = hi - lo;
    float clamped = max(distance2, 0.5 * sqrt(dot(diagonal, diagonal)));
    return max(n.min_phi.w * cos_theta_p / clamped, 0.0);
}

// Picks a light for `p` with the random number `u`: its index (area lights, then punctual ones)
// and probability, without the environment map's share. False where no light can light `p`.
bool light_tree_pick(vec3 p, float u, out uint light, out float pmf) {
    light = 0u;
    pmf = 0.0;
    float tree_share = frame.light_tree_share;
    float infinite_total = 1.0 - tree_share;
    if (SCENE_PUNCTUAL_LIGHTS == 1 && u < infinite_total) {
        float sum = 0.0;
        for (uint i = 0u; i < frame.punctual_light_count; ++i) {
            LOOP_ITERATION();
            float share = punctual_lights[i].shape.w;
            if (share > 0.0) {
                sum += share;
                light = frame.light_count + i;
                pmf = share;
                if (u < sum) break;
            }
        }
        return pmf > 0.0;
    }
    if (tree_share <= 0.0) return false;
    u = min((u - infinite_total) / tree_share, LIGHT_TREE_ONE_MINUS_EPSILON);
    pmf = tree_share;
    uint node = 0u;
    for (;;) {
        LOOP_ITERATION();
        LightTreeNode n = light_tree[node];
        if ((n.links.z & LIGHT_TREE_LEAF) != 0u) {
            light = n.links.x;
            return light_importance(n, p) > 0.0;
        }
        float c0 = light_importance(light_tree[node + 1u], p);
        float c1 = light_importance(light_tree[n.links.x], p);
        if (!(c0 + c1 > 0.0)) return false;
        float p0 = c0 / (c0 + c1);
        if (u < p0) {
            u = min(u / p0, LIGHT_TREE_ONE_MINUS_EPSILON);
            pmf *= c0 / (c0 + c1);
            node += 1u;
        } else {
            u = min((u - p0) / (1.0 - p0), LIGHT_TREE_ONE_MINUS_EPSILON);
            pmf *= c1 / (c0 + c1);
            node = n.links.x;
        }
    }
    return false;
}

// The probability that light_tree_pick at `p` gives `light`: a directional light's share, or the
// product of the choices from its leaf up to the root.
float light_tree_pmf(vec3 p, uint light) {
    if (SCENE_PUNCTUAL_LIGHTS == 1 && light >= frame.light_count) {
        float share = punctual_lights[light - frame.light_count].shape.w;
        if (share > 0.0) return share;
    }
    uint node = load_light_tree_index(light);
    if (node == LIGHT_TREE_NONE || light_importance(light_tree[node], p) <= 0.0) return 0.0;
    float pmf = frame.light_tree_share;
    for (;;) {
        LOOP_ITERATION();
        uint parent = light_tree[node].links.y;
        if (parent == LIGHT_TREE_NONE) break;
        uint second = light_tree[parent].links.x;
        float c0 = light_importance(light_tree[parent + 1u], p);
        float c1 = light_importance(light_tree[second], p);
        pmf *= (node == second ? c1 : c0) / (c0 + c1);
        node = parent;
    }
    return pmf;
}

// The area light that a hit on entry `prim` of instance `instance`'s shapes or mesh triangles is
// (src/render/light_tree_index.rs): the instance's first light plus the entry's place among its
// emitters.
uint hit_light(uint instance, uint prim) {
    uint pair = frame.light_count + frame.punctual_light_count + 2u * instance;
    return load_light_tree_index(pair) + load_light_tree_index(load_light_tree_index(pair + 1u) + prim);
}

#endif
