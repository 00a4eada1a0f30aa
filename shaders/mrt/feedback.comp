#version 450
// §7.3's feedback at its fixed point: b = (I - K)^-1 b0 per colour channel, K the
// coefficients of the light one bounce of b sends back (baked: relume_bake::mrt::baker), so b
// carries every bounce; with feedback off, b = b0 (the first bounce). One invocation per
// (block, mode).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Feedback { float feedback[]; };  // 3 x D x D, column-major
layout(std430, set = 0, binding = 1) readonly buffer B0 { vec4 b0[]; };
layout(std430, set = 0, binding = 2) writeonly buffer B { vec4 b[]; };

void main() {
    uint d = pc.block_count * pc.k_max;
    uint i = gl_GlobalInvocationID.x;
    if (i >= d) return;
    if (pc.feedback == 0u) {
        b[i] = b0[i];
        return;
    }
    vec3 sum = vec3(0.0);
    for (uint j = 0u; j < d; ++j) {
        vec3 x = b0[j].rgb;
        uint at = j * d + i;
        sum += vec3(feedback[at] * x.r, feedback[d * d + at] * x.g, feedback[2u * d * d + at] * x.b);
    }
    b[i] = vec4(sum, 0.0);
}
