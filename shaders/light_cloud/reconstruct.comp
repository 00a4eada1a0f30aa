#version 450
// 004 eq. (12) with n_b = 1 and no compression: per vertex, the indirect irradiance
// E = sum_k w_k X[v][j_k] over this frame's non-zero cloud-light weights, in their order
// (relume_bake::light_cloud::LightCloud::irradiance on the CPU). One invocation per vertex.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// X[v][j] at 3 * (v * light_count + j): packed rgb, lux per candela.
layout(std430, set = 0, binding = 0) readonly buffer Transfer { float transfer[]; };
// rgb the weight (candela), w the cloud light's index as uint bits.
layout(std430, set = 0, binding = 1) readonly buffer Weights { vec4 weights[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Irradiance { vec4 irradiance[]; };

layout(push_constant) uniform ReconstructPush {
    uint vertex_count;
    uint light_count;
    uint weight_count;
} pc;

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= pc.vertex_count) return;
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < pc.weight_count; ++k) {
        vec4 w = weights[k];
        uint at = 3u * (v * pc.light_count + floatBitsToUint(w.w));
        sum += w.rgb * vec3(transfer[at], transfer[at + 1u], transfer[at + 2u]);
    }
    irradiance[v] = vec4(sum, 1.0);
}
