#version 450
// The engine's shadow-map pass, fragment stage: the first two moments of the light depth, what
// variance shadow maps store (Donnelly and Lauritzen 2006) and relume's techniques read.
layout(push_constant) uniform EngineShadowView {
    mat4 clip_from_world;
    vec4 depth;             // xyz: the light's position (w 0) or direction (w 1)
    vec4 origin;            // x: a directional light's depth origin
} view;

layout(location = 0) in vec3 world_position;
layout(location = 0) out vec2 moments;

void main() {
    float d = view.depth.w == 0.0 ? length(world_position - view.depth.xyz) : dot(world_position, view.depth.xyz) - view.origin.x;
    moments = vec2(d, d * d);
}
