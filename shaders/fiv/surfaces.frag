#version 450
// FIV's surfaces pass: world position (w = 1 marks a surface; the clear leaves 0), the unit
// normal turned towards the viewer as lighting.frag and the path tracer turn it (surfaces are
// two-sided), and in its w the occluder the surface belongs to, plus one (0: none).
#extension GL_GOOGLE_include_directive : require
#define FRAME_BINDING 0
#include "frame.glsl"

layout(push_constant) uniform SurfacesPush {
    uint occluder;   // of the current draw (one mesh): its occluder index + 1, 0 for none
} pc;

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    vec3 n = normalize(world_normal);
    if (dot(n, frame.camera_position.xyz - world_position) < 0.0) n = -n;
    out_position = vec4(world_position, 1.0);
    out_normal = vec4(n, float(pc.occluder));
}
