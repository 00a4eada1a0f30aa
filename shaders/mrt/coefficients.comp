#version 450
// §7.3 step 2 (eq. 3): each block's coefficients b0 = T_d->b l_d on its dictionary shape's
// samples (the block's own, turned). One invocation per (block, mode).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Shapes { Shape shapes[]; };
layout(std430, set = 0, binding = 1) readonly buffer Operators { float operators[]; };
layout(std430, set = 0, binding = 2) readonly buffer Blocks { uvec2 blocks[]; };   // shape, first row
layout(std430, set = 0, binding = 3) readonly buffer Rows { uint rows[]; };        // level sample per row
layout(std430, set = 0, binding = 4) readonly buffer Light_ { vec4 light[]; };
layout(std430, set = 0, binding = 5) writeonly buffer B0 { vec4 b0[]; };           // block * k_max + mode

void main() {
    uint id = gl_GlobalInvocationID.x;
    if (id >= pc.block_count * pc.k_max) return;
    uint block = id / pc.k_max;
    uint m = id % pc.k_max;
    Shape shape = shapes[blocks[block].x];
    vec3 sum = vec3(0.0);
    if (m < shape.k) {
        uint first = blocks[block].y;
        for (uint j = 0u; j < shape.n; ++j) {
            sum += operators[shape.t_d_b + j * shape.k + m] * light[rows[first + j]].rgb;
        }
    }
    b0[id] = vec4(sum, 0.0);
}
