// A path through participating media (medium.glsl): free-flight sampling of where its ray meets a
// particle, scattering there by the phase function (phase.glsl) with next-event estimation, and
// the null boundaries it passes on the way. The megakernel's path_step runs it between tracing a
// ray and the surface vertex; the walk queue and the wavefront do not run scenes with media
// (src/render/kernel_options.rs).
//
// Chromatic media, by spectral MIS (the one-sample balance heuristic over the channels, as
// Mitsuba 3's volpathmis and pbrt-v4's volpath): each path samples every distance by the
// extinction of one channel, `path.channel`, picked uniformly when it first needs one; its
// estimate is f / mean over channels c of p_c, p_c the pdf of all its distance decisions had each
// been sampled by channel c. path.spectral holds p_c / p_channel per channel, and path.throughput
// is kept as f / mean(p_c) times the surfaces' own weights, so that every radiance the path adds
// (emission, NEE, the sky) is weighted already. A grey medium gives exp(-sigma_t t) sampling with
// weight 1; a chromatic one no channel's distances can starve (no colour noise where one channel's
// sigma_t is far above the others'), and the estimate stays unbiased for each.

// Folds one distance decision into the path: f its contribution per channel, q its pdf (or
// probability) per channel had that channel sampled it (q[path.channel] > 0).
void spectral_event(inout Path path, vec3 f, vec3 q) {
    float q_channel = channel_of(q, path.channel);
    vec3 spectral = path.spectral * (q / q_channel);
    path.throughput *= f * (mean3(path.spectral) / (q_channel * mean3(spectral)));
    path.spectral = spectral;
}

// The path's vertex where its ray met a particle of `med` at `point`: next-event estimation with
// the phase function, MIS-weighted against phase sampling, and the next direction by the phase
// function. False once the path ended (roulette, max_bounces). The rng is at the bounce's window.
bool medium_vertex(inout Path path, inout Rng rng, inout uint rays, inout FirstHit first, vec3 point, float t, Medium med) {
    uint depth = path.depth;
    if (AOVS == 1 && first.open) {
        // A medium scatters as a rough surface would: the first vertex that is not specular.
        if (depth == 0u) {
            first.depth = t;
            first.hit = true;
        }
        first.albedo = medium_albedo(med);
        first.normal = vec3(0.0);
        first.open = false;
    }
    if (depth >= frame.rr_start) {
        float q = survival_probability(path.throughput);
        if (rng_next(rng) >= q) return false;
        path.throughput /= q;
    }
    float g = medium_g(med);
    vec3 wi = sample_phase_hg(g, path.dir, rng_next2(rng));
    float phase_pdf = phase_hg(g, dot(path.dir, wi));
    if (frame.nee != 0u && depth + 1u < frame.max_bounces) {
        bounce_dimensions(rng, depth, DIMS_SCATTER, DIMS_DIRECT);
        LightSample ls;
        if (sample_direct(point, rng, ls)) {
            rays += 1u;
            float phase = phase_hg(g, dot(path.dir, ls.dir));
            // Stop short of the light so its own surface does not count as a blocker.
            vec3 transmittance = shadow_transmittance(point, ls.dir, ls.dist * (1.0 - 1e-4), path.media, rng, rays);
            float weight = ls.delta ? 1.0 : power_heuristic(ls.pdf, phase);
            path.radiance += path.throughput * transmittance * ls.radiance * (phase * weight / ls.pdf);
        }
    }
    // The phase function is sampled exactly: its weight is 1.
    path.bsdf_pdf = phase_pdf;
    path.prev_point = point;
    path.travelled = 0.0;
    path.origin = point;
    path.dir = wi;
    path.depth = depth + 1u;
    return true;
}

// Delta tracking (Woodcock) through a heterogeneous medium up to t_surface, as a null-scattering
// path (Miller et al. 2019): tentative collisions at the majorant's rate; at each, a real
// collision with probability sigma_t / majorant in the path's channel (the path scatters there),
// else a null one, with sigma_n = majorant - sigma_t. Each decision's contribution and per-channel
// probabilities go through spectral MIS as the homogeneous medium's (the majorant is the same in
// every channel, so its exponentials cancel). True when the path scattered and goes on; false
// with `scattered` when it scattered and ended (or took MAX_TRACKING_STEPS); false otherwise when
// it reached t_surface.
bool grid_free_flight(inout Path path, inout Rng rng, inout uint rays, inout FirstHit first, Medium med, float t_surface, out bool scattered) {
    scattered = false;
    float majorant = medium_majorant(med);
    float t, t1;
    if (majorant <= 0.0 || !grid_span(med, path.origin, path.dir, t_surface, t, t1)) return false;
    for (uint step = 0u; step < MAX_TRACKING_STEPS; ++step) {
        LOOP_ITERATION();
        t -= log(1.0 - rng_next(rng)) / majorant;
        if (t >= t1) return false;
        vec3 point = path.origin + t * path.dir;
        vec3 sigma_t = medium_sigma_t(med) * medium_density(med, point);
        if (rng_next(rng) * majorant < channel_of(sigma_t, path.channel)) {
            spectral_event(path, sigma_t * medium_albedo(med), sigma_t);
            scattered = true;
            return medium_vertex(path, rng, rays, first, point, path.travelled + t, med);
        }
        vec3 sigma_n = vec3(majorant) - sigma_t;
        spectral_event(path, sigma_n, sigma_n);
        if (max3(path.throughput) <= 0.0) {
            scattered = true;
            return false;
        }
    }
    scattered = true;
    return false;
}

// What happens to the path's ray (traced to `found`, `hit`) before any surface vertex: in a
// medium, a particle met on the way (the path scatters there: `scattered`, and the result is
// whether it goes on), or the transmittance to the surface folded into the throughput; a null
// boundary met is passed (the ray traced on, `found` and `hit` updated) until a surface or the
// sky. False with `scattered` false: the path goes on to path_vertex at `found`, `hit`.
bool medium_walk(inout Path path, inout Rng rng, inout uint rays, inout FirstHit first, inout bool found, inout Hit hit, out bool scattered) {
    scattered = false;
    for (uint crossing = 0u; crossing <= MAX_NULL_CROSSINGS; ++crossing) {
        LOOP_ITERATION();
        uint code = current_medium(path.media);
        if (code != MEDIUM_VACUUM && medium_is_grid(medium_of(code))) {
            if (path.channel == NO_CHANNEL) path.channel = min(uint(rng_next(rng) * 3.0), 2u);
            float t_surface = found ? hit.t : 1e30;
            if (grid_free_flight(path, rng, rays, first, medium_of(code), t_surface, scattered)) return true;
            if (scattered) return false;
        } else if (code != MEDIUM_VACUUM) {
            Medium med = medium_of(code);
            vec3 sigma_t = medium_sigma_t(med);
            if (path.channel == NO_CHANNEL) path.channel = min(uint(rng_next(rng) * 3.0), 2u);
            float t_surface = found ? hit.t : 1e30;
            float sigma_c = channel_of(sigma_t, path.channel);
            // Free flight: exponential in the path's channel (1 - u in (0, 1]: no log of 0).
            float t = sigma_c > 0.0 ? -log(1.0 - rng_next(rng)) / sigma_c : 1e30;
            if (t < t_surface) {
                vec3 transmittance = medium_transmittance(med, t);
                spectral_event(path, sigma_t * medium_albedo(med) * transmittance, sigma_t * transmittance);
                scattered = true;
                vec3 point = path.origin + t * path.dir;
                return medium_vertex(path, rng, rays, first, point, path.travelled + t, med);
            }
            // No particle before the surface: probability exp(-sigma_c t_surface) of that channel.
            vec3 transmittance = medium_transmittance(med, t_surface);
            spectral_event(path, transmittance, transmittance);
            if (max3(path.throughput) <= 0.0) {
                scattered = true;
                return false;
            }
        }
        if (!found) return false;
        Surface surface = surface_at(hit, path.origin, path.dir);
        Material m = load_materials(surface.material);
        if (!material_is_null(m)) return false;
        // A null boundary: the ray goes on unchanged, into or out of the medium it bounds. Light
        // sampling's pdf at an emitter hit later is from the last vertex: the distance so far.
        path.media = stack_crossing(path.media, m, dot(path.dir, surface.ng) < 0.0);
        path.travelled += hit.t;
        path.origin = offset_origin(surface.point, surface.ng, path.dir);
        rays += 1u;
        found = trace_ray(path.origin, path.dir, 1e30, false, hit);
    }
    // More null boundaries on one ray than MAX_NULL_CROSSINGS: the path ends.
    scattered = true;
    return false;
}
