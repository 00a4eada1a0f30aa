// The light volume's tables (renderer/src/techniques/mrt/volume.rs; relume_bake::mrt::volume):
// 4^3 probes a block, 9 spherical-harmonic coefficients of radiance a probe, in the frame of
// the block's dictionary shape.

const uint VOLUME_PROBES = 4u;
const uint VOLUME_ROWS = 64u * 9u;

// One block as the volume passes read it.
struct VolumeBlock {
    uvec4 info;        // where its shape's U_bvol starts, its modes k, the quarter turns from
                       // its shape to it, -
    uvec4 receivers;   // up to four: receiver * 4 + the side (0-3: -x, +x, -z, +z) it enters
                       // through in the shape's frame (NONE: none)
    vec4 lo;           // its bounds, widened by OUTSIDE of a mean edge
    vec4 hi;
    vec4 corners[8];   // corner i at local (i & 1, i >> 1 & 1, i >> 2 & 1)
};
