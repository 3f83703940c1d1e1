#version 460
// caustica's path tracing kernel: one invocation per pixel of the dispatched row band, adding
// `pass.sample_count` samples to the pixel's running sum.
// The host prepends `#define BVH_MAX_DEPTH` and `BVH_MAX_LEAF_SIZE` (the BVH builder's bounds), and
// `AOVS` (1: also accumulate the denoiser features at bindings 20 and 21; 0: a kernel without them).

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "layout.glsl"
#include "chunked_buffers.glsl"
#include "rng.glsl"
#include "sampling.glsl"
#include "intersect.glsl"
#include "bvh.glsl"
#include "textures.glsl"
#include "surface.glsl"
#include "materials.glsl"
#include "environment.glsl"
#include "lights.glsl"
#include "camera.glsl"
#include "integrator.glsl"

void main() {
    uvec2 pixel = uvec2(gl_GlobalInvocationID.x, gl_GlobalInvocationID.y + pass.row_offset);
    uint width = frame.image.x;
    if (pixel.x >= width || gl_GlobalInvocationID.y >= pass.row_count || pixel.y >= frame.image.y) return;
    uint index = pixel.y * width + pixel.x;
    vec4 sum = load_accum(index);
    uint rays = 0u;
    uint nonfinite = 0u;
    float clamp_max = frame.lens.z;
#if AOVS
    vec4 albedo_depth = load_aov_albedo_depth(index);
    vec4 normal_hits = load_aov_normal_hits(index);
#endif
    for (uint s = 0u; s < pass.sample_count; ++s) {
        Rng rng = rng_for_sample(frame.image.z, index, pass.sample_base + s, frame.sampling.x);
        rng_set_dimensions(rng, 0u, DIMS_CAMERA);
        vec3 origin, dir;
        camera_ray(pixel, rng, origin, dir);
        FirstHit first = FirstHit(vec3(0.0), vec3(0.0), 0.0, false, AOVS == 1);
        vec3 radiance = trace_path(origin, dir, rng, rays, first);
        // A NaN or infinity would poison the pixel for good; drop that sample's radiance, count it.
        if (any(isnan(radiance)) || any(isinf(radiance))) {
            radiance = vec3(0.0);
            nonfinite += 1u;
        }
        // Optional firefly clamp (biased): scale down, keeping the sample's colour.
        float peak = max3(radiance);
        if (clamp_max > 0.0 && peak > clamp_max) radiance *= clamp_max / peak;
        sum += vec4(radiance, 1.0);
#if AOVS
        albedo_depth += vec4(first.albedo, first.depth);
        normal_hits += vec4(first.normal, first.hit ? 1.0 : 0.0);
#endif
    }
    store_accum(index, sum);
#if AOVS
    store_aov_albedo_depth(index, albedo_depth);
    store_aov_normal_hits(index, normal_hits);
#endif
    atomicAdd(stats.ray_count, rays);
    if (nonfinite > 0u) atomicAdd(stats.nonfinite_samples, nonfinite);
}
