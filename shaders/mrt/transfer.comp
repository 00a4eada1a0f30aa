#version 450
// §7.3 step 4 (§6.3): each receiver's response coefficients r = sum over its source blocks of
// T_b->r b (T_b->r per source: T_rlf->r times the paths' turns times R_b->rlf, summed at bake
// time). One invocation per (receiver, response mode).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Shapes { Shape shapes[]; };
layout(std430, set = 0, binding = 1) readonly buffer Blocks { uvec2 blocks[]; };
layout(std430, set = 0, binding = 2) readonly buffer Receivers { uvec2 receivers[]; };  // first source, source count
layout(std430, set = 0, binding = 3) readonly buffer Sources { uvec2 sources[]; };      // block, first matrix value
layout(std430, set = 0, binding = 4) readonly buffer Matrices { float matrices[]; };    // k_r x k, column-major
layout(std430, set = 0, binding = 5) readonly buffer B { vec4 b[]; };
layout(std430, set = 0, binding = 6) writeonly buffer R { vec4 r[]; };                  // receiver * k_r + mode

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= pc.receiver_count * pc.k_r) return;
    uint receiver = id / pc.k_r;
    uint m = id % pc.k_r;
    vec3 sum = vec3(0.0);
    for (uint s = 0u; s < receivers[receiver].y; ++s) {
        uvec2 source = sources[receivers[receiver].x + s];
        uint k = shapes[blocks[source.x].x].k;
        for (uint j = 0u; j < k; ++j) {
            sum += matrices[source.y + j * pc.k_r + m] * b[source.x * pc.k_max + j].rgb;
        }
    }
    r[id] = vec4(sum, 0.0);
}
