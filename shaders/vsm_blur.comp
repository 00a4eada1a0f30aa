#version 450
// One direction of the separable Gaussian blur of the shadow moments, every layer at once.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rg32f) uniform readonly image2DArray source;
layout(set = 0, binding = 1, rg32f) uniform writeonly image2DArray target;
layout(push_constant) uniform BlurPush {
    ivec2 step;
    int radius;
} pc;

void main() {
    ivec3 texel = ivec3(gl_GlobalInvocationID);
    ivec2 size = imageSize(source).xy;
    if (any(greaterThanEqual(texel.xy, size))) return;
    // sigma = radius / 2 puts the kernel's ends at two standard deviations.
    float sigma = max(float(pc.radius) * 0.5, 0.5);
    vec2 sum = vec2(0.0);
    float weight_sum = 0.0;
    for (int i = -pc.radius; i <= pc.radius; ++i) {
        ivec2 at = clamp(texel.xy + i * pc.step, ivec2(0), size - 1);
        float w = exp(-0.5 * float(i * i) / (sigma * sigma));
        sum += w * imageLoad(source, ivec3(at, texel.z)).xy;
        weight_sum += w;
    }
    imageStore(target, texel, vec4(sum / weight_sum, 0.0, 0.0));
}
