#version 450
// Atlas padding by jump flooding (Rong & Tan 2006) with the extra k = 1 step of JFA+1:
// every empty texel (alpha <= 0) takes the rgb of its nearest covered texel (alpha > 0) in
// the same layer, and alpha = -distance in texels. One module, three modes (push constant);
// passes/padding.rs runs SEED, then JUMP for each k, then RESOLVE, all layers at once.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;
layout(set = 0, binding = 0, rgba32f) uniform image2DArray atlas_image;
// The nearest covered texel found so far, or NONE; read from one image, written to the other.
layout(set = 0, binding = 1, rg32i) uniform readonly iimage2DArray seeds_in;
layout(set = 0, binding = 2, rg32i) uniform writeonly iimage2DArray seeds_out;
layout(push_constant) uniform PaddingPush {
    int mode;
    int step;
} pc;

const int SEED = 0;
const int JUMP = 1;
const int RESOLVE = 2;
const ivec2 NONE = ivec2(-1);

// Squared distances stay in int range for sides up to 16384 texels (GpuAtlasImage's limit).
int distance2(ivec2 a, ivec2 b) {
    ivec2 d = a - b;
    return d.x * d.x + d.y * d.y;
}

void seed(ivec3 texel) {
    bool covered = imageLoad(atlas_image, texel).a > 0.0;
    imageStore(seeds_out, texel, ivec4(covered ? texel.xy : NONE, 0, 0));
}

// Keeps the closest of the seeds held by the 9 texels at offsets {-k, 0, k}^2; the strict
// comparison in a fixed order makes ties resolve the same way on every run.
void jump(ivec3 texel, ivec2 size) {
    ivec2 best = NONE;
    int best_distance2 = 0x7fffffff;
    for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
            ivec2 at = texel.xy + ivec2(dx, dy) * pc.step;
            if (any(lessThan(at, ivec2(0))) || any(greaterThanEqual(at, size))) continue;
            ivec2 candidate = imageLoad(seeds_in, ivec3(at, texel.z)).xy;
            if (candidate.x < 0) continue;
            int d2 = distance2(candidate, texel.xy);
            if (d2 < best_distance2) {
                best = candidate;
                best_distance2 = d2;
            }
        }
    }
    imageStore(seeds_out, texel, ivec4(best, 0, 0));
}

// Covered texels are their own seed and are never written, so the reads of their rgb here
// never race with the writes of the empty texels. No seed: the layer has no covered texel.
void resolve(ivec3 texel) {
    ivec2 nearest = imageLoad(seeds_in, texel).xy;
    if (nearest.x < 0 || nearest == texel.xy) return;
    vec3 rgb = imageLoad(atlas_image, ivec3(nearest, texel.z)).rgb;
    imageStore(atlas_image, texel, vec4(rgb, -length(vec2(nearest - texel.xy))));
}

void main() {
    ivec3 texel = ivec3(gl_GlobalInvocationID);
    ivec2 size = imageSize(atlas_image).xy;
    if (any(greaterThanEqual(texel.xy, size))) return;
    if (pc.mode == SEED) {
        seed(texel);
    } else if (pc.mode == JUMP) {
        jump(texel, size);
    } else {
        resolve(texel);
    }
}
