// Punctual lights and their variance shadow maps, shared by every pass that lights a surface.
// The falloff is the same as relume_bake::scene::Light::incident (KHR_lights_punctual).

const uint LIGHT_POINT = 0u;
const uint LIGHT_SPOT = 1u;
const uint LIGHT_DIRECTIONAL = 2u;

struct Light {
    vec4 position_kind;     // xyz position, w kind
    vec4 direction_range;   // xyz unit direction the light points, w range (0: none)
    vec4 intensity_layer;   // rgb colour times intensity, w first shadow-map layer
    vec4 cone_depth;        // x cos(outer), y 1/(cos(inner)-cos(outer)), z directional depth origin
};

struct ShadowLayer {
    mat4 clip_from_world;
};

float range_window(float distance, float range) {
    if (range <= 0.0) return 1.0;
    float x = clamp(1.0 - pow(distance / range, 4.0), 0.0, 1.0);
    return x * x;
}

float cone_attenuation(Light light, vec3 from_light) {
    if (uint(light.position_kind.w) != LIGHT_SPOT) return 1.0;
    float t = clamp((dot(light.direction_range.xyz, from_light) - light.cone_depth.x)
                    * light.cone_depth.y, 0.0, 1.0);
    return t * t;
}

// Irradiance on a surface facing the light, before the receiver's cosine and visibility;
// `to_light` is the unit direction towards the light.
vec3 incident_light(Light light, vec3 p, out vec3 to_light) {
    if (uint(light.position_kind.w) == LIGHT_DIRECTIONAL) {
        to_light = -light.direction_range.xyz;
        return light.intensity_layer.rgb;
    }
    vec3 offset = light.position_kind.xyz - p;
    float distance = length(offset);
    to_light = offset / distance;
    return light.intensity_layer.rgb * range_window(distance, light.direction_range.w)
           / (distance * distance) * cone_attenuation(light, -to_light);
}

// The depth a variance shadow map stores: distance from the light for point and spot
// lights, distance along the light's direction from the fitted box for directional ones.
float light_depth(Light light, vec3 p) {
    if (uint(light.position_kind.w) == LIGHT_DIRECTIONAL)
        return dot(p, light.direction_range.xyz) - light.cone_depth.z;
    return length(p - light.position_kind.xyz);
}

// The shadow-map layer that sees p: point lights own six cube faces, chosen by major axis
// in the order +X, -X, +Y, -Y, +Z, -Z.
uint shadow_layer(Light light, vec3 p) {
    uint first = uint(light.intensity_layer.w);
    if (uint(light.position_kind.w) != LIGHT_POINT) return first;
    vec3 d = p - light.position_kind.xyz;
    vec3 a = abs(d);
    if (a.x >= a.y && a.x >= a.z) return first + (d.x > 0.0 ? 0u : 1u);
    if (a.y >= a.z) return first + (d.y > 0.0 ? 2u : 3u);
    return first + (d.z > 0.0 ? 4u : 5u);
}

// Chebyshev's upper bound on the lit fraction (Donnelly & Lauritzen, as 000 §3.4 uses it),
// with a floor on the variance and the light-bleeding reduction that cuts the bound's tail.
float chebyshev_visibility(vec2 moments, float depth, float min_variance, float bleeding) {
    if (depth <= moments.x) return 1.0;
    float variance = max(moments.y - moments.x * moments.x, min_variance);
    float d = depth - moments.x;
    float p_max = variance / (variance + d * d);
    return clamp((p_max - bleeding) / (1.0 - bleeding), 0.0, 1.0);
}
