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

// exp(-sigma_t t) per channel: the share of light left after distance t in a homogeneous medium.
vec3 medium_transmittance(Medium med, float t) {
    return exp(-medium_sigma_t(med) * t);
}

// The transmittance from `origin` along `dir` to distance t_max, starting in the innermost medium
// of `stack`: the product of each medium's over its part of the ray, passing null boundaries
// (entering and leaving the media they bound). Zero where any other surface blocks the ray, and
// past MAX_NULL_CROSSINGS boundaries. Homogeneous media have it in closed form, so it is exact,
// not estimated (ratio tracking is for media whose density varies).
vec3 shadow_transmittance(vec3 origin, vec3 dir, float t_max, uint stack, inout uint rays) {
    vec3 transmittance = vec3(1.0);
    vec3 end = origin + dir * t_max;
    for (uint crossing = 0u; crossing < MAX_NULL_CROSSINGS; ++crossing) {
        Hit hit;
        if (crossing > 0u) rays += 1u;  // the first is counted with the shadow ray
        bool found = trace_ray(origin, dir, t_max, false, hit);
        uint code = current_medium(stack);
        if (code != MEDIUM_VACUUM) transmittance *= medium_transmittance(medium_of(code), found ? hit.t : t_max);
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
