// Microfacet distributions, isotropic, in a local frame whose +z is the macro normal on the side
// the light leaves towards the viewer (wo.z > 0): GGX (Trowbridge-Reitz) and Beckmann (Mitsuba's
// default). Geometry only: the lobes in materials.glsl add Fresnel. Masking-shadowing is Smith's
// height-correlated form G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) (Heitz 2014) for both, used for
// refraction too as pbrt-v4 does. GGX samples the normals visible from wo (Heitz 2018); Beckmann
// samples D(m) cos(theta_m) (Walter et al. 2007), whose inversion is exact, where visible-normal
// sampling would need an approximate inverse of erf and so a pdf that is not quite the density.
// Only kernels for scenes with a rough Beckmann lobe have its branches (SCENE_BECKMANN).

// MICROFACET_* must match layout.rs (the material's MATERIAL_BECKMANN flag chooses).
const uint MICROFACET_GGX = 0u;
const uint MICROFACET_BECKMANN = 1u;

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

bool is_beckmann(uint distribution) {
    return SCENE_BECKMANN == 1 && distribution == MICROFACET_BECKMANN;
}

// erfc(x) for x >= 0 (Abramowitz and Stegun 7.1.26: absolute error below 1.5e-7).
float erfc_nonnegative(float x) {
    float t = 1.0 / (1.0 + 0.3275911 * x);
    float poly = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429))));
    return poly * exp(-x * x);
}

float beckmann_d(vec3 m, float alpha) {
    if (m.z <= 0.0) return 0.0;
    float c2 = m.z * m.z;
    float a2 = alpha * alpha;
    return exp(-max(0.0, 1.0 - c2) / (c2 * a2)) / (PI * a2 * c2 * c2);
}

// Smith's Lambda of Beckmann: (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi)), a = 1 / (alpha tan).
float beckmann_lambda(vec3 w, float alpha) {
    float c2 = w.z * w.z;
    if (c2 <= 0.0) return 1e30;
    float s2 = max(0.0, 1.0 - c2);
    if (s2 <= 0.0) return 0.0;
    float a = abs(w.z) / (alpha * sqrt(s2));
    return 0.5 * (exp(-a * a) / (a * 1.7724538509055159) - erfc_nonnegative(a));
}

// A normal with density D(m) cos(theta_m): tan^2 = -alpha^2 ln(1 - u.x), phi = 2 pi u.y.
vec3 sample_beckmann_normal(float alpha, vec2 u) {
    float tan2 = -alpha * alpha * log(max(1e-30, 1.0 - u.x));
    float c = inversesqrt(1.0 + tan2);
    float s = sqrt(max(0.0, 1.0 - c * c));
    float phi = 2.0 * PI * u.y;
    return vec3(s * cos(phi), s * sin(phi), c);
}

float microfacet_d(vec3 m, float alpha, uint distribution) {
    return is_beckmann(distribution) ? beckmann_d(m, alpha) : ggx_d(m, alpha);
}

float microfacet_g1(vec3 w, float alpha, uint distribution) {
    return is_beckmann(distribution) ? 1.0 / (1.0 + beckmann_lambda(w, alpha)) : ggx_g1(w, alpha);
}

float microfacet_g2(vec3 wo, vec3 wi, float alpha, uint distribution) {
    if (is_beckmann(distribution)) return 1.0 / (1.0 + beckmann_lambda(wo, alpha) + beckmann_lambda(wi, alpha));
    return ggx_g2(wo, wi, alpha);
}

// A microfacet normal for light leaving along wo, with density normal_pdf; false when it faces
// away from wo (Beckmann's sampling draws those; GGX's visible normals never do).
bool sample_normal(vec3 wo, float alpha, uint distribution, vec2 u, out vec3 m) {
    if (is_beckmann(distribution)) {
        m = sample_beckmann_normal(alpha, u);
        return dot(wo, m) > 0.0;
    }
    m = sample_vndf(wo, alpha, u);
    return true;
}

// The density of sample_normal's m.
float normal_pdf(vec3 wo, vec3 m, float alpha, uint distribution) {
    if (is_beckmann(distribution)) return beckmann_d(m, alpha) * max(0.0, m.z);
    return vndf_pdf(wo, m, alpha);
}

// Solid-angle pdf of wi = reflect(-wo, m) when m has density normal_pdf: times 1 / (4 wo.m).
float reflection_pdf(vec3 wo, vec3 m, float alpha, uint distribution) {
    if (is_beckmann(distribution)) return normal_pdf(wo, m, alpha, distribution) / (4.0 * abs(dot(wo, m)));
    return ggx_g1(wo, alpha) * ggx_d(m, alpha) / (4.0 * wo.z);
}

// Solid-angle pdf of a refracted wi through m (eta = eta_i / eta_t): the normal's density times
// Walter et al.'s Jacobian |wi.m| / (eta wo.m + wi.m)^2.
float refraction_pdf(vec3 wo, vec3 wi, vec3 m, float alpha, float eta, uint distribution) {
    float denom = eta * dot(wo, m) + dot(wi, m);
    return normal_pdf(wo, m, alpha, distribution) * abs(dot(wi, m)) / (denom * denom);
}

// f cos / pdf of a direction wi reached through sampled normal m, without Fresnel and the lobe's
// scale: D G2 (wo.m) / (wo.z normal_pdf), the same for reflection and refraction once the
// Jacobians cancel. For GGX's visible normals that is G2 / G1(wo); for Beckmann's D cos sampling,
// G2 (wo.m) / (wo.z m.z).
float microfacet_weight(vec3 wo, vec3 wi, vec3 m, float alpha, uint distribution) {
    if (is_beckmann(distribution)) return microfacet_g2(wo, wi, alpha, distribution) * dot(wo, m) / (wo.z * m.z);
    return ggx_g2(wo, wi, alpha) / ggx_g1(wo, alpha);
}
