#version 450
// The lighting pass, its indirect term irradiance: lighting_vertex.glsl.
#extension GL_GOOGLE_include_directive : require
#include "lighting_vertex.glsl"
