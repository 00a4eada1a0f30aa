#version 450
// 004 eq. (12)-(13): per vertex of cluster c and coefficient i, x^m + sum_{d <= D_c} z_d b_d with
// x^m = sums[c][0][i] and b_d = sums[c][d][i] from cluster_sums.comp: the indirect irradiance
// (n_b = 1, clamped at zero) or the exitant radiance's spherical-harmonic coefficients
// (relume_bake::light_cloud::LightCloud::reconstruct on the CPU). One invocation per vertex.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) readonly buffer Sums { vec4 sums[]; };
// Per vertex: its cluster c and where its D_c coordinates z_d start in `coords`.
layout(std430, set = 0, binding = 1) readonly buffer Vertices { uvec2 vertices[]; };
layout(std430, set = 0, binding = 2) readonly buffer Coords { float coords[]; };
// n_b values per vertex.
layout(std430, set = 0, binding = 3) writeonly buffer VertexValues { vec4 values[]; };
// Here only each cluster's D_c.
#include "light_cloud/cluster.glsl"
layout(std430, set = 0, binding = 4) readonly buffer Clusters { Cluster clusters[]; };

layout(push_constant) uniform ReconstructPush {
    uint vertex_count;
    uint basis;         // D, the most vectors of any cluster: the sums' stride
    uint coefficients;  // n_b
} pc;

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= pc.vertex_count) return;
    uvec2 at = vertices[v];
    uint first = at.x * (1u + pc.basis) * pc.coefficients, vectors = clusters[at.x].vectors;
    for (uint i = 0u; i < pc.coefficients; ++i) {
        vec3 a = sums[first + i].rgb;
        for (uint d = 1u; d <= vectors; ++d) {
            a += sums[first + d * pc.coefficients + i].rgb * coords[at.y + d - 1u];
        }
        values[v * pc.coefficients + i] = vec4(pc.coefficients == 1u ? max(a, vec3(0.0)) : a, 1.0);
    }
}
