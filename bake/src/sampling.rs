//! Deterministic random numbers and the warps the path tracer draws with.
//!
//! Every number is a pure function of (seed, pixel, sample, dimension): there is no generator
//! state shared between paths, so a render gives the same bytes whichever thread traces which
//! pixel, and any one sample of any one pixel can be replayed on its own.
//!
//! Two kinds of numbers are offered:
//! - [`PathSampler::uniform`]: an independent hash per dimension, for decisions whose
//!   stratification does not matter (light choice, Russian roulette).
//! - [`PathSampler::sobol4`]: a four-dimensional Owen-scrambled Sobol point, shuffled per pixel,
//!   after Burley, "Practical Hash-based Owen Scrambling" (JCGT 9(4), 2020). Across the samples of
//!   one pixel each dimension is stratified (the first 2^k samples fall one in each interval of
//!   length 2^-k), which lowers the noise of the pixel filter and of the first bounces. Each
//!   point on its own is uniform in [0, 1)^4 with independent coordinates (every dimension is
//!   scrambled with its own seed), so estimators stay unbiased; the direction numbers only
//!   affect variance. Separate groups use separate shuffles ("padding"), so dimensions of
//!   different groups are decorrelated.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Stafford's "mix13" 64-bit finaliser (the one SplitMix64 uses): a bijection with good
/// avalanche, so neighbouring keys give unrelated outputs.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A uniformly distributed u32 from (seed, pixel, sample, dimension).
#[inline]
pub fn hash_u32(seed: u64, pixel: u32, sample: u32, dim: u32) -> u32 {
    let key = pixel_key(seed, pixel);
    (mix64(key ^ mix64(((sample as u64) << 32) | dim as u64)) >> 32) as u32
}

/// A u32 mapped to [0, 1): the top 24 bits, so the result is exact in f32 and never 1.0.
#[inline]
pub fn u32_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

#[inline]
fn pixel_key(seed: u64, pixel: u32) -> u64 {
    mix64(mix64(seed ^ 0x9e37_79b9_7f4a_7c15) ^ pixel as u64)
}

/// The random numbers of one path: one sample of one pixel.
#[derive(Clone, Copy, Debug)]
pub struct PathSampler {
    key: u64,
    sample: u32,
}

impl PathSampler {
    pub fn new(seed: u64, pixel: u32, sample: u32) -> Self {
        PathSampler { key: pixel_key(seed, pixel), sample }
    }

    /// An independent uniform number in [0, 1) for dimension `dim` of this path.
    #[inline]
    pub fn uniform(&self, dim: u32) -> f32 {
        let bits = mix64(self.key ^ mix64(((self.sample as u64) << 32) | dim as u64)) >> 32;
        u32_to_unit(bits as u32)
    }

    /// An independent uniform number in [0, 1) with 53 random bits, for choices among very
    /// many options (one emitter among millions), where 24 bits would skew the odds.
    #[inline]
    pub fn uniform_f64(&self, dim: u32) -> f64 {
        let bits = mix64(self.key ^ mix64(((self.sample as u64) << 32) | dim as u64)) >> 11;
        bits as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// A point of the shuffled, Owen-scrambled 4D Sobol sequence; `group` selects an
    /// independent shuffle and scramble, so groups are decorrelated from one another.
    #[inline]
    pub fn sobol4(&self, group: u32) -> [f32; 4] {
        let group_seed = mix64(self.key ^ (0x5851_f42d_4c95_7f2d_u64.wrapping_mul(group as u64 + 1)));
        let index = nested_uniform_scramble(self.sample, group_seed as u32);
        let mut out = [0.0; 4];
        for (d, o) in out.iter_mut().enumerate() {
            let dim_seed = (mix64(group_seed ^ d as u64) >> 32) as u32;
            *o = u32_to_unit(nested_uniform_scramble(sobol(index, d), dim_seed));
        }
        out
    }
}

/// Sobol direction numbers of the first four dimensions, built by the Bratley-Fox recurrence
/// from Joe and Kuo's primitive polynomials and initial numbers (d = 2: s = 1, a = 0, m = 1;
/// d = 3: s = 2, a = 1, m = 1 3; d = 4: s = 3, a = 1, m = 1 3 1); dimension 1 is van der Corput.
const SOBOL_DIRECTIONS: [[u32; 32]; 4] =
    [van_der_corput_directions(), sobol_directions(1, 0, &[1]), sobol_directions(2, 1, &[1, 3]), sobol_directions(3, 1, &[1, 3, 1])];

const fn van_der_corput_directions() -> [u32; 32] {
    let mut v = [0u32; 32];
    let mut i = 0;
    while i < 32 {
        v[i] = 1 << (31 - i);
        i += 1;
    }
    v
}

/// Direction numbers v_1..v_32 (stored 0-based) for a primitive polynomial of degree `s` with
/// inner coefficients `a` and initial odd numbers `m`.
const fn sobol_directions(s: usize, a: u32, m: &[u32]) -> [u32; 32] {
    let mut v = [0u32; 32];
    let mut i = 0;
    while i < s {
        v[i] = m[i] << (31 - i);
        i += 1;
    }
    while i < 32 {
        let mut x = v[i - s] ^ (v[i - s] >> s);
        let mut k = 1;
        while k < s {
            if (a >> (s - 1 - k)) & 1 == 1 {
                x ^= v[i - k];
            }
            k += 1;
        }
        v[i] = x;
        i += 1;
    }
    v
}

/// The direction numbers XOR-combined per byte of the index: `SOBOL_BYTES[d][k][b]` is the
/// contribution of byte `k` of the index having the value `b`. A Sobol coordinate is then four
/// table reads instead of one step per set bit (shuffled indices have about 16 set bits).
static SOBOL_BYTES: [[[u32; 256]; 4]; 4] = sobol_byte_tables();

const fn sobol_byte_tables() -> [[[u32; 256]; 4]; 4] {
    let mut tables = [[[0u32; 256]; 4]; 4];
    let mut d = 0;
    while d < 4 {
        let mut k = 0;
        while k < 4 {
            let mut b = 0;
            while b < 256 {
                let mut x = 0;
                let mut bit = 0;
                while bit < 8 {
                    if (b >> bit) & 1 == 1 {
                        x ^= SOBOL_DIRECTIONS[d][8 * k + bit];
                    }
                    bit += 1;
                }
                tables[d][k][b] = x;
                b += 1;
            }
            k += 1;
        }
        d += 1;
    }
    tables
}

/// Coordinate `dim` of the Sobol point with this index.
#[inline]
fn sobol(index: u32, dim: usize) -> u32 {
    let t = &SOBOL_BYTES[dim];
    let b = index.to_le_bytes();
    t[0][b[0] as usize] ^ t[1][b[1] as usize] ^ t[2][b[2] as usize] ^ t[3][b[3] as usize]
}

/// The same coordinate one direction number per set bit: the definition, kept to check
/// the tables against.
#[cfg(test)]
fn sobol_by_bits(mut index: u32, dim: usize) -> u32 {
    let mut x = 0;
    while index != 0 {
        x ^= SOBOL_DIRECTIONS[dim][index.trailing_zeros() as usize];
        index &= index - 1;
    }
    x
}

/// Laine and Karras' hash: every step only carries information from low bits to high bits,
/// which on bit-reversed input is exactly a nested uniform (Owen) scramble.
#[inline]
fn laine_karras_permutation(mut x: u32, seed: u32) -> u32 {
    x = x.wrapping_add(seed);
    x ^= x.wrapping_mul(0x6c50_b47c);
    x ^= x.wrapping_mul(0xb82f_1e52);
    x ^= x.wrapping_mul(0xc7af_e638);
    x ^= x.wrapping_mul(0x8d22_f6e6);
    x
}

#[inline]
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

/// An orthonormal basis (t, b) completing the unit vector `n` to a right-handed frame
/// (t x b = n), branch-free apart from the sign; Duff et al., "Building an Orthonormal Basis,
/// Revisited" (JCGT 6(1), 2017).
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let bt = Vec3::new(b, sign + n.y * n.y * a, -n.y);
    (t, bt)
}

/// Shirley and Chiu's concentric map from the unit square to the unit disk: area-preserving
/// and low-distortion, so stratified input stays stratified on the disk.
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let a = 2.0 * u - Vec2::ONE;
    if a.x == 0.0 && a.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, phi) = if a.x.abs() > a.y.abs() { (a.x, FRAC_PI_4 * (a.y / a.x)) } else { (a.y, FRAC_PI_2 - FRAC_PI_4 * (a.x / a.y)) };
    let (s, c) = phi.sin_cos();
    Vec2::new(r * c, r * s)
}

/// A cosine-distributed direction about +Z (Malley's method: lift a uniform disk point);
/// its density in solid angle is [`cosine_hemisphere_pdf`].
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Solid-angle density of [`cosine_hemisphere`] for a direction with this cosine to the axis.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * (1.0 / PI)
}

/// Barycentric weights (of v0, v1, v2) of a uniformly distributed point on a triangle
/// (the square-root parameterisation; density 1/area).
#[inline]
pub fn uniform_triangle(u: Vec2) -> Vec3 {
    let su = u.x.sqrt();
    let b1 = su * (1.0 - u.y);
    let b2 = su * u.y;
    Vec3::new(1.0 - b1 - b2, b1, b2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniform_numbers_have_the_moments_of_u01() {
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        let mut bins = [0u32; 16];
        for i in 0..n {
            let x = PathSampler::new(7, i % 97, i / 97).uniform(i % 5) as f64;
            assert!((0.0..1.0).contains(&x));
            sum += x;
            sum2 += x * x;
            bins[(x * 16.0) as usize] += 1;
        }
        let mean = sum / n as f64;
        let var = sum2 / n as f64 - mean * mean;
        assert!((mean - 0.5).abs() < 0.005, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.002, "variance {var}");
        let expected = n as f64 / 16.0;
        let chi2: f64 = bins.iter().map(|&b| (b as f64 - expected).powi(2) / expected).sum();
        // 15 degrees of freedom: P(chi2 > 40) is about 5e-4.
        assert!(chi2 < 40.0, "chi2 {chi2} bins {bins:?}");
    }

    #[test]
    fn sobol_points_are_stratified_per_dimension_and_in_the_first_pair() {
        for pixel in 0..8 {
            for group in 0..3 {
                let s = |i: u32| PathSampler::new(3, pixel, i).sobol4(group);
                // Every 1D projection: 64 points, one per interval of 1/64.
                for d in 0..4 {
                    let mut seen = [false; 64];
                    for i in 0..64 {
                        let cell = (s(i)[d] * 64.0) as usize;
                        assert!(!seen[cell], "dim {d} cell {cell} hit twice");
                        seen[cell] = true;
                    }
                }
                // Dimensions 0 and 1 form a (0, 2)-sequence: 16 points, one per 4x4 cell.
                let mut seen = [false; 16];
                for i in 0..16 {
                    let p = s(i);
                    let cell = (p[0] * 4.0) as usize * 4 + (p[1] * 4.0) as usize;
                    assert!(!seen[cell], "2D cell {cell} hit twice");
                    seen[cell] = true;
                }
            }
        }
    }

    #[test]
    fn sobol_tables_match_the_definition() {
        for i in 0..5000u32 {
            let index = (mix64(i as u64) >> 32) as u32;
            for d in 0..4 {
                assert_eq!(sobol(index, d), sobol_by_bits(index, d));
            }
        }
        // The first points of dimension 2 are 0, 1/2, 3/4, 1/4 (as 32-bit fractions).
        let first: Vec<u32> = (0..4).map(|i| sobol(i, 1)).collect();
        assert_eq!(first, [0, 1 << 31, 3 << 30, 1 << 30]);
    }

    #[test]
    fn sobol_points_differ_between_pixels_and_groups() {
        let a = PathSampler::new(1, 0, 0).sobol4(0);
        assert_ne!(a, PathSampler::new(1, 1, 0).sobol4(0));
        assert_ne!(a, PathSampler::new(1, 0, 0).sobol4(1));
        assert_ne!(a, PathSampler::new(2, 0, 0).sobol4(0));
    }

    #[test]
    fn sobol_is_uniform_over_many_pixels() {
        // Unbiasedness needs each point, over the random scramble, to be uniform.
        let n = 50_000;
        let mut sums = [0.0f64; 4];
        let mut prod01 = 0.0f64;
        for p in 0..n {
            let x = PathSampler::new(11, p, 5).sobol4(2);
            for d in 0..4 {
                sums[d] += x[d] as f64;
            }
            prod01 += x[0] as f64 * x[1] as f64;
        }
        for s in sums {
            assert!((s / n as f64 - 0.5).abs() < 0.005, "mean {}", s / n as f64);
        }
        // Independent coordinates: E[x0 x1] = 1/4.
        assert!((prod01 / n as f64 - 0.25).abs() < 0.005);
    }

    #[test]
    fn basis_is_orthonormal_and_right_handed() {
        for i in 0..1000 {
            let s = PathSampler::new(0, i, 0);
            let n = Vec3::new(s.uniform(0) - 0.5, s.uniform(1) - 0.5, s.uniform(2) - 0.5).normalize();
            let n = if i == 0 {
                Vec3::NEG_Z
            } else if i == 1 {
                Vec3::Z
            } else {
                n
            };
            let (t, b) = orthonormal_basis(n);
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
            assert!(t.dot(b).abs() < 1e-5 && t.dot(n).abs() < 1e-5 && b.dot(n).abs() < 1e-5);
            assert!((t.cross(b) - n).length() < 1e-5);
        }
    }

    #[test]
    fn cosine_hemisphere_has_the_cosine_moments() {
        // E[cos] = 2/3 and E[cos^2] = 1/2 under p = cos/pi.
        let n = 100_000;
        let (mut c1, mut c2) = (0.0f64, 0.0f64);
        for i in 0..n {
            let s = PathSampler::new(5, 0, i);
            let d = cosine_hemisphere(Vec2::new(s.uniform(0), s.uniform(1)));
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
            c1 += d.z as f64;
            c2 += (d.z * d.z) as f64;
        }
        assert!((c1 / n as f64 - 2.0 / 3.0).abs() < 0.003);
        assert!((c2 / n as f64 - 0.5).abs() < 0.003);
    }

    #[test]
    fn triangle_samples_are_uniform() {
        // Uniform on the triangle: the mean is the centroid, and the fraction in the
        // sub-triangle cut off at b0 > 1/2 is its area, 1/4.
        let n = 100_000;
        let mut mean = Vec3::ZERO;
        let mut corner = 0;
        for i in 0..n {
            let s = PathSampler::new(9, 0, i);
            let b = uniform_triangle(Vec2::new(s.uniform(0), s.uniform(1)));
            assert!(b.min_element() >= 0.0 && (b.element_sum() - 1.0).abs() < 1e-5);
            mean += b;
            corner += (b.x > 0.5) as u32;
        }
        mean /= n as f32;
        assert!((mean - Vec3::splat(1.0 / 3.0)).abs().max_element() < 0.003, "{mean}");
        assert!((corner as f32 / n as f32 - 0.25).abs() < 0.005);
    }
}
