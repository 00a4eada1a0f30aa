// The engine's frame uniforms (renderer/examples/engine.rs `EngineFrame`), at the binding its
// includer defines as ENGINE_FRAME_BINDING.
layout(std140, set = 0, binding = ENGINE_FRAME_BINDING) uniform EngineFrame {
    mat4 clip_from_world;
    vec4 camera_position;
    vec4 ambient_beta;      // rgb ambient irradiance, w the share of every light's irradiance added to it
    uvec4 counts;           // x lights, y the irradiance term times the occlusion, z and the direct light too, w shadows on
    vec4 shadow;            // x the variance floor, y the light-bleeding reduction
} frame;
