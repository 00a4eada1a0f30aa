// Real spherical harmonics of bands l <= 3 (16 functions), orthonormal over the sphere, world
// space, index l (l + 1) + m, z the polar axis: the polynomials of bake/src/sh.rs.
void sh_eval(vec3 d, out float y[16]) {
    float x = d.x, yy = d.y, z = d.z;
    float x2 = x * x, y2 = yy * yy, z2 = z * z;
    y[0] = 0.2820948;
    y[1] = 0.4886025 * yy;
    y[2] = 0.4886025 * z;
    y[3] = 0.4886025 * x;
    y[4] = 1.0925484 * x * yy;
    y[5] = 1.0925484 * yy * z;
    y[6] = 0.31539157 * (3.0 * z2 - 1.0);
    y[7] = 1.0925484 * x * z;
    y[8] = 0.5462742 * (x2 - y2);
    y[9] = 0.5900436 * yy * (3.0 * x2 - y2);
    y[10] = 2.8906114 * x * yy * z;
    y[11] = 0.4570458 * yy * (5.0 * z2 - 1.0);
    y[12] = 0.37317633 * z * (5.0 * z2 - 3.0);
    y[13] = 0.4570458 * x * (5.0 * z2 - 1.0);
    y[14] = 1.4453057 * z * (x2 - y2);
    y[15] = 0.5900436 * x * (x2 - 3.0 * y2);
}

// The irradiance on a surface of unit normal n under radiance of bands l <= 2 (rgb per
// coefficient): the radiance convolved with the clamped cosine (Ramamoorthi and Hanrahan), not
// clamped; bake/src/sh.rs `irradiance`.
vec3 sh_irradiance(vec3 n, vec3 radiance[9]) {
    float y[16];
    sh_eval(n, y);
    const float lobe[9] = float[9](3.14159265, 2.0943951, 2.0943951, 2.0943951, 0.78539816, 0.78539816, 0.78539816,
                                   0.78539816, 0.78539816);
    vec3 e = vec3(0.0);
    for (uint s = 0u; s < 9u; ++s) e += radiance[s] * (lobe[s] * y[s]);
    return e;
}
