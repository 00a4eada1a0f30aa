#version 450
// 004 eq. (12): per cluster c and term t (t = 0 the mean X^c, t = d the basis vector B^c_d),
// sums[c][t] = sum_k w_k T[c][t][j_k] over this frame's non-zero cloud-light weights, in their
// order (relume_bake::light_cloud::LightCloud::cluster_sums on the CPU). One invocation per
// (cluster, term).
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// T[c][t][j] at 3 * (term * light_count + j), term = c * (1 + D) + t: packed rgb.
layout(std430, set = 0, binding = 0) readonly buffer Terms { float terms[]; };
// The weight (candela, rgb) and the cloud light it weighs: 16 bytes.
struct CloudWeight {
    vec3 weight;
    uint light;
};
layout(std430, set = 0, binding = 1) readonly buffer Weights { CloudWeight weights[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Sums { vec4 sums[]; };

layout(push_constant) uniform ClusterSumsPush {
    uint term_count;    // C * (1 + D)
    uint light_count;
    uint weight_count;
} pc;

void main() {
    uint term = gl_GlobalInvocationID.x;
    if (term >= pc.term_count) return;
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < pc.weight_count; ++k) {
        CloudWeight w = weights[k];
        uint at = 3u * (term * pc.light_count + w.light);
        sum += w.weight * vec3(terms[at], terms[at + 1u], terms[at + 2u]);
    }
    sums[term] = vec4(sum, 0.0);
}
