// What a ray hit: the world-space surface of an analytic primitive or of an instanced mesh
// triangle, with its geometric normal (for sides and ray offsets) and shading normal (for BSDFs).

struct Surface {
    vec3 point;
    vec3 ng;        // unit geometric normal on the front side (outward, or by winding)
    vec3 ns;        // unit shading normal: interpolated vertex normals, turned to ng's side (and
                    // bent by a normal map)
    vec3 tangent;   // the surface's u direction in the world, for anisotropic lobes (not unit,
                    // not normal to ns; zero where there is none). Kernels without anisotropic
                    // materials (SCENE_ANISOTROPIC) leave it zero.
    vec2 uv;
#if SCENE_VERTEX_COLORS
    vec3 color;     // the interpolated vertex colour (glTF COLOR_0) the albedo is multiplied by;
                    // white where there is none
#endif
    uint material;
};

// Octahedral decoding of a snorm16x2 unit vector (Cigolle et al. 2014).
vec3 unpack_normal(uint packed) {
    vec2 e = unpackSnorm2x16(packed);
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) {
        n.xy = (1.0 - abs(n.yx)) * vec2(n.x >= 0.0 ? 1.0 : -1.0, n.y >= 0.0 ? 1.0 : -1.0);
    }
    return normalize(n);
}

// Normals map by the inverse transpose of the placement, i.e. the transpose of world_to_object.
vec3 normal_to_world(vec4 world_to_object[3], vec3 n) {
    return normalize(world_to_object[0].xyz * n.x + world_to_object[1].xyz * n.y + world_to_object[2].xyz * n.z);
}

#if SCENE_NORMAL_MAPS
// The world-space shading normal `ns` bent by a tangent-space normal map, glTF's way: the texel
// (linear, (normal + 1) / 2) has x along the tangent, y along the bitangent cross(n, t) x sign and
// z along the normal, x and y times `scale`. `n` and `t` are the interpolated object-space normal
// and tangent (w: the bitangent's sign, the same at a triangle's corners). The tangent and
// bitangent are built in object space and carried to the world as directions, so a mirroring
// placement turns the bitangent with the surface.
vec3 normal_mapped(uint map, float scale, vec2 uv, vec3 n, vec4 t, vec4 object_to_world[3], vec3 ns) {
    vec3 tangent = t.xyz - dot(t.xyz, n) * n;
    if (dot(tangent, tangent) <= 1e-12) return ns;
    tangent = normalize(tangent);
    vec3 bitangent = cross(n, tangent) * (t.w < 0.0 ? -1.0 : 1.0);
    vec3 texel = texture_rgb(map, uv) * 2.0 - 1.0;
    vec3 bent = scale * texel.x * normalize(affine_vector(object_to_world, tangent))
              + scale * texel.y * normalize(affine_vector(object_to_world, bitangent)) + texel.z * ns;
    return dot(bent, bent) > 1e-12 ? normalize(bent) : ns;
}
#endif

// The object-space tangent (w: the bitangent's sign) of mesh triangle `tri` at barycentrics `w`,
// for a normal map and for an anisotropic lobe alike.
vec4 interpolated_tangent(uvec3 tri, vec3 w) {
    return w.x * load_vertex_tangents(tri.x) + w.y * load_vertex_tangents(tri.y) + w.z * load_vertex_tangents(tri.z);
}

// Shape `i`'s record. Where the scene's shapes are a handful of few shapes (SCENE_FEW_SHAPE_SELECTS:
// src/render/features.rs says how many), each is loaded at its constant index, a load lavapipe
// makes once for all lanes, and each lane's own is picked by selects; a storage load at each
// lane's own index runs lane by lane, behind a bounds check (docs/benchmarks/history.md, 2026-12-06, `ee3ce82`).
// FEW_SHAPE is bvh.glsl's, redefined here for the one list and then left undefined, so that no
// later file expands the list into the wrong code.
#undef FEW_SHAPE
#define FEW_SHAPE(k, kind) record = i == k ? prims[k] : record;
Primitive shape_record(uint i) {
#if SCENE_FEW_SHAPE_SELECTS
    Primitive record = prims[0];
    SCENE_FEW_SHAPES
    return record;
#else
    return prims[i];
#endif
}
#undef FEW_SHAPE

Surface surface_at(Hit hit, vec3 o, vec3 d) {
    Surface s;
    s.point = o + hit.t * d;
    uvec4 info = load_instances(hit.instance).info;
    if (SCENE_MESHES == 0 || (SCENE_PRIMITIVES == 1 && info.x == INSTANCE_PRIMITIVES)) {
        Primitive p = shape_record(hit.prim);
        s.ng = primitive_normal(p, s.point);
        s.ns = s.ng;
        s.tangent = SCENE_ANISOTROPIC == 1 ? primitive_tangent(p, s.point) : vec3(0.0);
        s.uv = vec2(0.0);
#if SCENE_VERTEX_COLORS
        s.color = vec3(1.0);
#endif
        s.material = prim_material(p);
        return s;
    }
    vec4 world_to_object[3] = load_instances(hit.instance).world_to_object;
    MeshTriangle triangle = load_mesh_triangles(hit.prim);
    uvec3 tri = floatBitsToUint(vec3(triangle.v0.w, triangle.e1.w, triangle.e2.w));
    vec3 w = vec3(1.0 - hit.bary.x - hit.bary.y, hit.bary);
    s.ng = normal_to_world(world_to_object, cross(triangle.e1.xyz, triangle.e2.xyz));
    s.ns = s.ng;
    s.tangent = vec3(0.0);
    s.uv = vec2(0.0);
    // A mesh with an anisotropic material carries tangents where it has texture coordinates
    // (src/scene/asset/mod.rs): MikkTSpace's, along growing u, carried to the world as directions.
    if (SCENE_ANISOTROPIC == 1 && (info.z & INSTANCE_HAS_TANGENTS) != 0u) {
        vec4 t = interpolated_tangent(tri, w);
        s.tangent = affine_vector(load_instances(hit.instance).object_to_world, t.xyz);
    }
    // Texture coordinates serve textures alone.
    if (SCENE_TEXTURES == 1 && (info.z & INSTANCE_HAS_UVS) != 0u) {
        s.uv = w.x * load_vertex_uvs(tri.x) + w.y * load_vertex_uvs(tri.y) + w.z * load_vertex_uvs(tri.z);
    }
#if SCENE_VERTEX_COLORS
    s.color = vec3(1.0);
    if ((info.z & INSTANCE_HAS_COLORS) != 0u) {
        s.color = w.x * load_vertex_colors(tri.x).rgb + w.y * load_vertex_colors(tri.y).rgb + w.z * load_vertex_colors(tri.z).rgb;
    }
#endif
    s.material = load_triangle_materials(hit.prim);
    if ((info.z & INSTANCE_HAS_NORMALS) != 0u) {
        vec3 n = w.x * unpack_normal(load_vertex_normals(tri.x)) + w.y * unpack_normal(load_vertex_normals(tri.y))
               + w.z * unpack_normal(load_vertex_normals(tri.z));
        if (dot(n, n) > 1e-12) {
            vec3 ns = normal_to_world(world_to_object, n);
            // The interpolated normal decides the side; a normal map only bends it.
            float side = dot(ns, s.ng) < 0.0 ? -1.0 : 1.0;
#if SCENE_NORMAL_MAPS
            uint normal_map = floatBitsToUint(load_materials(s.material).maps.y);
            if (normal_map != NO_TEXTURE && (info.z & INSTANCE_HAS_TANGENTS) != 0u) {
                vec4 t = interpolated_tangent(tri, w);
                ns = normal_mapped(normal_map, load_materials(s.material).maps.z, s.uv, normalize(n), t, load_instances(hit.instance).object_to_world, ns);
            }
#endif
            s.ns = side * ns;
        }
    }
    return s;
}

// The hit emitter as a world-space primitive, for its light-sampling pdf.
// Only emitters get here: without triangle lights (SCENE_TRIANGLE_LIGHTS; every emissive mesh
// triangle is one) the hit is one of the scene's own shapes.
Primitive world_primitive(Hit hit) {
    if (SCENE_MESHES == 0 || SCENE_TRIANGLE_LIGHTS == 0 || (SCENE_PRIMITIVES == 1 && load_instances(hit.instance).info.x == INSTANCE_PRIMITIVES)) return shape_record(hit.prim);
    vec4 object_to_world[3] = load_instances(hit.instance).object_to_world;
    MeshTriangle tri = load_mesh_triangles(hit.prim);
    Primitive p;
    p.a = vec4(affine_point(object_to_world, tri.v0.xyz), uintBitsToFloat(hit.prim));
    p.b = vec4(affine_vector(object_to_world, tri.e1.xyz), uintBitsToFloat(PRIM_TRIANGLE));
    p.c = vec4(affine_vector(object_to_world, tri.e2.xyz), uintBitsToFloat(load_triangle_materials(hit.prim)));
    return p;
}

// Material at the surface, with the vertex colour, the albedo, emission and clear coat textures applied, and the glTF
// metallic-roughness texture (G = roughness, B = metallic) turned into R, T and alpha as the loader
// does factors.
Material surface_material(Surface s) {
    Material m = load_materials(s.material);
#if SCENE_VERTEX_COLORS
    // glTF: the vertex colour multiplies the base colour (and so a metal's F0), before textures.
    m.albedo_r.rgb *= s.color;
#endif
#if SCENE_TEXTURES
    uint texture_index = floatBitsToUint(m.params.z);
    if (texture_index != NO_TEXTURE) m.albedo_r.rgb *= texture_rgb(texture_index, s.uv);
    uint mr_index = floatBitsToUint(m.metallic_roughness.x);
    if (mr_index != NO_TEXTURE) {
        vec3 mr = texture_rgb(mr_index, s.uv);
        float metallic = m.metallic_roughness.y * mr.b;
        float roughness = m.metallic_roughness.z * mr.g;
        m.albedo_r.w = metallic;
        m.emission_t.w = (1.0 - metallic) * m.metallic_roughness.w;
        m.params.w = roughness * roughness;
    }
#endif
#if SCENE_CLEARCOAT && SCENE_TEXTURES
    // The clear coat's factor from a texture's R channel, its roughness from one's G (glTF).
    uint coat_index = floatBitsToUint(m.coat.z);
    if (coat_index != NO_TEXTURE) m.coat.x *= texture_rgb(coat_index, s.uv).r;
    uint coat_roughness_index = floatBitsToUint(m.coat.w);
    if (coat_roughness_index != NO_TEXTURE) m.coat.y *= texture_rgb(coat_roughness_index, s.uv).g;
#endif
#if SCENE_EMISSIVE_TEXTURES
    uint emission_index = floatBitsToUint(m.maps.x);
    if (emission_index != NO_TEXTURE) m.emission_t.rgb *= texture_rgb(emission_index, s.uv);
#endif
    return m;
}
