// The lighting pass's vertex stage (lighting.vert, and lighting_sh.vert with SH_RADIANCE):
// scene geometry in world space, as the CPU scene holds it, and a vertex term for the fragment
// stage to interpolate: irradiance, or with SH_RADIANCE 16 spherical-harmonic coefficients of
// exitant radiance (48 floats in 12 vec4: with the four other outputs, the 64 components every
// Vulkan device takes).
#include "lighting_interface.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv0;
layout(location = 3) in vec2 in_uv1;

layout(location = 0) out vec3 world_position;
layout(location = 1) out vec3 world_normal;
layout(location = 2) out vec2 uv0;
layout(location = 3) out vec2 uv1;
#ifdef SH_RADIANCE
layout(location = 4) out vec4 radiance_sh[12];
#else
layout(location = 4) out vec4 vertex_term;
#endif

void main() {
    world_position = in_position;
    world_normal = in_normal;
    uv0 = in_uv0;
    uv1 = in_uv1;
#ifdef SH_RADIANCE
    relume_pack_radiance(uint(gl_VertexIndex), radiance_sh);
#else
    bool per_vertex = IRRADIANCE_TERM == RELUME_TERM_VERTEX || IRRADIANCE_TERM == RELUME_TERM_TEXEL_OR_VERTEX;
    vertex_term = per_vertex ? relume_vertex_value(uint(gl_VertexIndex)) : vec4(0.0);
#endif
    gl_Position = frame.clip_from_world * vec4(in_position, 1.0);
}
