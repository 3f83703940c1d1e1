// Textures: RGBA8 texels stored as written; colour (TEXTURE_SRGB) is decoded to linear here, data
// (glTF metallic-roughness) read as stored, and alpha (A) is always linear. Filtered bilinearly
// with wrapping (repeat) coordinates, after decoding. uv (0, 0) is the image's top-left corner.

vec3 srgb_to_linear(vec3 c) {
    return mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), greaterThan(c, vec3(0.04045)));
}

vec3 texel_rgb(TextureInfo t, uint x, uint y) {
    vec3 stored = unpackUnorm4x8(load_texels(t.offset + y * t.width + x)).rgb;
    return (t.flags & TEXTURE_SRGB) != 0u ? srgb_to_linear(stored) : stored;
}

float texel_alpha(TextureInfo t, uint x, uint y) {
    return unpackUnorm4x8(load_texels(t.offset + y * t.width + x)).a;
}

// The four texels a bilinear lookup at uv blends: columns i0.x, i1.x and rows i0.y, i1.y, with
// weights f towards the second of each.
struct Bilinear {
    uvec2 i0;
    uvec2 i1;
    vec2 f;
};

Bilinear bilinear_texels(TextureInfo t, vec2 uv) {
    vec2 size = vec2(t.width, t.height);
    vec2 p = uv * size - 0.5;  // texel centres sit at half-integer coordinates
    vec2 f = p - floor(p);
    // mod() can round up to `size` itself for tiny negative inputs; clamp keeps the index in range.
    uvec2 i0 = uvec2(min(mod(floor(p), size), size - 1.0));
    uvec2 i1 = uvec2(i0.x + 1u == t.width ? 0u : i0.x + 1u, i0.y + 1u == t.height ? 0u : i0.y + 1u);
    return Bilinear(i0, i1, f);
}

vec3 texture_rgb(uint index, vec2 uv) {
    TextureInfo t = texture_infos[index];
    Bilinear b = bilinear_texels(t, uv);
    vec3 top = mix(texel_rgb(t, b.i0.x, b.i0.y), texel_rgb(t, b.i1.x, b.i0.y), b.f.x);
    vec3 bottom = mix(texel_rgb(t, b.i0.x, b.i1.y), texel_rgb(t, b.i1.x, b.i1.y), b.f.x);
    return mix(top, bottom, b.f.y);
}

float texture_alpha(uint index, vec2 uv) {
    TextureInfo t = texture_infos[index];
    Bilinear b = bilinear_texels(t, uv);
    float top = mix(texel_alpha(t, b.i0.x, b.i0.y), texel_alpha(t, b.i1.x, b.i0.y), b.f.x);
    float bottom = mix(texel_alpha(t, b.i0.x, b.i1.y), texel_alpha(t, b.i1.x, b.i1.y), b.f.x);
    return mix(top, bottom, b.f.y);
}
