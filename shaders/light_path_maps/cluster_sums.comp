#version 450
// Step 3 of 000 §3.4: per cluster c of entry points, s_c = sum_e I_e and t_cd = sum_e I_e w^e_d,
// written as the textures are laid out (cluster after cluster, s_c then t_c1 .. t_cD), so
// that reconstruct.comp weighs texture k by sums[k]. One workgroup per (cluster, term):
// workgroup (c, k) sums term k (0: s_c, d: t_cd) over the cluster's entry points, each
// invocation a fixed strided share, then a tree reduction in shared memory. The order of
// additions is fixed, so the result is the same on every run.
layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

layout(std430, set = 0, binding = 0) readonly buffer Irradiance { vec4 irradiance[]; };   // rgb I_e
layout(std430, set = 0, binding = 1) readonly buffer Weights { float weights[]; };       // w^e_d at e * D + d - 1
layout(std430, set = 0, binding = 2) readonly buffer Starts { uint cluster_starts[]; };  // C + 1
layout(std430, set = 0, binding = 3) writeonly buffer Sums { vec4 sums[]; };             // C * (1 + D), rgb

layout(push_constant) uniform ClusterSumsPush {
    uint basis_count;   // D
} pc;

const uint GROUP = 64u;
shared vec3 partial[GROUP];

void main() {
    uint c = gl_WorkGroupID.x;
    uint k = gl_WorkGroupID.y;
    uint lane = gl_LocalInvocationID.x;
    uint end = cluster_starts[c + 1u];
    vec3 sum = vec3(0.0);
    for (uint e = cluster_starts[c] + lane; e < end; e += GROUP) {
        float w = k == 0u ? 1.0 : weights[e * pc.basis_count + k - 1u];
        sum += irradiance[e].rgb * w;
    }
    partial[lane] = sum;
    barrier();
    for (uint half_size = GROUP / 2u; half_size > 0u; half_size /= 2u) {
        if (lane < half_size) partial[lane] += partial[lane + half_size];
        barrier();
    }
    if (lane == 0u) sums[c * (1u + pc.basis_count) + k] = vec4(partial[0], 0.0);
}
