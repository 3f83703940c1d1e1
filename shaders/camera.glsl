// Thin-lens camera: vertical field of view, image row 0 at the top. With a zero lens radius it is a
// pinhole and draws two random numbers a sample (the film position); otherwise two more (the lens).

// Film position inside the pixel, relative to its top-left corner in pixels, sampled from the
// reconstruction filter so that every sample weighs 1 (filter importance sampling).
vec2 filter_sample(vec2 u) {
    uint kind = frame.pixel_filter;
    if (kind == FILTER_TENT) {
        // Per axis inverse CDF of the tent of radius 1 pixel around the pixel centre.
        vec2 t = mix(1.0 - sqrt(2.0 - 2.0 * u), sqrt(2.0 * u) - 1.0, lessThan(u, vec2(0.5)));
        return 0.5 + t;
    }
    if (kind == FILTER_GAUSSIAN) {
        // Box-Muller, sigma 0.5 pixel, not truncated (1 - u > 0 bounds it at 2.9 pixels).
        float r = 0.5 * sqrt(-2.0 * log(1.0 - u.x));
        float phi = 2.0 * PI * u.y;
        return 0.5 + r * vec2(cos(phi), sin(phi));
    }
    return u;
}

// Shirley and Chiu's concentric map of [0,1)^2 onto the unit disk (area-preserving, low distortion).
vec2 sample_concentric_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    if (abs(o.x) > abs(o.y)) {
        float theta = 0.25 * PI * (o.y / o.x);
        return o.x * vec2(cos(theta), sin(theta));
    }
    float theta = 0.5 * PI - 0.25 * PI * (o.x / o.y);
    return o.y * vec2(cos(theta), sin(theta));
}

void camera_ray(uvec2 pixel, inout Rng rng, out vec3 origin, out vec3 dir) {
    vec2 film = (vec2(pixel) + filter_sample(rng_next2(rng))) / vec2(frame.width, frame.height);
    float tan_half = frame.tan_half_fov;
    float x = (2.0 * film.x - 1.0) * tan_half * frame.aspect;
    float y = (1.0 - 2.0 * film.y) * tan_half;
    // Unit length along the viewing axis, so `focus * through` lies on the focal plane.
    vec3 through = frame.cam_forward + x * frame.cam_right + y * frame.cam_up;
    origin = frame.cam_origin;
    float radius = frame.lens_radius;
    if (radius > 0.0) {
        vec2 lens = radius * sample_concentric_disk(rng_next2(rng));
        vec3 offset = lens.x * frame.cam_right + lens.y * frame.cam_up;
        dir = normalize(frame.focus_distance * through - offset);
        origin += offset;
    } else {
        dir = normalize(through);
    }
}
