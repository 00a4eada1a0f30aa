//! Transfer between blocks (§5.1): light leaving a block through an open face is a lightfield
//! on that face, kept only as coefficients in a reduced basis H_rlf (the SVD of the implicit
//! lights' lightfields at every interface of the dictionary). R_b->rlf takes a block's b there;
//! R_ahead / R_left / R_right carry a lightfield across an empty block to its opposite or side
//! faces; T_rlf->r and U_r turn an arriving lightfield into the receiving block's response.
//!
//! Frames (spec B10): an interface's frame has `n` along the light's travel, `up` +y and
//! `right` = up x n, its origin at the face's corner, so the light leaving one block and
//! entering the next reads the same in both. Directions are cells of Shirley and Chiu's
//! square lifted by Malley's method (spec B7): equal cells hold equal projected solid angle.
//! Radiance across an interface is the source's direct radiosity over pi (spec B6): bounces in
//! the receiver come through the feedback.

use super::block::{exit, gather_rows, BlockOperators};
use super::level::{target, Turn};
use super::svd;
use super::volume;
pub use super::InterfaceSettings;
use super::{Face, Samples};
use crate::sampling::concentric_disk;
use glam::{Vec2, Vec3};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};

/// Where a face of the unit cube stands for light travelling along `n` through it.
#[derive(Clone, Copy, Debug)]
struct Frame {
    origin: Vec3,
    right: Vec3,
    up: Vec3,
    n: Vec3,
}

impl Frame {
    fn new(face: Face, n: Vec3) -> Frame {
        let up = Vec3::Y;
        let right = up.cross(n);
        Frame { origin: face.point(Vec2::splat(0.5)) - 0.5 * (right + up), right, up, n }
    }

    fn point(&self, local: Vec2) -> Vec3 {
        self.origin + self.right * local.x + self.up * local.y
    }

    fn local_point(&self, p: Vec3) -> Vec2 {
        Vec2::new((p - self.origin).dot(self.right), (p - self.origin).dot(self.up))
    }

    fn direction(&self, local: Vec3) -> Vec3 {
        self.right * local.x + self.up * local.y + self.n * local.z
    }

    fn local_direction(&self, d: Vec3) -> Vec3 {
        Vec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.n))
    }
}

/// The direction light travels when it leaves a block through `face`.
fn outward(face: Face) -> Vec3 {
    -face.inward()
}

/// Rows of a lightfield: positions^2 x directions^2 cells.
#[derive(Clone, Copy, Debug)]
struct Cells {
    positions: usize,
    directions: usize,
}

impl Cells {
    fn len(&self) -> usize {
        self.positions * self.positions * self.directions * self.directions
    }

    /// The row of the cell holding `local` (a point of the face) and `direction` (local, z > 0).
    fn row(&self, local: Vec2, direction: Vec3) -> usize {
        let cell = |t: f32, count: usize| ((t * count as f32) as usize).min(count - 1);
        let square = disk_to_square(Vec2::new(direction.x, direction.y));
        let (ps, pt) = (cell(local.x, self.positions), cell(local.y, self.positions));
        let (ds, dt) = (cell(square.x, self.directions), cell(square.y, self.directions));
        ((pt * self.positions + ps) * self.directions + dt) * self.directions + ds
    }

    /// The `sub`-th of `supersamples`^2 (point, local direction) of row `row`.
    fn sample(&self, row: usize, sub: usize, supersamples: usize) -> (Vec2, Vec3) {
        let (d, p) = (row % (self.directions * self.directions), row / (self.directions * self.directions));
        let point = (Vec2::new((p % self.positions) as f32, (p / self.positions) as f32) + 0.5) / self.positions as f32;
        let jitter = (Vec2::new((sub % supersamples) as f32, (sub / supersamples) as f32) + 0.5) / supersamples as f32;
        let square = (Vec2::new((d % self.directions) as f32, (d / self.directions) as f32) + jitter) / self.directions as f32;
        let disk = concentric_disk(square);
        (point, Vec3::new(disk.x, disk.y, (1.0 - disk.length_squared()).max(0.0).sqrt()))
    }
}

/// The inverse of Shirley and Chiu's concentric map: a point of the unit disk to the square.
fn disk_to_square(p: Vec2) -> Vec2 {
    let r = p.length();
    if r == 0.0 {
        return Vec2::splat(0.5);
    }
    let (a, b) = if p.x.abs() >= p.y.abs() {
        let a = r.copysign(p.x);
        let phi = if p.x >= 0.0 { p.y.atan2(p.x) } else { (-p.y).atan2(-p.x) };
        (a, a * phi / FRAC_PI_4)
    } else {
        let b = r.copysign(p.y);
        let phi = if p.y >= 0.0 { p.y.atan2(p.x) } else { (-p.y).atan2(-p.x) };
        (b * (FRAC_PI_2 - phi) / FRAC_PI_4, b)
    };
    Vec2::new((a + 1.0) * 0.5, (b + 1.0) * 0.5)
}

/// The canonical receiving interface: light enters through -z travelling +z.
const ENTRY: Face = Face { axis: 2, positive: false };

/// The interface operators of a dictionary (§5.1).
pub struct Interfaces {
    /// R_b->rlf per (block index, open face).
    pub from_blocks: Vec<((usize, Face), DMatrix<f64>)>,
    /// R_ahead, R_left, R_right (k_rlf x k_rlf).
    pub turns: [(Turn, DMatrix<f64>); 3],
    /// U_r (canonical receiver's samples x k_r) and T_rlf->r (k_r x k_rlf).
    pub u_r: DMatrix<f64>,
    pub t_rlf_r: DMatrix<f64>,
    /// The canonical receiver's samples (the unit cube open at -z only).
    pub receiver: Samples,
    /// U_rvol per side face (`volume::SIDES` order): the light volume's probes for response
    /// coefficients r arriving through that face (volume::ROWS x k_r).
    pub u_rvol: Vec<DMatrix<f64>>,
}

impl Interfaces {
    /// R_b->rlf of block `block` through its open face `face`.
    pub fn from_block(&self, block: usize, face: Face) -> Option<&DMatrix<f64>> {
        self.from_blocks.iter().find(|(key, _)| *key == (block, face)).map(|(_, r)| r)
    }

    pub fn turn(&self, turn: Turn) -> &DMatrix<f64> {
        &self.turns.iter().find(|(t, _)| *t == turn).expect("every turn").1
    }

    /// The canonical receiver's indirect light for arriving coefficients `c`: U_r T_rlf->r c.
    pub fn response(&self, c: &DVector<f64>) -> DVector<f64> {
        &self.u_r * (&self.t_rlf_r * c)
    }
}

/// The interface operators of `blocks` (each block's own operators, its open faces the
/// dictionary's interfaces).
pub fn build(blocks: &[BlockOperators], settings: &InterfaceSettings) -> Interfaces {
    let cells = Cells { positions: settings.positions, directions: settings.directions };
    let slots: Vec<(usize, Face)> =
        blocks.iter().enumerate().flat_map(|(b, ops)| ops.shape.open_faces().into_iter().map(move |f| (b, f))).collect();
    let lightfields: Vec<DMatrix<f64>> = slots.iter().map(|&(b, face)| leaving(&blocks[b], face, cells, settings.supersamples)).collect();
    let h_svd = svd::thin(&svd::side_by_side(&lightfields));
    let k = settings.lightfield_modes.min(h_svd.sigma.len());
    let basis = h_svd.u.columns(0, k).into_owned();
    let sigma = h_svd.sigma[..k].to_vec();
    let project = |h: &DMatrix<f64>| inverse_diagonal(&sigma) * basis.transpose() * h;
    let from_blocks = slots.iter().zip(&lightfields).map(|(slot, h)| (*slot, project(h))).collect();
    let h_rlf = &basis * DMatrix::from_diagonal(&DVector::from_column_slice(&sigma));
    let turns = [Turn::Ahead, Turn::Left, Turn::Right].map(|turn| (turn, project(&propagate(&h_rlf, cells, turn, settings.supersamples))));
    let receiver = super::dictionary::receiver(blocks.first().map_or(16, |b| b.samples.grid));
    let g = respond(&receiver, &h_rlf, cells, settings);
    let g_svd = svd::thin(&g);
    let k_r = settings.response_modes.min(g_svd.sigma.len());
    let u_r = g_svd.u.columns(0, k_r).into_owned();
    let t_rlf_r = DMatrix::from_diagonal(&DVector::from_column_slice(&g_svd.sigma[..k_r])) * g_svd.v.columns(0, k_r).transpose();
    // The response modes' implicit lightfields: the coefficients c with T_rlf->r c = r (spec B15).
    let implicit = g_svd.v.columns(0, k_r) * inverse_diagonal(&g_svd.sigma[..k_r]);
    let u_rvol = volume::SIDES.iter().map(|&face| arriving_volume(&h_rlf, cells, face) * &implicit).collect();
    Interfaces { from_blocks, turns, u_r, t_rlf_r, receiver, u_rvol }
}

fn inverse_diagonal(sigma: &[f64]) -> DMatrix<f64> {
    DMatrix::from_diagonal(&DVector::from_iterator(sigma.len(), sigma.iter().map(|s| 1.0 / s)))
}

/// The lightfield (rows: cells; columns: the block's implicit lights) leaving `block` through
/// its open face `face`: each cell traced back into the block, L_imp / pi where it lands on a
/// present face, 0 where it leaves through another opening.
fn leaving(block: &BlockOperators, face: Face, cells: Cells, supersamples: usize) -> DMatrix<f64> {
    let frame = Frame::new(face, outward(face));
    let k = block.l_imp.ncols();
    let subs = supersamples * supersamples;
    let rows: Vec<Vec<f64>> = (0..cells.len())
        .into_par_iter()
        .map(|row| {
            let mut values = vec![0.0f64; k];
            for sub in 0..subs {
                let (local, direction) = cells.sample(row, sub, supersamples);
                let (hit, point) = exit(frame.point(local), -frame.direction(direction));
                if let Some(slot) = block.samples.faces.iter().position(|f| *f == hit).filter(|_| !block.shape.is_open(hit)) {
                    for (j, w) in block.samples.bilinear(slot, hit.uv(point)) {
                        values.iter_mut().zip(block.l_imp.row(j).iter()).for_each(|(v, l)| *v += w as f64 * l);
                    }
                }
            }
            values.iter_mut().for_each(|v| *v /= subs as f64 * std::f64::consts::PI);
            values
        })
        .collect();
    DMatrix::from_fn(cells.len(), k, |r, c| rows[r][c])
}

/// Prop_turn H: the lightfield leaving an empty block through the face `turn` leads to, from
/// the lightfield `h` entering it through the canonical entry: each cell traced back across
/// the block, `h` where it crosses the entry, 0 where it came in through another face.
fn propagate(h: &DMatrix<f64>, cells: Cells, turn: Turn, supersamples: usize) -> DMatrix<f64> {
    let (entry, out) = (Frame::new(ENTRY, ENTRY.inward()), target(ENTRY, turn));
    let frame = Frame::new(out, outward(out));
    let subs = supersamples * supersamples;
    let rows: Vec<Vec<f64>> = (0..cells.len())
        .into_par_iter()
        .map(|row| {
            let mut values = vec![0.0f64; h.ncols()];
            for sub in 0..subs {
                let (local, direction) = cells.sample(row, sub, supersamples);
                let travel = frame.direction(direction);
                let (came_through, point) = exit(frame.point(local), -travel);
                if came_through == ENTRY {
                    let source = cells.row(entry.local_point(point), entry.local_direction(travel));
                    values.iter_mut().zip(h.row(source).iter()).for_each(|(v, x)| *v += x);
                }
            }
            values.iter_mut().for_each(|v| *v /= subs as f64);
            values
        })
        .collect();
    DMatrix::from_fn(cells.len(), h.ncols(), |r, c| rows[r][c])
}

/// G = F_rlf H_rlf: the irradiance each sample of the canonical receiver gets from each basis
/// lightfield entering through its opening (pi times the mean radiance over cosine rays).
fn respond(receiver: &Samples, h_rlf: &DMatrix<f64>, cells: Cells, settings: &InterfaceSettings) -> DMatrix<f64> {
    let entry = Frame::new(ENTRY, ENTRY.inward());
    let rows =
        gather_rows(receiver, 0..receiver.len(), settings.gather_rays, settings.seed, h_rlf.ncols(), |face, point, direction, row| {
            if face == ENTRY {
                let source = cells.row(entry.local_point(point), entry.local_direction(-direction));
                row.iter_mut().zip(h_rlf.row(source).iter()).for_each(|(v, x)| *v += x * std::f64::consts::PI);
            }
        });
    DMatrix::from_row_slice(receiver.len(), h_rlf.ncols(), &rows)
}

/// The light volume's probes (volume::ROWS x k_rlf) for each basis lightfield entering
/// through side face `face`: a probe's ray that leaves through it meets the arriving light.
fn arriving_volume(h_rlf: &DMatrix<f64>, cells: Cells, face: Face) -> DMatrix<f64> {
    let entry = Frame::new(face, face.inward());
    volume::gather(h_rlf.ncols(), |hit, point, direction, row| {
        if hit == face {
            let source = cells.row(entry.local_point(point), entry.local_direction(-direction));
            row.iter_mut().zip(h_rlf.row(source).iter()).for_each(|(v, x)| *v += x);
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_inverse_concentric_map_undoes_the_forward_one_and_cells_round_trip() {
        for i in 0..400 {
            let square = Vec2::new((i % 20) as f32 + 0.5, (i / 20) as f32 + 0.5) / 20.0;
            let back = disk_to_square(concentric_disk(square));
            assert!(back.abs_diff_eq(square, 1e-4), "{square} -> {back}");
        }
        let cells = Cells { positions: 3, directions: 4 };
        for row in 0..cells.len() {
            let (local, direction) = cells.sample(row, 1, 2);
            assert_eq!(cells.row(local, direction), row);
        }
    }

    #[test]
    fn frames_agree_across_a_shared_face_and_turns_reach_the_right_faces() {
        // Light leaving a block through a side face f enters the next block (one step along f's
        // outward normal) through the opposite face in the same frame: the same world point and
        // direction for the same local ones.
        let (p, d) = (Vec2::new(0.3, 0.8), Vec3::new(0.2, -0.1, 0.97).normalize());
        for f in [Face::ALL[0], Face::ALL[1], Face::ALL[4], Face::ALL[5]] {
            let step = outward(f);
            let other = Face { axis: f.axis, positive: !f.positive };
            let (leaving, entering) = (Frame::new(f, outward(f)), Frame::new(other, other.inward()));
            assert!(leaving.point(p).abs_diff_eq(entering.point(p) + step, 1e-6), "{f:?}");
            assert!(leaving.direction(d).abs_diff_eq(entering.direction(d), 1e-6), "{f:?}");
            // Turning a block turns its frames with it.
            let turned = Frame::new(f.turned(1), outward(f.turned(1)));
            let turn = |v: Vec3| Vec3::new(v.z, v.y, -v.x);
            assert!(turned.direction(d).abs_diff_eq(turn(leaving.direction(d)), 1e-6), "{f:?}");
        }
        assert_eq!(target(ENTRY, Turn::Ahead), Face::ALL[5]);
        assert_eq!(target(ENTRY, Turn::Right).axis, 0);
        assert_ne!(target(ENTRY, Turn::Left), target(ENTRY, Turn::Right));
    }
}
