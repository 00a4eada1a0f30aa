// The shadowed direct irradiance at a point from every light of the frame, shared by the
// passes that light points other than pixels (light_path_maps/entry_irradiance.comp, mrt/direct.comp):
//
//   E = sum_j E_j(p) * |l_j - p|^2 / (|l_j - p|^2 + delta-l / pi) * max(0, cos theta) * V_j(p)
//
// E_j(p) the light's irradiance on a surface facing it (lights.glsl's incident_light: glTF
// falloff, range window, spot cone), the squared distance widened by a light area delta-l
// (0: none; directional lights ignore it), V_j the Chebyshev visibility the lighting pass uses.
// Include after lights.glsl, frame.glsl and vsm_visibility.glsl, in a shader that declares
// `lights` (the Light storage buffer).

vec3 direct_irradiance(vec3 p, vec3 n, float light_area) {
    const float PI_ = 3.14159265358979;
    vec3 sum = vec3(0.0);
    for (uint i = 0u; i < frame.light_count; ++i) {
        vec3 to_light;
        vec3 incident = incident_light(lights[i], p, to_light);
        float cos_e = max(dot(n, to_light), 0.0);
        if (cos_e <= 0.0) continue;
        float widening = 1.0;
        if (uint(lights[i].position_kind.w) != LIGHT_DIRECTIONAL) {
            float distance = length(lights[i].position_kind.xyz - p);
            float d2 = distance * distance;
            widening = d2 / (d2 + light_area / PI_);
        }
        sum += incident * widening * cos_e
               * visibility(lights[i], p, frame.shadows, frame.min_variance, frame.bleeding_reduction);
    }
    return sum;
}
