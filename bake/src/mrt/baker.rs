//! A level's bake (§6.2-6.3): the scene mapped onto its block proxy (the light map with its
//! padded atlas), T_b->r by traversal, and the feedback solved (§7.3), from a dictionary made
//! (or read) before.

use super::dictionary::{self, Dictionary};
use super::evaluate::LevelTransfer;
use super::inverse::inverse;
use super::level_data::{k_max, LevelData, MAX_FEEDBACK};
use super::map::{map, Mapped};
use super::proxy::{dynamic_meshes, Proxy};
use crate::scene::Scene;
use nalgebra::DMatrix;
use rayon::prelude::*;
use std::ops::AddAssign;

/// The scene on the blocks it declares and the level's tables, made with `dictionary` to
/// `d_max` crossings.
pub fn bake_level(scene: &Scene, dictionary: &Dictionary, d_max: usize) -> Result<(Mapped, LevelData), String> {
    bake_on(scene, &Proxy::of(scene)?, &dynamic_meshes(scene)?, dictionary, d_max)
}

/// The scene on `proxy`'s blocks, the meshes `dynamic` (ascending) lit by the light volume,
/// and the level's tables, made with `dictionary` to `d_max` crossings.
pub fn bake_on(
    scene: &Scene,
    proxy: &Proxy,
    dynamic: &[usize],
    dictionary: &Dictionary,
    d_max: usize,
) -> Result<(Mapped, LevelData), String> {
    let level = proxy.level();
    let d = level.len() * k_max(dictionary);
    if d > MAX_FEEDBACK {
        return Err(format!(
            "{} blocks of {} modes couple {d} coefficients in the feedback, past {MAX_FEEDBACK}; use fewer blocks or --modes",
            level.len(),
            k_max(dictionary)
        ));
    }
    let mapped = map(scene, proxy, &level, dictionary.settings.samples_per_face, dynamic)?;
    let (operators, interfaces) = dictionary.operators();
    let transfer = LevelTransfer::new(&level, &operators, &interfaces, d_max)?;
    let mut data = transfer.level_data(dictionary::checksum(dictionary), &mapped);
    data.feedback = solve_feedback(&data, dictionary)?;
    data.corners = proxy.corners.iter().map(|c| c.map(|p| p.as_vec3())).collect();
    data.dynamic = dynamic.iter().map(|&m| m as u32).collect();
    Ok((mapped, data))
}

/// (I - K)^-1 per colour channel (`LevelData::feedback`). K's column j is what the unit
/// coefficient j sends back after one bounce: the coefficients of rho (U_b b + U_r r). The
/// feedback of §7.3 iterates b <- b0 + K b from frame to frame; its fixed point is this
/// inverse times b0, every bounce at once.
fn solve_feedback(level: &LevelData, dictionary: &Dictionary) -> Result<Vec<f32>, String> {
    let d = level.blocks.len() * k_max(dictionary);
    let mut feedback = vec![0f32; 3 * d * d];
    // Each channel's result kept, so that the error reported is the first channel's whichever
    // thread fails first.
    let solved: Vec<Result<(), String>> = feedback
        .par_chunks_mut((d * d).max(1))
        .enumerate()
        .map(|(c, out)| {
            let mut k = bounce_matrix(level, dictionary, c);
            let radius = spectral_radius(&k);
            if radius >= 1.0 {
                return Err(format!(
                    "the level's feedback diverges: one bounce returns {radius:.3} of some light (above 1; an albedo near 1, or too few modes)"
                ));
            }
            k.neg_mut();
            (0..d).for_each(|i| k[(i, i)] += 1.0);
            let inverse = inverse(k).ok_or("the level's feedback has no fixed point (I - K is singular: an albedo of 1 in a closed level?)")?;
            out.iter_mut().zip(inverse.iter()).for_each(|(o, &v)| *o = v as f32);
            Ok(())
        })
        .collect();
    solved.into_iter().collect::<Result<(), String>>()?;
    Ok(feedback)
}

/// K for colour channel `c`, block by block: K[a, a] = T_a rho U_b (the block's own bounce)
/// plus, for each receiver at block a and each of its sources b, T_a rho P U_r M (the light
/// that came from b), P the receiver's rows on a's samples and M its T_b->r.
fn bounce_matrix(level: &LevelData, dictionary: &Dictionary, c: usize) -> DMatrix<f64> {
    let k_max = k_max(dictionary);
    let d = level.blocks.len() * k_max;
    let mut k = DMatrix::zeros(d, d);
    let albedo = |s: u32| level.samples[s as usize].albedo[c] as f64;
    let mut row_of = vec![u32::MAX; level.samples.len()];
    for block in &level.blocks {
        block.rows.iter().enumerate().for_each(|(j, &s)| row_of[s as usize] = j as u32);
    }
    let operators = |block: usize| {
        let ops = &dictionary.blocks[level.blocks[block].shape as usize];
        let t = DMatrix::from_iterator(ops.modes, ops.samples, ops.t_d_b.iter().map(|&v| v as f64));
        (ops, t)
    };
    for (a, block) in level.blocks.iter().enumerate() {
        let (ops, t) = operators(a);
        let u_b = DMatrix::from_iterator(ops.samples, ops.modes, ops.u_b.iter().map(|&v| v as f64));
        let rho_u = DMatrix::from_fn(ops.samples, ops.modes, |j, m| albedo(block.rows[j]) * u_b[(j, m)]);
        k.view_mut((a * k_max, a * k_max), (ops.modes, ops.modes)).add_assign(&(&t * rho_u));
    }
    let i = &dictionary.interfaces;
    let (k_r, n_r) = (i.response_modes, i.u_r.len() / i.response_modes);
    let u_r = DMatrix::from_iterator(n_r, k_r, i.u_r.iter().map(|&v| v as f64));
    for receiver in &level.receivers {
        let a = receiver.block as usize;
        let (ops, t) = operators(a);
        // T_a rho P U_r: k x k_r.
        let mut landed = DMatrix::zeros(ops.samples, k_r);
        for (row, &s) in receiver.rows.iter().enumerate().filter(|(_, s)| **s != super::level_data::NONE) {
            let j = row_of[s as usize] as usize;
            for m in 0..k_r {
                landed[(j, m)] += albedo(s) * u_r[(row, m)];
            }
        }
        let arrives = &t * landed;
        for (source, matrix) in &receiver.sources {
            let b = *source as usize;
            let k_b = dictionary.blocks[level.blocks[b].shape as usize].modes;
            let m = DMatrix::from_iterator(k_r, k_b, matrix.iter().map(|&v| v as f64));
            k.view_mut((a * k_max, b * k_max), (ops.modes, k_b)).add_assign(&(&arrives * m));
        }
    }
    k
}

/// An estimate of K's spectral radius: the geometric mean growth of K^n x per step over steps
/// 64 to 128 (after the transient; a mean, not one step's ratio, so that a complex or negative
/// pair of largest eigenvalues, whose step ratios oscillate, still shows).
fn spectral_radius(k: &DMatrix<f64>) -> f64 {
    const SETTLE: usize = 64;
    let mut x = nalgebra::DVector::from_fn(k.nrows(), |i, _| 1.0 + (i % 7) as f64 / 7.0);
    x /= x.norm();
    let mut log_growth = 0.0;
    for step in 0..2 * SETTLE {
        let next = k * &x;
        let norm = next.norm();
        if norm == 0.0 {
            return 0.0;
        }
        if step >= SETTLE {
            log_growth += norm.ln();
        }
        x = next / norm;
    }
    (log_growth / SETTLE as f64).exp()
}
