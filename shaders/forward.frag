#version 450
// Lambertian direct light from every punctual light, visibility from the variance shadow
// maps, plus emission. Output is linear radiance.
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"
#include "forward_push.glsl"

struct Material {
    vec4 base_color;
    vec4 emission;
};

layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(std430, set = 0, binding = 1) readonly buffer Layers { ShadowLayer layers[]; };
layout(set = 0, binding = 2) uniform sampler2DArray shadow_moments;
layout(std430, set = 0, binding = 3) readonly buffer Materials { Material materials[]; };

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 3) flat in uint material;
layout(location = 0) out vec4 radiance;

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
    Material m = materials[material];
    vec3 to_camera = normalize(pc.camera_position.xyz - world_position);
    vec3 n = normalize(world_normal);
    bool front = dot(n, to_camera) >= 0.0;
    // Surfaces scatter on both sides, as in the reference path tracer; they emit from the front.
    if (!front) n = -n;
    vec3 albedo = m.base_color.rgb;
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
