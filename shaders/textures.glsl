// Textures: RGBA8 texels stored as written; colour (TEXTURE_SRGB) is decoded to linear here, data
// (glTF metallic-roughness) read as stored, and alpha (A) is always linear. Filtered bilinearly,
// after decoding, with each axis's wrap mode (repeat, clamp to edge or mirrored repeat; the flags).
// uv (0, 0) is the image's top-left corner.

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

// The texel column (or row) that whole-numbered position i (of any sign) reads in an axis of n
// texels, under the axis's TEXTURE_WRAP_* mode.
uint wrapped_texel(float i, float n, uint mode) {
    if (mode == TEXTURE_WRAP_CLAMP) return uint(clamp(i, 0.0, n - 1.0));
    if (mode == TEXTURE_WRAP_MIRROR) {
        float m = mod(i, 2.0 * n);  // a tile and its mirror image
        return uint(clamp(m < n ? m : 2.0 * n - 1.0 - m, 0.0, n - 1.0));
    }
    // mod() can round up to n itself for tiny negative inputs; min keeps the index in range.
    return uint(min(mod(i, n), n - 1.0));
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
    vec2 i = floor(p);
    uint wrap_u = (t.flags >> TEXTURE_WRAP_U_SHIFT) & 3u;
    uint wrap_v = (t.flags >> TEXTURE_WRAP_V_SHIFT) & 3u;
    uvec2 i0 = uvec2(wrapped_texel(i.x, size.x, wrap_u), wrapped_texel(i.y, size.y, wrap_v));
    uvec2 i1 = uvec2(wrapped_texel(i.x + 1.0, size.x, wrap_u), wrapped_texel(i.y + 1.0, size.y, wrap_v));
    return Bilinear(i0, i1, p - i);
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
