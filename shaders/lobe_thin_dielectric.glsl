// One lobe of the material model (materials.glsl): its sample_ and eval_ pair, as materials.glsl
// describes them. Included by materials.glsl after the Lobe and BsdfSample types.

// Thin dielectric (Mitsuba's and pbrt-v4's thindielectric): a sheet whose two parallel faces are
// the same interface. Light that enters leaves parallel to how it came, after any number of inner
// reflections; summing them, F + (1 - F)^2 F (1 + F^2 + F^4 + ...) = 2F / (1 + F) is reflected and
// the rest passes straight through. Smooth only (a delta lobe: no eval).
bool sample_thin_dielectric(Lobe l, vec3 d, inout Rng rng, inout BsdfSample s) {
    float f = fresnel_dielectric(-dot(d, l.n), l.eta);
    float reflected = 2.0 * f / (1.0 + f);
    s.dir = rng_next(rng) < reflected ? reflect(d, l.n) : d;
    s.weight = vec3(l.scale);
    return true;
}
