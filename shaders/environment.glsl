// Radiance arriving from infinitely far along a direction: a constant sky, or an HDR map.
// World axes: +y up, -z forward (the centre of an angular probe and of a lat-long map).
// Map texels are stored row-major, top row first.

// Bilinear lookup at continuous texel coordinates (texel centres at +0.5); `wrap_x` for lat-long maps.
vec3 env_bilinear(vec2 texel, bool wrap_x) {
    int w = int(frame.env_size.x);
    int h = int(frame.env_size.y);
    vec2 f = texel - 0.5;
    ivec2 i0 = ivec2(floor(f));
    vec2 frac_part = f - vec2(i0);
    vec3 sum = vec3(0.0);
    for (int dy = 0; dy <= 1; ++dy) {
        for (int dx = 0; dx <= 1; ++dx) {
            int x = i0.x + dx;
            x = wrap_x ? ((x % w) + w) % w : clamp(x, 0, w - 1);
            int y = clamp(i0.y + dy, 0, h - 1);
            float wx = dx == 0 ? 1.0 - frac_part.x : frac_part.x;
            float wy = dy == 0 ? 1.0 - frac_part.y : frac_part.y;
            sum += wx * wy * env_texels[y * w + x].rgb;
        }
    }
    return sum;
}

// Debevec angular map: r = acos(-z) / (pi * sqrt(x^2 + y^2)), (u, v) = (x r, y r) in [-1, 1],
// u to the right, v up. Texels outside the unit disk were replaced on the host by their nearest
// texel inside it, so no value from outside the circle is ever used.
vec2 angular_map_uv(vec3 d) {
    float xy = length(d.xy);
    if (xy < 1e-7) return vec2(0.0, d.z < 0.0 ? 0.0 : 1.0);  // straight ahead, or straight back
    float r = acos(clamp(-d.z, -1.0, 1.0)) / (PI * xy);
    return d.xy * r;
}

// Lat-long: u = 0.5 + atan(x, -z) / (2 pi) (centre column looks down -z, +x to the right),
// v = acos(y) / pi (top row is straight up).
vec2 latlong_uv(vec3 d) {
    float phi = atan(d.x, -d.z);
    float theta = acos(clamp(d.y, -1.0, 1.0));
    return vec2(0.5 + phi * (0.5 * INV_PI), theta * INV_PI);
}

vec3 environment_radiance(vec3 d) {
    uint kind = frame.integrator.z;
    if (kind == ENV_CONSTANT) return frame.env_color.rgb;
    // Rotating the map by +angle about +y is looking up the direction rotated by -angle.
    float c = frame.env_rotation.x;
    float s = frame.env_rotation.y;
    vec3 r = vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
    vec2 size = vec2(frame.env_size.xy);
    if (kind == ENV_ANGULAR) {
        vec2 uv = angular_map_uv(r);
        vec2 texel = vec2(0.5 * (uv.x + 1.0), 0.5 * (1.0 - uv.y)) * size;
        return frame.env_color.rgb * env_bilinear(texel, false);
    }
    return frame.env_color.rgb * env_bilinear(latlong_uv(r) * size, true);
}
