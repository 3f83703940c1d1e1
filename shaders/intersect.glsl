// Ray/primitive intersection. Each returns the hit distance in (0, t_max) or -1.

const float NO_HIT = -1.0;

float intersect_sphere(vec3 center, float radius, vec3 o, vec3 d, float t_max) {
    vec3 oc = o - center;
    float b = dot(oc, d);
    // Distance-to-plane form of the discriminant keeps precision for distant small spheres.
    vec3 perp = oc - b * d;
    float disc = radius * radius - dot(perp, perp);
    if (disc < 0.0) return NO_HIT;
    float root = sqrt(disc);
    float t_near = -b - root;
    float t_far = -b + root;
    if (t_near > 0.0 && t_near < t_max) return t_near;
    if (t_far > 0.0 && t_far < t_max) return t_far;
    return NO_HIT;
}

float intersect_quad(vec3 origin, vec3 eu, vec3 ev, vec3 o, vec3 d, float t_max) {
    vec3 n = cross(eu, ev);
    float denom = dot(n, d);
    if (abs(denom) < 1e-20) return NO_HIT;
    float t = dot(n, origin - o) / denom;
    if (!(t > 0.0 && t < t_max)) return NO_HIT;
    vec3 rel = o + t * d - origin;
    vec3 w = n / dot(n, n);
    float alpha = dot(w, cross(rel, ev));
    float beta = dot(w, cross(eu, rel));
    return (alpha >= 0.0 && alpha <= 1.0 && beta >= 0.0 && beta <= 1.0) ? t : NO_HIT;
}

// Moller-Trumbore; `bary` gets the hit's (u, v) weights of v1 and v2. `d` need not be unit length
// (instanced meshes are hit in object space).
// Every test is made at the end, with no early return: on lavapipe each early return is a mask
// test and a branch for the whole subgroup, and computing the few products it would skip measured
// faster (docs/benchmarks/history.md, 2026-12-05, `9e81c69`). Which triangles are hit is the same: u <= 1 follows from
// v >= 0 and u + v <= 1.
float intersect_triangle(vec3 v0, vec3 e1, vec3 e2, vec3 o, vec3 d, float t_max, out vec2 bary) {
    vec3 p = cross(d, e2);
    float det = dot(e1, p);
    float inv_det = 1.0 / det;
    vec3 s = o - v0;
    vec3 q = cross(s, e1);
    float u = dot(s, p) * inv_det;
    float v = dot(d, q) * inv_det;
    float t = dot(e2, q) * inv_det;
    bary = vec2(u, v);
    bool hit = abs(det) >= 1e-20 && u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > 0.0 && t < t_max;
    return hit ? t : NO_HIT;
}

// Every function that switches on a primitive's kind names each PRIM_* kind of layout.glsl, and
// an unknown kind has no surface (no hit, no normal, no area) rather than passing for another
// kind; a new kind is a case in each (src/render/layout.rs tests that every kind has one). A kind
// the scene has none of (SCENE_SPHERE_SHAPES, SCENE_QUAD_SHAPES, SCENE_TRIANGLE_SHAPES:
// src/render/features.rs) is compiled out of its case, which then answers as for an unknown kind.

// `kind` is the primitive's own (prim_kind(p)), or a constant where the host compiled it in: a
// scene's few shapes are each tested by their kind's test alone (SCENE_FEW_SHAPES, bvh.glsl).
float intersect_primitive_as(uint kind, Primitive p, vec3 o, vec3 d, float t_max) {
    vec2 unused_bary;
    switch (kind) {
        case PRIM_SPHERE: return SCENE_SPHERE_SHAPES == 1 ? intersect_sphere(p.a.xyz, p.a.w, o, d, t_max) : NO_HIT;
        case PRIM_QUAD: return SCENE_QUAD_SHAPES == 1 ? intersect_quad(p.a.xyz, p.b.xyz, p.c.xyz, o, d, t_max) : NO_HIT;
        case PRIM_TRIANGLE: return SCENE_TRIANGLE_SHAPES == 1 ? intersect_triangle(p.a.xyz, p.b.xyz, p.c.xyz, o, d, t_max, unused_bary) : NO_HIT;
        default: return NO_HIT;
    }
}

// Outward (sphere) or front-side (quad, triangle) unit normal at a point on the primitive.
vec3 primitive_normal(Primitive p, vec3 point) {
    switch (prim_kind(p)) {
        case PRIM_SPHERE: return SCENE_SPHERE_SHAPES == 1 ? (point - p.a.xyz) / p.a.w : vec3(0.0);
        case PRIM_QUAD:
        case PRIM_TRIANGLE: return SCENE_QUAD_SHAPES == 1 || SCENE_TRIANGLE_SHAPES == 1 ? normalize(cross(p.b.xyz, p.c.xyz)) : vec3(0.0);
        default: return vec3(0.0);
    }
}

// The surface's u direction, which an anisotropic lobe's x axis follows (not unit): a sphere's
// is that of increasing longitude phi about the world z axis through its centre, as Mitsuba's
// sphere about its local z (caustica's spheres have no rotation of their own), zero at the poles;
// a quad's is edge u; a triangle of the scene's own has no texture coordinates and so none (the
// lobe keeps an arbitrary frame, as Mitsuba's coordinate_system(n) for meshes without them).
vec3 primitive_tangent(Primitive p, vec3 point) {
    switch (prim_kind(p)) {
        case PRIM_SPHERE: return SCENE_SPHERE_SHAPES == 1 ? vec3(p.a.y - point.y, point.x - p.a.x, 0.0) : vec3(0.0);
        case PRIM_QUAD: return SCENE_QUAD_SHAPES == 1 ? p.b.xyz : vec3(0.0);
        case PRIM_TRIANGLE: return vec3(0.0);
        default: return vec3(0.0);
    }
}

float primitive_area(Primitive p) {
    switch (prim_kind(p)) {
        case PRIM_SPHERE: return SCENE_SPHERE_SHAPES == 1 ? 4.0 * PI * p.a.w * p.a.w : 0.0;
        case PRIM_QUAD: return SCENE_QUAD_SHAPES == 1 ? length(cross(p.b.xyz, p.c.xyz)) : 0.0;
        case PRIM_TRIANGLE: return SCENE_TRIANGLE_SHAPES == 1 ? 0.5 * length(cross(p.b.xyz, p.c.xyz)) : 0.0;
        default: return 0.0;
    }
}

// Whether the primitive radiates from both sides when its material is two-sided: flat ones do,
// a sphere shows only its outside.
bool primitive_is_flat(Primitive p) {
    switch (prim_kind(p)) {
        case PRIM_SPHERE: return false;
        case PRIM_QUAD:
        case PRIM_TRIANGLE: return true;
        default: return false;
    }
}
