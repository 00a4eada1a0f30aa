#version 450
// 004 eq. (12): per cluster c and term t (t = 0 the mean X^c, t = d the basis vector B^c_d),
// sums[c][t] = sum_k w_k T[c][t][j_k] over this frame's non-zero weights of c's zone's cloud
// lights, in their order (relume_bake::light_cloud::LightCloud::cluster_sums on the CPU). One
// invocation per (cluster, term).
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

// Cluster c's term t at clusters[c].offset + 3 * (t * clusters[c].lights + j) for the zone's
// light j (packed rgb).
layout(std430, set = 0, binding = 0) readonly buffer Terms { float terms[]; };
// The weight (candela, rgb) and the cloud light it weighs: 16 bytes.
struct CloudWeight {
    vec3 weight;
    uint light;
};
layout(std430, set = 0, binding = 1) readonly buffer Weights { CloudWeight weights[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Sums { vec4 sums[]; };
// Per cluster: where its terms start, its zone's first cloud light and light count.
struct Cluster {
    uint offset;
    uint first_light;
    uint lights;
    uint unused;
};
layout(std430, set = 0, binding = 3) readonly buffer Clusters { Cluster clusters[]; };

layout(push_constant) uniform ClusterSumsPush {
    uint term_count;    // C * (1 + D)
    uint terms;         // 1 + D
    uint weight_count;
} pc;

void main() {
    uint term = gl_GlobalInvocationID.x;
    if (term >= pc.term_count) return;
    Cluster c = clusters[term / pc.terms];
    uint first = c.offset + 3u * (term % pc.terms) * c.lights;
    vec3 sum = vec3(0.0);
    for (uint k = 0u; k < pc.weight_count; ++k) {
        CloudWeight w = weights[k];
        uint j = w.light - c.first_light;
        // Unsigned: a light before the zone wraps past its count too.
        if (j < c.lights) {
            uint at = first + 3u * j;
            sum += w.weight * vec3(terms[at], terms[at + 1u], terms[at + 2u]);
        }
    }
    sums[term] = vec4(sum, 0.0);
}
