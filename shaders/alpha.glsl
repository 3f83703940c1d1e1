// Alpha: how much of a mesh surface is there (glTF alphaMode MASK and BLEND, MTL d and map_d;
// Material.alpha in layout.glsl). It is decided where a ray meets a triangle, inside traversal
// (bvh.glsl), so camera, bounce and shadow rays alike pass through what is not there, and
// shading, light sampling and MIS never meet it. Only kernels for scenes with alpha materials
// call it (SCENE_ALPHA); there, a triangle a ray meets whose material is opaque costs two loads.
// An emitter with alpha is counted by next-event estimation as rays that meet it count it:
// light_presence (lights.glsl) weighs each point it samples by alpha_presence there.

// A uniform number in [0, 1) fixed by the ray and the triangle it meets: BLEND's coin. The same ray
// meeting the same triangle always gets the same answer (so an image does not depend on how its
// samples are split), while rays of different samples or bounces differ in origin or direction and
// draw independently: the surface is met with probability equal to its opacity, an unbiased
// estimate of blending it over what lies behind.
float blend_coin(vec3 o, vec3 d, uint triangle, uint instance) {
    uvec3 a = floatBitsToUint(o);
    uvec3 b = floatBitsToUint(d);
    uint h = pcg_hash(b.z ^ pcg_hash(b.y ^ pcg_hash(b.x ^ pcg_hash(a.z ^ pcg_hash(a.y ^ pcg_hash(a.x ^ pcg_hash(triangle ^ pcg_hash(instance))))))));
    return float(h >> 8u) * (1.0 / 16777216.0);
}

// Whether the ray o + t d (in the instance's object space) that meets mesh triangle `triangle`
// (`tri`, at barycentrics `bary`) hits it, or passes through where its material's opacity says
// the surface is absent.
bool alpha_passes(MeshTriangle tri, uint triangle, uint instance, vec2 bary, vec3 o, vec3 d) {
    vec4 alpha = load_materials(load_triangle_materials(triangle)).alpha;
    uint mode = floatBitsToUint(alpha.w);
    if (mode == ALPHA_OPAQUE) return true;
    float opacity = alpha.y;
    uint map = floatBitsToUint(alpha.x);
    // A mesh without texture coordinates has zeros in their place (acceleration.rs): its texture
    // is read at (0, 0) here as in shading (surface.glsl) and light sampling (light_presence).
    if (SCENE_TEXTURES == 1 && map != NO_TEXTURE) {
        uvec3 v = floatBitsToUint(vec3(tri.v0.w, tri.e1.w, tri.e2.w));
        vec2 uv = (1.0 - bary.x - bary.y) * load_vertex_uvs(v.x) + bary.x * load_vertex_uvs(v.y) + bary.y * load_vertex_uvs(v.z);
        opacity *= texture_alpha(map, uv);
    }
    return mode == ALPHA_MASK ? opacity >= alpha.z : blend_coin(o, d, triangle, instance) < opacity;
}

// How much of a surface of non-opaque alpha row `alpha` (Material.alpha) and opacity `opacity` is
// there, in expectation over the coin alpha_passes tosses: 1 or 0 under MASK, the opacity under
// BLEND. Next-event estimation takes this expectation instead of tossing the coin (less noise, the
// same mean), which also keeps MIS consistent: a BSDF ray meets the emitter with probability equal
// to the opacity, so both strategies estimate opacity x radiance.
float alpha_presence(vec4 alpha, float opacity) {
    return floatBitsToUint(alpha.w) == ALPHA_MASK ? (opacity >= alpha.z ? 1.0 : 0.0) : opacity;
}
