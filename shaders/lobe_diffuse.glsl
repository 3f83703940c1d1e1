// One lobe of the material model (materials.glsl): its sample_ and eval_ pair, as materials.glsl
// describes them. Included by materials.glsl after the Lobe and BsdfSample types.

// Diffuse: albedo / pi, cosine-weighted sampling.
bool sample_diffuse(Lobe l, vec3 d, inout Rng rng, inout BsdfSample s) {
    s.dir = sample_cosine_hemisphere(rng_next2(rng), l.n);
    s.pdf = max(0.0, dot(s.dir, l.n)) * INV_PI;
    s.weight = l.color * l.scale;
    return s.pdf > 0.0;
}

vec3 eval_diffuse(Lobe l, vec3 d, vec3 wi, out float pdf) {
    float cos_i = dot(wi, l.n);
    pdf = 0.0;
    if (cos_i <= 0.0) return vec3(0.0);
    pdf = cos_i * INV_PI;
    return l.color * (INV_PI * cos_i * l.scale);
}
