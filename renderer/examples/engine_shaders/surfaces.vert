#version 450
#extension GL_GOOGLE_include_directive : require
// The engine's surfaces pass (its G-buffer), vertex stage: the forward pass's geometry and
// transform, so both cover the same pixels.
#define ENGINE_FRAME_BINDING 0
#include "engine_frame.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;

void main() {
    world_position = in_position;
    world_normal = in_normal;
    gl_Position = frame.clip_from_world * vec4(in_position, 1.0);
}
