// The R/T material model: mirror with probability R, dielectric with probability T, diffuse otherwise.

const uint EVENT_DIFFUSE = 0u;
const uint EVENT_SPECULAR = 1u;

// Unpolarised Fresnel reflectance for a ray from a medium of index 1 into one of relative index
// eta_t/eta_i = 1/eta, with cos_i > 0. eta = eta_i / eta_t. Returns 1 on total internal reflection.
float fresnel_dielectric(float cos_i, float eta) {
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(1.0 - sin2_t);
    float rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

struct Scatter {
    vec3 dir;
    vec3 weight;   // throughput factor of this event (already divided by the event's probability)
    uint event;
};

// Picks and samples one event for a ray arriving along `d` at a surface with unit normal `n`
// (the front-side normal) at which the ray is `entering` (coming from the front side).
Scatter scatter(Material m, vec3 d, vec3 n, bool entering, inout Rng rng) {
    Scatter s;
    float r = m.albedo_r.w;
    float t = m.emission_t.w;
    vec3 n_in = entering ? n : -n;  // faces the side the ray came from
    float xi = rng_next(rng);
    if (xi < r) {
        s.dir = reflect(d, n_in);
        s.weight = vec3(1.0);
        s.event = EVENT_SPECULAR;
    } else if (xi < r + t) {
        float ior = m.params.x;
        float eta = entering ? 1.0 / ior : ior;
        float cos_i = -dot(d, n_in);
        float f = fresnel_dielectric(cos_i, eta);
        vec3 refracted = refract(d, n_in, eta);
        // refract() returns 0 at total internal reflection; rounding can put that just below f = 1.
        bool reflects = rng_next(rng) < f || dot(refracted, refracted) == 0.0;
        s.dir = reflects ? reflect(d, n_in) : refracted;
        s.weight = vec3(1.0);
        s.event = EVENT_SPECULAR;
    } else {
        s.dir = sample_cosine_hemisphere(rng_next2(rng), n_in);
        s.weight = m.albedo_r.rgb;
        s.event = EVENT_DIFFUSE;
    }
    return s;
}

// Radiance emitted towards a viewer on the front side (or either side when two-sided).
vec3 emitted_radiance(Material m, bool front_side) {
    return (front_side || m.params.y > 0.5) ? m.emission_t.rgb : vec3(0.0);
}
