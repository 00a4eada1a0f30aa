#version 450
// §7.3 step 6, the light map: every texel of the padded atlas, a sample's texel its indirect
// irradiance (alpha 1), every other texel 0 until the padding pass fills the tiles' borders.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"

layout(std430, set = 0, binding = 0) readonly buffer TexelSamples { uint texel_samples[]; };  // NONE: no sample
layout(std430, set = 0, binding = 1) readonly buffer Indirect { vec4 indirect[]; };
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2DArray light_map;

void main() {
    uint t = gl_GlobalInvocationID.x;
    if (t >= pc.texel_count) return;
    uint s = texel_samples[t];
    vec4 value = s == NONE ? vec4(0.0) : vec4(indirect[s].rgb, 1.0);
    imageStore(light_map, ivec3(int(t % pc.width), int(t / pc.width), 0), value);
}
