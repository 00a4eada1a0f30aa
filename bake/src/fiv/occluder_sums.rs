//! The run-time formula of 003 §4-5 per receiver point, on the CPU: the oracle of the GPU's
//! occluder-sum pass (shaders/fiv/occluder_sums.comp computes the same, step for step).

use super::{EnvironmentTerms, FivBake, OccluderTable};
use glam::Vec3;
use std::f32::consts::{PI, TAU};

/// What an occluder beyond the table's last distance contributes (spec fiv.md B4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Beyond {
    /// The outer shell's value times (distance_max / distance)^2: a far occluder's solid angle.
    Scale,
    /// Nothing.
    Drop,
}

/// How a table is interpolated between its distance shells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Radial {
    /// Linearly in log distance: the paper's trilinear lookup (003 §5).
    Linear,
    /// distance^2 x FIV linearly, then divided by distance^2: a far occluder's FIV falls as
    /// its solid angle, 1 / distance^2, which a linear blend of two shells overestimates
    /// between them (docs/BENCHMARKS.md "FIV" measures both).
    InverseSquare,
}

/// The run-time choices the paper leaves open or offers (spec fiv.md B4, B6-B8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SumOptions {
    /// Case B scaled by (d + R) / 2R (the paper's partial correction); off, case B counts whole.
    pub partial: bool,
    /// The pairwise overlap correction of eq. (13)-(14).
    pub overlap: bool,
    pub beyond: Beyond,
    pub radial: Radial,
    pub self_shadow: SelfShadow,
}

/// How a receiver on an occluder is shadowed by that occluder (003 §5).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SelfShadow {
    /// Not at all: DifMap(N).
    Off,
    /// The paper's: FIV_self looked up in the table, its samples inside the occluder left out.
    /// The table's samples lie off the surface, where the occluder no longer hides the whole
    /// lower hemisphere, and what it leaves open there counts against N (docs/BENCHMARKS.md).
    Paper,
    /// DifMap(N) less N . FIV_above, FIV_above looked up among the masks of the surface
    /// points nearest the samples, of the directions above their tangent planes only
    /// (`OccluderTable::surface`): what the occluder hides beyond the plane its own surface
    /// already hides; nothing on a convex occluder.
    Surface,
}

impl Default for SumOptions {
    fn default() -> Self {
        SumOptions { partial: true, overlap: true, beyond: Beyond::Scale, radial: Radial::InverseSquare, self_shadow: SelfShadow::Surface }
    }
}

/// An occluder at run time: its type's table, the scene mesh it is, and where its
/// bounding-sphere centre is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Occluder {
    pub table: usize,
    pub mesh: usize,
    pub centre: Vec3,
}

impl EnvironmentTerms {
    /// DifMap at normal `n`, eq. (5): bilinear, repeating in azimuth, clamped at the poles.
    pub fn difmap_lookup(&self, n: Vec3) -> Vec3 {
        let (w, h) = (self.difmap_width as i32, (self.difmap_width / 2) as i32);
        // Straight up or down the azimuth is undefined; 0.5 is what the GPU pass takes too.
        let u = if n.x == 0.0 && n.z == 0.0 { 0.5 } else { 0.5 + n.x.atan2(-n.z) / TAU };
        let v = n.y.clamp(-1.0, 1.0).acos() / PI;
        let (x, y) = (u * w as f32 - 0.5, v * h as f32 - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |i: i32, j: i32| self.difmap[(j.clamp(0, h - 1) * w + i.rem_euclid(w)) as usize];
        let (i, j) = (x0 as i32, y0 as i32);
        let top = texel(i, j).lerp(texel(i + 1, j), fx);
        top.lerp(texel(i, j + 1).lerp(texel(i + 1, j + 1), fx), fy)
    }
}

/// The least share of a lookup's trilinear weight its valid samples must carry.
pub const VALID_WEIGHT_MIN: f32 = 1e-3;

impl OccluderTable {
    /// FIV(EnvOcc) of the type with its centre at offset `v` from the receiver: trilinear over
    /// the 8 nearest samples (003 §5), distances in log space (weighted by `radial`) and
    /// clamped below, renormalised over the valid samples (spec fiv.md B9-B10); None when
    /// valid samples carry less than [`VALID_WEIGHT_MIN`] of the weight (the receiver is
    /// inside the type, as far as the grid can tell).
    pub fn lookup(&self, v: Vec3, beyond: Beyond, radial: Radial) -> Option<[Vec3; 3]> {
        self.interpolate(&self.fiv, &self.valid, v, beyond, radial)
    }

    /// FIV_self for a receiver on the type's surface at offset `v` from its centre: as
    /// [`Self::lookup`], among the surface points' masks (`surface`, the first shells only),
    /// linearly between shells (a surface point's mask does not fall with the sample's
    /// distance).
    pub fn lookup_surface(&self, v: Vec3) -> Option<[Vec3; 3]> {
        self.interpolate(&self.surface, &self.surface_valid, v, Beyond::Drop, Radial::Linear)
    }

    /// Trilinear over `values`, leaving out samples not `valid` and those past their end.
    fn interpolate(&self, values: &[[Vec3; 3]], valid: &[bool], v: Vec3, beyond: Beyond, radial: Radial) -> Option<[Vec3; 3]> {
        let g = self.grid;
        let distance = v.length().max(1e-20);
        let d = v / distance;
        let theta = if d.x == 0.0 && d.z == 0.0 { 0.0 } else { (-d.z).atan2(d.x) };
        let fi = (if theta < 0.0 { theta + TAU } else { theta }) / TAU * g.azimuths as f32;
        let fj = (d.y.clamp(-1.0, 1.0).acos() / PI * (g.polar - 1) as f32).min((g.polar - 1) as f32);
        let steps = (g.distances - 1) as f32;
        let fk = ((distance / self.distance_min).ln() / (self.distance_max / self.distance_min).ln() * steps).clamp(0.0, steps);
        let (i0, j0, k0) = (fi.floor(), fj.floor().min((g.polar - 2) as f32), fk.floor().min(steps - 1.0));
        let (ti, tj, tk) = (fi - i0, fj - j0, fk - k0);
        let (i0, j0, k0) = (i0 as u32 % g.azimuths, j0 as u32, k0 as u32);
        let i1 = (i0 + 1) % g.azimuths;
        let (mut out, mut weight) = ([Vec3::ZERO; 3], 0.0);
        let within = distance.clamp(self.distance_min, self.distance_max);
        let shell = |k: u32| match radial {
            Radial::Linear => 1.0,
            Radial::InverseSquare => (self.distance(k) / within).powi(2),
        };
        for (k, wk) in [(k0, 1.0 - tk), (k0 + 1, tk)] {
            for (j, wj) in [(j0, 1.0 - tj), (j0 + 1, tj)] {
                for (i, wi) in [(i0, 1.0 - ti), (i1, ti)] {
                    let s = g.index(i, j, k);
                    if valid.get(s) == Some(&true) {
                        weight += wi * wj * wk;
                        (0..3).for_each(|c| out[c] += values[s][c] * (wi * wj * wk * shell(k)));
                    }
                }
            }
        }
        if weight < VALID_WEIGHT_MIN {
            return None;
        }
        let scale = match (distance > self.distance_max, beyond) {
            (false, _) => 1.0,
            (true, Beyond::Scale) => (self.distance_max / distance).powi(2),
            (true, Beyond::Drop) => 0.0,
        };
        Some(out.map(|f| f * scale / weight))
    }
}

/// The occluder's disc on the plane at unit height along `n` (spec fiv.md B7): centre offset
/// (v - d n) / d', radius R / d', d' = max(d, R).
fn disc(v: Vec3, d: f32, radius: f32, n: Vec3) -> (Vec3, f32) {
    let height = d.max(radius);
    ((v - d * n) / height, radius / height)
}

/// The area two discs share (a lens; nested and disjoint discs included).
pub fn lens_area(distance: f32, r1: f32, r2: f32) -> f32 {
    if distance >= r1 + r2 {
        return 0.0;
    }
    if distance <= (r1 - r2).abs() {
        return PI * r1.min(r2).powi(2);
    }
    let a1 = ((distance * distance + r1 * r1 - r2 * r2) / (2.0 * distance * r1)).clamp(-1.0, 1.0).acos();
    let a2 = ((distance * distance + r2 * r2 - r1 * r1) / (2.0 * distance * r2)).clamp(-1.0, 1.0).acos();
    let kite = (-distance + r1 + r2) * (distance + r1 - r2) * (distance - r1 + r2) * (distance + r1 + r2);
    r1 * r1 * a1 + r2 * r2 * a2 - 0.5 * kite.max(0.0).sqrt()
}

/// N . f for each colour channel's vector.
fn dots(n: Vec3, f: [Vec3; 3]) -> Vec3 {
    Vec3::new(n.dot(f[0]), n.dot(f[1]), n.dot(f[2]))
}

/// A point that receives light: where it is, its unit normal (towards the viewer), and the
/// occluder it lies on, if any (index into the occluders).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    pub point: Vec3,
    pub normal: Vec3,
    pub occluder: Option<usize>,
}

impl FivBake {
    /// Irradiance at `receiver` (003 §5): DifMap(N), or on a self-shadowing occluder its
    /// [`Self::self_shadowed`] value, less each other occluder's N . FIV(EnvOcc) by its case
    /// (A: d >= R whole, B: scaled by (d + R) / 2R when `partial`, C: d <= -R nothing; a
    /// receiver inside it, all of DifMap(N)), plus the pairwise overlaps of eq. (13)-(14),
    /// written sum_a I_a sum_{b != a} Ov%_ab so that each occluder's table is read once; the
    /// overlap is at most sum I - max I, I_a >= 0 and the result in [0, DifMap(N)] (spec
    /// fiv.md B8, B11). The receiver's own occluder and one dropped beyond its table take no
    /// part in the sum or the pairs.
    pub fn irradiance(&self, occluders: &[Occluder], receiver: Receiver, options: SumOptions) -> Vec3 {
        let (p, n) = (receiver.point, receiver.normal);
        let total = self.environment.difmap_lookup(n);
        let unoccluded = self.self_shadowed(occluders, receiver, options).unwrap_or(total);
        let (mut occluded, mut overlap, mut largest) = (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);
        for (a, occluder) in occluders.iter().enumerate() {
            if !self.occludes(occluders, a, receiver, options) {
                continue;
            }
            let table = &self.tables[occluder.table];
            let v = occluder.centre - p;
            let d = n.dot(v);
            let factor = if options.partial && d < table.radius { (d + table.radius) / (2.0 * table.radius) } else { 1.0 };
            let share = match table.lookup(v, options.beyond, options.radial) {
                Some(fiv) => dots(n, fiv).max(Vec3::ZERO) * factor,
                None => total,
            };
            occluded += share;
            largest = largest.max(share);
            if options.overlap {
                overlap += share * self.overlap_shares(occluders, a, receiver, options);
            }
        }
        let overlap = overlap.min(occluded - largest);
        (unoccluded - occluded + overlap).clamp(Vec3::ZERO, total)
    }

    /// What a receiver on its own occluder sees of the environment past that occluder
    /// (003 §5, spec fiv.md B11). `Paper`: max(0, N . (FIV(Env) - FIV_self)), the fullsphere
    /// sum being the hemispherical one since the occluder hides every direction below the
    /// tangent plane (eq. 7). `Surface`: DifMap(N) - max(0, N . FIV_above), falling back on
    /// `Paper` where no surface sample is valid. None without self-shadowing, off an
    /// occluder, or where no valid sample is near (then DifMap(N) stands).
    pub fn self_shadowed(&self, occluders: &[Occluder], receiver: Receiver, options: SumOptions) -> Option<Vec3> {
        let own = &occluders[receiver.occluder.filter(|_| options.self_shadow != SelfShadow::Off)?];
        let (table, v, n) = (&self.tables[own.table], own.centre - receiver.point, receiver.normal);
        if let Some(above) = table.lookup_surface(v).filter(|_| options.self_shadow == SelfShadow::Surface) {
            return Some(self.environment.difmap_lookup(n) - dots(n, above).max(Vec3::ZERO));
        }
        let fiv = table.lookup(v, options.beyond, options.radial)?;
        let open = [0, 1, 2].map(|c| self.environment.fiv[c] - fiv[c]);
        Some(dots(n, open).max(Vec3::ZERO))
    }

    /// Whether occluder `o` takes light from `receiver`: not its own, not in case C, not
    /// dropped beyond its table.
    fn occludes(&self, occluders: &[Occluder], o: usize, receiver: Receiver, options: SumOptions) -> bool {
        let table = &self.tables[occluders[o].table];
        let v = occluders[o].centre - receiver.point;
        receiver.occluder != Some(o)
            && receiver.normal.dot(v) > -table.radius
            && (options.beyond == Beyond::Scale || v.length() <= table.distance_max)
    }

    /// sum over the other occluders b that occlude the receiver of Ov%_ab = A_ov / (A_a + A_b).
    fn overlap_shares(&self, occluders: &[Occluder], a: usize, receiver: Receiver, options: SumOptions) -> f32 {
        let disc_of = |o: &Occluder| {
            let (v, radius) = (o.centre - receiver.point, self.tables[o.table].radius);
            disc(v, receiver.normal.dot(v), radius, receiver.normal)
        };
        let (ca, ra) = disc_of(&occluders[a]);
        let others = (0..occluders.len()).filter(|&b| b != a && self.occludes(occluders, b, receiver, options));
        others.map(|b| disc_of(&occluders[b])).map(|(cb, rb)| lens_area(ca.distance(cb), ra, rb) / (PI * (ra * ra + rb * rb))).sum()
    }
}
