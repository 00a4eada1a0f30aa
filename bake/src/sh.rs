//! Real spherical harmonics of bands l <= 3 (16 functions), orthonormal over the sphere: the
//! basis in which the light cloud stores a glossy vertex's exitant radiance in world space
//! (004 eq. 7-8, "third order", n_b = 16), and whose first nine (l <= 2) hold the radiance of
//! modular radiance transfer's light-volume probes in each block's own frame (002 §6.5). `shaders/sh.glsl` evaluates the same polynomials.
//!
//! Index l (l + 1) + m; the constants are sqrt((2l + 1) / 4 pi (l - |m|)! / (l + |m|)!) times
//! sqrt(2) for m != 0, folded into the Cartesian forms, with z the polar axis.

use glam::Vec3;

/// Functions of bands 0..=3.
pub const COEFFICIENTS: usize = 16;

/// Functions of bands 0..=2: all irradiance needs (Ramamoorthi & Hanrahan 2001).
pub const IRRADIANCE_COEFFICIENTS: usize = 9;

/// The clamped cosine's factor per band l <= 2 (Ramamoorthi & Hanrahan 2001, eq. 8): pi,
/// 2 pi / 3, pi / 4.
const COSINE_BANDS: [f32; 3] = [std::f32::consts::PI, 2.0 * std::f32::consts::PI / 3.0, std::f32::consts::PI / 4.0];

/// The irradiance on a surface of unit normal `n` under radiance of bands l <= 2 (`radiance`:
/// rgb per coefficient): the radiance convolved with the clamped cosine (Ramamoorthi &
/// Hanrahan 2001), not clamped (nine coefficients ring below zero facing away from a bright
/// source; callers clamp). `sh_irradiance` in `shaders/sh.glsl` is the same.
pub fn irradiance(radiance: &[Vec3; IRRADIANCE_COEFFICIENTS], n: Vec3) -> Vec3 {
    let y = eval(n);
    (0..IRRADIANCE_COEFFICIENTS).map(|i| radiance[i] * (COSINE_BANDS[band(i)] * y[i])).sum()
}

/// The band l of coefficient `i` (index l (l + 1) + m).
fn band(i: usize) -> usize {
    (i as f32).sqrt() as usize
}

/// y_i(d) for the 16 functions at unit direction `d`.
pub fn eval(d: Vec3) -> [f32; COEFFICIENTS] {
    let (x, y, z) = (d.x, d.y, d.z);
    let (x2, y2, z2) = (x * x, y * y, z * z);
    [
        0.282_094_8,
        0.488_602_5 * y,
        0.488_602_5 * z,
        0.488_602_5 * x,
        1.092_548_4 * x * y,
        1.092_548_4 * y * z,
        0.315_391_57 * (3.0 * z2 - 1.0),
        1.092_548_4 * x * z,
        0.546_274_2 * (x2 - y2),
        0.590_043_6 * y * (3.0 * x2 - y2),
        2.890_611_4 * x * y * z,
        0.457_045_8 * y * (5.0 * z2 - 1.0),
        0.373_176_33 * z * (5.0 * z2 - 3.0),
        0.457_045_8 * x * (5.0 * z2 - 1.0),
        1.445_305_7 * z * (x2 - y2),
        0.590_043_6 * x * (x2 - 3.0 * y2),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Orthonormal over the sphere: a midpoint quadrature of 400 x 800 cells (uniform in
    /// cos theta and phi, so every cell holds the same solid angle) gives the identity within
    /// 1e-4.
    #[test]
    fn the_sixteen_functions_are_orthonormal_by_quadrature() {
        let (bands, sectors) = (400, 800);
        let mut gram = [[0f64; COEFFICIENTS]; COEFFICIENTS];
        let weight = 4.0 * PI / (bands * sectors) as f64;
        for i in 0..bands {
            let cos = 1.0 - 2.0 * (i as f64 + 0.5) / bands as f64;
            let sin = (1.0 - cos * cos).sqrt();
            for j in 0..sectors {
                let phi = 2.0 * PI * (j as f64 + 0.5) / sectors as f64;
                let y = eval(Vec3::new((sin * phi.cos()) as f32, (sin * phi.sin()) as f32, cos as f32));
                for a in 0..COEFFICIENTS {
                    for b in 0..COEFFICIENTS {
                        gram[a][b] += y[a] as f64 * y[b] as f64 * weight;
                    }
                }
            }
        }
        for (a, row) in gram.iter().enumerate() {
            for (b, &g) in row.iter().enumerate() {
                let expected = if a == b { 1.0 } else { 0.0 };
                assert!((g - expected).abs() < 1e-4, "<y_{a}, y_{b}> = {g}");
            }
        }
    }
}
