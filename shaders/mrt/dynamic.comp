#version 450
// §7.3 step 9: each dynamic vertex's indirect irradiance from the light volume. The block it
// stands deepest in (within OUTSIDE of a block), by Newton's inverse of the block's trilinear
// warp as relume_bake::mrt::proxy undoes it; the probes read trilinearly in the dictionary
// shape's frame; the normal carried there as a covector (J^T n); the radiance convolved with
// the clamped cosine (Ramamoorthi and Hanrahan), clamped at zero. Alpha 1 marks the vertex as
// lit per vertex. Newton works relative to the block's corner 0, so that f32 keeps its
// precision far from the origin.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 64, local_size_y = 1, local_size_z = 1) in;

#include "mrt/push.glsl"
#include "mrt/volume.glsl"
#include "sh.glsl"

layout(std430, set = 0, binding = 0) readonly buffer Vertices { float vertices[]; };
layout(std430, set = 0, binding = 1) readonly buffer DynamicVertices { uint dynamic_vertices[]; };
layout(std430, set = 0, binding = 2) readonly buffer VolumeBlocks { VolumeBlock volume_blocks[]; };
layout(std430, set = 0, binding = 3) readonly buffer Volume { vec4 volume[]; };
layout(std430, set = 0, binding = 4) writeonly buffer VertexLight { vec4 vertex_light[]; };

// The scene's vertex: position, normal, uv0, uv1 (renderer/src/gpu_scene.rs's GpuVertex).
const uint VERTEX_FLOATS = 10u;
// relume_bake::mrt::volume::OUTSIDE, and proxy's INSIDE: how far outside the cube a root may be.
const float OUTSIDE = 0.05;
const float INSIDE = 1e-3;

// The warp relative to corner 0 (weights sum to 1, so corner 0 drops out of the sum).
vec3 warp(uint b, vec3 q) {
    vec3 p = vec3(0.0);
    vec3 origin = volume_blocks[b].corners[0].xyz;
    for (uint i = 1u; i < 8u; ++i) {
        vec3 t = mix(1.0 - q, q, vec3(uvec3(i, i >> 1u, i >> 2u) & 1u));
        p += (volume_blocks[b].corners[i].xyz - origin) * (t.x * t.y * t.z);
    }
    return p;
}

// d(world)/d(local): columns along local x, y, z.
mat3 jacobian(uint b, vec3 q) {
    mat3 j = mat3(0.0);
    vec3 origin = volume_blocks[b].corners[0].xyz;
    for (uint i = 1u; i < 8u; ++i) {
        vec3 high = vec3(uvec3(i, i >> 1u, i >> 2u) & 1u);
        vec3 t = mix(1.0 - q, q, high);
        vec3 slope = 2.0 * high - 1.0;
        vec3 c = volume_blocks[b].corners[i].xyz - origin;
        j[0] += c * (slope.x * t.y * t.z);
        j[1] += c * (t.x * slope.y * t.z);
        j[2] += c * (t.x * t.y * slope.z);
    }
    return j;
}

float depth(vec3 q) {
    return min(min(q.x, min(q.y, q.z)), 1.0 - max(q.x, max(q.y, q.z)));
}

bool newton(uint b, vec3 p, vec3 seed, float size, out vec3 q) {
    q = seed;
    for (int k = 0; k < 32; ++k) {
        vec3 miss = warp(b, q) - p;
        if (length(miss) <= 1e-5 * size) return true;
        mat3 j = jacobian(b, q);
        if (abs(determinant(j)) < 1e-9 * size * size * size) return false;
        q = clamp(q - inverse(j) * miss, vec3(-2.0), vec3(3.0));
    }
    return length(warp(b, q) - p) <= 1e-4 * size;
}

// The local point of block b at p (relative to its corner 0): from the centre, then near each
// corner; the first root inside the cube, else the first found.
bool local_point(uint b, vec3 p, float size, out vec3 q) {
    bool found = false;
    vec3 first = vec3(0.0);
    for (uint s = 0u; s < 9u; ++s) {
        vec3 seed = s == 0u ? vec3(0.5) : vec3(0.1) + 0.8 * vec3(uvec3(s - 1u, (s - 1u) >> 1u, (s - 1u) >> 2u) & 1u);
        vec3 root;
        if (newton(b, p, seed, size, root)) {
            if (depth(root) >= -INSIDE) {
                q = root;
                return true;
            }
            if (!found) first = root;
            found = true;
        }
    }
    q = first;
    return found;
}

vec3 turn(vec3 d, uint quarter_turns) {
    for (uint k = 0u; k < quarter_turns % 4u; ++k) d = vec3(d.z, d.y, -d.x);
    return d;
}

vec3 irradiance(uint b, vec3 q, vec3 n) {
    vec3 t = clamp(q * float(VOLUME_PROBES) - 0.5, vec3(0.0), vec3(float(VOLUME_PROBES - 1u)));
    vec3 lo = min(floor(t), vec3(float(VOLUME_PROBES - 2u)));
    vec3 f = t - lo;
    vec3 sh[9];
    for (uint s = 0u; s < 9u; ++s) sh[s] = vec3(0.0);
    for (uint c = 0u; c < 8u; ++c) {
        vec3 pick = vec3(uvec3(c, c >> 1u, c >> 2u) & 1u);
        vec3 w3 = mix(1.0 - f, f, pick);
        uvec3 at = uvec3(lo + pick);
        uint base = (b * 64u + at.x + VOLUME_PROBES * (at.y + VOLUME_PROBES * at.z)) * 9u;
        for (uint s = 0u; s < 9u; ++s) sh[s] += volume[base + s].rgb * (w3.x * w3.y * w3.z);
    }
    return sh_irradiance(n, sh);
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.dynamic_count) return;
    uint v = dynamic_vertices[i];
    uint f = v * VERTEX_FLOATS;
    vec3 p = vec3(vertices[f], vertices[f + 1u], vertices[f + 2u]);
    vec3 n = vec3(vertices[f + 3u], vertices[f + 4u], vertices[f + 5u]);
    float best = -OUTSIDE;
    uint block = NONE;
    vec3 local = vec3(0.0);
    for (uint b = 0u; b < pc.block_count; ++b) {
        VolumeBlock at = volume_blocks[b];
        if (any(lessThan(p, at.lo.xyz)) || any(greaterThan(p, at.hi.xyz))) continue;
        vec3 q;
        // The deepest block; the first of equal depth (as relume_bake::mrt::volume's locate).
        if (local_point(b, p - at.corners[0].xyz, length(at.hi.xyz - at.lo.xyz), q) && depth(q) >= -OUTSIDE
            && (block == NONE || depth(q) > best)) {
            best = depth(q);
            block = b;
            local = q;
        }
    }
    vec3 e = vec3(0.0);
    if (block != NONE) {
        uint back = (4u - volume_blocks[block].info.z % 4u) % 4u;
        vec3 covector = transpose(jacobian(block, local)) * n;
        vec3 normal = dot(covector, covector) > 0.0 ? normalize(covector) : vec3(0.0);
        vec3 q = turn(clamp(local, 0.0, 1.0) - 0.5, back) + 0.5;
        e = max(irradiance(block, q, turn(normal, back)), vec3(0.0));
    }
    vertex_light[v] = vec4(e, 1.0);
}
