// Phase functions of participating media (shaders/medium.glsl): isotropic and Henyey-Greenstein,
// each sampled exactly, so a sampled direction's weight (phase / pdf) is 1. Directions are the
// ways light travels: `dir` along the path's ray into the scattering point, `wi` out of it, and
// cos_theta = dot(dir, wi) (g > 0 scatters forward, along dir).

// Below this |g| Henyey-Greenstein is taken as isotropic, in evaluation and sampling alike (its
// inverse CDF divides by g).
const float HG_ISOTROPIC_G = 1e-3;

// Henyey-Greenstein's density per unit solid angle at cos_theta, normalised over the sphere.
float phase_hg(float g, float cos_theta) {
    if (abs(g) < HG_ISOTROPIC_G) return 0.25 * INV_PI;
    float g2 = g * g;
    float denom = 1.0 + g2 - 2.0 * g * cos_theta;
    return 0.25 * INV_PI * (1.0 - g2) / (denom * sqrt(denom));
}

// A direction about `dir` distributed as phase_hg(g, .): cos_theta by the inverse of HG's CDF,
// the azimuth uniform.
vec3 sample_phase_hg(float g, vec3 dir, vec2 u) {
    float cos_theta;
    if (abs(g) < HG_ISOTROPIC_G) {
        cos_theta = 1.0 - 2.0 * u.x;
    } else {
        float s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        cos_theta = clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
    }
    float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    float phi = 2.0 * PI * u.y;
    return to_world(vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta), dir);
}
