// The frame's uniform buffer: `FrameUniforms` in renderer/src/gpu_scene.rs (std140, 272
// bytes), rewritten in the command stream at the start of every frame. Define FRAME_BINDING
// before including this file.
layout(std140, set = 0, binding = FRAME_BINDING) uniform Frame {
    mat4 clip_from_world;
    vec4 camera_position;              // xyz, w unused
    vec4 ambient_beta;                 // rgb: I_A (lux) of 001 eq. (5); w: beta of eq. (7)
    uint light_count;
    uint shadows;                      // 0: visibility off (shading only), 1: variance shadow maps
    float min_variance;
    float bleeding_reduction;
    uint irradiance_times_occlusion;   // 1: the irradiance term is scaled by the occlusion term
    uint occluded_direct;              // 1: the occlusion term also scales E_direct, added again
    uint environment_ambient;          // 1: I_A adds the environment's irradiance at the normal
    uint frame_pad0;
    vec4 environment_sh[9];            // the environment's radiance, bands l <= 2 (rgb)
} frame;
