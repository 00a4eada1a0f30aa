// The engine's forward pass's interface (renderer/examples/engine.rs): its lights, its frame
// uniforms, its materials, and relume's terms bound where the engine chose. The engine
// compiles one variant per effect, defining RELUME_TERM (the irradiance term's kind, 0 for
// none), OCCLUSION when the effect hands an occlusion term and RADIANCE for a radiance term.

struct EngineLight {
    vec4 position_kind;     // xyz position, w 0 point, 1 spot, 2 directional
    vec4 direction_range;   // xyz unit direction the light points, w range (0: none)
    vec4 intensity;         // rgb colour times intensity
    vec4 cone;              // x cos(outer), y 1 / (cos(inner) - cos(outer))
    vec4 shadow;            // x its first shadow-map layer, y a directional light's depth origin
};

layout(std430, set = 0, binding = 0) readonly buffer EngineLights { EngineLight lights[]; };
#define ENGINE_FRAME_BINDING 1
#include "engine_frame.glsl"
// relume's terms (stand-ins where the effect hands none).
layout(set = 0, binding = 2) uniform sampler2DArray relume_occlusion;
layout(set = 0, binding = 3) uniform sampler2DArray relume_texels;
layout(set = 0, binding = 4) uniform sampler2DArray relume_pixels;
layout(std430, set = 0, binding = 5) readonly buffer RelumeValues { vec4 relume_values[]; };
// The engine's own shadow maps (moments of the light depth), which it also hands relume.
layout(std430, set = 0, binding = 6) readonly buffer EngineShadowLayers { mat4 shadow_layers[]; };
layout(set = 0, binding = 7) uniform sampler2DArray shadow_moments;
#define RELUME_VERTEX_VALUES relume_values
#include "include/relume.glsl"

layout(push_constant) uniform EngineMaterial {
    vec4 base_color;
    vec4 emission;
    vec4 phong;             // glossy lobe: rho_s rgb, exponent
} material;
