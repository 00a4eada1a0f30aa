// What both stages of the lighting pass share (renderer/src/passes/lighting.rs): the variant
// (specialization constants: which terms the frame's techniques hand over), the frame's
// uniform buffer, the per-vertex irradiance of a vertex term, and the per-draw push block.

// A texel term scaling the ambient light, read through uv1 (W of 001 eq. (5)).
layout(constant_id = 0) const bool OCCLUSION_TERM = false;
// The indirect irradiance term's kind: RELUME_TERM_NONE, _TEXEL (through uv1), _VERTEX (one
// value per vertex, interpolated), _PIXEL (one value per pixel of the frame), _TEXEL_OR_VERTEX
// (through uv1, but the vertex value where its alpha is 1); include/relume.glsl samples each.
layout(constant_id = 1) const uint IRRADIANCE_TERM = 0u;

#define FRAME_BINDING 9
#include "frame.glsl"

// The vertex term: rgb irradiance (lux) per vertex of the scene's vertex buffer, in its order.
layout(std430, set = 0, binding = 8) readonly buffer VertexIrradiance { vec4 vertex_irradiance[]; };
#define RELUME_VERTEX_VALUES vertex_irradiance
#include "include/relume.glsl"

layout(push_constant) uniform LightingPush {
    uint material;   // of the current draw: one draw per mesh
} pc;
