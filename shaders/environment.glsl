// Radiance arriving from infinitely far along a direction: a constant sky, or an HDR map.
// World axes: +y up, -z forward (the centre of an angular probe and of a lat-long map).
// Map texels are stored row-major, top row first.

// Bilinear lookup at continuous texel coordinates (texel centres at +0.5); `wrap_x` for lat-long maps.
vec3 env_bilinear(vec2 texel, bool wrap_x) {
    int w = int(frame.env_width);
    int h = int(frame.env_height);
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
            sum += wx * wy * load_env_texels(y * w + x).rgb;
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

// Rotating the map by +angle about +y is looking up the direction rotated by -angle.
vec3 world_to_map(vec3 d) {
    float c = frame.env_rotation.x;
    float s = frame.env_rotation.y;
    return vec3(c * d.x - s * d.z, d.y, s * d.x + c * d.z);
}

vec3 map_to_world(vec3 r) {
    float c = frame.env_rotation.x;
    float s = frame.env_rotation.y;
    return vec3(c * r.x + s * r.z, r.y, -s * r.x + c * r.z);
}

// Where a map-space direction falls on the map, in [0, 1]^2 (x right, y down the image).
vec2 map_position(vec3 r) {
    if (frame.env_kind == ENV_ANGULAR) {
        vec2 uv = angular_map_uv(r);
        return vec2(0.5 * (uv.x + 1.0), 0.5 * (1.0 - uv.y));
    }
    return latlong_uv(r);
}

vec3 environment_radiance(vec3 d) {
    uint kind = frame.env_kind;
    if (SCENE_ENV_MAP == 0 || kind == ENV_CONSTANT) return frame.env_color;
    vec2 texel = map_position(world_to_map(d)) * vec2(frame.env_width, frame.env_height);
    return frame.env_color * env_bilinear(texel, kind == ENV_LATLONG);
}

// Importance sampling of the map (src/render/env_sampling.rs builds the distribution): a cell is
// picked from the marginal and conditional CDFs, a point uniformly inside it, and the point's
// density on the map, p(x, y) = p(cell) * width * height, becomes a solid-angle density through
// the projection's Jacobian: dw = 2 pi^2 sin(theta) dx dy (lat-long), 4 pi sin(pi r) / r dx dy
// (angular, r the distance from the centre in [-1, 1]^2 units).

bool environment_sampled() {
    return SCENE_ENV_MAP == 1 && frame.env_selection_probability > 0.0;
}

// Index i in [0, count) with cdf[offset + i] <= u < cdf[offset + i + 1].
uint cdf_search(uint offset, uint count, float u) {
    uint lo = 0u;
    uint hi = count;
    while (hi - lo > 1u) {
        LOOP_ITERATION();
        uint mid = (lo + hi) / 2u;
        if (load_env_cdf(offset + mid) <= u) lo = mid; else hi = mid;
    }
    return lo;
}

// Solid angle per unit map area at map position p (0 where the map has no direction).
float map_jacobian(vec2 p) {
    if (frame.env_kind == ENV_ANGULAR) {
        float r = length(vec2(2.0 * p.x - 1.0, 1.0 - 2.0 * p.y));
        if (r > 1.0) return 0.0;
        return 4.0 * PI * (r < 1e-6 ? PI : sin(PI * r) / r);
    }
    return 2.0 * PI * PI * sin(PI * p.y);
}

// Solid-angle density with which sample_environment picks world direction d.
float environment_pdf(vec3 d) {
    uint w = frame.env_width;
    uint h = frame.env_height;
    vec2 p = map_position(world_to_map(d));
    uint x = min(uint(p.x * float(w)), w - 1u);
    uint y = min(uint(p.y * float(h)), h - 1u);
    uint row = h + 1u + y * (w + 1u);
    float p_cell = (load_env_cdf(y + 1u) - load_env_cdf(y)) * (load_env_cdf(row + x + 1u) - load_env_cdf(row + x));
    float jacobian = map_jacobian(p);
    return jacobian > 0.0 ? p_cell * float(w * h) / jacobian : 0.0;
}

bool sample_environment(vec2 u, out vec3 dir, out float pdf) {
    uint w = frame.env_width;
    uint h = frame.env_height;
    uint y = cdf_search(0u, h, u.y);
    float p_row = load_env_cdf(y + 1u) - load_env_cdf(y);
    uint row = h + 1u + y * (w + 1u);
    uint x = cdf_search(row, w, u.x);
    float p_column = load_env_cdf(row + x + 1u) - load_env_cdf(row + x);
    // Reuse each number's position inside its CDF step as the position inside the cell.
    vec2 inside = vec2((u.x - load_env_cdf(row + x)) / p_column, (u.y - load_env_cdf(y)) / p_row);
    vec2 p = (vec2(x, y) + clamp(inside, 0.0, 1.0)) / vec2(w, h);
    float jacobian = map_jacobian(p);
    if (!(jacobian > 0.0)) return false;
    vec3 r;
    if (frame.env_kind == ENV_ANGULAR) {
        vec2 ab = vec2(2.0 * p.x - 1.0, 1.0 - 2.0 * p.y);
        float radius = length(ab);
        float angle = PI * radius;
        vec2 xy = radius > 0.0 ? ab / radius * sin(angle) : vec2(0.0);
        r = vec3(xy, -cos(angle));
    } else {
        float phi = (p.x - 0.5) * 2.0 * PI;
        float theta = p.y * PI;
        r = vec3(sin(theta) * sin(phi), cos(theta), -sin(theta) * cos(phi));
    }
    dir = map_to_world(r);
    pdf = p_row * p_column * float(w * h) / jacobian;
    return pdf > 0.0;
}
