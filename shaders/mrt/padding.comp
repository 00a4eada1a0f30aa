#version 450
// The MRT light-map padding (§6-7, the padded atlas): each copy record writes a tile's border
// texel with the sample texel beyond it, across a seam into the connected block's same face or
// clamped to its own edge at a crease, so bilinear reads near a face's edge blend the right
// neighbours. Sources are always sample texels, never written here: no record reads another's
// write.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Copies { uvec2 copies[]; };   // written texel, source texel
layout(set = 0, binding = 1, rgba32f) uniform image2DArray light_map;

ivec3 at(uint t) {
    return ivec3(int(t % pc.width), int(t / pc.width), 0);
}

void main() {
    uint c = gl_GlobalInvocationID.x;
    if (c >= pc.copy_count) return;
    vec4 value = imageLoad(light_map, at(copies[c].y));
    imageStore(light_map, at(copies[c].x), vec4(value.rgb, -1.0));
}
