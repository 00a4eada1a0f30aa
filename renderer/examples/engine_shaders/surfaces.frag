#version 450
#extension GL_GOOGLE_include_directive : require
// The engine's surfaces pass, fragment stage: what relume's pixel terms read of the engine's
// view (renderer::technique::Surfaces): the world position with w 1, the unit normal turned
// towards the viewer with, in w, the id relume gave the mesh (Effect::surface_ids).
#define ENGINE_FRAME_BINDING 0
#include "engine_frame.glsl"

layout(push_constant) uniform EngineSurface {
    uint id;   // of the current mesh
} surface;

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    vec3 n = normalize(world_normal);
    if (dot(n, frame.camera_position.xyz - world_position) < 0.0) n = -n;
    out_position = vec4(world_position, 1.0);
    out_normal = vec4(n, float(surface.id));
}
