// Microfacet distributions in a local frame whose +z is the macro normal on the side the light
// leaves towards the viewer (wo.z > 0) and whose x axis is the surface's u direction where the
// lobe is anisotropic: GGX (Trowbridge-Reitz) and Beckmann (Mitsuba's default). Geometry only: the lobes in materials.glsl add Fresnel. Masking-shadowing is Smith's
// height-correlated form G2 = 1 / (1 + Lambda(wo) + Lambda(wi)) (Heitz 2014) for both, used for
// refraction too as pbrt-v4 does. GGX samples the normals visible from wo (Heitz 2018); Beckmann
// samples D(m) cos(theta_m) (Walter et al. 2007), whose inversion is exact, where visible-normal
// sampling would need an approximate inverse of erf and so a pdf that is not quite the density.
// Only kernels for scenes with a rough Beckmann lobe have its branches (SCENE_BECKMANN).
// alpha is vec2(alpha_x, alpha_y), the roughness along local x and y. Where they differ (and only
// in kernels for scenes with an anisotropic material, SCENE_ANISOTROPIC) the anisotropic forms of
// pbrt-v4 (util/scattering.h) and Mitsuba 3 (render/microfacet.h) apply; where they are equal the
// isotropic code runs as it always did, so isotropic lobes render bit for bit as before.

// MICROFACET_* must match layout.rs (the material's MATERIAL_BECKMANN flag chooses).
const uint MICROFACET_GGX = 0u;
const uint MICROFACET_BECKMANN = 1u;

// Below this alpha a lobe is treated as perfectly smooth (a delta lobe): D would overflow floats.
const float ALPHA_DELTA = 1e-3;

bool is_anisotropic(vec2 alpha) {
    return SCENE_ANISOTROPIC == 1 && alpha.x != alpha.y;
}

// alpha^2 tan^2 of w in the plane of w and z, the one number Smith's Lambda depends on: the
// anisotropic distribution seen along w's azimuth phi is isotropic with
// alpha^2 = alpha_x^2 cos^2 phi + alpha_y^2 sin^2 phi (Heitz 2014, section 5.4).
float alpha2_tan2(vec3 w, vec2 alpha) {
    float ax = alpha.x * w.x;
    float ay = alpha.y * w.y;
    return (ax * ax + ay * ay) / (w.z * w.z);
}

float ggx_d(vec3 m, vec2 alpha_xy) {
    if (m.z <= 0.0) return 0.0;
    if (is_anisotropic(alpha_xy)) {
        // 1 / (pi alpha_x alpha_y (x^2 / alpha_x^2 + y^2 / alpha_y^2 + z^2)^2) for unit m.
        vec3 stretched = vec3(m.x / alpha_xy.x, m.y / alpha_xy.y, m.z);
        float t = dot(stretched, stretched);
        return 1.0 / (PI * alpha_xy.x * alpha_xy.y * t * t);
    }
    float alpha = alpha_xy.x;
    float a2 = alpha * alpha;
    float c2 = m.z * m.z;
    float t = c2 * (a2 - 1.0) + 1.0;
    return a2 / (PI * t * t);
}

// Smith's Lambda for direction w (either hemisphere).
float ggx_lambda(vec3 w, vec2 alpha_xy) {
    float c2 = w.z * w.z;
    if (c2 <= 0.0) return 1e30;
    if (is_anisotropic(alpha_xy)) return 0.5 * (sqrt(1.0 + alpha2_tan2(w, alpha_xy)) - 1.0);
    float alpha = alpha_xy.x;
    float tan2 = max(0.0, 1.0 - c2) / c2;
    return 0.5 * (sqrt(1.0 + alpha * alpha * tan2) - 1.0);
}

float ggx_g1(vec3 w, vec2 alpha) {
    return 1.0 / (1.0 + ggx_lambda(w, alpha));
}

float ggx_g2(vec3 wo, vec3 wi, vec2 alpha) {
    return 1.0 / (1.0 + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

// A microfacet normal visible from wo (wo.z > 0), with density vndf_pdf: wo stretched by alpha
// to the configuration of alpha 1, a normal sampled there and stretched back (Heitz 2018; the
// same code for both axes' alphas, so equal ones take exactly the isotropic path).
vec3 sample_vndf(vec3 wo, vec2 alpha, vec2 u) {
    vec3 vh = normalize(vec3(alpha.x * wo.x, alpha.y * wo.y, wo.z));
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
    return normalize(vec3(alpha.x * nh.x, alpha.y * nh.y, max(1e-7, nh.z)));
}

// Density of visible normals: G1(wo) max(0, wo.m) D(m) / wo.z.
float vndf_pdf(vec3 wo, vec3 m, vec2 alpha) {
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

float beckmann_d(vec3 m, vec2 alpha_xy) {
    if (m.z <= 0.0) return 0.0;
    float c2 = m.z * m.z;
    if (is_anisotropic(alpha_xy)) {
        // exp(-tan^2 (cos^2 phi / alpha_x^2 + sin^2 phi / alpha_y^2)) / (pi alpha_x alpha_y cos^4).
        float sx = m.x / alpha_xy.x;
        float sy = m.y / alpha_xy.y;
        return exp(-(sx * sx + sy * sy) / c2) / (PI * alpha_xy.x * alpha_xy.y * c2 * c2);
    }
    float alpha = alpha_xy.x;
    float a2 = alpha * alpha;
    return exp(-max(0.0, 1.0 - c2) / (c2 * a2)) / (PI * a2 * c2 * c2);
}

// Smith's Lambda of Beckmann: (erf(a) - 1) / 2 + exp(-a^2) / (2 a sqrt(pi)), a = 1 / (alpha tan).
float beckmann_lambda(vec3 w, vec2 alpha_xy) {
    float c2 = w.z * w.z;
    if (c2 <= 0.0) return 1e30;
    float a;
    if (is_anisotropic(alpha_xy)) {
        float a2t2 = alpha2_tan2(w, alpha_xy);
        if (a2t2 <= 0.0) return 0.0;
        a = inversesqrt(a2t2);
    } else {
        float alpha = alpha_xy.x;
        float s2 = max(0.0, 1.0 - c2);
        if (s2 <= 0.0) return 0.0;
        a = abs(w.z) / (alpha * sqrt(s2));
    }
    return 0.5 * (exp(-a * a) / (a * 1.7724538509055159) - erfc_nonnegative(a));
}

// A normal with density D(m) cos(theta_m): tan^2 = -alpha^2 ln(1 - u.x), phi = 2 pi u.y.
// Anisotropic: D cos is a Gaussian of the slopes (-m.x / m.z, -m.y / m.z) with standard deviations
// alpha_x / sqrt(2) and alpha_y / sqrt(2), so the isotropic slope of alpha 1 is stretched by
// alpha. That is the distribution of pbrt-v3's and Mitsuba 3's phi = atan(alpha_y / alpha_x
// tan(2 pi u.y)), tan^2 = -ln(1 - u.x) / (cos^2 phi / alpha_x^2 + sin^2 phi / alpha_y^2), without
// the quadrant bookkeeping of the arctangent.
vec3 sample_beckmann_normal(vec2 alpha_xy, vec2 u) {
    float phi = 2.0 * PI * u.y;
    if (is_anisotropic(alpha_xy)) {
        float slope = sqrt(-log(max(1e-30, 1.0 - u.x)));
        return normalize(vec3(alpha_xy.x * slope * cos(phi), alpha_xy.y * slope * sin(phi), 1.0));
    }
    float alpha = alpha_xy.x;
    float tan2 = -alpha * alpha * log(max(1e-30, 1.0 - u.x));
    float c = inversesqrt(1.0 + tan2);
    float s = sqrt(max(0.0, 1.0 - c * c));
    return vec3(s * cos(phi), s * sin(phi), c);
}

float microfacet_d(vec3 m, vec2 alpha, uint distribution) {
    return is_beckmann(distribution) ? beckmann_d(m, alpha) : ggx_d(m, alpha);
}

float microfacet_g1(vec3 w, vec2 alpha, uint distribution) {
    return is_beckmann(distribution) ? 1.0 / (1.0 + beckmann_lambda(w, alpha)) : ggx_g1(w, alpha);
}

float microfacet_g2(vec3 wo, vec3 wi, vec2 alpha, uint distribution) {
    if (is_beckmann(distribution)) return 1.0 / (1.0 + beckmann_lambda(wo, alpha) + beckmann_lambda(wi, alpha));
    return ggx_g2(wo, wi, alpha);
}

// A microfacet normal for light leaving along wo, with density normal_pdf; false when it faces
// away from wo (Beckmann's sampling draws those; GGX's visible normals never do).
bool sample_normal(vec3 wo, vec2 alpha, uint distribution, vec2 u, out vec3 m) {
    if (is_beckmann(distribution)) {
        m = sample_beckmann_normal(alpha, u);
        return dot(wo, m) > 0.0;
    }
    m = sample_vndf(wo, alpha, u);
    return true;
}

// The density of sample_normal's m.
float normal_pdf(vec3 wo, vec3 m, vec2 alpha, uint distribution) {
    if (is_beckmann(distribution)) return beckmann_d(m, alpha) * max(0.0, m.z);
    return vndf_pdf(wo, m, alpha);
}

// Solid-angle pdf of wi = reflect(-wo, m) when m has density normal_pdf: times 1 / (4 wo.m).
float reflection_pdf(vec3 wo, vec3 m, vec2 alpha, uint distribution) {
    if (is_beckmann(distribution)) return normal_pdf(wo, m, alpha, distribution) / (4.0 * abs(dot(wo, m)));
    return ggx_g1(wo, alpha) * ggx_d(m, alpha) / (4.0 * wo.z);
}

// Solid-angle pdf of a refracted wi through m (eta = eta_i / eta_t): the normal's density times
// Walter et al.'s Jacobian |wi.m| / (eta wo.m + wi.m)^2.
float refraction_pdf(vec3 wo, vec3 wi, vec3 m, vec2 alpha, float eta, uint distribution) {
    float denom = eta * dot(wo, m) + dot(wi, m);
    return normal_pdf(wo, m, alpha, distribution) * abs(dot(wi, m)) / (denom * denom);
}

// f cos / pdf of a direction wi reached through sampled normal m, without Fresnel and the lobe's
// scale: D G2 (wo.m) / (wo.z normal_pdf), the same for reflection and refraction once the
// Jacobians cancel. For GGX's visible normals that is G2 / G1(wo); for Beckmann's D cos sampling,
// G2 (wo.m) / (wo.z m.z).
float microfacet_weight(vec3 wo, vec3 wi, vec3 m, vec2 alpha, uint distribution) {
    if (is_beckmann(distribution)) return microfacet_g2(wo, wi, alpha, distribution) * dot(wo, m) / (wo.z * m.z);
    return ggx_g2(wo, wi, alpha) / ggx_g1(wo, alpha);
}
