// Visibility of a point from a light through the variance shadow maps (000 §3.4), shared by
// every pass that lights a point (lighting.frag at a pixel, light_path_maps/entry_irradiance.comp
// at an entry point), so all see the same shadows. Include after lights.glsl, in a shader that declares
//   layers          the ShadowLayer storage buffer (every light's shadow layers);
//   shadow_moments  the moments of every layer (sampler2DArray, RG32F, blurred).

// 1 when `shadows` is 0 (visibility off: shading only); else Chebyshev's bound on the lit
// fraction of p in the layer of `light` that sees it, with the variance floor `min_variance`
// and the light-bleeding reduction `bleeding`.
float visibility(Light light, vec3 p, uint shadows, float min_variance, float bleeding) {
    if (shadows == 0u) return 1.0;
    uint layer = shadow_layer(light, p);
    vec4 clip = layers[layer].clip_from_world * vec4(p, 1.0);
    vec2 uv = clip.xy / clip.w * 0.5 + 0.5;
    // Explicit LOD: fragment shaders call this in non-uniform control flow, where implicit
    // derivatives are undefined; compute shaders have none.
    vec2 moments = textureLod(shadow_moments, vec3(uv, float(layer)), 0.0).xy;
    return chebyshev_visibility(moments, light_depth(light, p), min_variance, bleeding);
}
