#version 460
// caustica's path tracing kernel: one invocation per pixel of the dispatched row band, adding
// `pass.sample_count` samples to the pixel's running sum.
// The host prepends `#define BVH_MAX_DEPTH` and `BVH_MAX_LEAF_SIZE` (the BVH builder's bounds).

layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

#include "layout.glsl"
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
    vec4 sum = accum[index];
    uint rays = 0u;
    for (uint s = 0u; s < pass.sample_count; ++s) {
        Rng rng = rng_for_sample(frame.image.z, index, pass.sample_base + s);
        vec3 dir = camera_ray(pixel, rng_next2(rng));
        vec3 radiance = trace_path(frame.cam_origin.xyz, dir, rng, rays);
        // A NaN or infinity would poison the pixel for good; drop that sample's radiance.
        if (any(isnan(radiance)) || any(isinf(radiance))) radiance = vec3(0.0);
        sum += vec4(radiance, 1.0);
    }
    accum[index] = sum;
    atomicAdd(stats.ray_count, rays);
}
