// The ray-query traversal (SCENE_RAY_QUERY, src/gpu/traversal.rs): trace_ray as bvh.glsl's walk
// answers it, from the device's acceleration structures (src/render/ray_query_scene.rs builds
// them) instead of caustica's own BVH. bvh.glsl includes this file in place of its walk; the
// integrator, shading and light sampling are the same code either way.
//
// The top level's instances are the scene's instances in the same order, so the hit's instance
// is the instance index the rest of the kernel reads (`rayQueryGetIntersectionInstanceIdEXT`).
// Each instance's custom index is where its records begin: a mesh's first triangle in
// mesh_triangles, 0 for the scene's own shapes, so the hit's record is that plus the primitive's
// index in its bottom level (built in the records' order).
// - Mesh triangles are the device's triangles, flagged opaque unless their mesh has a material
//   with alpha; a candidate of such a mesh is confirmed where alpha_passes says the surface is
//   there, with the same coin, tossed by the ray in the instance's object space.
// - The scene's own spheres, quads and triangles are boxes: each candidate is intersected by the
//   exact test of intersect.glsl, and its hit generated. A scene's few shapes (SCENE_FEW_SHAPES)
//   are tested before the query, as the walk does, and their instance is masked out of it.
// - Shadow rays (any_hit) end at the first hit confirmed: gl_RayFlagsTerminateOnFirstHitEXT.

// Cull masks (src/render/ray_query_scene.rs): meshes, and the scene's shapes where they are walked.
const uint RAY_QUERY_MESHES = 1u;
const uint RAY_QUERY_SHAPES = 2u;

// Closest hit along o + t d with 0 < t < t_max, as bvh.glsl's trace_ray. With any_hit, returns at
// the first hit found (shadow rays).
bool trace_ray(vec3 o, vec3 d, float t_max, bool any_hit, out Hit hit) {
    hit = Hit(t_max, NO_INDEX, NO_INDEX, vec2(0.0));
    if (few_shapes_hit(o, d, any_hit, hit)) return true;
    if (frame.node_count == 0u) return hit.prim != NO_INDEX;  // empty scene: an empty top level
    uint flags = any_hit ? gl_RayFlagsTerminateOnFirstHitEXT : gl_RayFlagsNoneEXT;
    uint mask = SCENE_WALKED_SHAPES == 1 ? (RAY_QUERY_MESHES | RAY_QUERY_SHAPES) : RAY_QUERY_MESHES;
    rayQueryEXT query;
    // tMin 0: the walk's tests accept any t > 0, and every ray leaves its surface offset already.
    rayQueryInitializeEXT(query, scene_structure, flags, mask, o, 0.0, d, hit.t);
    float t_start = hit.t;
    while (rayQueryProceedEXT(query)) {
        LOOP_ITERATION();
        uint prim = rayQueryGetIntersectionInstanceCustomIndexEXT(query, false) + rayQueryGetIntersectionPrimitiveIndexEXT(query, false);
        vec3 ro = rayQueryGetIntersectionObjectRayOriginEXT(query, false);
        vec3 rd = rayQueryGetIntersectionObjectRayDirectionEXT(query, false);
        if (rayQueryGetIntersectionTypeEXT(query, false) == gl_RayQueryCandidateIntersectionTriangleEXT) {
            // A triangle of a mesh with alpha (the others are opaque and never candidates here).
            if (SCENE_ALPHA == 1) {
                uint instance = rayQueryGetIntersectionInstanceIdEXT(query, false);
                vec2 bary = rayQueryGetIntersectionBarycentricsEXT(query, false);
                if (alpha_passes(load_mesh_triangles(prim), prim, instance, bary, ro, rd)) rayQueryConfirmIntersectionEXT(query);
            } else {
                rayQueryConfirmIntersectionEXT(query);
            }
        } else if (SCENE_WALKED_SHAPES == 1) {
            // A shape's box: its exact test, in the shapes' instance (placed by the identity),
            // before the nearest hit committed so far.
            bool none = rayQueryGetIntersectionTypeEXT(query, true) == gl_RayQueryCommittedIntersectionNoneEXT;
            float t_near = none ? t_start : rayQueryGetIntersectionTEXT(query, true);
            Primitive p = prims[prim];
            float t = intersect_primitive_as(prim_kind(p), p, ro, rd, t_near);
            if (t > 0.0) rayQueryGenerateIntersectionEXT(query, t);
        }
    }
    uint committed = rayQueryGetIntersectionTypeEXT(query, true);
    if (committed == gl_RayQueryCommittedIntersectionNoneEXT) return hit.prim != NO_INDEX;
    hit.t = rayQueryGetIntersectionTEXT(query, true);
    hit.prim = rayQueryGetIntersectionInstanceCustomIndexEXT(query, true) + rayQueryGetIntersectionPrimitiveIndexEXT(query, true);
    hit.instance = rayQueryGetIntersectionInstanceIdEXT(query, true);
    hit.bary = committed == gl_RayQueryCommittedIntersectionTriangleEXT ? rayQueryGetIntersectionBarycentricsEXT(query, true) : vec2(0.0);
    return true;
}
