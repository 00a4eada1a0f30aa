#version 450
// The lighting pass's vertex stage: scene geometry in world space, as the CPU scene holds it,
// and a vertex term's irradiance for the fragment stage to interpolate.
#extension GL_GOOGLE_include_directive : require
#include "lighting_interface.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv0;
layout(location = 3) in vec2 in_uv1;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;
layout(location = 2) out vec2 uv0;
layout(location = 3) out vec2 uv1;
layout(location = 4) out vec3 vertex_term;

void main() {
    world_position = in_position;
    world_normal = in_normal;
    uv0 = in_uv0;
    uv1 = in_uv1;
    vertex_term = IRRADIANCE_TERM == TERM_VERTEX ? vertex_irradiance[gl_VertexIndex].rgb : vec3(0.0);
    gl_Position = frame.clip_from_world * vec4(in_position, 1.0);
}
