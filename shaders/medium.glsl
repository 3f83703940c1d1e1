// Participating media: which medium a point of a path is in, how far light travels in it before
// it meets a particle, and what reaches a shadow ray's end through media and null boundaries.
// Compiled in only for scenes with media or null boundaries (SCENE_MEDIA, src/render/features.rs).
//
// Which medium: media are named by 8-bit codes (MEDIUM_CODES, src/render/layout.rs): a medium's
// index + 1, MEDIUM_VACUUM for empty space. A path keeps a stack of the codes of what it entered,
// MEDIUM_STACK_DEPTH deep in one uint, the innermost in the low byte. Crossing a solid surface (a
// dielectric or a null boundary; not a thin sheet) against its geometric normal enters it: the
// material's interior is pushed (empty space where it names none). Crossing along the normal leaves
// it: the innermost is popped. Below the stack is the camera's medium (frame.camera_medium), which
// fills everything outside all boundaries. So a glass of milk in fog nests: fog, then the glass's
// empty space, then milk, and back out in turn. Rules that follow: surfaces of closed shapes must
// face out (their normals say which side is inside); a camera placed inside a closed medium needs
// that medium as camera.medium, and that medium is then also what lies outside every boundary;
// nesting deeper than MEDIUM_STACK_DEPTH forgets the outermost entries (leaving then returns to
// the camera's medium early).

// Most null boundaries one ray passes before it meets a surface or its end: a ray that meets more
// ends there (its shadow ray counts as blocked, its path ends). 64 exceeds any nesting a scene of
// closed media has on one line of sight.
const uint MAX_NULL_CROSSINGS = 64u;

// The medium the innermost entry of `stack` names, or the camera's below every entry.
uint current_medium(uint stack) {
    uint top = stack & 0xffu;
    return top == MEDIUM_STACK_EMPTY ? frame.camera_medium : top;
}

// A material's interior medium code: MEDIUM_VACUUM where it names none.
uint material_interior(Material m) {
    uint code = (material_flags(m) >> MATERIAL_INTERIOR_SHIFT) & 0xffu;
    return code == MEDIUM_STACK_EMPTY ? MEDIUM_VACUUM : code;
}

bool material_is_null(Material m) {
    return (material_flags(m) & MATERIAL_NULL) != 0u;
}

// The stack after crossing a surface of material `m`: into its inside (`entering`, against its
// geometric normal) or out of it. A thin sheet has no inside.
uint stack_crossing(uint stack, Material m, bool entering) {
    if ((material_flags(m) & MATERIAL_THIN) != 0u) return stack;
    return entering ? (stack << 8u) | material_interior(m) : stack >> 8u;
}

// The record of medium `code` (not MEDIUM_VACUUM).
Medium medium_of(uint code) {
    return media[code - 1u];
}

vec3 medium_sigma_t(Medium med) { return med.sigma_t_g.rgb; }
vec3 medium_albedo(Medium med) { return med.albedo_kind.rgb; }
float medium_g(Medium med) { return med.sigma_t_g.w; }
bool medium_is_grid(Medium med) { return floatBitsToUint(med.albedo_kind.w) == MEDIUM_HETEROGENEOUS; }
float medium_majorant(Medium med) { return med.box_min_majorant.w; }

// exp(-sigma_t t) per channel: the share of light left after distance t in a homogeneous medium.
vec3 medium_transmittance(Medium med, float t) {
    return exp(-medium_sigma_t(med) * t);
}

// Most tentative collisions one ray's delta or ratio tracking takes through a grid (at the
// majorant's rate, about majorant x length of the ray in the grid's box): a ray that needs more
// ends there (a path ends, a shadow ray counts as blocked). Per-brick majorants, which would
// bound it by the density along the ray, are not built yet.
const uint MAX_TRACKING_STEPS = 65536u;

// A grid's value at cell (x, y, z).
float grid_value(Medium med, uint x, uint y, uint z) {
    uvec4 g = med.grid;
    return load_medium_densities(g.x + (z * g.z + y) * g.y + x);
}

// The density of a heterogeneous medium at `p`: trilinear between its cells' centres (clamped to
// the outermost centres at the box's faces), 0 outside its box.
float medium_density(Medium med, vec3 p) {
    vec3 lo = med.box_min_majorant.xyz;
    vec3 hi = med.box_max.xyz;
    if (any(lessThan(p, lo)) || any(greaterThan(p, hi))) return 0.0;
    uvec3 res = med.grid.yzw;
    vec3 g = clamp((p - lo) / (hi - lo) * vec3(res) - 0.5, vec3(0.0), vec3(res - 1u));
    uvec3 i0 = uvec3(g);
    uvec3 i1 = min(i0 + 1u, res - 1u);
    vec3 f = g - vec3(i0);
    float c00 = mix(grid_value(med, i0.x, i0.y, i0.z), grid_value(med, i1.x, i0.y, i0.z), f.x);
    float c10 = mix(grid_value(med, i0.x, i1.y, i0.z), grid_value(med, i1.x, i1.y, i0.z), f.x);
    float c01 = mix(grid_value(med, i0.x, i0.y, i1.z), grid_value(med, i1.x, i0.y, i1.z), f.x);
    float c11 = mix(grid_value(med, i0.x, i1.y, i1.z), grid_value(med, i1.x, i1.y, i1.z), f.x);
    return mix(mix(c00, c10, f.y), mix(c01, c11, f.y), f.z);
}

// The part [t0, t1] of the ray o + t d, t in [0, t_max], inside a grid's box; false if none.
bool grid_span(Medium med, vec3 o, vec3 d, float t_max, out float t0, out float t1) {
    vec3 inv = 1.0 / d;
    vec3 a = (med.box_min_majorant.xyz - o) * inv;
    vec3 b = (med.box_max.xyz - o) * inv;
    vec3 near = min(a, b);
    vec3 far = max(a, b);
    t0 = max(0.0, max(near.x, max(near.y, near.z)));
    t1 = min(t_max, min(far.x, min(far.y, far.z)));
    return t0 < t1;
}

// Ratio tracking (Novak et al. 2014) of a grid's transmittance over [0, t_max] of a ray: tentative
// collisions at the majorant's rate, each multiplying the estimate by the share of the majorant
// that is not the medium's there, per channel. Unbiased; 0 past MAX_TRACKING_STEPS.
vec3 grid_transmittance(Medium med, vec3 o, vec3 d, float t_max, inout Rng rng) {
    float majorant = medium_majorant(med);
    float t, t1;
    if (majorant <= 0.0 || !grid_span(med, o, d, t_max, t, t1)) return vec3(1.0);
    vec3 transmittance = vec3(1.0);
    for (uint step = 0u; step < MAX_TRACKING_STEPS; ++step) {
        LOOP_ITERATION();
        t -= log(1.0 - rng_next(rng)) / majorant;
        if (t >= t1) return transmittance;
        transmittance *= 1.0 - medium_sigma_t(med) * (medium_density(med, o + t * d) / majorant);
        if (max3(transmittance) <= 0.0) return vec3(0.0);
    }
    return vec3(0.0);
}

// The transmittance of medium `code` over [0, t] of a ray: closed form, or ratio tracking.
vec3 segment_transmittance(uint code, vec3 o, vec3 d, float t, inout Rng rng) {
    Medium med = medium_of(code);
    return medium_is_grid(med) ? grid_transmittance(med, o, d, t, rng) : medium_transmittance(med, t);
}

// The transmittance from `origin` along `dir` to distance t_max, starting in the innermost medium
// of `stack`: the product of each medium's over its part of the ray, passing null boundaries
// (entering and leaving the media they bound). Zero where any other surface blocks the ray, and
// past MAX_NULL_CROSSINGS boundaries. Homogeneous media have it in closed form, so it is exact;
// heterogeneous ones an unbiased estimate by ratio tracking.
vec3 shadow_transmittance(vec3 origin, vec3 dir, float t_max, uint stack, inout Rng rng, inout uint rays) {
    vec3 transmittance = vec3(1.0);
    vec3 end = origin + dir * t_max;
    for (uint crossing = 0u; crossing < MAX_NULL_CROSSINGS; ++crossing) {
        LOOP_ITERATION();
        Hit hit;
        if (crossing > 0u) rays += 1u;  // the first is counted with the shadow ray
        bool found = trace_ray(origin, dir, t_max, false, hit);
        uint code = current_medium(stack);
        if (code != MEDIUM_VACUUM) transmittance *= segment_transmittance(code, origin, dir, found ? hit.t : t_max, rng);
        if (!found) return transmittance;
        Surface surface = surface_at(hit, origin, dir);
        Material m = load_materials(surface.material);
        if (!material_is_null(m)) return vec3(0.0);
        stack = stack_crossing(stack, m, dot(dir, surface.ng) < 0.0);
        origin = offset_origin(surface.point, surface.ng, dir);
        t_max = dot(end - origin, dir);
        if (t_max <= 0.0 || max3(transmittance) <= 0.0) return transmittance;
    }
    return vec3(0.0);
}

// A path's channel before it samples its first distance (medium_path.glsl).
const uint NO_CHANNEL = 3u;

// Component `c` (0, 1, 2) of v.
float channel_of(vec3 v, uint c) {
    return c == 0u ? v.x : (c == 1u ? v.y : v.z);
}

float mean3(vec3 v) {
    return (v.x + v.y + v.z) * (1.0 / 3.0);
}
