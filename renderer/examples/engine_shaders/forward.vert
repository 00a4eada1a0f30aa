#version 450
#extension GL_GOOGLE_include_directive : require
// The engine's forward pass, vertex stage: world-space geometry, and relume's per-vertex term
// for the fragment stage to interpolate.
#include "engine.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv1;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;
layout(location = 2) out vec2 uv1;
#ifdef RADIANCE
layout(location = 3) out vec4 radiance_sh[12];
#else
layout(location = 3) out vec4 vertex_value;
#endif

void main() {
    world_position = in_position;
    world_normal = in_normal;
    uv1 = in_uv1;
#ifdef RADIANCE
    relume_pack_radiance(uint(gl_VertexIndex), radiance_sh);
#elif RELUME_TERM == 2 || RELUME_TERM == 4
    vertex_value = relume_vertex_value(uint(gl_VertexIndex));
#else
    vertex_value = vec4(0.0);
#endif
    gl_Position = frame.clip_from_world * vec4(in_position, 1.0);
}
