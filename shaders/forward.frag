#version 450
// The obscurance illumination model of Iones et al., "Fast realistic lighting for video
// games" (001) eq. (5)-(7), I = (I_A + I'_S) k_A W + k_D I_S, in relume's radiometric terms,
// plus the large-scale indirect light of the light path maps (000 §3.4) when the renderer has
// them. Output is linear radiance of a Lambertian surface:
//
//   L = emission + albedo / pi * ( (I_A + I'_S) * W + E_direct + LPM )
//
//   E_direct = sum_j E_j cos(theta_j) V_j   eq. (6)'s I_S: every punctual light's irradiance
//              (glTF falloff, lights.glsl) times the receiver's cosine and its visibility from
//              the variance shadow maps (000 §3.4);
//   I'_S     = beta * sum_j E_j             eq. (7): every light's unshadowed irradiance on a
//              surface facing it, with the same range window and spot cone but no cosine and
//              no visibility (the lux of a directional light);
//   I_A      = the ambient irradiance (lux), constant over the scene;
//   W        = the obscurance (rgb; grey except for the spectral variant), bilinear from the
//              lightmap through uv1, 1 where there is no lightmap;
//   k_A = k_D = albedo, the /pi turning irradiance into Lambertian radiance;
//   LPM      = by pc.lpm_mode (frame.rs's Composition), with I the indirect irradiance the
//              light path maps reconstructed (bilinear from `indirect` through uv1, as W):
//              LPM_NONE 0 (no light path maps); LPM_PLAIN I; LPM_TIMES_OBSCURANCE W * I;
//              LPM_TIMES_OBSCURANCE_WITH_DIRECT W * (I + E_direct).
//
// I_A = beta = 0 (the default) skips the ambient term: direct light and emission alone.
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"
#include "forward_push.glsl"
#include "bilinear.glsl"

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
// The obscurance W in rgb, one layer per atlas page, padded (lightmap.rs); a single texel
// of 1 when the renderer has no lightmap.
layout(set = 0, binding = 5) uniform sampler2DArray lightmap;
// The light path maps' indirect irradiance I (lux) in rgb, alpha coverage, laid out as the
// lightmap and padded every frame (light_path_maps.rs); a single texel of 0 without them.
layout(set = 0, binding = 6) uniform sampler2DArray indirect;

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 uv0;
layout(location = 3) in vec2 uv1;
layout(location = 0) out vec4 radiance;

#include "vsm_visibility.glsl"

const float PI = 3.14159265358979;
const uint LPM_NONE = 0u;
const uint LPM_PLAIN = 1u;
const uint LPM_TIMES_OBSCURANCE = 2u;
const uint LPM_TIMES_OBSCURANCE_WITH_DIRECT = 3u;

// An atlas image (the lightmap's W, the indirect I) at uv1 (relume_bake::atlas's convention):
// page = floor(u), the page's own u = fract(u), v in [0, 1] with row 0 at the top; filtered
// within the page, clamped to its edge.
vec3 atlas_sample(sampler2DArray image, vec2 uv) {
    ivec3 size = textureSize(image, 0);
    float page = floor(uv.x);
    int layer = clamp(int(page), 0, size.z - 1);
    return sample_bilinear(image, layer, size.xy, vec2(uv.x - page, uv.y), WRAP_CLAMP).rgb;
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
    if (m.texture.z >= 0.0) {
        ivec2 size = ivec2(m.texture.xy);
        albedo *= sample_bilinear(textures, int(m.texture.z), size, uv0, WRAP_REPEAT).rgb;
    }
    vec3 result = front ? m.emission.rgb : vec3(0.0);
    vec3 unshadowed = vec3(0.0);    // sum_j E_j, for I'_S
    vec3 direct = vec3(0.0);        // E_direct, for LPM_TIMES_OBSCURANCE_WITH_DIRECT
    for (uint i = 0u; i < pc.light_count; ++i) {
        vec3 to_light;
        vec3 irradiance = incident_light(lights[i], world_position, to_light);
        unshadowed += irradiance;
        float cos_theta = dot(n, to_light);
        if (cos_theta <= 0.0) continue;
        float v = visibility(lights[i], world_position, pc.shadows, pc.min_variance,
                             pc.bleeding_reduction);
        result += albedo / PI * irradiance * cos_theta * v;
        direct += irradiance * cos_theta * v;
    }
    if (pc.ambient_beta != vec4(0.0)) {
        vec3 ambient = pc.ambient_beta.rgb + pc.ambient_beta.w * unshadowed;   // I_A + I'_S
        result += albedo / PI * ambient * atlas_sample(lightmap, uv1);
    }
    if (pc.lpm_mode != LPM_NONE) {
        vec3 large_scale = atlas_sample(indirect, uv1);   // I
        vec3 lpm = large_scale;
        if (pc.lpm_mode == LPM_TIMES_OBSCURANCE) {
            lpm = atlas_sample(lightmap, uv1) * large_scale;
        } else if (pc.lpm_mode == LPM_TIMES_OBSCURANCE_WITH_DIRECT) {
            lpm = atlas_sample(lightmap, uv1) * (large_scale + direct);
        }
        result += albedo / PI * lpm;
    }
    radiance = vec4(result, 1.0);
}
