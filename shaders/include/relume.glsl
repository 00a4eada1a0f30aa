// relume's terms, sampled exactly as relume's own lighting pass samples them (it includes this
// file): for an engine that runs a technique as an effect (renderer/src/effect.rs) and shades
// with the term in its own shaders. Add relume's `shaders/` folder to the include path and
// `#include "include/relume.glsl"` (GL_GOOGLE_include_directive). docs/ARCHITECTURE.md,
// "Effect mode", says which term each technique hands over and how the engine binds it.
//
// The terms (technique.rs `Terms`), all in linear units:
//   occlusion  an atlas image: rgb W (001 eq. (5)) scaling the engine's ambient light;
//              relume_atlas(image, uv1)
//   texel      an atlas image: rgb irradiance (lux); relume_atlas(image, uv1)
//   vertex     one vec4 per vertex of the scene's vertices (its meshes' in order): rgb
//              irradiance, read in the vertex stage and interpolated; relume_vertex_value(v)
//   pixel      an image of the effect's size: rgb irradiance at the fragment's pixel;
//              relume_pixel(image, gl_FragCoord.xy)
//   texel or vertex  the atlas image and the vertex buffer: relume_texel_or_vertex(image,
//              uv1, interpolated vertex value)
//   radiance   16 vec4 per vertex: exitant radiance in spherical harmonics (bands l <= 3, world
//              space), packed in the vertex stage (relume_pack_radiance, 12 vec4 outputs),
//              evaluated towards the viewer in the fragment stage (relume_radiance)
// An irradiance term E becomes Lambertian radiance as albedo / pi * E; a radiance term is added
// as it is. uv1 is the atlas coordinate the bake gave each vertex: the page in u's integer part.
//
// Before including, an engine that reads a vertex or radiance term in this stage declares the
// term's buffer and names its array: for example
//   layout(std430, set = 0, binding = 3) readonly buffer RelumeTerm { vec4 term_values[]; };
//   #define RELUME_VERTEX_VALUES term_values
#include "bilinear.glsl"
#include "sh.glsl"

// The irradiance term's kinds, as `renderer::technique::TERM_*` numbers them.
const uint RELUME_TERM_NONE = 0u;
const uint RELUME_TERM_TEXEL = 1u;
const uint RELUME_TERM_VERTEX = 2u;
const uint RELUME_TERM_PIXEL = 3u;
const uint RELUME_TERM_TEXEL_OR_VERTEX = 4u;

// An atlas image at uv1 (relume_bake::atlas's convention): page = floor(u), the page's own
// u = fract(u), v in [0, 1] with row 0 at the top; bilinear within the page, clamped to its edge
// (the images are padded, so a texel's neighbours outside its chart hold its chart's values).
vec3 relume_atlas(sampler2DArray image, vec2 uv1) {
    ivec3 size = textureSize(image, 0);
    float page = floor(uv1.x);
    int layer = clamp(int(page), 0, size.z - 1);
    return sample_bilinear(image, layer, size.xy, vec2(uv1.x - page, uv1.y), WRAP_CLAMP).rgb;
}

// A pixel term at a fragment's window coordinate (gl_FragCoord.xy): the texel of its pixel.
vec3 relume_pixel(sampler2DArray image, vec2 frag_coord) {
    return texelFetch(image, ivec3(ivec2(frag_coord), 0), 0).rgb;
}

// A texel-or-vertex term: the interpolated vertex value where its alpha is 1 (a mesh lit per
// vertex: alpha is 1 across it, 0 across the others, so exact when interpolated), else the
// atlas image at uv1.
vec3 relume_texel_or_vertex(sampler2DArray image, vec2 uv1, vec4 vertex_value) {
    return vertex_value.a > 0.5 ? vertex_value.rgb : relume_atlas(image, uv1);
}

// 004 eq. (8): the exitant radiance towards the viewer (unit, world space) from a vertex's
// coefficients as relume_pack_radiance packed them (interpolated), clamped at zero.
vec3 relume_radiance(vec4 packed[12], vec3 to_viewer) {
    float y[16];
    sh_eval(to_viewer, y);
    vec3 sum = vec3(0.0);
    for (int k = 0; k < 16; ++k) {
        int f = 3 * k;
        vec3 a = vec3(packed[f / 4][f % 4], packed[(f + 1) / 4][(f + 1) % 4], packed[(f + 2) / 4][(f + 2) % 4]);
        sum += a * y[k];
    }
    return max(sum, vec3(0.0));
}

#ifdef RELUME_VERTEX_VALUES
// A vertex (or texel-or-vertex) term's value at vertex `v` of the scene's vertices.
vec4 relume_vertex_value(uint v) {
    return RELUME_VERTEX_VALUES[v];
}

// A radiance term's 16 rgb coefficients of vertex `v`, packed into 12 vec4 (48 floats: with
// four other vec4 outputs, the 64 output components every Vulkan device takes).
void relume_pack_radiance(uint v, out vec4 packed[12]) {
    for (int i = 0; i < 12; ++i) {
        for (int c = 0; c < 4; ++c) {
            int f = 4 * i + c;
            packed[i][c] = RELUME_VERTEX_VALUES[16 * v + uint(f / 3)][f % 3];
        }
    }
}
#endif
