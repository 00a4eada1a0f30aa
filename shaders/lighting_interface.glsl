// What both stages of the lighting pass share (renderer/src/passes/lighting.rs): the variant
// (specialization constants: which terms the frame's techniques hand over), the frame's
// uniform buffer, the per-vertex irradiance of a vertex term, and the per-draw push block.

// A texel term scaling the ambient light, read through uv1 (W of 001 eq. (5)).
layout(constant_id = 0) const bool OCCLUSION_TERM = false;
// The indirect irradiance term's kind: TERM_NONE, TERM_TEXEL (through uv1), TERM_VERTEX
// (one value per vertex, interpolated), TERM_PIXEL (one value per pixel of the frame),
// TERM_TEXEL_OR_VERTEX (through uv1, but the vertex value where its alpha is 1).
layout(constant_id = 1) const uint IRRADIANCE_TERM = 0u;
const uint TERM_NONE = 0u;
const uint TERM_TEXEL = 1u;
const uint TERM_VERTEX = 2u;
const uint TERM_PIXEL = 3u;
const uint TERM_TEXEL_OR_VERTEX = 4u;

#define FRAME_BINDING 9
#include "frame.glsl"

// The vertex term: rgb irradiance (lux) per vertex of the scene's vertex buffer, in its order.
layout(std430, set = 0, binding = 8) readonly buffer VertexIrradiance { vec4 vertex_irradiance[]; };

layout(push_constant) uniform LightingPush {
    uint material;   // of the current draw: one draw per mesh
} pc;
