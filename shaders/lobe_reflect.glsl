// One lobe of the material model (materials.glsl): its sample_ and eval_ pair, as materials.glsl
// describes them. Included by materials.glsl after the Lobe and BsdfSample types.

// Reflector: a mirror (smooth) or GGX reflection, with the lobe's Fresnel.
bool sample_reflect(Lobe l, vec3 d, inout Rng rng, inout BsdfSample s) {
    if (s.delta) {
        s.dir = reflect(d, l.n);
        s.weight = lobe_fresnel(l, -dot(d, l.n)) * l.scale;
        return true;
    }
    vec3 wo = to_local(l, -d);
    if (wo.z <= 0.0) return false;
    vec3 m;
    if (!sample_normal(wo, l.alpha, l.distribution, rng_next2(rng), m)) return false;
    vec3 wi = reflect(-wo, m);
    if (wi.z <= 0.0) return false;
    s.pdf = reflection_pdf(wo, m, l.alpha, l.distribution);
    s.weight = lobe_fresnel(l, dot(wo, m)) * (microfacet_weight(wo, wi, m, l.alpha, l.distribution) * l.scale);
    s.dir = from_local(l, wi);
    return s.pdf > 0.0;
}

vec3 eval_reflect(Lobe l, vec3 d, vec3 wi_world, out float pdf) {
    pdf = 0.0;
    vec3 wo = to_local(l, -d);
    vec3 wi = to_local(l, wi_world);
    if (wo.z <= 0.0 || wi.z <= 0.0) return vec3(0.0);
    vec3 h = normalize(wo + wi);
    float cos_h = dot(wo, h);
    if (cos_h <= 0.0) return vec3(0.0);
    pdf = reflection_pdf(wo, h, l.alpha, l.distribution);
    return lobe_fresnel(l, cos_h) * (microfacet_d(h, l.alpha, l.distribution) * microfacet_g2(wo, wi, l.alpha, l.distribution) / (4.0 * wo.z) * l.scale);
}
