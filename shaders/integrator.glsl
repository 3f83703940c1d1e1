// Unidirectional path tracing with next-event estimation and MIS (power heuristic) at every
// vertex whose lobe is not a delta, Russian roulette after `rr_start` bounces.
// integrator.max_bounces is only a safety cap far beyond where roulette ends any path that
// carries energy.

// Sobol dimensions (rng.glsl): the camera's film and lens pair first, then per bounce one window
// for Russian roulette and the BSDF and one for next-event estimation. Fixed windows keep a decision
// on the same dimension in every sample whatever was drawn before it; draws beyond a window, and
// bounces from SOBOL_BOUNCES on (rare after roulette, where stratification has worn off), are
// independent numbers.
const uint DIMS_CAMERA = 4u;
const uint DIMS_SCATTER = 8u;
const uint DIMS_DIRECT = 8u;
const uint SOBOL_BOUNCES = 8u;

void bounce_dimensions(inout Rng rng, uint depth, uint offset, uint count) {
    uint first = DIMS_CAMERA + depth * (DIMS_SCATTER + DIMS_DIRECT) + offset;
    rng_set_dimensions(rng, first, depth < SOBOL_BOUNCES ? count : 0u);
}

// Offsets a ray origin off the surface to the side `dir` leaves towards.
vec3 offset_origin(vec3 p, vec3 n, vec3 dir) {
    float scale = 1e-4 * max(1.0, max3(abs(p)));
    return p + (dot(dir, n) > 0.0 ? n : -n) * scale;
}

// Survival probability for Russian roulette at a bounce past rr_start.
float survival_probability(vec3 throughput) {
    float absorption = frame.rr_absorption;
    if (absorption >= 0.0) return 1.0 - absorption;
    return clamp(max3(throughput), frame.rr_survival_min, frame.rr_survival_max);
}

#if SCENE_MEDIA
#include "medium.glsl"
#include "phase.glsl"
#endif

// A shadow ray of next-event estimation and what it adds to the path's radiance when nothing blocks it
// (the path's throughput at the vertex times the MIS-weighted light sample).
struct ShadowRay {
    vec3 origin;
    vec3 dir;
    float t_max;
    vec3 contribution;
};

// Next-event estimation at a vertex with a non-delta lobe: one light sample, MIS-weighted
// against the lobe's own pdf for that direction. False where the sample adds nothing whatever the
// shadow ray meets; else `shadow` is the ray to trace and what the path gains if it is not occluded.
bool direct_light(Lobe lobe, vec3 d, Surface surface, vec3 throughput, inout Rng rng, inout uint rays, out ShadowRay shadow) {
    LightSample ls;
    if (!sample_direct(surface.point, rng, ls)) return false;
    // As for sampled directions: the shading and geometric normals must agree on the side.
    if (dot(ls.dir, surface.ns) * dot(ls.dir, surface.ng) <= 0.0) return false;
    float lobe_pdf;
    vec3 f_cos = eval_lobe(lobe, d, ls.dir, lobe_pdf);
    if (max3(f_cos) <= 0.0) return false;
    rays += 1u;
    shadow.origin = offset_origin(surface.point, surface.ng, ls.dir);
    shadow.dir = ls.dir;
    float shadow_dist = ls.dist;
    // Aim from the offset origin at the sampled point: from the surface point, a ray that leaves
    // at a grazing angle reaches the light's plane up to offset / cos short of ls.dist, and the
    // light would shadow itself.
    if (ls.dist < 1e30) {
        vec3 to_light = surface.point + ls.dist * ls.dir - shadow.origin;
        shadow_dist = length(to_light);
        shadow.dir = to_light / shadow_dist;
    }
    // Stop short of the light so its own surface does not count as a blocker.
    shadow.t_max = shadow_dist * (1.0 - 1e-4);
    // A delta light cannot be hit by BSDF sampling: this is its only strategy.
    float weight = ls.delta ? 1.0 : power_heuristic(ls.pdf, lobe_pdf);
    shadow.contribution = throughput * (f_cos * ls.radiance * (weight / ls.pdf));
    return true;
}

// Denoiser features of one path (AOVs): albedo and camera-facing shading normal of the first vertex
// that is not a perfectly specular bounce (mirror and glass are followed, as Open Image Denoise
// recommends), and the distance to the first hit. An escaping ray counts as a vertex with the
// environment's radiance, clamped to [0, 1], as albedo and a zero normal. `open` while the
// vertex is still ahead; pathtrace.comp starts it closed when AOVs are off.
struct FirstHit {
    vec3 albedo;
    vec3 normal;
    float depth;
    bool hit;
    bool open;
};

// A path in flight: what one sample's walk keeps from vertex to vertex, so that a path advances
// one vertex at a time and a lane whose path has ended starts its next sample at once (path
// regeneration, pathtrace.comp) instead of idling until the longest path of its subgroup ends.
struct Path {
    vec3 origin;
    vec3 dir;
    vec3 radiance;
    vec3 throughput;
    // The previous vertex, for the MIS weight of emitters hit by BSDF sampling: the pdf of its
    // direction, 0 after the camera or a delta lobe (which light sampling cannot reproduce).
    float bsdf_pdf;
    vec3 prev_point;
    uint depth;
#if SCENE_MEDIA
    // The media it is in (medium.glsl's stack), the channel its distances are sampled by, their
    // pdfs per channel over that channel's (medium_path.glsl), and how far its ray has come from
    // prev_point through null boundaries.
    uint media;
    uint channel;
    vec3 spectral;
    float travelled;
#endif
};

Path path_start(vec3 origin, vec3 dir) {
#if SCENE_MEDIA
    return Path(origin, dir, vec3(0.0), vec3(1.0), 0.0, origin, 0u, MEDIUM_STACK_EMPTY, NO_CHANNEL, vec3(1.0), 0.0);
#else
    return Path(origin, dir, vec3(0.0), vec3(1.0), 0.0, origin, 0u);
#endif
}

#if SCENE_MEDIA
#include "medium_path.glsl"
#endif

// The path's vertex at what its ray (path.origin, path.dir) met: `found` and `hit`, as trace_ray
// returns them. Adds what is seen there, samples the light and the next direction. In a kernel
// with the walk queue the light's shadow ray is handed back (`shadow_wanted`: `shadow` is to be
// traced, and its contribution added where it is not occluded, before the path's next vertex; so
// too in the wavefront's);
// in any other it is traced here. False once the path has ended: path.radiance, with the shadow ray's contribution,
// is then the sample's estimate. The rng's dimensions are the vertex's (bounce_dimensions).
bool path_vertex(inout Path path, inout Rng rng, inout uint rays, inout FirstHit first, bool found, Hit hit, out bool shadow_wanted, out ShadowRay shadow) {
    uint depth = path.depth;
    bool nee = frame.nee != 0u;
    shadow_wanted = false;
    if (!found) {
        float weight = 1.0;
        if (nee && path.bsdf_pdf > 0.0 && environment_sampled()) {
            weight = power_heuristic(path.bsdf_pdf, frame.env_selection_probability * environment_pdf(path.dir));
        }
        vec3 env = environment_radiance(path.dir);
        path.radiance += path.throughput * env * weight;
        path.radiance += path.throughput * light_disks_radiance(path.dir, nee ? path.bsdf_pdf : 0.0);
        if (AOVS == 1 && first.open) {
            first.albedo = clamp(env, 0.0, 1.0);
            first.normal = vec3(0.0);
        }
        return false;
    }
    Surface surface = surface_at(hit, path.origin, path.dir);
    Material m = surface_material(surface);
    vec3 point = surface.point;
    vec3 n = surface.ng;
    bool front = dot(n, path.dir) < 0.0;
    // A ray that meets an absorbing dielectric from behind travelled hit.t inside it (the mesh is
    // closed): Beer-Lambert. Before the surface's own emission, which inside is absorbed too.
    // Only the segment ending on the absorbing surface itself is attenuated: an object nested
    // inside the medium interrupts it unattenuated.
    if (SCENE_ABSORPTION == 1 && !front) path.throughput *= exp(-m.volume.rgb * hit.t);
    if (AOVS == 1 && first.open) {
        // Written at every vertex while open, so a path that ends on a specular chain keeps
        // its last surface.
        if (depth == 0u) {
#if SCENE_MEDIA
            first.depth = path.travelled + hit.t;
#else
            first.depth = hit.t;
#endif
            first.hit = true;
        }
        first.albedo = m.albedo_r.rgb;
        first.normal = front ? surface.ns : -surface.ns;
    }

    vec3 le = emitted_radiance(m, front);
    if (max3(le) > 0.0) {
        float weight = 1.0;
        if (nee && path.bsdf_pdf > 0.0) {
#if SCENE_MEDIA
            // From the last vertex, through the null boundaries passed since.
            float dist = path.travelled + hit.t;
#else
            float dist = hit.t;
#endif
            weight = power_heuristic(path.bsdf_pdf, hit_light_pdf(hit, path.prev_point, path.dir, dist));
        }
        path.radiance += path.throughput * le * weight;
    }

    // A one-sided surface met from behind scatters nothing: no light is sampled there and the
    // path ends (its emission, above, has its own sidedness).
    if (SCENE_ONE_SIDED == 1 && !front && (material_flags(m) & MATERIAL_ONE_SIDED) != 0u) return false;

    if (depth >= frame.rr_start) {
        float q = survival_probability(path.throughput);
        if (rng_next(rng) >= q) return false;
        path.throughput /= q;
    }

    Lobe lobe = pick_lobe(m, path.dir, surface.ns, surface.tangent, front, rng);
    if (!lobe_is_delta(lobe)) first.open = false;
    BsdfSample s;
    bool sampled = sample_lobe(lobe, path.dir, rng, s);
    // Even when the sample fails (a rough lobe's can point below the surface): the direct
    // light must not be dropped with it. Not at the last vertex max_bounces allows: a light
    // sampled there would make a path one segment longer than any the BSDF can continue to, so
    // max_bounces is the longest path in segments, as Mitsuba's max_depth (and MIS stays whole).
    if (nee && !lobe_is_delta(lobe) && depth + 1u < frame.max_bounces) {
        bounce_dimensions(rng, depth, DIMS_SCATTER, DIMS_DIRECT);
        shadow_wanted = direct_light(lobe, path.dir, surface, path.throughput, rng, rays, shadow);
#if !WALK_QUEUE && !WAVEFRONT
        // Traced here where no queue or wavefront takes it: held past the BSDF sample's state, it measured
        // 1-4 % slower on lavapipe (docs/benchmarks/history.md, 2026-12-04, `d1c2c17`).
#if SCENE_MEDIA
        // Through the media it crosses and the null boundaries it passes, from the side it
        // leaves towards (medium.glsl).
        if (shadow_wanted) {
            bool crosses = (dot(shadow.dir, n) < 0.0) == front;
            uint stack = crosses ? stack_crossing(path.media, m, front) : path.media;
            path.radiance += shadow.contribution * shadow_transmittance(shadow.origin, shadow.dir, shadow.t_max, stack, rng, rays);
        }
#else
        if (shadow_wanted && !occluded(shadow.origin, shadow.dir, shadow.t_max)) path.radiance += shadow.contribution;
#endif
        shadow_wanted = false;
#endif
    }
    if (!sampled) return false;
    // Shading normals can send a ray through the geometric surface; such paths end here.
    if (dot(s.dir, surface.ns) * dot(s.dir, n) <= 0.0) return false;
#if SCENE_MEDIA
    // Refracted through a solid surface: into its inside or out of it (medium.glsl).
    if ((dot(s.dir, n) < 0.0) == front) path.media = stack_crossing(path.media, m, front);
    path.travelled = 0.0;
#endif
    path.throughput *= s.weight;
    path.bsdf_pdf = s.delta ? 0.0 : s.pdf;
    path.prev_point = point;
    if (max3(path.throughput) <= 0.0) return false;
    path.origin = offset_origin(point, n, s.dir);
    path.dir = s.dir;
    path.depth = depth + 1u;
    return true;
}

// Whether the path goes on to trace its next ray: max_bounces is the longest path in segments.
// Sets the rng to the next vertex's dimensions.
bool path_ray_wanted(Path path, inout Rng rng) {
    if (path.depth >= frame.max_bounces) return false;
    bounce_dimensions(rng, path.depth, 0u, DIMS_SCATTER);
    return true;
}

// Takes the path through its next vertex, tracing its ray and its shadow ray (the kernel without
// the walk queue). False once the
// path has ended: path.radiance is then the sample's estimate.
bool path_step(inout Path path, inout Rng rng, inout uint rays, inout FirstHit first) {
    if (!path_ray_wanted(path, rng)) return false;
    Hit hit;
    rays += 1u;
    bool found = trace_ray(path.origin, path.dir, 1e30, false, hit);
#if SCENE_MEDIA
    bool scattered;
    bool goes_on = medium_walk(path, rng, rays, first, found, hit, scattered);
    if (scattered) return goes_on;
#endif
    bool shadow_wanted;  // false: without the queue, path_vertex traces its shadow ray itself
    ShadowRay shadow;
    return path_vertex(path, rng, rays, first, found, hit, shadow_wanted, shadow);
}
