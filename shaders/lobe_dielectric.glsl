// One lobe of the material model (materials.glsl): its sample_ and eval_ pair, as materials.glsl
// describes them. Included by materials.glsl after the Lobe and BsdfSample types.

// Dielectric: smooth or GGX reflection and refraction (Walter et al. 2007), each picked with its
// Fresnel weight.
bool sample_dielectric(Lobe l, vec3 d, inout Rng rng, inout BsdfSample s) {
    if (s.delta) {
        float f = fresnel_dielectric(-dot(d, l.n), l.eta);
        vec3 refracted = refract(d, l.n, l.eta);
        // refract() returns 0 at total internal reflection; rounding can put that just below f = 1.
        bool reflects = rng_next(rng) < f || dot(refracted, refracted) == 0.0;
        s.dir = reflects ? reflect(d, l.n) : refracted;
        s.weight = vec3(l.scale);
        return true;
    }
    vec3 wo = to_local(l, -d);
    if (wo.z <= 0.0) return false;
    vec3 m;
    if (!sample_normal(wo, l.alpha, l.distribution, rng_next2(rng), m)) return false;
    float f = fresnel_dielectric(dot(wo, m), l.eta);
    vec3 refracted = refract(-wo, m, l.eta);
    vec3 wi;
    if (rng_next(rng) < f || dot(refracted, refracted) == 0.0) {
        wi = reflect(-wo, m);
        if (wi.z <= 0.0) return false;
        s.pdf = f * reflection_pdf(wo, m, l.alpha, l.distribution);
    } else {
        wi = refracted;
        if (wi.z >= 0.0) return false;
        s.pdf = (1.0 - f) * refraction_pdf(wo, wi, m, l.alpha, l.eta, l.distribution);
    }
    s.weight = vec3(microfacet_weight(wo, wi, m, l.alpha, l.distribution) * l.scale);
    s.dir = from_local(l, wi);
    return s.pdf > 0.0;
}

vec3 eval_dielectric(Lobe l, vec3 d, vec3 wi_world, out float pdf) {
    pdf = 0.0;
    vec3 wo = to_local(l, -d);
    vec3 wi = to_local(l, wi_world);
    if (wo.z <= 0.0 || wi.z == 0.0) return vec3(0.0);
    if (wi.z > 0.0) {
        vec3 h = normalize(wo + wi);
        float cos_h = dot(wo, h);
        if (cos_h <= 0.0) return vec3(0.0);
        float f = fresnel_dielectric(cos_h, l.eta);
        pdf = f * reflection_pdf(wo, h, l.alpha, l.distribution);
        return vec3(f * microfacet_d(h, l.alpha, l.distribution) * microfacet_g2(wo, wi, l.alpha, l.distribution) / (4.0 * wo.z) * l.scale);
    }
    // Refraction: the generalised half vector, turned to the +z side.
    vec3 h = -(l.eta * wo + wi);
    if (dot(h, h) <= 0.0) return vec3(0.0);
    h = normalize(h);
    if (h.z < 0.0) h = -h;
    float cos_o = dot(wo, h);
    float cos_t = dot(wi, h);
    if (cos_o <= 0.0 || cos_t >= 0.0) return vec3(0.0);
    float f = fresnel_dielectric(cos_o, l.eta);
    float denom = l.eta * cos_o + cos_t;
    pdf = (1.0 - f) * refraction_pdf(wo, wi, h, l.alpha, l.eta, l.distribution);
    // Walter et al.'s BTDF times |wi.z|, without the 1/eta^2 radiance scaling (as the smooth
    // dielectric above: the factors cancel for a camera outside a closed object).
    float fcos = (1.0 - f) * microfacet_d(h, l.alpha, l.distribution) * microfacet_g2(wo, wi, l.alpha, l.distribution) * cos_o * abs(cos_t) / (wo.z * denom * denom);
    return vec3(fcos * l.scale);
}
