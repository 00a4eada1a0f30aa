//! One block's reduced direct-to-indirect transfer (§4): the one-bounce operator F gathered
//! on the block's samples, the light prior L_d of sphere lights in and beyond the block, and
//! the operators U_b, T_d->b and L_imp, with the prior enriched as App. A says.
//!
//! Quantities (spec B1): l_d is the direct radiosity's irradiance part, rho * E_direct (the
//! prior's albedo is 1); F is albedo-free: a cosine-weighted gather of l_d, read bilinearly on
//! the face a ray hits, 0 through an open face. The block is convex, so a ray from a sample
//! leaves it through exactly one face: no ray tracing beyond a ray-box exit.

use super::dictionary::BlockData;
use super::svd::{self, Svd};
use super::{BlockSettings, Face, PriorLattice, Samples, Shape};
use crate::sampling::{cosine_hemisphere, orthonormal_basis, PathSampler};
use crate::shards::{self, Items, Role};
use crate::work::with_threads;
use glam::{Vec2, Vec3};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::ops::Range;

/// One block's operators (n samples, k modes); matrices are nalgebra's, column-major.
pub struct BlockOperators {
    pub shape: Shape,
    pub samples: Samples,
    /// U_b (n x k): the indirect light basis, columns scaled by Sigma_m (eq. 3).
    pub u_b: DMatrix<f64>,
    /// T_d->b (k x n): direct light to coefficients b (eq. 3).
    pub t_d_b: DMatrix<f64>,
    /// L_imp (n x k): the implicit lighting, F L_imp = U_b (§4.1).
    pub l_imp: DMatrix<f64>,
    /// Sigma_m: the singular values of M = F P S (those above the rank cut).
    pub m_sigma: Vec<f64>,
    /// Sigma_d: the singular values of the (unenriched) prior L_d (above the rank cut).
    pub prior_sigma: Vec<f64>,
    /// U_bvol (volume::ROWS x k): the light volume's probes for coefficients b (§6.5); empty
    /// from `reduce` alone, gathered by `build`.
    pub u_bvol: DMatrix<f64>,
}

impl BlockOperators {
    /// U_b T_d->b l_d: the block's own indirect light for direct light `l_d`.
    pub fn indirect(&self, l_d: &DVector<f64>) -> DVector<f64> {
        &self.u_b * (&self.t_d_b * l_d)
    }

    /// The operators as the dictionary stores them (f32, column-major).
    pub fn data(&self) -> BlockData {
        let f32s = |m: &DMatrix<f64>| m.iter().map(|&v| v as f32).collect();
        BlockData {
            shape: self.shape,
            samples: self.samples.len(),
            modes: self.u_b.ncols(),
            u_b: f32s(&self.u_b),
            t_d_b: f32s(&self.t_d_b),
            l_imp: f32s(&self.l_imp),
            u_bvol: f32s(&self.u_bvol),
        }
    }
}

/// The relative error of the block's own indirect light `U_b T_d->b l_d` against the
/// brute-force bounce `F l_d`, over the direct light of unit sphere lights at `lights`.
pub fn transfer_error(ops: &BlockOperators, f: &DMatrix<f64>, lights: &[Vec3], radius: f32) -> f64 {
    let (mut squared, mut total) = (0.0, 0.0);
    for &light in lights {
        let direct = direct_irradiance(ops.shape, &ops.samples, light, radius);
        let truth = f * &direct;
        squared += (ops.indirect(&direct) - &truth).norm_squared();
        total += truth.norm_squared();
    }
    (squared / total).sqrt()
}

/// The block's operators: F, the prior, the reduction (with enrichment when asked) and the
/// light volume's U_bvol.
pub fn build(shape: Shape, settings: &BlockSettings) -> BlockOperators {
    let samples = Samples::new(shape, settings.samples_per_face);
    let f = with_threads(settings.threads, || gather(shape, &samples, settings.gather_rays, settings.seed));
    reduced(shape, samples, &f, settings)
}

/// A shape's operators from its gathered F.
pub fn reduced(shape: Shape, samples: Samples, f: &DMatrix<f64>, settings: &BlockSettings) -> BlockOperators {
    let l_d = prior(shape, &samples, (settings.prior_grid, settings.prior_lattice), settings.light_radius);
    let mut ops = reduce(shape, samples, f, &l_d, settings);
    ops.u_bvol = with_threads(settings.threads, || super::volume::own(&ops));
    ops
}

/// F (n x n): row i averages, over cosine-weighted directions from sample i, the bilinear
/// weights of the samples around where the ray leaves the block (none through an open face).
pub fn gather(shape: Shape, samples: &Samples, rays: u32, seed: u64) -> DMatrix<f64> {
    let n = samples.len();
    DMatrix::from_row_slice(n, n, &f_rows(shape, samples, 0..n, rays, seed))
}

/// Rows `range` of F, one after another.
fn f_rows(shape: Shape, samples: &Samples, range: Range<usize>, rays: u32, seed: u64) -> Vec<f64> {
    let rows = gather_rows(samples, range, rays, seed, samples.len(), |face, point, _, row| {
        if let Some(slot) = samples.faces.iter().position(|f| *f == face).filter(|_| !shape.is_open(face)) {
            for (j, w) in samples.bilinear(slot, face.uv(point)) {
                row[j] += w as f64;
            }
        }
    });
    rows
}

/// A shape's F, its rows a gather of the bake (`role`: the bake's in a sharded one, `shards`;
/// `followed`: another shape's gather follows), handed to `take` once made or read.
pub fn gather_shape(
    shape: Shape,
    samples: &Samples,
    settings: &BlockSettings,
    role: Option<&Role>,
    followed: bool,
    take: impl FnOnce(DMatrix<f64>) -> Result<(), String>,
) -> Result<(), String> {
    let n = samples.len();
    let items = Items::whole::<f64>(n as u64, n).followed(followed);
    let make = |_, range: Range<u64>| {
        let rows = range.start as usize..range.end as usize;
        Ok(with_threads(settings.threads, || f_rows(shape, samples, rows, settings.gather_rays, settings.seed)))
    };
    let mut take = Some(take);
    shards::gather(role, &items, make, |rows: Vec<f64>| take.take().map_or(Ok(()), |take| take(DMatrix::from_row_slice(n, n, &rows))))
}

/// For each sample of `range` (in parallel; each row on its own, so the result does not depend
/// on the thread count) `rays` cosine-distributed directions about its normal: `visit(face,
/// point, direction, row)` adds what the ray brings, where it leaves the block, into the
/// sample's row of `width` values; the rows, averaged over the rays, one after another.
pub(super) fn gather_rows(
    samples: &Samples,
    range: Range<usize>,
    rays: u32,
    seed: u64,
    width: usize,
    visit: impl Fn(Face, Vec3, Vec3, &mut [f64]) + Sync,
) -> Vec<f64> {
    let mut rows = vec![0.0f64; range.len() * width];
    rows.par_chunks_mut(width.max(1)).zip(range.into_par_iter()).for_each(|(row, i)| {
        let (_, origin, normal) = samples.sample(i);
        let (t, b) = orthonormal_basis(normal);
        for r in 0..rays {
            let u = PathSampler::new(seed, i as u32, r).sobol4(0);
            let local = cosine_hemisphere(Vec2::new(u[0], u[1]));
            let direction = t * local.x + b * local.y + normal * local.z;
            let (face, point) = exit(origin, direction);
            visit(face, point, direction, row);
        }
        row.iter_mut().for_each(|v| *v /= rays as f64);
    });
    rows
}

/// Where a ray from inside the unit cube leaves it: the face and the point.
pub(super) fn exit(origin: Vec3, direction: Vec3) -> (Face, Vec3) {
    let mut best = (f32::INFINITY, Face::ALL[0]);
    for axis in 0..3 {
        let d = direction[axis];
        if d.abs() > 1e-12 {
            let positive = d > 0.0;
            let t = ((positive as u32 as f32) - origin[axis]) / d;
            if t >= 0.0 && t < best.0 {
                best = (t, Face { axis, positive });
            }
        }
    }
    let (t, face) = best;
    let mut point = origin + direction * t;
    point[face.axis] = face.positive as u32 as f32;
    (face, point.clamp(Vec3::ZERO, Vec3::ONE))
}

/// L_d (n x m): the direct irradiance of unit sphere lights on a grid^3 `lattice` in the block
/// and in the cube beyond each open face (spec B3), seen through the opening.
pub fn prior(shape: Shape, samples: &Samples, (grid, lattice): (usize, PriorLattice), radius: f32) -> DMatrix<f64> {
    let at = |i: usize| lattice.coordinate(i, grid);
    let lattice: Vec<Vec3> = (0..grid * grid * grid).map(|c| Vec3::new(at(c % grid), at(c / grid % grid), at(c / grid / grid))).collect();
    let mut lights: Vec<Vec3> = lattice.clone();
    for face in shape.open_faces() {
        lights.extend(lattice.iter().map(|p| *p - face.inward()));
    }
    let columns: Vec<DVector<f64>> = lights.iter().map(|&light| direct_irradiance(shape, samples, light, radius)).collect();
    DMatrix::from_columns(&columns)
}

/// The irradiance each sample receives from a unit-intensity sphere light of `radius` at
/// `light` (cos / r^2, r at least the radius), visible where the light is in the block or its
/// line of sight crosses an open face into the cube beyond it.
pub fn direct_irradiance(shape: Shape, samples: &Samples, light: Vec3, radius: f32) -> DVector<f64> {
    DVector::from_iterator(
        samples.len(),
        (0..samples.len()).map(|i| {
            let (_, x, n) = samples.sample(i);
            let to = light - x;
            let r = to.length().max(radius);
            let cos = n.dot(to) / to.length().max(1e-9);
            if cos <= 0.0 || !visible(shape, x, light) {
                return 0.0;
            }
            (cos / (r * r)) as f64
        }),
    )
}

fn visible(shape: Shape, x: Vec3, light: Vec3) -> bool {
    if light.cmpge(Vec3::ZERO).all() && light.cmple(Vec3::ONE).all() {
        return true;
    }
    shape.open_faces().into_iter().any(|face| {
        let plane = face.positive as u32 as f32;
        let (a, b) = (x[face.axis], light[face.axis]);
        if (a - plane) * (b - plane) > 0.0 || (a - b).abs() < 1e-9 {
            return false;
        }
        let crossing = x + (light - x) * ((plane - a) / (b - a));
        let uv = face.uv(crossing);
        (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y)
    })
}

/// U_b, T_d->b and L_imp from F and L_d (eq. 2-3), after App. A's enrichment when asked.
pub fn reduce(shape: Shape, samples: Samples, f: &DMatrix<f64>, l_d: &DMatrix<f64>, settings: &BlockSettings) -> BlockOperators {
    let prior_svd = svd::thin(l_d);
    let (mut p, mut s) = leading(&prior_svd, settings.prior_modes);
    let mut reduced = from_prior(f, &p, &s, settings.modes);
    if settings.enrich {
        (p, s) = enriched(&p, &s, &reduced.0, &samples, settings.prior_modes);
        reduced = from_prior(f, &p, &s, settings.modes);
    }
    let (u_b, t_d_b, l_imp, m_sigma) = reduced;
    BlockOperators { shape, samples, u_b, t_d_b, l_imp, m_sigma, prior_sigma: prior_svd.sigma, u_bvol: DMatrix::zeros(0, 0) }
}

/// P (the first `k` left singular vectors) and S (their singular values).
fn leading(svd: &Svd, k: usize) -> (DMatrix<f64>, Vec<f64>) {
    let k = k.min(svd.sigma.len());
    (svd.u.columns(0, k).into_owned(), svd.sigma[..k].to_vec())
}

/// (U_b, T_d->b, L_imp, Sigma_m) of the prior P, S: M = F P S = U_m Sigma_m V_m^T (eq. 2).
fn from_prior(f: &DMatrix<f64>, p: &DMatrix<f64>, s: &[f64], modes: usize) -> (DMatrix<f64>, DMatrix<f64>, DMatrix<f64>, Vec<f64>) {
    let s_diag = DMatrix::from_diagonal(&DVector::from_column_slice(s));
    let ps = p * &s_diag;
    let m = f * &ps;
    let m_svd = svd::thin(&m);
    let k = modes.min(m_svd.sigma.len());
    let v = m_svd.v.columns(0, k).into_owned();
    let sigma_k = DMatrix::from_diagonal(&DVector::from_column_slice(&m_svd.sigma[..k]));
    let u_b = m_svd.u.columns(0, k) * sigma_k;
    let s_inverse = DMatrix::from_diagonal(&DVector::from_iterator(s.len(), s.iter().map(|x| 1.0 / x)));
    let t_d_b = v.transpose() * s_inverse * p.transpose();
    let l_imp = ps * v;
    (u_b, t_d_b, l_imp, m_svd.sigma)
}

/// App. A (spec B4): the SVD of [PS, C, U_b], each block scaled to unit Frobenius norm (C: one
/// indicator column per present face); the new P and S are its leading `k` vectors and values.
fn enriched(p: &DMatrix<f64>, s: &[f64], u_b: &DMatrix<f64>, samples: &Samples, k: usize) -> (DMatrix<f64>, Vec<f64>) {
    let ps = p * DMatrix::from_diagonal(&DVector::from_column_slice(s));
    let per_face = samples.grid * samples.grid;
    let c = DMatrix::from_fn(samples.len(), samples.faces.len(), |i, face| (i / per_face == face) as u8 as f64);
    let unit = |m: DMatrix<f64>| {
        let norm = m.norm();
        m / norm
    };
    leading(&svd::thin(&svd::side_by_side(&[unit(ps), unit(c), unit(u_b.clone())])), k)
}
