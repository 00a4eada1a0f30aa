#version 450
// 004 eq. (12): per cluster c, term t (t = 0 the mean X^c, t = d the basis vector B^c_d) and
// coefficient i (n_b of them), sums[c][t][i] = sum_k w_k T[c][t][j_k][i] over this frame's
// non-zero weights of c's zone's columns (cloud light x emission function), in their order
// (relume_bake::light_cloud::LightCloud::cluster_sums on the CPU). One invocation per
// (cluster, term, coefficient).
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// Cluster c's term t, coefficient i at clusters[c].offset + 3 * ((t * clusters[c].columns + j) *
// n_b + i) for the zone's column j (packed rgb).
layout(std430, set = 0, binding = 0) readonly buffer Terms { float terms[]; };
// The weight (candela, rgb) and the column it weighs: 16 bytes.
struct CloudWeight {
    vec3 weight;
    uint column;
};
layout(std430, set = 0, binding = 1) readonly buffer Weights { CloudWeight weights[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Sums { vec4 sums[]; };
#include "light_cloud/cluster.glsl"
layout(std430, set = 0, binding = 3) readonly buffer Clusters { Cluster clusters[]; };

layout(push_constant) uniform ClusterSumsPush {
    uint term_count;    // C * (1 + D) * n_b
    uint terms;         // 1 + D, D the most vectors of any cluster
    uint weight_count;
    uint coefficients;  // n_b
} pc;

void main() {
    uint index = gl_GlobalInvocationID.x;
    if (index >= pc.term_count) return;
    uint term = index / pc.coefficients, i = index % pc.coefficients;
    Cluster c = clusters[term / pc.terms];
    uint t = term % pc.terms;
    vec3 sum = vec3(0.0);
    // Past the cluster's own D_c: zero, which its vertices never read.
    if (t > c.vectors) {
        sums[index] = vec4(sum, 0.0);
        return;
    }
    uint first = c.offset + 3u * (t * c.columns * pc.coefficients + i);
    for (uint k = 0u; k < pc.weight_count; ++k) {
        CloudWeight w = weights[k];
        uint j = w.column - c.first_column;
        // Unsigned: a column before the zone wraps past its count too.
        if (j < c.columns) {
            uint at = first + 3u * j * pc.coefficients;
            sum += w.weight * vec3(terms[at], terms[at + 1u], terms[at + 2u]);
        }
    }
    sums[index] = vec4(sum, 0.0);
}
