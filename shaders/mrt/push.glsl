// The counts every MRT pass reads (renderer/src/techniques/mrt/mod.rs's MrtPush).
layout(push_constant) uniform MrtPush {
    uint sample_count;    // level samples
    uint block_count;
    uint k_max;           // the most modes of a dictionary shape: b's stride per block
    uint receiver_count;
    uint k_r;             // response modes: r's stride per receiver
    uint n_r;             // the canonical receiver's samples: U_r's column length
    uint texel_count;     // of the light map
    uint copy_count;      // copy records of the padded atlas
    uint width;           // of the light map, texels
    uint feedback;        // 1: every bounce (the solved feedback); 0: the first only
    uint u_r;             // where U_r (n_r x k_r) starts in the operator buffer
    uint u_rvol;          // where U_rvol (4 side faces x VOLUME_ROWS x k_r) starts there
    uint dynamic_count;   // vertices of the meshes the light volume lights
} pc;

const uint NONE = 0xffffffffu;

// A dictionary shape: n samples, k modes, where T_d->b (k x n) and U_b (n x k) start in the
// operator buffer (column-major).
struct Shape {
    uint n;
    uint k;
    uint t_d_b;
    uint u_b;
};
