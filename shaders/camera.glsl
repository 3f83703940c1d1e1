// Pinhole camera: vertical field of view, image row 0 at the top, `jitter` in [0,1)^2 inside the pixel.
vec3 camera_ray(uvec2 pixel, vec2 jitter) {
    vec2 film = (vec2(pixel) + jitter) / vec2(frame.image.xy);
    float tan_half = frame.cam_forward.w;
    float x = (2.0 * film.x - 1.0) * tan_half * frame.cam_right.w;
    float y = (1.0 - 2.0 * film.y) * tan_half;
    return normalize(frame.cam_forward.xyz + x * frame.cam_right.xyz + y * frame.cam_up.xyz);
}
