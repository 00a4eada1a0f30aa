// Bilinear filtering done by hand from texelFetch on one layer of a 2D-array image, texel
// centres at (i + 0.5) / size, for every image the lighting passes filter: material textures
// (WRAP_REPEAT: the same arithmetic as relume_bake::scene::Texture::sample_bilinear) and
// lightmap pages (WRAP_CLAMP: the page's edge texels extend past it, so neighbouring pages
// never blend). By hand because a texture fills only the top-left `size` of its array layer,
// because Mesa 22.3's llvmpipe aborts compiling a REPEAT + LINEAR sampler on RGBA32F, and
// because linear filtering of RGBA32F is optional on real GPUs.

const int WRAP_REPEAT = 0;
const int WRAP_CLAMP = 1;

ivec2 wrap_texel(ivec2 i, ivec2 size, int wrap) {
    if (wrap == WRAP_REPEAT) return (i % size + size) % size;
    return clamp(i, ivec2(0), size - 1);
}

vec4 fetch_wrapped(sampler2DArray image, ivec2 i, ivec2 size, int layer, int wrap) {
    return texelFetch(image, ivec3(wrap_texel(i, size, wrap), layer), 0);
}

// `uv` in [0, 1] spans `size` texels of layer `layer` (row 0 at v = 0).
vec4 sample_bilinear(sampler2DArray image, int layer, ivec2 size, vec2 uv, int wrap) {
    vec2 x = uv * vec2(size) - 0.5;
    vec2 base = floor(x);
    vec2 f = x - base;
    ivec2 i = ivec2(base);
    vec4 top = mix(fetch_wrapped(image, i, size, layer, wrap),
                   fetch_wrapped(image, i + ivec2(1, 0), size, layer, wrap), f.x);
    vec4 bottom = mix(fetch_wrapped(image, i + ivec2(0, 1), size, layer, wrap),
                      fetch_wrapped(image, i + ivec2(1, 1), size, layer, wrap), f.x);
    return mix(top, bottom, f.y);
}
