#version 450
// Lambertian direct light from every punctual light, visibility from the variance shadow
// maps, plus emission. Output is linear radiance.
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"
#include "forward_push.glsl"

struct Material {
    vec4 base_color;
    vec4 emission;
    vec4 texture;            // base-colour texture: width, height, array layer (-1: none)
};

layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(std430, set = 0, binding = 1) readonly buffer Layers { ShadowLayer layers[]; };
layout(set = 0, binding = 2) uniform sampler2DArray shadow_moments;
layout(std430, set = 0, binding = 3) readonly buffer Materials { Material materials[]; };
layout(set = 0, binding = 4) uniform sampler2DArray textures;

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 uv0;
layout(location = 0) out vec4 radiance;

// Bilinear filtering with repeat wrapping done by hand from texelFetch, texel centres at
// (i + 0.5) / size: the same arithmetic as relume_bake::scene::Texture::sample_bilinear.
// By hand because each texture fills only the top-left of its array layer, and because
// Mesa 22.3's llvmpipe aborts compiling a REPEAT + LINEAR sampler on RGBA32F.
vec4 texel_repeat(ivec2 i, ivec2 size, int layer) {
    return texelFetch(textures, ivec3((i % size + size) % size, layer), 0);
}

vec4 sample_bilinear_repeat(vec4 texture_info, vec2 uv) {
    ivec2 size = ivec2(texture_info.xy);
    int layer = int(texture_info.z);
    vec2 x = uv * vec2(size) - 0.5;
    vec2 base = floor(x);
    vec2 f = x - base;
    ivec2 i = ivec2(base);
    vec4 top = mix(texel_repeat(i, size, layer), texel_repeat(i + ivec2(1, 0), size, layer), f.x);
    vec4 bottom = mix(texel_repeat(i + ivec2(0, 1), size, layer), texel_repeat(i + ivec2(1, 1), size, layer), f.x);
    return mix(top, bottom, f.y);
}

float visibility(Light light, vec3 p) {
    if (pc.shadows == 0u) return 1.0;
    uint layer = shadow_layer(light, p);
    vec4 clip = layers[layer].clip_from_world * vec4(p, 1.0);
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    // Explicit LOD: this runs in non-uniform control flow, where implicit derivatives are undefined.
    vec2 moments = textureLod(shadow_moments, vec3(uv, float(layer)), 0.0).xy;
    return chebyshev_visibility(moments, light_depth(light, p), pc.min_variance,
                                pc.bleeding_reduction);
}

void main() {
    Material m = materials[pc.material];
    vec3 to_camera = normalize(pc.camera_position.xyz - world_position);
    vec3 n = normalize(world_normal);
    // Surfaces scatter on both sides, as in the reference path tracer, which turns the
    // shading normal towards the viewer; they emit from their front (counter-clockwise) face.
    if (dot(n, to_camera) < 0.0) n = -n;
    bool front = gl_FrontFacing;
    vec3 albedo = m.base_color.rgb;
    if (m.texture.z >= 0.0) albedo *= sample_bilinear_repeat(m.texture, uv0).rgb;
    vec3 result = front ? m.emission.rgb : vec3(0.0);
    for (uint i = 0u; i < pc.light_count; ++i) {
        vec3 to_light;
        vec3 irradiance = incident_light(lights[i], world_position, to_light);
        float cos_theta = dot(n, to_light);
        if (cos_theta <= 0.0) continue;
        result += albedo / 3.14159265358979 * irradiance * cos_theta
                  * visibility(lights[i], world_position);
    }
    radiance = vec4(result, 1.0);
}
