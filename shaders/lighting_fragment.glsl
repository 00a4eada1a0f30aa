// The lighting pass's fragment stage (lighting.frag, and lighting_sh.frag with SH_RADIANCE):
// direct light of every punctual light for Lambertian surfaces, plus what
// the frame's techniques hand over, in radiometric terms. The output is linear radiance:
//
//   L = emission + albedo / pi * ( E_direct + (I_A + I'_S) * O + E_term )
//
//   E_direct = sum_j E_j cos(theta_j) V_j   every punctual light's irradiance (glTF falloff,
//              lights.glsl) times the receiver's cosine and its visibility from the variance
//              shadow maps (000 §3.4); 001 eq. (6)'s I_S;
//   I'_S     = beta * sum_j E_j             001 eq. (7): every light's unshadowed irradiance on a
//              surface facing it, with the same range window and spot cone but no cosine and
//              no visibility (the lux of a directional light);
//   I_A      = the ambient irradiance (lux), constant over the scene (001 eq. (5)), plus, when
//              frame.environment_ambient, the environment's unoccluded irradiance at the
//              normal from nine spherical harmonics (Ramamoorthi and Hanrahan 2001), clamped
//              at zero: the ambient light a game lights by an environment;
//   O        = the occlusion term (rgb), bilinear from its atlas image through uv1; 1 without
//              one (OCCLUSION_TERM false): W of 001 eq. (5);
//   E_term   = the irradiance term (lux) of kind IRRADIANCE_TERM: bilinear through uv1 (texel),
//              interpolated from the vertices (vertex), one of those two per mesh (texel or
//              vertex: a mesh whose vertices say so reads them) or this pixel's (pixel); times O when
//              frame.irradiance_times_occlusion; plus O * E_direct when frame.occluded_direct
//              (000 §3.4's readings of "the two texture values are multiplied").
//
// I_A = beta = 0 without the environment's skips the ambient term. k_A = k_D = albedo; the /pi turns irradiance into
// Lambertian radiance. With SH_RADIANCE the indirect term is exitant radiance instead, added as
// max(0, y(to camera) . a) (004 eq. 8), a the interpolated coefficients (16 rgb).
#include "lights.glsl"
#include "lighting_interface.glsl"

struct Material {
    vec4 base_color;
    vec4 emission;
    vec4 texture;            // base-colour texture: width, height, array layer (-1: none)
    vec4 phong;              // glossy lobe: rho_s rgb, exponent e (rho_s 0: Lambertian)
};

layout(std430, set = 0, binding = 0) readonly buffer Lights { Light lights[]; };
layout(std430, set = 0, binding = 1) readonly buffer Layers { ShadowLayer layers[]; };
layout(set = 0, binding = 2) uniform sampler2DArray shadow_moments;
layout(std430, set = 0, binding = 3) readonly buffer Materials { Material materials[]; };
layout(set = 0, binding = 4) uniform sampler2DArray textures;
// The occlusion term O in rgb, one layer per atlas page, padded (atlas_image.rs).
layout(set = 0, binding = 5) uniform sampler2DArray occlusion;
// A texel irradiance term in rgb, laid out as the atlas and padded.
layout(set = 0, binding = 6) uniform sampler2DArray irradiance_texels;
// A pixel irradiance term in rgb: one texel per pixel of the frame, layer 0.
layout(set = 0, binding = 7) uniform sampler2DArray irradiance_pixels;

layout(location = 0) in vec3 world_position;
layout(location = 1) in vec3 world_normal;
layout(location = 2) in vec2 uv0;
layout(location = 3) in vec2 uv1;
#ifdef SH_RADIANCE
layout(location = 4) in vec4 radiance_sh[12];
#else
layout(location = 4) in vec4 vertex_term;
#endif
layout(location = 0) out vec4 radiance;

#include "vsm_visibility.glsl"

const float PI = 3.14159265358979;

// The glossy lobe of f, the normalised modified Phong lobe the path tracer also evaluates
// (bake/src/bsdf.rs): rho_s (e + 2) / 2 pi max(0, wi . reflect(wo))^e.
vec3 phong_lobe(vec4 phong, vec3 n, vec3 to_camera, vec3 to_light) {
    if (phong.rgb == vec3(0.0)) return vec3(0.0);
    float c = max(dot(to_light, reflect(-to_camera, n)), 0.0);
    // pow(0, 0) is undefined in GLSL; the lobe of exponent 0 is the constant (e + 2) / 2 pi.
    float lobe = phong.w == 0.0 ? 1.0 : pow(c, phong.w);
    return phong.rgb * ((phong.w + 2.0) / (2.0 * PI) * lobe);
}

// The environment's unoccluded irradiance at normal n, clamped at zero.
vec3 environment_irradiance(vec3 n) {
    vec3 radiance[9];
    for (int k = 0; k < 9; ++k) radiance[k] = frame.environment_sh[k].rgb;
    return max(sh_irradiance(n, radiance), vec3(0.0));
}

#ifndef SH_RADIANCE
vec3 irradiance_term() {
    if (IRRADIANCE_TERM == RELUME_TERM_TEXEL) return relume_atlas(irradiance_texels, uv1);
    if (IRRADIANCE_TERM == RELUME_TERM_VERTEX) return vertex_term.rgb;
    if (IRRADIANCE_TERM == RELUME_TERM_TEXEL_OR_VERTEX) return relume_texel_or_vertex(irradiance_texels, uv1, vertex_term);
    return relume_pixel(irradiance_pixels, gl_FragCoord.xy);
}
#endif

void main() {
    Material m = materials[pc.material];
    vec3 to_camera = normalize(frame.camera_position.xyz - world_position);
    vec3 n = normalize(world_normal);
    // Surfaces scatter on both sides, as in the reference path tracer, which turns the
    // shading normal towards the viewer; they emit from their front (counter-clockwise) face.
    if (dot(n, to_camera) < 0.0) n = -n;
    bool front = gl_FrontFacing;
    vec3 albedo = m.base_color.rgb;
    if (m.texture.z >= 0.0) {
        ivec2 size = ivec2(m.texture.xy);
        albedo *= sample_bilinear(textures, int(m.texture.z), size, uv0, WRAP_REPEAT).rgb;
    }
    vec3 result = front ? m.emission.rgb : vec3(0.0);
    vec3 unshadowed = vec3(0.0);    // sum_j E_j, for I'_S
    vec3 direct = vec3(0.0);        // E_direct, for frame.occluded_direct
    for (uint i = 0u; i < frame.light_count; ++i) {
        vec3 to_light;
        vec3 irradiance = incident_light(lights[i], world_position, to_light);
        unshadowed += irradiance;
        float cos_theta = dot(n, to_light);
        if (cos_theta <= 0.0) continue;
        float v = visibility(lights[i], world_position, frame.shadows, frame.min_variance,
                             frame.bleeding_reduction);
        result += (albedo / PI + phong_lobe(m.phong, n, to_camera, to_light)) * irradiance * cos_theta * v;
        direct += irradiance * cos_theta * v;
    }
    if (frame.ambient_beta != vec4(0.0) || frame.environment_ambient != 0u) {
        vec3 ambient = frame.ambient_beta.rgb + frame.ambient_beta.w * unshadowed;   // I_A + I'_S
        if (frame.environment_ambient != 0u) ambient += environment_irradiance(n);
        vec3 o = OCCLUSION_TERM ? relume_atlas(occlusion, uv1) : vec3(1.0);
        result += albedo / PI * ambient * o;
    }
#ifdef SH_RADIANCE
    result += relume_radiance(radiance_sh, to_camera);
#else
    if (IRRADIANCE_TERM != RELUME_TERM_NONE) {
        vec3 term = irradiance_term();
        if (OCCLUSION_TERM && frame.irradiance_times_occlusion != 0u) {
            vec3 o = relume_atlas(occlusion, uv1);
            term = frame.occluded_direct != 0u ? o * (term + direct) : o * term;
        }
        result += albedo / PI * term;
    }
#endif
    radiance = vec4(result, 1.0);
}
