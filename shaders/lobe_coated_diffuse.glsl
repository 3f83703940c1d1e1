// One lobe of the material model (materials.glsl): its sample_ and eval_ pair, as materials.glsl
// describes them. Included by materials.glsl after the Lobe and BsdfSample types.

// The coated base of a plastic: light refracts into the coat (1 - F(wi)), scatters diffusely and
// leaves through it (1 - F(wo)). Dividing by 1 - the average of F over the cosine-weighted
// hemisphere makes the exit factor integrate to 1, so a white base under a smooth coat reflects
// exactly 1 - F(wo) beside the coat's F(wo): no energy is created. The coat's internal
// reflections and the eta^2 spreading are not modelled; under a rough coat the sum stays at or
// below 1 (it is E_spec(wo) + 1 - F(wo), and GGX reflects E_spec <= F up to ~1e-3 at low
// roughness). Sampled like the diffuse lobe.
vec3 coated_diffuse(Lobe l, float cos_o, float cos_i) {
    float through = (1.0 - fresnel_dielectric(cos_o, l.eta)) * (1.0 - fresnel_dielectric(cos_i, l.eta));
    return l.color * (INV_PI * through * l.coat_norm);
}

bool sample_coated_diffuse(Lobe l, vec3 d, inout Rng rng, inout BsdfSample s) {
    s.dir = sample_cosine_hemisphere(rng_next2(rng), l.n);
    float cos_i = max(0.0, dot(s.dir, l.n));
    s.pdf = cos_i * INV_PI;
    s.weight = coated_diffuse(l, clamp(-dot(d, l.n), 0.0, 1.0), cos_i) * (PI * l.scale);
    return s.pdf > 0.0;
}

vec3 eval_coated_diffuse(Lobe l, vec3 d, vec3 wi, out float pdf) {
    float cos_i = dot(wi, l.n);
    pdf = 0.0;
    if (cos_i <= 0.0) return vec3(0.0);
    pdf = cos_i * INV_PI;
    return coated_diffuse(l, clamp(-dot(d, l.n), 0.0, 1.0), cos_i) * (cos_i * l.scale);
}
