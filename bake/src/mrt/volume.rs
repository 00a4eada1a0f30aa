//! The light volume (§6.5, §7.3 steps 8-9): radiance probes in order-3 spherical harmonics (9
//! coefficients, `crate::sh`'s first three bands) on a uniform 4^3 grid in each block (spec
//! B15), which light the meshes a scene declares dynamic (`extras.relume.mrt.dynamic`:
//! characters, clutter) instead of mapping them onto the blocks' faces. A probe gathers what
//! its block's faces send, U_bvol b (9 x k_self per probe, from the implicit lights L_imp,
//! §6.5), and what arrives through the block's openings, U_rvol r: the paper leaves that term
//! undefined; here it is the volume of the response modes' implicit lightfields,
//! H_rlf V_g Sigma_g^-1 (spec B15), one operator per side face.
//!
//! Probes and their coefficients stand in the frame of the block's dictionary shape; a point
//! and normal of a turned block are turned into that frame before the probes are read.

use super::dictionary::Dictionary;
use super::level::{turn_direction, turn_point, undo};
use super::level_data::LevelData;
use super::{proxy, Face};
use glam::{DVec3, Vec3};

/// Probes per block edge.
pub const PROBES: usize = 4;
/// Probes per block.
pub const PROBE_COUNT: usize = PROBES * PROBES * PROBES;
/// Spherical-harmonic coefficients per probe (bands l <= 2).
pub const SH: usize = crate::sh::IRRADIANCE_COEFFICIENTS;
/// Rows of U_bvol and U_rvol: probe-major, coefficient-minor.
pub const ROWS: usize = PROBE_COUNT * SH;
/// The side faces through which light enters a block, in the order U_rvol is stored.
pub const SIDES: [Face; 4] = [Face::ALL[0], Face::ALL[1], Face::ALL[4], Face::ALL[5]];
/// How far outside a block (in its local coordinates) a dynamic vertex may stand and still be
/// lit by its probes: a vertex sunk a little into the floor is still in the room.
pub const OUTSIDE: f32 = 0.05;

/// Probe `i`'s point in the unit cube: cell centres, x fastest.
pub fn probe(i: usize) -> Vec3 {
    (Vec3::new((i % PROBES) as f32, (i / PROBES % PROBES) as f32, (i / (PROBES * PROBES)) as f32) + 0.5) / PROBES as f32
}

/// The index of side face `face` in [`SIDES`].
pub fn side(face: Face) -> Option<usize> {
    SIDES.iter().position(|f| *f == face)
}

/// The probes of one block read at local point `q` (the dictionary shape's frame): trilinear
/// between the nearest eight, clamped to the outermost.
pub fn interpolate(probes: &[[Vec3; SH]], q: Vec3) -> [Vec3; SH] {
    let top = (PROBES - 1) as f32;
    let t = (q * PROBES as f32 - 0.5).clamp(Vec3::ZERO, Vec3::splat(top));
    let lo = t.floor().min(Vec3::splat(top - 1.0));
    let f = t - lo;
    let mut out = [Vec3::ZERO; SH];
    for corner in 0..8 {
        let pick = |axis: usize| (corner >> axis) & 1;
        let w: f32 = (0..3).map(|a| if pick(a) == 1 { f[a] } else { 1.0 - f[a] }).product();
        let at = |a: usize| lo[a] as usize + pick(a);
        let index = at(0) + PROBES * (at(1) + PROBES * at(2));
        out.iter_mut().zip(&probes[index]).for_each(|(o, v)| *o += *v * w);
    }
    out
}

impl LevelData {
    /// §7.3 step 8: every block's probes (blocks x [`PROBE_COUNT`], each [`SH`] rgb
    /// coefficients of radiance, in its dictionary shape's frame): U_bvol b plus U_rvol r of
    /// every receiver at the block. Sums in f64, in the tables' order.
    pub fn volume(&self, dictionary: &Dictionary, b: &[Vec<Vec3>], r: &[Vec<Vec3>]) -> Vec<[Vec3; SH]> {
        let k_r = dictionary.interfaces.response_modes;
        (0..self.blocks.len())
            .flat_map(|block| (0..ROWS).map(move |row| (block, row)))
            .map(|(block, row)| {
                let own = &dictionary.blocks[self.blocks[block].shape as usize];
                let mut sum = [0.0f64; 3];
                let mut add = |w: f32, v: Vec3| (0..3).for_each(|c| sum[c] += w as f64 * v[c] as f64);
                b[block].iter().enumerate().for_each(|(m, v)| add(own.u_bvol[m * ROWS + row], *v));
                for (receiver, r) in self.receivers.iter().zip(r).filter(|(rc, _)| rc.block as usize == block) {
                    let u = &dictionary.interfaces.u_rvol[self.canonical_side(receiver)];
                    (0..k_r).for_each(|m| add(u[m * ROWS + row], r[m]));
                }
                Vec3::new(sum[0] as f32, sum[1] as f32, sum[2] as f32)
            })
            .collect::<Vec<Vec3>>()
            .chunks_exact(SH)
            .map(|c| std::array::from_fn(|i| c[i]))
            .collect()
    }

    /// The index in [`SIDES`] of the face a receiver's light enters through, in its block's
    /// dictionary shape's frame.
    pub fn canonical_side(&self, receiver: &super::level_data::LevelReceiver) -> usize {
        let turns = self.blocks[receiver.block as usize].turns;
        side(receiver.entry.turned(undo(turns))).expect("receivers enter through side faces")
    }

    /// §7.3 step 9: the indirect irradiance the volume `volume` gives a surface at world point
    /// `p` with world normal `n`: the block it stands in (or within [`OUTSIDE`] of), its probes
    /// read there, the normal carried into the block's frame as a covector (J^T n), clamped at
    /// zero (nine coefficients ring below zero facing away from a bright opening). Zero outside
    /// every block.
    pub fn volume_irradiance(&self, volume: &[[Vec3; SH]], p: Vec3, n: Vec3) -> Vec3 {
        let Some((block, q)) = self.locate(p) else { return Vec3::ZERO };
        let corners = self.corners[block].map(|c| c.as_dvec3());
        let local_normal = (proxy::jacobian(&corners, q.as_dvec3()).as_mat3().transpose() * n).normalize_or_zero();
        let turns = undo(self.blocks[block].turns);
        let probes = &volume[block * PROBE_COUNT..(block + 1) * PROBE_COUNT];
        crate::sh::irradiance(&interpolate(probes, turn_point(q.clamp(Vec3::ZERO, Vec3::ONE), turns)), turn_direction(local_normal, turns))
            .max(Vec3::ZERO)
    }

    /// The block `p` stands deepest in, within [`OUTSIDE`] of its cube (the first of equal
    /// depth, as the GPU takes it), and its local point.
    fn locate(&self, p: Vec3) -> Option<(usize, Vec3)> {
        let p = p.as_dvec3();
        let outside = OUTSIDE as f64;
        self.corners
            .iter()
            .enumerate()
            .filter_map(|(b, c)| {
                let c = c.map(|v| v.as_dvec3());
                let widen = outside * proxy::mean_edge(&c);
                let (lo, hi) = c.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| (lo.min(*v), hi.max(*v)));
                let inside = p.cmpge(lo - widen).all() && p.cmple(hi + widen).all();
                inside.then(|| proxy::local(&c, p)).flatten().map(|q| (b, q))
            })
            .filter(|(_, q)| proxy::depth(*q) >= -outside)
            .reduce(|best, next| if proxy::depth(next.1) > proxy::depth(best.1) { next } else { best })
            .map(|(b, q)| (b, q.as_vec3()))
    }
}

#[cfg(feature = "baking")]
pub use built::*;

#[cfg(feature = "baking")]
mod built {
    use super::*;
    use crate::mrt::block::{exit, BlockOperators};
    use nalgebra::DMatrix;
    use rayon::prelude::*;

    /// Directions per probe: a spherical Fibonacci set (equal areas, no seed).
    pub const RAYS: usize = 2048;

    fn direction(i: usize) -> Vec3 {
        let z = 1.0 - (2 * i + 1) as f64 / RAYS as f64;
        let phi = i as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let s = (1.0 - z * z).max(0.0).sqrt();
        Vec3::new((s * phi.cos()) as f32, (s * phi.sin()) as f32, z as f32)
    }

    /// A [`ROWS`] x `width` operator: each probe's [`RAYS`] rays leave the unit cube, `radiance`
    /// adds what each brings (`width` values: one per mode) into a row, and each is projected
    /// onto the nine functions (4 pi / RAYS per ray). Probes in parallel, each on its own.
    pub fn gather(width: usize, radiance: impl Fn(Face, Vec3, Vec3, &mut [f64]) + Sync) -> DMatrix<f64> {
        let probes: Vec<Vec<f64>> = (0..PROBE_COUNT)
            .into_par_iter()
            .map(|p| {
                let mut rows = vec![0.0f64; SH * width];
                let mut brought = vec![0.0f64; width];
                for i in 0..RAYS {
                    let d = direction(i);
                    let (face, point) = exit(probe(p), d);
                    brought.iter_mut().for_each(|v| *v = 0.0);
                    radiance(face, point, d, &mut brought);
                    let y = crate::sh::eval(d);
                    for (s, row) in rows.chunks_exact_mut(width).enumerate() {
                        let w = y[s] as f64 * 4.0 * std::f64::consts::PI / RAYS as f64;
                        row.iter_mut().zip(&brought).for_each(|(r, b)| *r += w * b);
                    }
                }
                rows
            })
            .collect();
        DMatrix::from_fn(ROWS, width, |row, m| probes[row / SH][(row % SH) * width + m])
    }

    /// U_bvol (§6.5): the radiance of the block's implicit lights, L_imp / pi where a probe's
    /// ray meets a present face (none through an opening: U_rvol brings that).
    pub fn own(block: &BlockOperators) -> DMatrix<f64> {
        gather(block.l_imp.ncols(), |face, point, _, row| {
            if let Some(slot) = block.samples.faces.iter().position(|f| *f == face).filter(|_| !block.shape.is_open(face)) {
                for (j, w) in block.samples.bilinear(slot, face.uv(point)) {
                    let scale = w as f64 / std::f64::consts::PI;
                    row.iter_mut().zip(block.l_imp.row(j).iter()).for_each(|(v, l)| *v += scale * l);
                }
            }
        })
    }
}
