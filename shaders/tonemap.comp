#version 450
// Display transform, the same as relume_bake::image::tonemap_to_srgb8: exposure, the ACES
// filmic fit of Narkowicz (2015) per channel, then the sRGB curve.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, rgba32f) uniform readonly image2D hdr;
layout(set = 0, binding = 1, rgba8) uniform writeonly image2D ldr;
layout(push_constant) uniform TonemapPush { float exposure; } pc;

vec3 aces(vec3 x) {
    x = max(x * pc.exposure, 0.0);
    return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
}

vec3 linear_to_srgb(vec3 c) {
    return mix(12.92 * c, 1.055 * pow(c, vec3(1.0 / 2.4)) - 0.055, greaterThan(c, vec3(0.0031308)));
}

void main() {
    ivec2 texel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(texel, imageSize(hdr)))) return;
    imageStore(ldr, texel, vec4(linear_to_srgb(aces(imageLoad(hdr, texel).rgb)), 1.0));
}
