// The R/T material model. Each vertex picks one lobe: with probability R a reflector (a mirror, or
// a conductor with Fresnel), with probability T a dielectric, otherwise the base (diffuse, or a
// plastic: diffuse under a dielectric coat); a glTF clear coat over all of them comes first. A lobe's weight equals the probability of picking it,
// so the two cancel; the path then samples, evaluates and MIS-weights that lobe alone, which keeps
// delta lobes (roughness ~0) and rough lobes in one scheme. Rough lobes are GGX or Beckmann
// (microfacet.glsl), anisotropic where the material's alpha along v differs from its alpha along u.

#include "fresnel.glsl"
#include "microfacet.glsl"

const uint LOBE_DIFFUSE = 0u;         // albedo / pi
const uint LOBE_REFLECT = 1u;         // GGX or mirror reflection with Fresnel `fresnel`
const uint LOBE_DIELECTRIC = 2u;      // GGX or smooth reflection + refraction (Walter et al. 2007)
const uint LOBE_COATED_DIFFUSE = 3u;  // the diffuse base of a plastic, seen through its coat
const uint LOBE_THIN_DIELECTRIC = 4u; // a thin sheet of glass: reflects, or passes straight through

// Fresnel of the coat's reflection, next to the CONDUCTOR_* kinds of layout.glsl.
const uint FRESNEL_COAT = 3u;

// Index of refraction of glTF's clear coat (KHR_materials_clearcoat fixes it).
const float CLEARCOAT_IOR = 1.5;

struct Lobe {
    uint kind;
    uint fresnel;     // LOBE_REFLECT: CONDUCTOR_* or FRESNEL_COAT
    vec2 alpha;       // microfacet alpha along t and b; below ALPHA_DELTA the lobe is smooth (a delta lobe)
    uint distribution;  // MICROFACET_* of the rough R and T lobes and the coat
    float eta;        // eta_i / eta_t across the interface (dielectric and coat)
    vec3 color;       // diffuse albedo, F0 (CONDUCTOR_ALBEDO) or eta (CONDUCTOR_COMPLEX)
    vec3 k;           // CONDUCTOR_COMPLEX: extinction coefficient
    float scale;      // the lobe's weight over the probability of picking it
    float coat_norm;  // coated diffuse: 1 / (1 - the coat's cosine-weighted average Fresnel)
    vec3 t;           // shading frame; n faces the side the ray came from, t is the surface's u
                      // direction where the lobe is anisotropic (else any)
    vec3 b;
    vec3 n;
};

struct BsdfSample {
    vec3 dir;
    vec3 weight;  // f cos / pdf, times the lobe's scale
    float pdf;    // solid angle; meaningless for a delta lobe
    bool delta;
};

vec3 to_local(Lobe l, vec3 w) {
    return vec3(dot(w, l.t), dot(w, l.b), dot(w, l.n));
}

vec3 from_local(Lobe l, vec3 w) {
    return w.x * l.t + w.y * l.b + w.z * l.n;
}

bool lobe_is_delta(Lobe l) {
    return ((l.kind == LOBE_REFLECT || l.kind == LOBE_DIELECTRIC) && max(l.alpha.x, l.alpha.y) < ALPHA_DELTA) || l.kind == LOBE_THIN_DIELECTRIC;
}

vec3 lobe_fresnel(Lobe l, float cos_i) {
    float c = clamp(cos_i, 0.0, 1.0);
    if (SCENE_COMPLEX_CONDUCTORS == 1 && l.fresnel == CONDUCTOR_COMPLEX) return fresnel_conductor(c, l.color, l.k);
    if (l.fresnel == CONDUCTOR_ALBEDO) return fresnel_schlick(c, l.color);
    if (l.fresnel == FRESNEL_COAT) return vec3(fresnel_dielectric(c, l.eta));
    return vec3(1.0);
}

// Picks the lobe for a ray arriving along `d` at a surface with unit shading normal `ns` (on the
// front side) and `tangent` (the surface's u direction, not necessarily unit nor normal to ns;
// zero where the surface has none), at which the ray is `entering` (coming from the front side).
Lobe pick_lobe(Material m, vec3 d, vec3 ns, vec3 tangent, bool entering, inout Rng rng) {
    Lobe l;
    l.n = entering ? ns : -ns;
    onb(l.n, l.t, l.b);
    // A scene without rough lobes (SCENE_ROUGH_LOBES, src/render/features.rs) has every R and T lobe
    // smooth: the constant lets the compiler drop the GGX code.
    l.alpha = vec2(SCENE_ROUGH_LOBES == 1 ? m.params.w : 0.0);
    // An anisotropic material (its alpha along v in volume.w) lays its lobes' x axis along the
    // surface's u direction, made normal to the shading normal (Mitsuba's and pbrt-v4's shading
    // frame). Without a tangent the arbitrary frame above stays (Mitsuba's coordinate_system(n)).
    // The sign of b does not matter: D and Lambda depend on the squares of x and y alone.
    if (SCENE_ANISOTROPIC == 1 && m.volume.w > 0.0) {
        l.alpha.y = m.volume.w;
        vec3 t = tangent - dot(tangent, l.n) * l.n;
        if (dot(t, t) > 1e-12) {
            l.t = normalize(t);
            l.b = cross(l.n, l.t);
        }
    }
    l.distribution = (material_flags(m) & MATERIAL_BECKMANN) != 0u ? MICROFACET_BECKMANN : MICROFACET_GGX;
    l.eta = 1.0;
    l.color = m.albedo_r.rgb;
    l.k = vec3(0.0);
    l.fresnel = CONDUCTOR_MIRROR;
    l.scale = 1.0;
    l.coat_norm = 0.0;
    // glTF's clear coat over the whole material (KHR_materials_clearcoat): mix(material, coat,
    // factor x F(cos_o)), with F the Fresnel of a dielectric of index CLEARCOAT_IOR on the
    // viewing direction and the coat's BRDF a GGX reflection with no Fresnel of its own. Picked
    // with probability equal to its weight (scale 1), else the material's own pick below, whose
    // weight 1 - factor x F(cos_o) is likewise its probability. The coat lies on the front side:
    // a ray from behind (inside a closed mesh) meets the material alone. A material without a
    // coat draws no number here, so it renders exactly as it would without this code.
    if (SCENE_CLEARCOAT == 1 && entering && m.coat.x > 0.0) {
        float f = fresnel_dielectric(clamp(-dot(d, l.n), 0.0, 1.0), 1.0 / CLEARCOAT_IOR);
        if (rng_next(rng) < m.coat.x * f) {
            l.kind = LOBE_REFLECT;
            l.alpha = vec2(SCENE_ROUGH_LOBES == 1 ? m.coat.y * m.coat.y : 0.0);
            l.distribution = MICROFACET_GGX;  // glTF's, whatever the material's own lobes use
            return l;
        }
    }
    float r = m.albedo_r.w;
    float t = m.emission_t.w;
    float xi = rng_next(rng);
    // Without reflectors (SCENE_REFLECTORS) every r is 0, without dielectrics every t.
    if (SCENE_REFLECTORS == 1 && xi < r) {
        l.kind = LOBE_REFLECT;
        l.fresnel = floatBitsToUint(m.conductor_eta.w);
        if (SCENE_COMPLEX_CONDUCTORS == 1 && l.fresnel == CONDUCTOR_COMPLEX) {
            l.color = m.conductor_eta.rgb;
            l.k = m.conductor_k.rgb;
        }
    } else if (SCENE_DIELECTRICS == 1 && xi < r + t && SCENE_THIN_DIELECTRICS == 1 && (material_flags(m) & MATERIAL_THIN) != 0u) {
        // A sheet has the outside medium on both sides, whichever side the ray comes from.
        l.kind = LOBE_THIN_DIELECTRIC;
        l.eta = 1.0 / m.params.x;
    } else if (SCENE_DIELECTRICS == 1 && xi < r + t) {
        l.kind = LOBE_DIELECTRIC;
        l.eta = entering ? 1.0 / m.params.x : m.params.x;
    } else if (SCENE_COATED == 1 && m.conductor_k.w > 0.0) {
        // A plastic is coated on both sides. Its coat reflects F(wo) and passes the rest to the
        // base; pick by the share each carries, so that a dark base is rarely sampled.
        l.eta = 1.0 / m.params.x;
        l.coat_norm = m.conductor_k.w;
        if ((material_flags(m) & MATERIAL_COAT_INTERNAL) != 0u) {
            // Light the coat reflects back down scatters off the base again: of what the base
            // sends up, the share 1 - Fin leaves (Fin the coat's average internal reflectance,
            // 1 - Fin = (1 - Fout) / ior^2 by reciprocity) and the rest returns, so the base's
            // albedo becomes rho (1 - Fin) / (1 - rho Fin) (Mitsuba's nonlinear plastic).
            float leaves = 1.0 / (l.coat_norm * m.params.x * m.params.x);
            l.color = l.color * leaves / (1.0 - l.color * (1.0 - leaves));
        }
        float f = fresnel_dielectric(clamp(-dot(d, l.n), 0.0, 1.0), l.eta);
        float share = f + (1.0 - f) * max3(l.color);
        float p_coat = share > 0.0 ? f / share : 1.0;
        if (rng_next(rng) < p_coat) {
            l.kind = LOBE_REFLECT;
            l.fresnel = FRESNEL_COAT;
            l.scale = 1.0 / p_coat;
        } else {
            l.kind = LOBE_COATED_DIFFUSE;
            l.scale = 1.0 / (1.0 - p_coat);
        }
    } else {
        l.kind = LOBE_DIFFUSE;
    }
    return l;
}

// Each lobe is a pair, in its own file lobe_<lobe>.glsl: sample_<lobe> (given s.delta, the rest
// of s to fill) draws a direction for a ray arriving along `d` (false when it yields none: the
// path ends) with its weight f cos / pdf times the lobe's scale and its solid-angle pdf;
// eval_<lobe> gives f cos times the scale for light arriving from `wi` (world) and leaving along
// -d, and the pdf with which sample_<lobe> draws wi (a delta lobe has no eval_). sample_lobe and
// eval_lobe dispatch on the kind; a new lobe is a LOBE_* kind, its file, an include here and a case
// in each (and its cases in tests/bsdf_sampling.rs, which checks every kind listed here has some;
// render/kernel.rs's tests check the file and the cases).

#include "lobe_diffuse.glsl"
#include "lobe_coated_diffuse.glsl"
#include "lobe_reflect.glsl"
#include "lobe_dielectric.glsl"
#include "lobe_thin_dielectric.glsl"

// Samples the lobe for a ray arriving along `d`. False when it yields no direction (the path ends).
bool sample_lobe(Lobe l, vec3 d, inout Rng rng, out BsdfSample s) {
    s.delta = lobe_is_delta(l);
    s.pdf = 0.0;
    s.dir = vec3(0.0);
    s.weight = vec3(0.0);
    switch (l.kind) {
        case LOBE_DIFFUSE: return sample_diffuse(l, d, rng, s);
        case LOBE_COATED_DIFFUSE: return sample_coated_diffuse(l, d, rng, s);
        case LOBE_REFLECT: return SCENE_REFLECTORS == 1 ? sample_reflect(l, d, rng, s) : false;
        case LOBE_DIELECTRIC: return SCENE_DIELECTRICS == 1 ? sample_dielectric(l, d, rng, s) : false;
        case LOBE_THIN_DIELECTRIC: return SCENE_THIN_DIELECTRICS == 1 ? sample_thin_dielectric(l, d, rng, s) : false;
        default: return false;
    }
}

// f cos for light arriving from `wi` (world) and leaving along -d, times the lobe's scale, and the
// solid-angle pdf with which sample_lobe picks wi. Delta lobes have neither (both 0).
vec3 eval_lobe(Lobe l, vec3 d, vec3 wi, out float pdf) {
    pdf = 0.0;
    if (lobe_is_delta(l)) return vec3(0.0);
    switch (l.kind) {
        case LOBE_DIFFUSE: return eval_diffuse(l, d, wi, pdf);
        case LOBE_COATED_DIFFUSE: return eval_coated_diffuse(l, d, wi, pdf);
        case LOBE_REFLECT: return SCENE_REFLECTORS == 1 ? eval_reflect(l, d, wi, pdf) : vec3(0.0);
        case LOBE_DIELECTRIC: return SCENE_DIELECTRICS == 1 ? eval_dielectric(l, d, wi, pdf) : vec3(0.0);
        default: return vec3(0.0);
    }
}

// Radiance emitted towards a viewer on the front side (or either side when two-sided).
vec3 emitted_radiance(Material m, bool front_side) {
    return (front_side || m.params.y > 0.5) ? m.emission_t.rgb : vec3(0.0);
}
