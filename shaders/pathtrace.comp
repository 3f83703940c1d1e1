#version 460
// caustica's path tracing kernel: one invocation per pixel of the dispatched row band, bringing the
// pixel's running sum up to `pass.target_samples` samples. Each pixel continues from the count it
// holds, so a dispatch repeated after it was cut short (see loop_limit.glsl) adds exactly the
// samples that are missing, and the sums are bit for bit those of one uninterrupted render.
// The host prepends `#define BVH_MAX_DEPTH` (the BVH builder's bound), `AOVS` (1: also
// accumulate the denoiser features, the AOV sums; 0: a kernel without them),
// `COUNT_LOOP_ITERATIONS` (1 on devices that end loops early), `WALK_QUEUE` (1: rays walked from
// a queue the subgroup shares, walk_queue.glsl, and `QUEUE_WALKS_PER_RAY`; src/render/walk_queue.rs),
// `TAKE_TILES` (1: subgroups take their pixels from a counter, main below; src/render/tile_taking.rs)
// and the `SCENE_*` features the scene uses (src/render/features.rs: what is 0 is compiled out).
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_ballot : require
// texelFetch of the texel buffers the walk and shading read their records from (bindings.rs).
#extension GL_EXT_samplerless_texture_functions : require
// The ray-query traversal (ray_query.glsl, src/gpu/traversal.rs): SCENE_RAY_QUERY 1.
#if SCENE_RAY_QUERY
#extension GL_EXT_ray_query : require
#endif

// The workgroup's shape is a kernel variant (src/render/workgroup.rs).
layout(local_size_x = WORKGROUP_WIDTH, local_size_y = WORKGROUP_HEIGHT, local_size_z = 1) in;

#include "layout.glsl"
#include "loop_limit.glsl"
#include "rng.glsl"
#include "sampling.glsl"
#include "intersect.glsl"
#include "textures.glsl"
#include "alpha.glsl"
#include "bvh.glsl"
#if WALK_QUEUE
// The queue's rounds must run whole on every lane of a subgroup: only where loops run to their end.
#if COUNT_LOOP_ITERATIONS
#error "WALK_QUEUE needs a device whose loops run to their end"
#endif
#include "walk_queue.glsl"
#endif
#include "surface.glsl"
#include "materials.glsl"
#include "environment.glsl"
#include "light_tree.glsl"
#include "lights.glsl"
#include "camera.glsl"
#include "integrator.glsl"

// Sample `s` of the pixel: its random numbers, its camera ray, its path at the camera.
void start_sample(uvec2 pixel, uint index, uint s, out Rng rng, out Path path, out FirstHit first_hit) {
    rng = rng_for_sample(frame.seed, index, pass.stream_offset + s, frame.sampler_kind);
    rng_set_dimensions(rng, 0u, DIMS_CAMERA);
    vec3 origin, dir;
    camera_ray(pixel, rng, origin, dir);
    first_hit = FirstHit(vec3(0.0), vec3(0.0), 0.0, false, AOVS == 1);
    path = path_start(origin, dir);
}

// The band's row of workgroups that workgroup row `r` of `n` renders. lavapipe hands each of its
// threads one contiguous run of a dispatch's workgroups, decided up front; when those are whole
// regions of the image (a sky above, a mesh below) one thread finishes early and idles. Dealing
// the rows into `pass.group_row_stripes` stripes (row r of stripe k is band row r * stripes + k)
// gives every run rows from the whole band. One stripe is the identity (GPUs balance their own
// workgroups). A bijection either way: every pixel is rendered once, and its sums do not depend
// on which workgroup renders them.
uint group_row_of(uint r, uint n) {
    uint stripes = pass.group_row_stripes;
    uint per_stripe = n / stripes;
    uint longer = n % stripes;  // the first `longer` stripes hold one row more
    if (r < longer * (per_stripe + 1u)) return (r % (per_stripe + 1u)) * stripes + r / (per_stripe + 1u);
    uint rest = r - longer * (per_stripe + 1u);
    return (rest % per_stripe) * stripes + longer + rest / per_stripe;
}

// A pixel's running sums and what its samples add to them.
struct PixelSums {
    vec4 sum;        // radiance, and the sample count in w
    uint nonfinite;  // samples whose radiance was dropped as NaN or infinite
#if AOVS
    vec4 albedo_depth;
    vec4 normal_hits;
#endif
};

// Adds one sample, its radiance and its denoiser features (its path's first vertex, AOVs), to the
// pixel's sums.
void add_sample(inout PixelSums sums, vec3 radiance, FirstHit first_hit) {
    // Optional firefly clamp (biased): scale down, keeping the sample's colour.
    float peak = max3(radiance);
    float clamp_max = frame.radiance_clamp;
    if (clamp_max > 0.0 && peak > clamp_max) radiance *= clamp_max / peak;
    // A NaN or infinity, in the sample or in the sum it would make (an emission near the float
    // range), would poison the pixel for good; drop that sample's radiance, count it.
    vec3 next = sums.sum.rgb + radiance;
    if (any(isnan(next)) || any(isinf(next))) {
        radiance = vec3(0.0);
        sums.nonfinite += 1u;
    }
    sums.sum += vec4(radiance, 1.0);
#if AOVS
    sums.albedo_depth += vec4(first_hit.albedo, first_hit.depth);
    sums.normal_hits += vec4(first_hit.normal, first_hit.hit ? 1.0 : 0.0);
#endif
}

#if WALK_QUEUE
#include "queued_paths.glsl"
#endif
#if WAVEFRONT
#include "wavefront.glsl"
#endif

// The work of invocation `local` of workgroup `group` of the dispatch: its pixel's samples.
void render_invocation(uvec2 group, uvec2 local) {
    uint band_row = group_row_of(group.y, gl_NumWorkGroups.y) * gl_WorkGroupSize.y + local.y;
    uvec2 pixel = uvec2(group.x * gl_WorkGroupSize.x + local.x, band_row + pass.row_offset);
    uint width = frame.width;
    bool inside = pixel.x < width && band_row < pass.row_count && pixel.y < frame.height;
    uint index = pixel.y * width + pixel.x;
#if WAVEFRONT
    // One step of a round for the pixel's path (wavefront.glsl): its state, not its sums, is here.
    bool in_band = pixel.x < width && band_row < pass.row_count;
#if WAVEFRONT_STAGE == WAVEFRONT_SHADE
    wavefront_step(state_base(band_row, pixel.x), in_band, inside, pixel, index);
#else
    wavefront_step(state_base(band_row, pixel.x), in_band);
#endif
    return;
#endif
    PixelSums sums;
    sums.sum = inside ? load_accum(index) : vec4(0.0);
    sums.nonfinite = 0u;
#if AOVS
    sums.albedo_depth = inside ? load_aov_albedo_depth(index) : vec4(0.0);
    sums.normal_hits = inside ? load_aov_normal_hits(index) : vec4(0.0);
#endif
    // Counts are exact in a float up to 2^24, which the host does not exceed.
    uint first = uint(sums.sum.w);
    uint target = inside ? pass.target_samples : first;
    uint rays = 0u;
    uint s = first;
#if WALK_QUEUE
    render_queued_samples(pixel, index, s, target, sums, rays);
#else
    Rng rng;
    Path path;
    FirstHit first_hit;
    // One vertex an iteration; a lane whose path ends adds its sample and starts the next at once,
    // so the lanes of a subgroup stay busy until each has done all its samples, rather than each
    // sample waiting for the subgroup's longest path. The sums are added in sample order as before.
    bool starting = true;
    while (s < target) {
        LOOP_ITERATION();
        if (starting) start_sample(pixel, index, s, rng, path, first_hit);
        starting = false;
        if (path_step(path, rng, rays, first_hit)) continue;
        add_sample(sums, path.radiance, first_hit);
        ++s;
        starting = true;
    }
#endif
    report_loop_iterations();
    if (!inside) return;
    atomicAdd(stats.ray_count, rays);
    // Cut short (the sample loop ended early, or any loop did): keep the samples the pixel held,
    // so that the host's repeat adds exactly the missing ones. It sees this pixel missing from
    // pixels_complete.
    if (uint(sums.sum.w) < target || !loop_limit_intact()) return;
    if (target > first) {
        store_accum(index, sums.sum);
#if AOVS
        store_aov_albedo_depth(index, sums.albedo_depth);
        store_aov_normal_hits(index, sums.normal_hits);
#endif
        atomicAdd(stats.samples_added, target - first);
        if (sums.nonfinite > 0u) atomicAdd(stats.nonfinite_samples, sums.nonfinite);
    }
    atomicAdd(stats.pixels_complete, 1u);
}

void main() {
#if TAKE_TILES
    // A tile is one subgroup's share of one workgroup. Each subgroup takes the next from the
    // counter as soon as it has rendered one, until none is left, so the device's thread that
    // finishes first takes more: lavapipe splits a dispatch's workgroups among its threads up
    // front, and their costs differ. The workgroups left when the tiles run out find none and end.
    uint subgroups = gl_NumSubgroups;
    uint tiles = gl_NumWorkGroups.x * gl_NumWorkGroups.y * subgroups;
    while (true) {
        uint tile = 0u;
        if (subgroupElect()) tile = atomicAdd(stats.tiles_taken, 1u);
        tile = subgroupBroadcastFirst(tile);
        if (tile >= tiles) break;
        uint group = tile / subgroups;
        uint local = (tile % subgroups) * gl_SubgroupSize + gl_SubgroupInvocationID;
        render_invocation(uvec2(group % gl_NumWorkGroups.x, group / gl_NumWorkGroups.x), uvec2(local % gl_WorkGroupSize.x, local / gl_WorkGroupSize.x));
    }
#else
    render_invocation(gl_WorkGroupID.xy, gl_LocalInvocationID.xy);
#endif
}
