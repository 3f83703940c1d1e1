// Fresnel reflectance: dielectric interfaces, conductors (complex IOR) and Schlick's F0 form.

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

// Unpolarised reflectance of a conductor of complex index eta + i k (relative to the outside
// medium), per channel, for cos_i in (0, 1] (pbrt-v3's FrConductor).
vec3 fresnel_conductor(float cos_i, vec3 eta, vec3 k) {
    float c2 = cos_i * cos_i;
    float s2 = 1.0 - c2;
    vec3 eta2 = eta * eta;
    vec3 k2 = k * k;
    vec3 t0 = eta2 - k2 - s2;
    vec3 a2b2 = sqrt(t0 * t0 + 4.0 * eta2 * k2);
    vec3 t1 = a2b2 + c2;
    vec3 a = sqrt(max(vec3(0.0), 0.5 * (a2b2 + t0)));
    vec3 t2 = 2.0 * cos_i * a;
    vec3 rs = (t1 - t2) / (t1 + t2);
    vec3 t3 = c2 * a2b2 + s2 * s2;
    vec3 t4 = t2 * s2;
    vec3 rp = rs * (t3 - t4) / (t3 + t4);
    return clamp(0.5 * (rp + rs), 0.0, 1.0);
}

// Schlick's approximation from the reflectance at normal incidence (glTF's metals).
vec3 fresnel_schlick(float cos_i, vec3 f0) {
    float m = 1.0 - clamp(cos_i, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}
