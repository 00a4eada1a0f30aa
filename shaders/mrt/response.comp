#version 450
// §7.3 steps 3 and 5: each level sample's indirect irradiance, its own block's U_b b plus
// U_r r of every receiver (at most one per opening) that lands on it.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"

struct SampleRows {
    uvec4 own;          // block, row of its dictionary shape, -, -
    uvec4 receivers;    // up to four receivers (NONE: none)
    uvec4 rows;         // the sample's row of each receiver
};

layout(std430, set = 0, binding = 0) readonly buffer Shapes { Shape shapes[]; };
layout(std430, set = 0, binding = 1) readonly buffer Operators { float operators[]; };
layout(std430, set = 0, binding = 2) readonly buffer Blocks { uvec2 blocks[]; };
layout(std430, set = 0, binding = 3) readonly buffer Rows_ { SampleRows sample_rows[]; };
layout(std430, set = 0, binding = 4) readonly buffer B { vec4 b[]; };
layout(std430, set = 0, binding = 5) readonly buffer R { vec4 r[]; };
layout(std430, set = 0, binding = 6) writeonly buffer Indirect { vec4 indirect[]; };

void main() {
    uint s = gl_GlobalInvocationID.x;
    if (s >= pc.sample_count) return;
    SampleRows at = sample_rows[s];
    uint block = at.own.x;
    Shape shape = shapes[blocks[block].x];
    vec3 e = vec3(0.0);
    for (uint m = 0u; m < shape.k; ++m) {
        e += operators[shape.u_b + m * shape.n + at.own.y] * b[block * pc.k_max + m].rgb;
    }
    for (uint i = 0u; i < 4u; ++i) {
        uint receiver = at.receivers[i];
        if (receiver == NONE) continue;
        for (uint m = 0u; m < pc.k_r; ++m) {
            e += operators[pc.u_r + m * pc.n_r + at.rows[i]] * r[receiver * pc.k_r + m].rgb;
        }
    }
    indirect[s] = vec4(e, 0.0);
}
