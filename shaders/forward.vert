#version 450
// Forward pass: scene geometry in world space, as the CPU scene holds it.
#extension GL_GOOGLE_include_directive : require
#include "forward_push.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv0;
layout(location = 3) in vec2 in_uv1;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;
layout(location = 2) out vec2 uv0;
layout(location = 3) out vec2 uv1;

void main() {
    world_position = in_position;
    world_normal = in_normal;
    uv0 = in_uv0;
    uv1 = in_uv1;
    gl_Position = pc.clip_from_world * vec4(in_position, 1.0);
}
