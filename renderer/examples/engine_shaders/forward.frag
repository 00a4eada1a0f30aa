#version 450
#extension GL_GOOGLE_include_directive : require
// The engine's forward pass, fragment stage: its own Lambertian-plus-Phong materials lit by
// its own punctual lights (KHR_lights_punctual's falloff, shadowed by its own variance shadow
// maps), its ambient light, and relume's term sampled with include/relume.glsl.
#include "engine.glsl"

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 uv1;
#ifdef RADIANCE
layout(location = 3) in vec4 radiance_sh[12];
#else
layout(location = 3) in vec4 vertex_value;
#endif
layout(location = 0) out vec4 color;

const float PI = 3.14159265358979;

// Irradiance from light `l` on a surface at p facing it; `to_light` the unit direction to it.
vec3 light_irradiance(EngineLight l, vec3 p, out vec3 to_light) {
    uint kind = uint(l.position_kind.w);
    if (kind == 2u) {
        to_light = -l.direction_range.xyz;
        return l.intensity.rgb;
    }
    vec3 offset = l.position_kind.xyz - p;
    float distance = length(offset);
    to_light = offset / distance;
    float window = 1.0;
    if (l.direction_range.w > 0.0) {
        float x = clamp(1.0 - pow(distance / l.direction_range.w, 4.0), 0.0, 1.0);
        window = x * x;
    }
    float cone = 1.0;
    if (kind == 1u) {
        float t = clamp((dot(l.direction_range.xyz, -to_light) - l.cone.x) * l.cone.y, 0.0, 1.0);
        cone = t * t;
    }
    return l.intensity.rgb * window / (distance * distance) * cone;
}

// The lit fraction of p from light `l` of kind `kind`: Chebyshev's bound on its variance shadow
// map (point lights read the cube face of the offset's major axis: +X, -X, +Y, -Y, +Z, -Z).
float visibility(EngineLight l, uint kind, vec3 p) {
    if (frame.counts.w == 0u) return 1.0;
    uint layer = uint(l.shadow.x);
    if (kind == 0u) {
        vec3 d = p - l.position_kind.xyz;
        vec3 a = abs(d);
        if (a.x >= a.y && a.x >= a.z) layer += d.x > 0.0 ? 0u : 1u;
        else if (a.y >= a.z) layer += d.y > 0.0 ? 2u : 3u;
        else layer += d.z > 0.0 ? 4u : 5u;
    }
    vec4 clip = shadow_layers[layer] * vec4(p, 1.0);
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    vec2 m = textureLod(shadow_moments, vec3(uv, float(layer)), 0.0).xy;
    float depth = kind == 2u ? dot(p, l.direction_range.xyz) - l.shadow.y : length(p - l.position_kind.xyz);
    if (depth <= m.x) return 1.0;
    float variance = max(m.y - m.x * m.x, frame.shadow.x);
    float t = depth - m.x;
    float lit = variance / (variance + t * t);
    return clamp((lit - frame.shadow.y) / (1.0 - frame.shadow.y), 0.0, 1.0);
}

// The normalised modified Phong lobe: rho_s (e + 2) / 2 pi max(0, wi . reflect(wo))^e.
vec3 glossy(vec3 n, vec3 to_camera, vec3 to_light) {
    if (material.phong.rgb == vec3(0.0)) return vec3(0.0);
    float c = max(dot(to_light, reflect(-to_camera, n)), 0.0);
    float lobe = material.phong.w == 0.0 ? 1.0 : pow(c, material.phong.w);
    return material.phong.rgb * ((material.phong.w + 2.0) / (2.0 * PI) * lobe);
}

vec3 irradiance_term() {
#if RELUME_TERM == 1
    return relume_atlas(relume_texels, uv1);
#elif RELUME_TERM == 2
    return vertex_value.rgb;
#elif RELUME_TERM == 3
    return relume_pixel(relume_pixels, gl_FragCoord.xy);
#elif RELUME_TERM == 4
    return relume_texel_or_vertex(relume_texels, uv1, vertex_value);
#else
    return vec3(0.0);
#endif
}

void main() {
    vec3 to_camera = normalize(frame.camera_position.xyz - world_position);
    vec3 n = normalize(world_normal);
    if (dot(n, to_camera) < 0.0) n = -n;
    vec3 albedo = material.base_color.rgb;
    vec3 result = gl_FrontFacing ? material.emission.rgb : vec3(0.0);
    vec3 unshadowed = vec3(0.0);
    vec3 direct = vec3(0.0);
    for (uint i = 0u; i < frame.counts.x; ++i) {
        vec3 to_light;
        vec3 irradiance = light_irradiance(lights[i], world_position, to_light);
        unshadowed += irradiance;
        float cos_theta = dot(n, to_light);
        if (cos_theta <= 0.0) continue;
        float v = visibility(lights[i], uint(lights[i].position_kind.w), world_position);
        result += (albedo / PI + glossy(n, to_camera, to_light)) * irradiance * cos_theta * v;
        direct += irradiance * cos_theta * v;
    }
#ifdef OCCLUSION
    vec3 o = relume_atlas(relume_occlusion, uv1);
#else
    vec3 o = vec3(1.0);
#endif
    if (frame.ambient_beta != vec4(0.0)) result += albedo / PI * (frame.ambient_beta.rgb + frame.ambient_beta.w * unshadowed) * o;
#ifdef RADIANCE
    result += relume_radiance(radiance_sh, to_camera);
#elif RELUME_TERM != 0
    vec3 term = irradiance_term();
#ifdef OCCLUSION
    if (frame.counts.y != 0u) term = frame.counts.z != 0u ? o * (term + direct) : o * term;
#endif
    result += albedo / PI * term;
#endif
    color = vec4(result, 1.0);
}
