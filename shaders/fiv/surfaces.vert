#version 450
// FIV's surfaces pass: each pixel's world position and normal, for the occluder sums. The
// position is the expression lighting.vert computes, from the same buffers, so both passes
// cover the same pixels. (Not declared invariant: glslang decorates a struct member with it,
// which the validation layers flag.)
#extension GL_GOOGLE_include_directive : require
#define FRAME_BINDING 0
#include "frame.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;

void main() {
    world_position = in_position;
    world_normal = in_normal;
    gl_Position = frame.clip_from_world * vec4(in_position, 1.0);
}
