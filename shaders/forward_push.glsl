// Layout of ForwardParams in renderer/src/passes/forward.rs: 128 bytes, the push-constant
// size every Vulkan device guarantees.
layout(push_constant) uniform ForwardPush {
    mat4 clip_from_world;
    vec4 camera_position;    // xyz, w unused
    uint light_count;
    uint shadows;            // 0: visibility off (shading only), 1: variance shadow maps
    float min_variance;
    float bleeding_reduction;
    uint material;           // of the current draw: one draw per mesh
    uint lpm_mode;           // LPM_* of forward.frag: how the light path maps' I is added
    // Offset 112 (vec4 alignment). rgb: I_A, the ambient irradiance (lux), of 001 eq. (5);
    // w: beta of eq. (7). Both 0: the obscurance term is skipped (direct light only).
    vec4 ambient_beta;
} pc;
