#version 450
// The FIV occluder sums, 003 §5, per pixel (relume_bake::fiv::FivBake::irradiance is the same
// formula on the CPU, step for step): DifMap(N), or on a self-shadowing occluder
// max(0, N . (FIV(Env) - FIV_self)), less each other occluder's N . FIV(EnvOcc) by its case
// (A: d >= R, B: scaled by (d + R) / 2R when partial, C: d <= -R nothing; a receiver inside
// it, all of DifMap(N)), plus the pairwise overlaps of eq. (13)-(14) as
// sum_a I_a sum_{b != a} Ov%_ab; the overlap at most sum I - max I and the result in
// [0, DifMap(N)]. Pixels with no surface get 0.
layout(local_size_x = 8, local_size_y = 8, local_size_z = 1) in;

layout(set = 0, binding = 0, rgba32f) uniform readonly image2D positions;   // w 1: a surface
layout(set = 0, binding = 1, rgba32f) uniform readonly image2D normals;     // w: own occluder + 1
layout(set = 0, binding = 2, rgba32f) uniform writeonly image2DArray irradiance;
// DifMap: width x width / 2 lat-long texels, rgb; then FIV(Env), the r, g and b vectors.
layout(std430, set = 0, binding = 3) readonly buffer DifMap { vec4 difmap[]; };
// Every type's table, 3 vec4 per sample (the r, g and b vectors; the first one's w 1 where
// the sample is valid, 0 where not), then its surface points' masks for its first shells
// alike; types one after another.
layout(std430, set = 0, binding = 4) readonly buffer Tables { vec4 tables[]; };
struct OccluderType {
    uvec4 grid;     // azimuths, polar angles, distances, first sample in `tables`
    vec4 facts;     // radius R, distance_min, distance_max, ln(distance_max / distance_min)
    uvec4 surface;  // the surface points' masks: first sample in `tables`, shells
};
layout(std430, set = 0, binding = 5) readonly buffer Types { OccluderType types[]; };
struct Occluder {
    vec4 centre;    // xyz: the bounding-sphere centre; w unused
    uvec4 type;     // x: the type
};
layout(std430, set = 0, binding = 6) readonly buffer Occluders { Occluder occluders[]; };

layout(push_constant) uniform OccluderSumsPush {
    uint occluder_count;
    uint difmap_width;
    uint partial;       // 1: case B scaled by (d + R) / 2R
    uint overlap;       // 1: the pairwise overlap correction
    uint beyond_scale;  // 1: beyond distance_max the outer shell times (max / distance)^2; 0: nothing
    uint inverse_square; // 1: shells blended as distance^2 x FIV, divided by distance^2; 0: linearly
    uint self_shadow;   // a receiver on an occluder shadowed by it: 0 not, 1 the paper's lookup, 2 the surface points'
} pc;

// relume_bake::fiv::VALID_WEIGHT_MIN
const float VALID_WEIGHT_MIN = 1e-3;

const float PI = 3.14159265358979;
const float TAU = 6.28318530717959;

// The azimuth of a direction from +X towards -Z, 0 straight up or down.
float azimuth(vec3 d) {
    return (d.x == 0.0 && d.z == 0.0) ? 0.0 : atan(-d.z, d.x);
}

vec3 difmap_texel(int i, int j) {
    int w = int(pc.difmap_width);
    int h = w / 2;
    i = i < 0 ? i + w : (i >= w ? i - w : i);
    return difmap[clamp(j, 0, h - 1) * w + i].rgb;
}

// DifMap at N, bilinear, repeating in azimuth, clamped at the poles.
vec3 difmap_lookup(vec3 n) {
    float u = (n.x == 0.0 && n.z == 0.0) ? 0.5 : 0.5 + atan(n.x, -n.z) / TAU;
    float v = acos(clamp(n.y, -1.0, 1.0)) / PI;
    float x = u * float(pc.difmap_width) - 0.5;
    float y = v * float(pc.difmap_width / 2u) - 0.5;
    float x0 = floor(x);
    float y0 = floor(y);
    int i = int(x0);
    int j = int(y0);
    vec3 top = mix(difmap_texel(i, j), difmap_texel(i + 1, j), x - x0);
    vec3 bottom = mix(difmap_texel(i, j + 1), difmap_texel(i + 1, j + 1), x - x0);
    return mix(top, bottom, y - y0);
}

// N . FIV(EnvOcc) of type t centred at offset v: trilinear over the 8 nearest of the samples
// from `first` on (`shells` shells of them; beyond, none is valid), distances in log space
// (each shell weighted by (its distance / distance)^2 when `inverse_square`), clamped below,
// renormalised over the valid samples; the r, g, b rows dotted with N. w: 1, or 0 where the
// valid samples carry too little weight. Beyond distance_max: the outer shell scaled when
// `beyond_scale`, else nothing.
vec4 interpolate(uint t, uint first, uint shells, bool beyond_scale, bool inverse_square, vec3 v, vec3 n) {
    uvec4 g = types[t].grid;
    vec4 facts = types[t].facts;
    float distance = max(length(v), 1e-20);
    vec3 d = v / distance;
    float theta = azimuth(d);
    float fi = (theta < 0.0 ? theta + TAU : theta) / TAU * float(g.x);
    float fj = min(acos(clamp(d.y, -1.0, 1.0)) / PI * float(g.y - 1u), float(g.y - 1u));
    float steps = float(g.z - 1u);
    float fk = clamp(log(distance / facts.y) / facts.w * steps, 0.0, steps);
    float i0 = floor(fi);
    float j0 = min(floor(fj), float(g.y - 2u));
    float k0 = min(floor(fk), steps - 1.0);
    vec3 weights = vec3(fi - i0, fj - j0, fk - k0);
    uint i = uint(i0) % g.x;
    uint ii = (i + 1u) % g.x;
    uint j = uint(j0);
    uint k = uint(k0);
    vec3 sum = vec3(0.0);
    float weight = 0.0;
    float within = clamp(distance, facts.y, facts.z);
    for (uint dk = 0u; dk < 2u; ++dk) {
        float wk = dk == 0u ? 1.0 - weights.z : weights.z;
        float shell = 1.0;
        if (inverse_square) {
            shell = facts.y * pow(facts.z / facts.y, float(k + dk) / steps) / within;
            shell *= shell;
        }
        for (uint dj = 0u; dj < 2u; ++dj) {
            float wj = dj == 0u ? 1.0 - weights.y : weights.y;
            for (uint di = 0u; di < 2u; ++di) {
                float wi = di == 0u ? 1.0 - weights.x : weights.x;
                if (k + dk >= shells) continue;
                uint sample_index = first + ((k + dk) * g.y + j + dj) * g.x + (di == 0u ? i : ii);
                vec4 red = tables[3u * sample_index];
                if (red.w == 0.0) continue;
                float w = wi * wj * wk;
                weight += w;
                w *= shell;
                sum += w * vec3(dot(n, tables[3u * sample_index].xyz), dot(n, tables[3u * sample_index + 1u].xyz),
                                dot(n, tables[3u * sample_index + 2u].xyz));
            }
        }
    }
    if (weight < VALID_WEIGHT_MIN) return vec4(0.0);
    if (distance > facts.z) {
        sum *= beyond_scale ? (facts.z / distance) * (facts.z / distance) : 0.0;
    }
    return vec4(sum / weight, 1.0);
}

// The table's lookup (relume_bake::fiv::OccluderTable::lookup).
vec4 table_lookup(uint t, vec3 v, vec3 n) {
    return interpolate(t, types[t].grid.w, types[t].grid.z, pc.beyond_scale == 1u, pc.inverse_square == 1u, v, n);
}

// For a receiver on its own occluder: DifMap(N) - max(0, N . FIV_above) from the surface
// points' masks above their tangent planes (self_shadow 2), or max(0, N . (FIV(Env) -
// FIV_self)) from the table (self_shadow 1, or where the surface has no valid sample);
// DifMap(N) where there is no occluder, no self-shadowing or no valid sample.
vec3 unoccluded(uint own, vec3 p, vec3 n, vec3 total) {
    if (pc.self_shadow == 0u || own >= pc.occluder_count) return total;
    uint t = occluders[own].type.x;
    vec3 v = occluders[own].centre.xyz - p;
    if (pc.self_shadow == 2u) {
        vec4 above = interpolate(t, types[t].surface.x, types[t].surface.y, false, false, v, n);
        if (above.w != 0.0) return total - max(above.xyz, vec3(0.0));
    }
    vec4 self_fiv = table_lookup(t, v, n);
    if (self_fiv.w == 0.0) return total;
    uint e = pc.difmap_width * (pc.difmap_width / 2u);
    vec3 environment = vec3(dot(n, difmap[e].xyz), dot(n, difmap[e + 1u].xyz), dot(n, difmap[e + 2u].xyz));
    return max(environment - self_fiv.xyz, vec3(0.0));
}

// The area two discs share (a lens; nested and disjoint discs included).
float lens_area(float distance, float r1, float r2) {
    if (distance >= r1 + r2) return 0.0;
    if (distance <= abs(r1 - r2)) return PI * min(r1, r2) * min(r1, r2);
    float a1 = acos(clamp((distance * distance + r1 * r1 - r2 * r2) / (2.0 * distance * r1), -1.0, 1.0));
    float a2 = acos(clamp((distance * distance + r2 * r2 - r1 * r1) / (2.0 * distance * r2), -1.0, 1.0));
    float kite = (-distance + r1 + r2) * (distance + r1 - r2) * (distance - r1 + r2) * (distance + r1 + r2);
    return r1 * r1 * a1 + r2 * r2 * a2 - 0.5 * sqrt(max(kite, 0.0));
}

// Whether occluder o takes light from the receiver at p with normal n: not its own, not in
// case C, not dropped beyond the tables.
bool occludes(uint o, uint own, vec3 p, vec3 n) {
    vec3 v = occluders[o].centre.xyz - p;
    vec4 facts = types[occluders[o].type.x].facts;
    return o != own && dot(n, v) > -facts.x && (pc.beyond_scale == 1u || length(v) <= facts.z);
}

// Occluder o's disc on the plane at unit height along n (centre in xyz, radius in w).
vec4 disc(uint o, vec3 p, vec3 n) {
    vec3 v = occluders[o].centre.xyz - p;
    float radius = types[occluders[o].type.x].facts.x;
    float d = dot(n, v);
    float height = max(d, radius);
    return vec4((v - d * n) / height, radius / height);
}

float overlap_shares(uint a, uint own, vec3 p, vec3 n) {
    vec4 da = disc(a, p, n);
    float shares = 0.0;
    for (uint b = 0u; b < pc.occluder_count; ++b) {
        if (b == a || !occludes(b, own, p, n)) continue;
        vec4 db = disc(b, p, n);
        shares += lens_area(distance(da.xyz, db.xyz), da.w, db.w) / (PI * (da.w * da.w + db.w * db.w));
    }
    return shares;
}

void main() {
    ivec2 pixel = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(pixel, imageSize(positions)))) return;
    vec4 surface = imageLoad(positions, pixel);
    if (surface.w == 0.0) {
        imageStore(irradiance, ivec3(pixel, 0), vec4(0.0));
        return;
    }
    vec3 p = surface.xyz;
    vec4 normal = imageLoad(normals, pixel);
    vec3 n = normalize(normal.xyz);
    uint own = uint(normal.w) - 1u;   // all ones (no occluder) when w is 0
    vec3 total = difmap_lookup(n);
    vec3 occluded = vec3(0.0);
    vec3 overlap = vec3(0.0);
    vec3 largest = vec3(0.0);
    for (uint a = 0u; a < pc.occluder_count; ++a) {
        if (!occludes(a, own, p, n)) continue;
        uint t = occluders[a].type.x;
        float radius = types[t].facts.x;
        vec3 v = occluders[a].centre.xyz - p;
        float d = dot(n, v);
        float factor = (pc.partial == 1u && d < radius) ? (d + radius) / (2.0 * radius) : 1.0;
        vec4 fiv = table_lookup(t, v, n);
        vec3 share = fiv.w == 0.0 ? total : max(fiv.xyz, vec3(0.0)) * factor;
        occluded += share;
        largest = max(largest, share);
        if (pc.overlap == 1u) overlap += share * overlap_shares(a, own, p, n);
    }
    overlap = min(overlap, occluded - largest);
    vec3 open = unoccluded(own, p, n, total);
    imageStore(irradiance, ivec3(pixel, 0), vec4(clamp(open - occluded + overlap, vec3(0.0), total), 1.0));
}
