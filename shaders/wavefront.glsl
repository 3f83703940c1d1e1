// The wavefront split of the path loop (kernels with WAVEFRONT 1: src/render/wavefront.rs). Where
// the megakernel takes each lane's path through its vertices in one loop, tracing its path ray and
// its shadow ray there, the wavefront runs each step over every pixel of the band as a kernel of
// its own, a round at a time: EXTEND traces each path's ray to its hit, SHADOW each shadow ray the
// last vertex handed back, SHADE takes each path through the vertex its ray met (adding the shadow
// ray's light first, as the plain kernel does) and starts the pixel's next sample where one ends.
// Each kernel holds one of the two walks (trace_ray inlined once) and its lanes all run the same
// step, where the megakernel's lanes run the two walks and the shading in turn as their paths reach
// them: on a GPU that is the cost the profile of 2026-12-04 (`3e96a5c`) pointed at (docs/benchmarks/history.md). What
// it pays is the paths' state, read and written through memory at each step.
//
// The sums are the plain kernel's bit for bit: the same vertices, the shadow ray's light added
// before the next vertex's, the samples in sample order (a pixel has one path in flight).

#if COUNT_LOOP_ITERATIONS
#error "the wavefront needs a device whose loops run to their end"
#endif

// The kernels of a round, WAVEFRONT_STAGE of each (the host's WavefrontStage, wavefront.rs).
#define WAVEFRONT_EXTEND 1
#define WAVEFRONT_SHADOW 2
#define WAVEFRONT_SHADE 3

// A pixel's state between the rounds' kernels, WAVEFRONT_STATE_VEC4S uvec4s in path_states from
// (its row in the band * width + x) * WAVEFRONT_STATE_VEC4S. The host sizes the buffer by the same
// count (wavefront.rs); a layout that outgrew it would not compile:
const uint WAVEFRONT_STATE_LAYOUT_VEC4S = 16u;
const uint wavefront_state_fits_the_hosts_buffer[WAVEFRONT_STATE_LAYOUT_VEC4S == WAVEFRONT_STATE_VEC4S ? 1 : -1] = uint[](0u);

// The uvec4s of a pixel's state, named so that load_state, store_state and the stages' kernels,
// which read or write some alone, agree on each.
const uint STATE_RNG = 0u;               // rng.state, rng.kind, rng.pixel_key, rng.sample_index
const uint STATE_RNG_FLAGS = 1u;         // rng.dim, rng.dim_end, next_sample, flags
const uint STATE_RAY_ORIGIN = 2u;        // path.origin, path.bsdf_pdf
const uint STATE_RAY_DIR = 3u;           // path.dir, path.depth
const uint STATE_RADIANCE = 4u;          // path.radiance, target
const uint STATE_THROUGHPUT = 5u;        // path.throughput, sums.nonfinite
const uint STATE_PREV_POINT_HIT_T = 6u;  // path.prev_point, hit.t
const uint STATE_HIT = 7u;               // hit.prim, hit.instance, hit.bary
const uint STATE_SHADOW_ORIGIN = 8u;     // shadow.origin, shadow.t_max
const uint STATE_SHADOW_DIR = 9u;        // shadow.dir, first
const uint STATE_SHADOW_LIGHT = 10u;     // shadow.contribution, first_hit.depth
const uint STATE_SUM = 11u;              // sums.sum
const uint STATE_FIRST_ALBEDO = 12u;     // first_hit.albedo, first_hit.hit and .open (AOVS)
const uint STATE_FIRST_NORMAL = 13u;     // first_hit.normal (AOVS)
const uint STATE_AOV_ALBEDO_DEPTH = 14u; // sums.albedo_depth (AOVS)
const uint STATE_AOV_NORMAL_HITS = 15u;  // sums.normal_hits (AOVS)

// What a pixel's path is waiting for.
const uint PATH_TRACING = 1u;    // its ray, in the next EXTEND
const uint PATH_SHADOWING = 2u;  // its last vertex's shadow ray, in the next SHADOW
const uint PATH_ENDED = 4u;      // nothing: its sample is complete once no shadow ray is left
const uint PIXEL_DONE = 8u;      // the pixel holds the pass's target: its sums are stored

struct WavefrontState {
    Rng rng;
    Path path;
    FirstHit first_hit;
    ShadowRay shadow;
    Hit hit;
    PixelSums sums;
    uint next_sample;  // the next sample to start
    uint target;       // the pass's target, or the count the pixel held where it is outside
    uint first;        // the count the pixel held at the pass's start
    uint flags;        // PATH_* and PIXEL_DONE
};

uint state_base(uint band_row, uint x) {
    return (band_row * frame.width + x) * WAVEFRONT_STATE_VEC4S;
}

uvec4 bits(vec3 v, float w) {
    return uvec4(floatBitsToUint(v), floatBitsToUint(w));
}

uvec4 bits(vec3 v, uint w) {
    return uvec4(floatBitsToUint(v), w);
}

WavefrontState load_state(uint base) {
    WavefrontState s;
    uvec4 w0 = path_states[base + STATE_RNG], w1 = path_states[base + STATE_RNG_FLAGS], w2 = path_states[base + STATE_RAY_ORIGIN], w3 = path_states[base + STATE_RAY_DIR];
    uvec4 w4 = path_states[base + STATE_RADIANCE], w5 = path_states[base + STATE_THROUGHPUT], w6 = path_states[base + STATE_PREV_POINT_HIT_T], w7 = path_states[base + STATE_HIT];
    uvec4 w8 = path_states[base + STATE_SHADOW_ORIGIN], w9 = path_states[base + STATE_SHADOW_DIR], w10 = path_states[base + STATE_SHADOW_LIGHT], w11 = path_states[base + STATE_SUM];
    s.rng = Rng(w0.x, w0.y, w0.z, w0.w, w1.x, w1.y);
    s.next_sample = w1.z;
    s.flags = w1.w;
    s.path.origin = uintBitsToFloat(w2.xyz);
    s.path.bsdf_pdf = uintBitsToFloat(w2.w);
    s.path.dir = uintBitsToFloat(w3.xyz);
    s.path.depth = w3.w;
    s.path.radiance = uintBitsToFloat(w4.xyz);
    s.target = w4.w;
    s.path.throughput = uintBitsToFloat(w5.xyz);
    s.sums.nonfinite = w5.w;
    s.path.prev_point = uintBitsToFloat(w6.xyz);
#if SCENE_MEDIA
    // The wavefront runs no scene with media (src/render/kernel_options.rs): a path in none.
    s.path.media = MEDIUM_STACK_EMPTY;
    s.path.channel = NO_CHANNEL;
    s.path.spectral = vec3(1.0);
    s.path.travelled = 0.0;
#endif
    s.hit.t = uintBitsToFloat(w6.w);
    s.hit.prim = w7.x;
    s.hit.instance = w7.y;
    s.hit.bary = uintBitsToFloat(w7.zw);
    s.shadow.origin = uintBitsToFloat(w8.xyz);
    s.shadow.t_max = uintBitsToFloat(w8.w);
    s.shadow.dir = uintBitsToFloat(w9.xyz);
    s.first = w9.w;
    s.shadow.contribution = uintBitsToFloat(w10.xyz);
    s.first_hit.depth = uintBitsToFloat(w10.w);
    s.sums.sum = uintBitsToFloat(w11);
#if AOVS
    uvec4 w12 = path_states[base + STATE_FIRST_ALBEDO], w13 = path_states[base + STATE_FIRST_NORMAL], w14 = path_states[base + STATE_AOV_ALBEDO_DEPTH], w15 = path_states[base + STATE_AOV_NORMAL_HITS];
    s.first_hit.albedo = uintBitsToFloat(w12.xyz);
    s.first_hit.hit = (w12.w & 1u) != 0u;
    s.first_hit.open = (w12.w & 2u) != 0u;
    s.first_hit.normal = uintBitsToFloat(w13.xyz);
    s.sums.albedo_depth = uintBitsToFloat(w14);
    s.sums.normal_hits = uintBitsToFloat(w15);
#else
    s.first_hit = FirstHit(vec3(0.0), vec3(0.0), 0.0, false, false);
#endif
    return s;
}

void store_state(uint base, WavefrontState s) {
    path_states[base + STATE_RNG] = uvec4(s.rng.state, s.rng.kind, s.rng.pixel_key, s.rng.sample_index);
    path_states[base + STATE_RNG_FLAGS] = uvec4(s.rng.dim, s.rng.dim_end, s.next_sample, s.flags);
    path_states[base + STATE_RAY_ORIGIN] = bits(s.path.origin, s.path.bsdf_pdf);
    path_states[base + STATE_RAY_DIR] = bits(s.path.dir, s.path.depth);
    path_states[base + STATE_RADIANCE] = bits(s.path.radiance, s.target);
    path_states[base + STATE_THROUGHPUT] = bits(s.path.throughput, s.sums.nonfinite);
    path_states[base + STATE_PREV_POINT_HIT_T] = bits(s.path.prev_point, s.hit.t);
    path_states[base + STATE_HIT] = uvec4(s.hit.prim, s.hit.instance, floatBitsToUint(s.hit.bary));
    path_states[base + STATE_SHADOW_ORIGIN] = bits(s.shadow.origin, s.shadow.t_max);
    path_states[base + STATE_SHADOW_DIR] = bits(s.shadow.dir, s.first);
    path_states[base + STATE_SHADOW_LIGHT] = bits(s.shadow.contribution, s.first_hit.depth);
    path_states[base + STATE_SUM] = floatBitsToUint(s.sums.sum);
#if AOVS
    path_states[base + STATE_FIRST_ALBEDO] = bits(s.first_hit.albedo, (s.first_hit.hit ? 1u : 0u) | (s.first_hit.open ? 2u : 0u));
    path_states[base + STATE_FIRST_NORMAL] = bits(s.first_hit.normal, 0u);
    path_states[base + STATE_AOV_ALBEDO_DEPTH] = floatBitsToUint(s.sums.albedo_depth);
    path_states[base + STATE_AOV_NORMAL_HITS] = floatBitsToUint(s.sums.normal_hits);
#endif
}

// Adds this subgroup's rays to the dispatch's count with one atomic. Every lane calls it, in
// uniform control flow.
void count_rays(uint rays) {
    uint total = subgroupAdd(rays);
    if (subgroupElect() && total > 0u) atomicAdd(stats.ray_count, total);
}

#if WAVEFRONT_STAGE == WAVEFRONT_EXTEND
// Traces the ray of each path that has one to its hit.
// SHADE counts the ray, where the plain kernel does.
void wavefront_step(uint base, bool in_band) {
    if (in_band) {
        uint flags = path_states[base + STATE_RNG_FLAGS].w;
        if ((flags & PATH_TRACING) != 0u) {
            vec3 origin = uintBitsToFloat(path_states[base + STATE_RAY_ORIGIN].xyz);
            vec3 dir = uintBitsToFloat(path_states[base + STATE_RAY_DIR].xyz);
            Hit hit;
            trace_ray(origin, dir, 1e30, false, hit);
            path_states[base + STATE_PREV_POINT_HIT_T].w = floatBitsToUint(hit.t);
            path_states[base + STATE_HIT] = uvec4(hit.prim, hit.instance, floatBitsToUint(hit.bary));
        }
    }
}
#elif WAVEFRONT_STAGE == WAVEFRONT_SHADOW
// Adds the light of each shadow ray that nothing blocks.
void wavefront_step(uint base, bool in_band) {
    if (in_band) {
        uvec4 w1 = path_states[base + STATE_RNG_FLAGS];
        if ((w1.w & PATH_SHADOWING) != 0u) {
            vec4 origin = uintBitsToFloat(path_states[base + STATE_SHADOW_ORIGIN]);  // and t_max
            vec3 dir = uintBitsToFloat(path_states[base + STATE_SHADOW_DIR].xyz);
            if (!occluded(origin.xyz, dir, origin.w)) {
                uvec4 w4 = path_states[base + STATE_RADIANCE];
                vec3 radiance = uintBitsToFloat(w4.xyz) + uintBitsToFloat(path_states[base + STATE_SHADOW_LIGHT].xyz);
                path_states[base + STATE_RADIANCE] = bits(radiance, w4.w);
            }
            path_states[base + STATE_RNG_FLAGS].w = w1.w & ~PATH_SHADOWING;
        }
    }
}
#else
// Starts sample s.next_sample on the pixel's idle path, as the queue's start_queued_sample.
void start_next_sample(inout WavefrontState s, uvec2 pixel, uint index) {
    start_sample(pixel, index, s.next_sample, s.rng, s.path, s.first_hit);
    s.next_sample += 1u;
    bool tracing = path_ray_wanted(s.path, s.rng);
    s.flags = tracing ? PATH_TRACING : PATH_ENDED;
}

// Round 0 (pass.wavefront_round): loads the pixel's sums and starts its first sample. Later
// rounds take the path through the vertex its ray met; then, while the path has nothing left to
// trace, add its sample and start the next, until the pixel holds the target and its sums are
// stored. Counts the paths still in flight in stats.paths_in_flight_even or _odd (by the round's
// parity; the other is cleared for the next round), which the host reads to know when every
// pixel of the band is done.
void wavefront_step(uint base, bool in_band, bool inside, uvec2 pixel, uint index) {
    uint round = pass.wavefront_round;
    uint rays = 0u;
    bool in_flight = false;
    // A pixel already done reads one word, not its whole state.
    if (in_band && (round == 0u || (path_states[base + STATE_RNG_FLAGS].w & PIXEL_DONE) == 0u)) {
        WavefrontState s;
        if (round == 0u) {
            s.sums.sum = inside ? load_accum(index) : vec4(0.0);
            s.sums.nonfinite = 0u;
#if AOVS
            s.sums.albedo_depth = inside ? load_aov_albedo_depth(index) : vec4(0.0);
            s.sums.normal_hits = inside ? load_aov_normal_hits(index) : vec4(0.0);
#endif
            s.first = uint(s.sums.sum.w);
            s.target = inside ? pass.target_samples : s.first;
            s.next_sample = s.first;
            s.flags = 0u;
            s.hit = Hit(0.0, NO_INDEX, NO_INDEX, vec2(0.0));
            s.shadow = ShadowRay(vec3(0.0), vec3(0.0), 0.0, vec3(0.0));
            s.first_hit = FirstHit(vec3(0.0), vec3(0.0), 0.0, false, false);
            s.path = path_start(vec3(0.0), vec3(0.0));
            s.rng = Rng(0u, 0u, 0u, 0u, 0u, 0u);
        } else {
            s = load_state(base);
        }
        if ((s.flags & PATH_TRACING) != 0u) {
            rays += 1u;  // the ray EXTEND traced, counted where the plain kernel counts it
            bool shadowing;
            bool goes_on = path_vertex(s.path, s.rng, rays, s.first_hit, s.hit.prim != NO_INDEX, s.hit, shadowing, s.shadow);
            bool tracing = goes_on && path_ray_wanted(s.path, s.rng);
            s.flags = (tracing ? PATH_TRACING : PATH_ENDED) | (shadowing ? PATH_SHADOWING : 0u);
        }
        // A path whose ray max_bounces forbids ends at once, hence the loop.
        while ((s.flags & (PATH_TRACING | PATH_SHADOWING)) == 0u) {
            if ((s.flags & PATH_ENDED) != 0u) {
                add_sample(s.sums, s.path.radiance, s.first_hit);
                s.flags = 0u;
            }
            if (s.next_sample >= s.target) break;
            start_next_sample(s, pixel, index);
        }
        in_flight = (s.flags & (PATH_TRACING | PATH_SHADOWING)) != 0u;
        if (!in_flight) {
            // The pixel holds the target: store its sums, as the plain kernel's main does.
            s.flags = PIXEL_DONE;
            if (inside) {
                if (s.target > s.first) {
                    store_accum(index, s.sums.sum);
#if AOVS
                    store_aov_albedo_depth(index, s.sums.albedo_depth);
                    store_aov_normal_hits(index, s.sums.normal_hits);
#endif
                    atomicAdd(stats.samples_added, s.target - s.first);
                    if (s.sums.nonfinite > 0u) atomicAdd(stats.nonfinite_samples, s.sums.nonfinite);
                }
                atomicAdd(stats.pixels_complete, 1u);
            }
        }
        store_state(base, s);
    }
    count_rays(rays);
    uint flights = subgroupAdd(in_flight ? 1u : 0u);
    if (subgroupElect()) {
        if ((round & 1u) == 0u) {
            if (flights > 0u) atomicAdd(stats.paths_in_flight_even, flights);
        } else {
            if (flights > 0u) atomicAdd(stats.paths_in_flight_odd, flights);
        }
    }
    if (gl_GlobalInvocationID.x == 0u && gl_GlobalInvocationID.y == 0u) {
        if ((round & 1u) == 0u) stats.paths_in_flight_odd = 0u;
        else stats.paths_in_flight_even = 0u;
    }
}
#endif
