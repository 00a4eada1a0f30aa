#version 450
// The engine's shadow-map pass, vertex stage: the scene seen from one layer of relume's shadow
// views (Effect::shadow_map_views).
layout(push_constant) uniform EngineShadowView {
    mat4 clip_from_world;
    vec4 depth;             // xyz: the light's position (w 0) or direction (w 1)
    vec4 origin;            // x: a directional light's depth origin
} view;

layout(location = 0) in vec3 in_position;
layout(location = 0) out vec3 world_position;

void main() {
    world_position = in_position;
    gl_Position = view.clip_from_world * vec4(in_position, 1.0);
}
