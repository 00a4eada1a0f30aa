#version 450
// Writes the first two moments of the light depth (000 §3.4: variance shadow maps).
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"
#include "vsm_push.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(location = 0) in vec3 world_position;
layout(location = 0) out vec2 moments;

void main() {
    float depth = light_depth(lights[pc.light], world_position);
    moments = vec2(depth, depth * depth);
}
