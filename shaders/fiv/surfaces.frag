#version 450
// FIV's surfaces pass: world position (w = 1 marks a surface; the clear leaves 0) and the
// interpolated normal, unnormalised (the occluder sums normalise it, as lighting.frag does).

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    out_position = vec4(world_position, 1.0);
    out_normal = vec4(world_normal, 0.0);
}
