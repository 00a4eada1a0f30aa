#version 450
// 004 eq. (12)-(13): per vertex of cluster c, the indirect irradiance
// E = x^m + sum_d z_d b_d with x^m = sums[c][0] and b_d = sums[c][d] from cluster_sums.comp,
// clamped at zero (relume_bake::light_cloud::LightCloud::irradiance on the CPU). One invocation
// per vertex.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) readonly buffer Sums { vec4 sums[]; };
layout(std430, set = 0, binding = 1) readonly buffer Assignment { uint assignment[]; };
// z[v][d - 1] at v * D + d - 1.
layout(std430, set = 0, binding = 2) readonly buffer Coords { float coords[]; };
layout(std430, set = 0, binding = 3) writeonly buffer Irradiance { vec4 irradiance[]; };

layout(push_constant) uniform ReconstructPush {
    uint vertex_count;
    uint basis;         // D
} pc;

void main() {
    uint v = gl_GlobalInvocationID.x;
    if (v >= pc.vertex_count) return;
    uint first = assignment[v] * (1u + pc.basis);
    vec3 e = sums[first].rgb;
    for (uint d = 1u; d <= pc.basis; ++d) {
        e += sums[first + d].rgb * coords[v * pc.basis + d - 1u];
    }
    irradiance[v] = vec4(max(e, vec3(0.0)), 1.0);
}
