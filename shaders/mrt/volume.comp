#version 450
// §7.3 step 8 (§6.5): every block's light-volume probes, U_bvol b plus U_rvol r of each
// receiver at the block (spec B15); one invocation per (block, probe, coefficient).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"
#include "mrt/volume.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Operators { float operators[]; };
layout(std430, set = 0, binding = 1) readonly buffer VolumeBlocks { VolumeBlock volume_blocks[]; };
layout(std430, set = 0, binding = 2) readonly buffer B { vec4 b[]; };
layout(std430, set = 0, binding = 3) readonly buffer R { vec4 r[]; };
layout(std430, set = 0, binding = 4) writeonly buffer Volume { vec4 volume[]; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.block_count * VOLUME_ROWS) return;
    uint block = i / VOLUME_ROWS;
    uint row = i % VOLUME_ROWS;
    VolumeBlock at = volume_blocks[block];
    vec3 sum = vec3(0.0);
    for (uint m = 0u; m < at.info.y; ++m) {
        sum += operators[at.info.x + m * VOLUME_ROWS + row] * b[block * pc.k_max + m].rgb;
    }
    for (uint k = 0u; k < 4u; ++k) {
        uint entry = at.receivers[k];
        if (entry == NONE) continue;
        uint start = pc.u_rvol + (entry & 3u) * VOLUME_ROWS * pc.k_r;
        uint receiver = entry >> 2u;
        for (uint m = 0u; m < pc.k_r; ++m) {
            sum += operators[start + m * VOLUME_ROWS + row] * r[receiver * pc.k_r + m].rgb;
        }
    }
    volume[i] = vec4(sum, 0.0);
}
