// Direct lighting: the environment map (when importance sampled) with probability
// frame.env_selection_probability, otherwise a light: an area light (every emissive primitive and
// mesh triangle, in world space: the `lights` buffer) or a point, spot or directional light
// (`punctual_lights`). A light is picked by the light tree (light_tree.glsl; where the scene
// selects "bvh" and has more than one light), in proportion to its power through an alias table,
// or uniformly (integrator.light_selection), then a point on an area light (or, for spheres, a
// direction in the cone they subtend; for triangles, in their spherical triangle), or a direction
// in a sun disk, is sampled. Pdfs are per unit solid angle at `ref` and include the probability of
// the pick. Point, spot and delta directional lights are delta lights: only next-event estimation
// reaches them, and it needs no MIS weight.
//
// The pick probability is a function of the light alone (light_pick_probability): its power by
// the host's formula (src/render/light_selection.rs) over the host's total. Next-event estimation
// and the MIS weight of an emitter hit by BSDF sampling both evaluate it, so the two weights of a
// path come from the same pdfs and sum to 1, with no light index needed at a hit; the alias table,
// built from the same powers in double precision, picks with that probability up to f32 rounding.
// With the light tree the pick probability depends on the shading point too, and a hit finds its
// light's index (hit_light in light_tree.glsl) to evaluate it.
//
// Each kind of light the scene lacks is compiled out (SCENE_SPHERE_LIGHTS, SCENE_TRIANGLE_LIGHTS,
// SCENE_PUNCTUAL_LIGHTS, SCENE_LIGHT_DISKS: src/render/features.rs): a quad-lit box samples no
// cones or spherical triangles. On Mesa 22.3's lavapipe every branch runs, taken or not.

struct LightSample {
    vec3 dir;
    float dist;
    float pdf;      // solid angle, including the probability of the pick; a delta light's: the pick
    vec3 radiance;  // a delta light's: what arrives at `ref` (intensity / d^2, or irradiance)
    bool delta;     // no other strategy can sample this light (no MIS weight)
};

// Flux of an emitter: area x pi x luminance of its radiance, twice for a two-sided quad or
// triangle (area_light_power in light_selection.rs). A textured emitter's luminance is its mean
// over the triangle, from the host (textured_emission.rs).
float light_power(Primitive p) {
    Material m = load_materials(prim_material(p));
    float sides = primitive_is_flat(p) && m.params.y > 0.5 ? 2.0 : 1.0;
    float luminance = dot(m.emission_t.rgb, vec3(0.2126, 0.7152, 0.0722));
#if SCENE_EMISSIVE_TEXTURES
    if (floatBitsToUint(m.maps.x) != NO_TEXTURE) luminance = load_triangle_emission(light_mesh_triangle(p));
#endif
    return primitive_area(p) * PI * luminance * sides;
}

#if SCENE_EMISSIVE_TEXTURES || SCENE_ALPHA
// Texture coordinates at `point` on the mesh-triangle light `p`: its barycentric coordinates in
// the world-space triangle, applied to the corners' coordinates in the order the light keeps.
vec2 light_uv(Primitive p, vec3 point) {
    vec3 e1 = p.b.xyz, e2 = p.c.xyz, v = point - p.a.xyz;
    float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    float v1 = dot(v, e1), v2 = dot(v, e2);
    float inv = 1.0 / (d11 * d22 - d12 * d12);
    float b1 = (d22 * v1 - d12 * v2) * inv, b2 = (d11 * v2 - d12 * v1) * inv;
    MeshTriangle triangle = load_mesh_triangles(light_mesh_triangle(p));
    uvec3 corner = floatBitsToUint(vec3(triangle.v0.w, triangle.e1.w, triangle.e2.w));
    if ((floatBitsToUint(p.a.w) & TRIANGLE_LIGHT_MIRRORED) != 0u) corner.yz = corner.zy;
    return (1.0 - b1 - b2) * load_vertex_uvs(corner.x) + b1 * load_vertex_uvs(corner.y) + b2 * load_vertex_uvs(corner.z);
}
#endif

#if SCENE_ALPHA
// How much of area light `p` (of material `m`) is there at `point`, which light sampling drew from
// the whole triangle: rays that meet the light find it only where its alpha keeps it (alpha_passes),
// and next-event estimation must count the same light, or an emitter with alpha is too bright by
// its light-sampled share. Only mesh triangles carry alpha.
float light_presence(Primitive p, Material m, vec3 point) {
    if (floatBitsToUint(m.alpha.w) == ALPHA_OPAQUE) return 1.0;
    float opacity = m.alpha.y;
    uint map = floatBitsToUint(m.alpha.x);
    if (SCENE_TEXTURES == 1 && map != NO_TEXTURE) opacity *= texture_alpha(map, light_uv(p, point));
    return alpha_presence(m.alpha, opacity);
}
#endif

// Probability that next-event estimation picks a light of power `power` (the map's share taken
// out): by power, or uniformly among the area and punctual lights.
float pick_probability(float power) {
    float share = 1.0 - frame.env_selection_probability;
    float total_power = frame.light_total_power;
    return total_power > 0.0 ? share * power / total_power : share / float(frame.light_count + frame.punctual_light_count);
}

// Probability that next-event estimation picks area light `p`.
float light_pick_probability(Primitive p) {
    return pick_probability(light_power(p));
}

// Spherical triangles (Arvo 1995): a triangle light that subtends a solid angle large enough for
// f32 to resolve is sampled uniformly in that solid angle, which takes the 1/r^2 and cosine at the
// light out of the estimator; smaller (or huge) ones are sampled by area. light_pdf makes the same
// choice from the same numbers.
const float MIN_SPHERICAL_AREA = 3e-4;
const float MAX_SPHERICAL_AREA = 6.22;

// The triangle `p` projected onto the unit sphere around `ref`: unit vertices, the cosine and sine
// of the angle at a, and the solid angle. False where it is too small or large to sample by solid
// angle. No inverse trigonometry: Mesa lowers asin and acos to polynomials good to about 1e-4,
// which made the solid angle (the sum of three angles, minus pi) 0.1 % too large on lavapipe and
// every such light 0.1 % too dark; the angle's cosine and sine come from dot and cross products,
// and the solid angle from one atan (Van Oosterom and Strackee 1983).
struct SphericalTriangle {
    vec3 a, b, c;
    float cos_alpha, sin_alpha;
    float area;
};

bool spherical_triangle(Primitive p, vec3 ref, out SphericalTriangle s) {
    s.a = normalize(p.a.xyz - ref);
    s.b = normalize(p.a.xyz + p.b.xyz - ref);
    s.c = normalize(p.a.xyz + p.c.xyz - ref);
    vec3 n_ab = cross(s.a, s.b), n_bc = cross(s.b, s.c), n_ca = cross(s.c, s.a);
    if (dot(n_ab, n_ab) == 0.0 || dot(n_bc, n_bc) == 0.0 || dot(n_ca, n_ca) == 0.0) return false;
    n_ab = normalize(n_ab);
    n_bc = normalize(n_bc);
    n_ca = normalize(n_ca);
    s.cos_alpha = dot(n_ab, -n_ca);
    s.sin_alpha = length(cross(n_ab, -n_ca));
    s.area = 2.0 * atan(abs(dot(s.a, cross(s.b, s.c))), 1.0 + dot(s.a, s.b) + dot(s.b, s.c) + dot(s.c, s.a));
    return s.area >= MIN_SPHERICAL_AREA && s.area <= MAX_SPHERICAL_AREA;
}

// Component of unit `v` orthogonal to unit `w`, normalised.
vec3 orthonormal_to(vec3 v, vec3 w) {
    return normalize(v - dot(v, w) * w);
}

// A direction uniform in the spherical triangle (Arvo 1995; as in pbrt-v4's
// SampleSphericalTriangle): pick the sub-triangle of area u.x * area, then a point on its edge arc.
vec3 sample_spherical_triangle(SphericalTriangle s, vec2 u) {
    float area_pi = s.area + PI;
    float ap_pi = mix(PI, area_pi, u.x);
    float cos_alpha = s.cos_alpha, sin_alpha = s.sin_alpha;
    float sin_phi = sin(ap_pi) * cos_alpha - cos(ap_pi) * sin_alpha;
    float cos_phi = cos(ap_pi) * cos_alpha + sin(ap_pi) * sin_alpha;
    float k1 = cos_phi + cos_alpha;
    float k2 = sin_phi - sin_alpha * dot(s.a, s.b);
    float cos_bp = (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / ((k2 * sin_phi + k1 * cos_phi) * sin_alpha);
    cos_bp = clamp(cos_bp, -1.0, 1.0);
    float sin_bp = sqrt(max(0.0, 1.0 - cos_bp * cos_bp));
    vec3 cp = cos_bp * s.a + sin_bp * orthonormal_to(s.c, s.a);
    float cos_theta = 1.0 - u.y * (1.0 - dot(cp, s.b));
    float sin_theta = sqrt(max(0.0, 1.0 - cos_theta * cos_theta));
    return cos_theta * s.b + sin_theta * orthonormal_to(cp, s.b);
}

// Whether a sphere light is sampled by the cone it subtends from a point `d2` (squared) from its
// centre: only from clearly outside. A point on the sphere itself (a surface of the light lit by
// its own inside) is sampled by area: the cone there is the whole inward hemisphere, and its near
// intersection is the point itself, so cone samples would be lost to rounding (5 % of the light
// inside an emissive sphere was, before).
bool sphere_sampled_by_cone(float d2, float r2) {
    return d2 > r2 * 1.0001;
}

// The cone sphere light `p` subtends from `ref`, as both its pdf and its sampling need it.
struct SphereCone {
    vec3 to_center;
    float distance2;  // squared distance to the centre
    float radius2;
    float cos_max;    // cosine of the cone's half angle; meaningful only when sampled by cone
};

// False when `ref` is not clearly outside the sphere (sampled by area then, see above).
bool sphere_cone(Primitive p, vec3 ref, out SphereCone c) {
    c.to_center = p.a.xyz - ref;
    c.distance2 = dot(c.to_center, c.to_center);
    c.radius2 = p.a.w * p.a.w;
    c.cos_max = sqrt(max(0.0, 1.0 - c.radius2 / c.distance2));
    return sphere_sampled_by_cone(c.distance2, c.radius2);
}

// Solid-angle pdf of sampling `p` from `ref` (sphere by cone when outside, triangle by solid
// angle where it can, otherwise by area), once picked with probability `pick`.
float light_pdf_picked(Primitive p, float pick, vec3 ref, vec3 dir, float dist) {
    switch (prim_kind(p)) {
        case PRIM_SPHERE: {
            SphereCone cone;
            if (SCENE_SPHERE_LIGHTS == 1 && sphere_cone(p, ref, cone)) return pick / (2.0 * PI * (1.0 - cone.cos_max));
            break;
        }
        case PRIM_QUAD: break;
        case PRIM_TRIANGLE: {
            SphericalTriangle s;
            if (SCENE_TRIANGLE_LIGHTS == 1 && spherical_triangle(p, ref, s)) return pick / s.area;
            break;
        }
        default: return 0.0;
    }
    // By area.
    vec3 point = ref + dist * dir;
    float cos_light = abs(dot(primitive_normal(p, point), dir));
    if (cos_light <= 0.0) return 0.0;
    return pick * dist * dist / (cos_light * primitive_area(p));
}

// Solid-angle pdf of picking and sampling `p` from `ref` by power or uniformly.
float light_pdf(Primitive p, vec3 ref, vec3 dir, float dist) {
    return light_pdf_picked(p, light_pick_probability(p), ref, dir, dist);
}

// Solid-angle pdf with which next-event estimation at `ref` samples the emitter `hit` that a ray
// along `dir` met `dist` away: with the light tree, its pick probability depends on `ref` and
// on which light it is (light_tree.glsl); otherwise on its power alone.
float hit_light_pdf(Hit hit, vec3 ref, vec3 dir, float dist) {
    Primitive p = world_primitive(hit);
#if SCENE_LIGHT_TREE
    if (light_tree_picks()) {
        float pick = (1.0 - frame.env_selection_probability) * light_tree_pmf(ref, hit_light(hit.instance, hit.prim));
        return light_pdf_picked(p, pick, ref, dir, dist);
    }
#endif
    return light_pdf(p, ref, dir, dist);
}

// Index of the area light to sample: a uniform entry of the alias table, kept or swapped for its
// alias; or a uniform index. Two numbers rather than one split into entry and remainder: with
// thousands of lights the remainder keeps too few bits for the thresholds of dim lights.
uint pick_light(uint count, inout Rng rng) {
    uint index = min(uint(rng_next(rng) * float(count)), count - 1u);
    if (frame.light_total_power > 0.0 && rng_next(rng) >= light_alias[index].threshold) index = light_alias[index].alias;
    return index;
}

// A point on area light `p` seen from `ref`, drawn as light_pdf says: a sphere by the cone it
// subtends (from outside) or by area, a quad by area, a triangle by solid angle where it can and
// otherwise by area. False when no point is drawn (or the kind is unknown).
bool sample_area_light_point(Primitive p, vec3 ref, vec2 u, out vec3 point) {
    point = ref;
    switch (prim_kind(p)) {
        case PRIM_SPHERE: {
            if (SCENE_SPHERE_LIGHTS == 0) return false;
            SphereCone cone;
            if (sphere_cone(p, ref, cone)) {
                vec3 dir = sample_cone(u, cone.to_center / sqrt(cone.distance2), cone.cos_max);
                float t = intersect_sphere(p.a.xyz, p.a.w, ref, dir, 1e30);
                // Grazing directions can miss by rounding: use the tangent distance.
                point = ref + dir * (t > 0.0 ? t : sqrt(max(0.0, cone.distance2 - cone.radius2)));
            } else {
                point = p.a.xyz + p.a.w * sample_uniform_sphere(u);
            }
            return true;
        }
        case PRIM_QUAD:
            point = p.a.xyz + u.x * p.b.xyz + u.y * p.c.xyz;
            return true;
        case PRIM_TRIANGLE: {
            if (SCENE_TRIANGLE_LIGHTS == 0) return false;
            SphericalTriangle s;
            if (spherical_triangle(p, ref, s)) {
                vec3 dir = sample_spherical_triangle(s, u);
                vec3 n = cross(p.b.xyz, p.c.xyz);
                float t = dot(p.a.xyz - ref, n) / dot(dir, n);
                if (!(t > 0.0) || isinf(t)) return false;
                point = ref + t * dir;
            } else {
                vec2 b = sample_triangle(u);
                point = p.a.xyz + b.x * p.b.xyz + b.y * p.c.xyz;
            }
            return true;
        }
        default: return false;
    }
}

// Spot falloff at unit direction `from_light` (from the light outwards): 1 within falloff_start
// of the axis, 0 beyond cone_angle, linear in the angle between (Mitsuba 3's spot). The angle
// comes from atan of sine and cosine: Mesa's acos is a polynomial good to about 1e-4.
float spot_falloff(PunctualLight l, vec3 from_light) {
    vec3 axis = l.axis_cos.xyz;
    float theta = atan(length(cross(from_light, axis)), dot(from_light, axis));
    float cone_angle = l.shape.x, falloff_start = l.shape.y;
    if (theta >= cone_angle) return 0.0;
    if (theta <= falloff_start) return 1.0;
    return (cone_angle - theta) / (cone_angle - falloff_start);
}

// A direction uniform in the cone around unit `axis` whose half-angle has 1 - cos =
// `one_minus_cos` (pdf 1 / (2 pi one_minus_cos)); exact for cones as narrow as the sun's, where
// sample_cone's 1 - cos_t^2 would cancel.
vec3 sample_narrow_cone(vec2 u, vec3 axis, float one_minus_cos) {
    float x = u.x * one_minus_cos;
    float sin_t = sqrt(max(0.0, x * (2.0 - x)));
    float phi = 2.0 * PI * u.y;
    return to_world(vec3(sin_t * cos(phi), sin_t * sin(phi), 1.0 - x), axis);
}

// Whether unit `dir` lies in the disk of directional light `l` (one with shape.z > 0): 1 - cos of
// its angle to the disk's centre, as half the squared chord, within the disk's.
bool in_light_disk(PunctualLight l, vec3 dir) {
    vec3 chord = dir + l.axis_cos.xyz;
    return 0.5 * dot(chord, chord) <= l.shape.z;
}

// Samples punctual light `l` from `ref`; ls.pdf is left without the pick probability.
bool sample_punctual_light(PunctualLight l, vec3 ref, vec2 u, inout LightSample ls) {
    ls.delta = true;
    ls.pdf = 1.0;
    switch (punctual_kind(l)) {
        case LIGHT_POINT:
        case LIGHT_SPOT: {
            vec3 to_light = l.position_kind.xyz - ref;
            float d2 = dot(to_light, to_light);
            if (!(d2 > 0.0)) return false;
            ls.dist = sqrt(d2);
            ls.dir = to_light / ls.dist;
            float falloff = punctual_kind(l) == LIGHT_SPOT ? spot_falloff(l, -ls.dir) : 1.0;
            ls.radiance = l.value_power.rgb * (falloff / d2);
            return true;
        }
        case LIGHT_DIRECTIONAL: {
            ls.dist = 1e30;
            ls.radiance = l.value_power.rgb;
            if (l.shape.z <= 0.0) {
                ls.dir = -l.axis_cos.xyz;
                return true;
            }
            // A disk: a direction uniform in its cone, weighed against BSDF sampling.
            ls.delta = false;
            ls.dir = sample_narrow_cone(u, -l.axis_cos.xyz, l.shape.z);
            ls.pdf = 1.0 / (2.0 * PI * l.shape.z);
            return true;
        }
        default: return false;
    }
}

// Radiance of the light disks (sun-like directional lights) along a ray `dir` that left the scene,
// MIS-weighted against their sampling by next-event estimation when the ray was drawn by a BSDF
// with solid-angle pdf `bsdf_pdf` (0: a camera ray, a delta lobe's or no next-event estimation:
// weight 1).
vec3 light_disks_radiance(vec3 dir, float bsdf_pdf) {
    vec3 sum = vec3(0.0);
    if (SCENE_LIGHT_DISKS == 0) return sum;
#if SCENE_LIGHT_TREE
    bool tree = light_tree_picks();
#else
    bool tree = false;
#endif
    for (uint i = 0u; i < frame.punctual_light_count; ++i) {
        LOOP_ITERATION();
        PunctualLight l = punctual_lights[i];
        if (punctual_kind(l) != LIGHT_DIRECTIONAL || l.shape.z <= 0.0 || !in_light_disk(l, dir)) continue;
        // Its pick: beside the light tree, its share there; else by power or uniformly.
        float pick = tree ? (1.0 - frame.env_selection_probability) * l.shape.w : pick_probability(l.value_power.w);
        float light_pdf = pick / (2.0 * PI * l.shape.z);
        sum += l.value_power.rgb * (bsdf_pdf > 0.0 ? power_heuristic(bsdf_pdf, light_pdf) : 1.0);
    }
    return sum;
}

bool sample_light(vec3 ref, inout Rng rng, out LightSample ls) {
    uint area_count = frame.light_count;
    uint count = area_count + frame.punctual_light_count;
    ls.pdf = 0.0;
    ls.delta = false;
    if (count == 0u) return false;
    // The light tree's pick probability of the light it picks (the map's share taken out).
    float tree_pick = 0.0;
    bool tree = false;
    uint index;
#if SCENE_LIGHT_TREE
    tree = light_tree_picks();
    if (tree) {
        if (!light_tree_pick(ref, rng_next(rng), index, tree_pick)) return false;
        tree_pick *= 1.0 - frame.env_selection_probability;
    } else
#endif
    {
        index = pick_light(count, rng);
        // One light (area or punctual): index 0, a constant, so that it and its material are
        // loaded once for the subgroup. The pick still draws its numbers: the general kernel's
        // sample streams.
        if (SCENE_LIGHT_PICK == 0) index = 0u;
    }
    vec2 u = rng_next2(rng);
    if (SCENE_PUNCTUAL_LIGHTS == 1 && index >= area_count) {
        PunctualLight l = punctual_lights[index - area_count];
        if (!sample_punctual_light(l, ref, u, ls)) return false;
        ls.pdf *= tree ? tree_pick : pick_probability(l.value_power.w);
        return ls.pdf > 0.0 && max3(ls.radiance) > 0.0;
    }
    Primitive p = load_lights(index);
    vec3 point;
    if (!sample_area_light_point(p, ref, u, point)) return false;
    vec3 to_point = point - ref;
    ls.dist = length(to_point);
    if (ls.dist <= 0.0) return false;
    ls.dir = to_point / ls.dist;
    bool front = dot(primitive_normal(p, point), ls.dir) < 0.0;
    Material m = load_materials(prim_material(p));
    ls.radiance = emitted_radiance(m, front);
#if SCENE_EMISSIVE_TEXTURES
    uint emission_index = floatBitsToUint(m.maps.x);
    if (emission_index != NO_TEXTURE) ls.radiance *= texture_rgb(emission_index, light_uv(p, point));
#endif
#if SCENE_ALPHA
    ls.radiance *= light_presence(p, m, point);
#endif
    ls.pdf = tree ? light_pdf_picked(p, tree_pick, ref, ls.dir, ls.dist) : light_pdf(p, ref, ls.dir, ls.dist);
    return ls.pdf > 0.0 && max3(ls.radiance) > 0.0;
}

// One direct-lighting sample from `ref`. No random number is drawn for the choice when the map is
// not sampled, so scenes without one keep their sample streams.
bool sample_direct(vec3 ref, inout Rng rng, out LightSample ls) {
    float p_env = frame.env_selection_probability;
    if (p_env > 0.0 && rng_next(rng) < p_env) {
        float pdf;
        if (!sample_environment(rng_next2(rng), ls.dir, pdf)) return false;
        ls.dist = 1e30;
        ls.delta = false;
        ls.pdf = p_env * pdf;
        ls.radiance = environment_radiance(ls.dir);
        return max3(ls.radiance) > 0.0;
    }
    return sample_light(ref, rng, ls);
}
