#version 450
// Step 2 of 000 §3.4: the irradiance I_e at every entry point from every light, with the
// entry point's visibility from the variance shadow maps. One invocation per entry point:
//
//   I_e = sum_j E_j(e) * |l_j - e|^2 / (|l_j - e|^2 + delta-l / pi) * max(0, cos theta_e) * V_j(e)
//
// E_j(e) the light's irradiance on a surface facing it (lights.glsl's incident_light: glTF
// falloff, range window, spot cone), the squared distance widened by the light area delta-l
// (directional lights ignore it), V_j the same Chebyshev visibility the lighting pass uses.
// relume_bake::light_path_maps::entry_irradiance_unshadowed is this without V_j.
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

struct EntryPoint {
    vec4 position;   // xyz, w unused
    vec4 normal;     // xyz unit, on the side the light arrives from
};

layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(std430, set = 0, binding = 1) readonly buffer Layers { ShadowLayer layers[]; };
layout(set = 0, binding = 2) uniform sampler2DArray shadow_moments;
layout(std430, set = 0, binding = 3) readonly buffer Entries { EntryPoint entries[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Irradiance { vec4 irradiance[]; };   // rgb I_e

#define FRAME_BINDING 5
#include "frame.glsl"

layout(push_constant) uniform EntryIrradiancePush {
    uint entry_count;
    float light_area;        // delta-l, square metres
} pc;

#include "vsm_visibility.glsl"

#include "direct_irradiance.glsl"

void main() {
    uint e = gl_GlobalInvocationID.x;
    if (e >= pc.entry_count) return;
    irradiance[e] = vec4(direct_irradiance(entries[e].position.xyz, entries[e].normal.xyz, pc.light_area), 0.0);
}
