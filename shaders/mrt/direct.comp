#version 450
// §7.3 step 1: the direct light at every level sample (a block face's sample point in the
// world), shadowed through the variance shadow maps as the lighting pass shadows pixels, and
// the radiosity l_d = rho E_d the transfer starts from; E_d kept for the CPU oracle.
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

struct Sample {
    vec4 position;   // xyz world
    vec4 normal;     // xyz unit, into the block
    vec4 albedo;     // rgb
};

layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(std430, set = 0, binding = 1) readonly buffer Layers { ShadowLayer layers[]; };
layout(set = 0, binding = 2) uniform sampler2DArray shadow_moments;
layout(std430, set = 0, binding = 3) readonly buffer Samples { Sample samples[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Light_ { vec4 light[]; };      // rgb rho E
layout(std430, set = 0, binding = 5) writeonly buffer Direct { vec4 direct[]; };     // rgb E_d

#define FRAME_BINDING 6
#include "frame.glsl"
#include "mrt/push.glsl"
#include "vsm_visibility.glsl"
#include "direct_irradiance.glsl"

void main() {
    uint s = gl_GlobalInvocationID.x;
    if (s >= pc.sample_count) return;
    vec3 e = direct_irradiance(samples[s].position.xyz, samples[s].normal.xyz, 0.0);
    light[s] = vec4(samples[s].albedo.rgb * e, 0.0);
    direct[s] = vec4(e, 0.0);
}
