#version 450
// Lambertian direct light from every punctual light, visibility from the variance shadow
// maps, plus emission. Output is linear radiance.
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"
#include "forward_push.glsl"

struct Material {
    vec4 base_color;
    vec4 emission_texture;   // rgb emission, w base-colour texture index (-1: none)
};

layout(constant_id = 0) const uint TEXTURE_COUNT = 1u;

layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(std430, set = 0, binding = 1) readonly buffer Layers { ShadowLayer layers[]; };
layout(set = 0, binding = 2) uniform sampler2DArray shadow_moments;
layout(std430, set = 0, binding = 3) readonly buffer Materials { Material materials[]; };
layout(set = 0, binding = 4) uniform sampler2D textures[TEXTURE_COUNT];

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 uv0;
layout(location = 0) out vec4 radiance;

// Bilinear filtering with repeat wrapping done by hand from texelFetch, texel centres at
// (i + 0.5) / size: the same arithmetic as relume_bake::scene::Texture::sample_bilinear.
// (Mesa 22.3's llvmpipe aborts compiling a REPEAT + LINEAR sampler on RGBA32F.)
vec4 sample_bilinear_repeat(int index, vec2 uv) {
    ivec2 size = textureSize(textures[index], 0);
    vec2 x = uv * vec2(size) - 0.5;
    vec2 base = floor(x);
    vec2 f = x - base;
    ivec2 i = ivec2(base);
    vec4 t00 = texelFetch(textures[index], (i % size + size) % size, 0);
    vec4 t10 = texelFetch(textures[index], ((i + ivec2(1, 0)) % size + size) % size, 0);
    vec4 t01 = texelFetch(textures[index], ((i + ivec2(0, 1)) % size + size) % size, 0);
    vec4 t11 = texelFetch(textures[index], ((i + ivec2(1, 1)) % size + size) % size, 0);
    return mix(mix(t00, t10, f.x), mix(t01, t11, f.x), f.y);
}

float visibility(Light light, vec3 p) {
    if (pc.shadows == 0u) return 1.0;
    uint layer = shadow_layer(light, p);
    vec4 clip = layers[layer].clip_from_world * vec4(p, 1.0);
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    vec2 moments = texture(shadow_moments, vec3(uv, float(layer))).xy;
    return chebyshev_visibility(moments, light_depth(light, p), pc.min_variance,
                                pc.bleeding_reduction);
}

void main() {
    Material m = materials[pc.material];
    vec3 to_camera = normalize(pc.camera_position.xyz - world_position);
    vec3 n = normalize(world_normal);
    bool front = dot(n, to_camera) >= 0.0;
    // Surfaces scatter on both sides, as in the reference path tracer; they emit from the front.
    if (!front) n = -n;
    vec3 albedo = m.base_color.rgb;
    // The texture index is uniform across the draw (one draw per mesh, material in push constants).
    int texture_index = int(m.emission_texture.w);
    if (texture_index >= 0) albedo *= sample_bilinear_repeat(texture_index, uv0).rgb;
    vec3 result = front ? m.emission_texture.rgb : vec3(0.0);
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
