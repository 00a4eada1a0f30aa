#version 450
// The lighting pass, its indirect term exitant radiance in spherical harmonics: lighting_vertex.glsl.
#extension GL_GOOGLE_include_directive : require
#define SH_RADIANCE
#include "lighting_vertex.glsl"
