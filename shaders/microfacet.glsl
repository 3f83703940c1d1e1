// The GGX (Trowbridge-Reitz) microfacet distribution, isotropic, in a local frame whose +z is the
// macro normal on the side the light leaves towards the viewer (wo.z > 0). Geometry only: the
// lobes in materials.glsl add Fresnel. Masking-shadowing is Smith's height-correlated form
// G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) (Heitz 2014), used for refraction too as pbrt-v4 does.
// Directions are sampled from the distribution of normals visible from wo (Heitz 2018).

// Below this alpha a lobe is treated as perfectly smooth (a delta lobe): D would overflow floats.
const float ALPHA_DELTA = 1e-3;

float ggx_d(vec3 m, float alpha) {
    if (m.z <= 0.0) return 0.0;
    float a2 = alpha * alpha;
    float c2 = m.z * m.z;
    float t = c2 * (a2 - 1.0) + 1.0;
    return a2 / (PI * t * t);
}

// Smith's Lambda for direction w (either hemisphere).
float ggx_lambda(vec3 w, float alpha) {
    float c2 = w.z * w.z;
    if (c2 <= 0.0) return 1e30;
    float tan2 = max(0.0, 1.0 - c2) / c2;
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

float ggx_g1(vec3 w, float alpha) {
    return 1.0 / (1.0 + ggx_lambda(w, alpha));
}

float ggx_g2(vec3 wo, vec3 wi, float alpha) {
    return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

// A microfacet normal visible from wo (wo.z > 0), with density vndf_pdf.
vec3 sample_vndf(vec3 wo, float alpha, vec2 u) {
    vec3 vh = normalize(vec3(alpha * wo.x, alpha * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    vec3 t1 = len2 > 0.0 ? vec3(-vh.y, vh.x, 0.0) * inversesqrt(len2) : vec3(1.0, 0.0, 0.0);
    vec3 t2 = cross(vh, t1);
    float r = sqrt(u.x);
    float phi = 2.0 * PI * u.y;
    float p1 = r * cos(phi);
    float p2 = r * sin(phi);
    float s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt(max(0.0, 1.0 - p1 * p1)) + s * p2;
    vec3 nh = p1 * t1 + p2 * t2 + sqrt(max(0.0, 1.0 - p1 * p1 - p2 * p2)) * vh;
    return normalize(vec3(alpha * nh.x, alpha * nh.y, max(1e-7, nh.z)));
}

// Density of visible normals: G1(wo) max(0, wo.m) D(m) / wo.z.
float vndf_pdf(vec3 wo, vec3 m, float alpha) {
    return ggx_g1(wo, alpha) * max(0.0, dot(wo, m)) * ggx_d(m, alpha) / wo.z;
}

// Solid-angle pdf of wi = reflect(-wo, m) when m has density vndf_pdf: times 1 / (4 wo.m).
float reflection_pdf(vec3 wo, vec3 m, float alpha) {
    return ggx_g1(wo, alpha) * ggx_d(m, alpha) / (4.0 * wo.z);
}

// Solid-angle pdf of a refracted wi through m (eta = eta_i / eta_t): the vndf density times
// Walter et al.'s Jacobian |wi.m| / (eta wo.m + wi.m)^2.
float refraction_pdf(vec3 wo, vec3 wi, vec3 m, float alpha, float eta) {
    float denom = eta * dot(wo, m) + dot(wi, m);
    return vndf_pdf(wo, m, alpha) * abs(dot(wi, m)) / (denom * denom);
}
