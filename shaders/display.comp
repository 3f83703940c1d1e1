#version 450
// The viewer's picture: the accumulation (or an AOV) of every pixel as the 8-bit sRGB bytes the
// window shows, packed in the swapchain's byte order (src/view/display.rs binds and drives it).
//
// The beauty is PNG output's tonemap exactly: no curve is evaluated here. The host computes, from
// the very functions PNG output uses, the smallest radiance sum that reaches each 8-bit code for
// the pixels' sample count (src/image/display_codes.rs); a channel's code is the number of those
// thresholds its sum's bits reach. Comparing bit patterns is exact on every device, where pow()
// and division are not. The AOV views are for looking only and use ordinary float maths.

layout(local_size_x = 8, local_size_y = 8) in;

layout(std430, binding = 0) readonly buffer Accumulation { vec4 accumulation[]; };   // rgb: radiance sum, a: samples
layout(std430, binding = 1) readonly buffer AlbedoDepth { vec4 albedo_depth[]; };     // rgb: albedo sum, a: depth sum
layout(std430, binding = 2) readonly buffer NormalHits { vec4 normal_hits[]; };       // xyz: normal sum, w: hits
// Two tables of 256 thresholds (f32 bit patterns): for pixels holding count_low samples, then count_high.
layout(std430, binding = 3) readonly buffer Thresholds { uint thresholds[512]; };
layout(std430, binding = 4) writeonly buffer Pixels { uint pixels[]; };

const uint VIEW_BEAUTY = 0u;
const uint VIEW_ALBEDO = 1u;
const uint VIEW_NORMAL = 2u;
const uint VIEW_DEPTH = 3u;

layout(push_constant) uniform DisplayParams {
    uint width;
    uint height;
    // While a pass is dispatched in bands, pixels hold one of two sample counts.
    float count_low;
    float count_high;
    uint view;
    // 1: the swapchain stores B, G, R, A; 0: R, G, B, A.
    uint bgra;
    // Distance shown black in the depth view.
    float depth_far;
    uint unused;
};

const uint INFINITY_BITS = 0x7f800000u;

// The largest code k whose threshold the sum reaches; NaN and negative sums (sign bit set) are 0,
// as PNG output clamps them.
uint code_of(float sum, uint table) {
    uint bits = floatBitsToUint(sum);
    if (bits > INFINITY_BITS) {
        return 0u;
    }
    uint low = 0u;   // thresholds[table + 0] is 0: every sum reaches code 0
    uint high = 255u;
    while (low < high) {
        uint mid = (low + high + 1u) / 2u;
        if (thresholds[table * 256u + mid] <= bits) {
            low = mid;
        } else {
            high = mid - 1u;
        }
    }
    return low;
}

float srgb(float linear) {
    float x = clamp(linear, 0.0, 1.0);
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

uvec3 bytes_of(vec3 display) {
    return uvec3(round(clamp(display, 0.0, 1.0) * 255.0));
}

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= width || p.y >= height) {
        return;
    }
    uint i = p.y * width + p.x;
    vec4 a = accumulation[i];
    uvec3 rgb;
    if (view == VIEW_BEAUTY) {
        uint table = a.w == count_high ? 1u : 0u;
        rgb = uvec3(code_of(a.r, table), code_of(a.g, table), code_of(a.b, table));
    } else if (view == VIEW_ALBEDO) {
        vec3 albedo = albedo_depth[i].rgb / max(a.w, 1.0);
        rgb = bytes_of(vec3(srgb(albedo.r), srgb(albedo.g), srgb(albedo.b)));
    } else if (view == VIEW_NORMAL) {
        vec4 n = normal_hits[i];
        rgb = n.w > 0.0 && dot(n.xyz, n.xyz) > 0.0 ? bytes_of(normalize(n.xyz) * 0.5 + 0.5) : uvec3(0u);
    } else {
        vec4 n = normal_hits[i];
        float depth = albedo_depth[i].a / max(n.w, 1.0);
        // sRGB-encoded, so that the near half of the scene is not all dark.
        rgb = n.w > 0.0 ? bytes_of(vec3(srgb(1.0 - clamp(depth / depth_far, 0.0, 1.0)))) : uvec3(0u);
    }
    uvec3 ordered = bgra == 1u ? rgb.bgr : rgb;
    pixels[i] = ordered.x | (ordered.y << 8) | (ordered.z << 16) | (255u << 24);
}
