#version 450
// Variance shadow map pass: renders the scene from one shadow-map layer of one light.
#extension GL_GOOGLE_include_directive : require
#include "lights.glsl"
#include "vsm_push.glsl"

layout(location = 0) in vec3 in_position;
layout(std430, set = 0, binding = 1) readonly buffer Layers { ShadowLayer layers[]; };
layout(location = 0) out vec3 world_position;

void main() {
    world_position = in_position;
    gl_Position = layers[pc.layer].clip_from_world * vec4(in_position, 1.0);
}
