#version 450
// Step 4 of 000 §3.4: per atlas texel, I[u, v] = sum_k sums[k] * textures[k][u, v], k over
// every cluster's mean and eigen-textures (sums from cluster_sums.comp: s_c for M^c, t_cd for
// B^c_d), written to the indirect image with alpha = the texel's coverage. Empty texels get
// 0 (alpha 0), for the padding pass that follows to fill. One invocation per texel, every
// page at once.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) readonly buffer Sums { vec4 sums[]; };          // rgb, K of them
// Texture k's texel t at 3 * (k * texel_count + t): packed rgb, texels in atlas order.
layout(std430, set = 0, binding = 1) readonly buffer Textures { float textures[]; };
layout(std430, set = 0, binding = 2) readonly buffer Coverage { float coverage[]; };  // > 0 covered
layout(set = 0, binding = 3, rgba32f) uniform writeonly image2DArray indirect;

layout(push_constant) uniform ReconstructPush {
    uint term_count;    // K = C * (1 + D)
} pc;

void main() {
    ivec3 texel = ivec3(gl_GlobalInvocationID);
    ivec3 size = imageSize(indirect);
    if (any(greaterThanEqual(texel, size))) return;
    uint texel_count = uint(size.x * size.y * size.z);
    uint t = uint((texel.z * size.y + texel.y) * size.x + texel.x);
    float covered = coverage[t];
    vec3 sum = vec3(0.0);
    if (covered > 0.0) {
        for (uint k = 0u; k < pc.term_count; ++k) {
            uint at = 3u * (k * texel_count + t);
            sum += sums[k].rgb * vec3(textures[at], textures[at + 1u], textures[at + 2u]);
        }
    }
    imageStore(indirect, texel, vec4(sum, max(covered, 0.0)));
}
