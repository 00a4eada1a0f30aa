layout(push_constant) uniform ForwardPush {
    mat4 clip_from_world;
    vec4 camera_position;    // xyz, w unused
    uint light_count;
    uint shadows;            // 0: visibility off (shading only), 1: variance shadow maps
    float min_variance;
    float bleeding_reduction;
    uint material;           // of the current draw: one draw per mesh
} pc;
