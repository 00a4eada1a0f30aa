//! A level's bake (§6.2-6.3): the scene mapped onto its block proxy (the light map with its
//! padded atlas), T_b->r by traversal, and the feedback solved (§7.3), from a dictionary made
//! (or read) before.

use super::dictionary::{self, Dictionary};
use super::evaluate::LevelTransfer;
use super::level_data::{k_max, LevelData};
use super::map::{map, Mapped};
use super::proxy::Proxy;
use crate::scene::Scene;
use glam::Vec3;
use nalgebra::DMatrix;
use rayon::prelude::*;

/// The scene on its blocks and the level's tables, made with `dictionary` to `d_max` crossings.
pub fn bake_level(scene: &Scene, dictionary: &Dictionary, d_max: usize) -> Result<(Mapped, LevelData), String> {
    let proxy = Proxy::of(scene)?;
    let level = proxy.level();
    let mapped = map(scene, &proxy, &level, dictionary.settings.samples_per_face)?;
    let (operators, interfaces) = dictionary.operators();
    let transfer = LevelTransfer::new(&level, &operators, &interfaces, d_max)?;
    let mut data = transfer.level_data(dictionary::checksum(dictionary), &mapped);
    data.feedback = solve_feedback(&data, dictionary)?;
    Ok((mapped, data))
}

/// (I - K)^-1 per colour channel (`LevelData::feedback`). K's column j is what the unit
/// coefficient j sends back after one bounce: the coefficients of rho (U_b b + U_r r). The
/// feedback of §7.3 iterates b <- b0 + K b from frame to frame; its fixed point is this
/// inverse times b0, every bounce at once.
fn solve_feedback(level: &LevelData, dictionary: &Dictionary) -> Result<Vec<f32>, String> {
    let k_max = k_max(dictionary);
    let d = level.blocks.len() * k_max;
    let modes: Vec<usize> = level.blocks.iter().map(|b| dictionary.blocks[b.shape as usize].modes).collect();
    let columns: Vec<Vec<Vec3>> = (0..d)
        .into_par_iter()
        .map(|j| {
            let (block, mode) = (j / k_max, j % k_max);
            let unit: Vec<Vec<Vec3>> = modes
                .iter()
                .enumerate()
                .map(|(b, &k)| (0..k).map(|m| Vec3::splat(((b, m) == (block, mode)) as u32 as f32)).collect())
                .collect();
            if mode >= modes[block] {
                return vec![Vec3::ZERO; d];
            }
            let r = level.received(dictionary, &unit);
            let e = level.response(dictionary, &unit, &r);
            let light: Vec<Vec3> = e.iter().zip(&level.samples).map(|(e, s)| *e * s.albedo).collect();
            let back = level.coefficients(dictionary, &light);
            back.iter().flat_map(|b| (0..k_max).map(move |m| b.get(m).copied().unwrap_or(Vec3::ZERO))).collect()
        })
        .collect();
    let mut out = Vec::with_capacity(3 * d * d);
    for c in 0..3 {
        let k = DMatrix::from_fn(d, d, |i, j| columns[j][i][c] as f64);
        let radius = spectral_radius(&k);
        if radius >= 1.0 {
            return Err(format!(
                "the level's feedback diverges: one bounce returns {radius:.3} of some light (above 1; an albedo near 1, or too few modes)"
            ));
        }
        let inverse = (DMatrix::identity(d, d) - k)
            .try_inverse()
            .filter(|m| m.iter().all(|v| v.is_finite()))
            .ok_or("the level's feedback has no fixed point (I - K is singular: an albedo of 1 in a closed level?)")?;
        out.extend(inverse.iter().map(|&v| v as f32));
    }
    Ok(out)
}

/// An estimate of K's largest absolute eigenvalue: the growth of K^n x over 64 steps.
fn spectral_radius(k: &DMatrix<f64>) -> f64 {
    let mut x = nalgebra::DVector::from_fn(k.nrows(), |i, _| 1.0 + (i % 7) as f64 / 7.0);
    let mut growth = 0.0;
    for _ in 0..64 {
        let next = k * &x;
        let norm = next.norm();
        if norm == 0.0 {
            return 0.0;
        }
        growth = norm / x.norm();
        x = next / norm;
    }
    growth
}
