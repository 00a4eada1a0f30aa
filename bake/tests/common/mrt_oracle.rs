//! The tests' own brute-force one bounce across block openings (shared by bake/tests/mrt.rs
//! and the mrt_interfaces example). Independent of the operators in what matters most: the
//! walk through the level, the turning of blocks and the visibility; it shares the block's
//! sample layout and bilinear reads (`Samples`, tested on their own), and its ray-box exit is
//! written anew.

use glam::Vec3;
use nalgebra::DVector;
use relume_bake::mrt::{Face, Samples};

/// Where a ray from inside (or on) the unit cube leaves it: the face's axis, its side and the
/// point. The tests' own, independent of the operators'.
pub fn leave(origin: Vec3, d: Vec3) -> (usize, bool, Vec3) {
    let mut best = (f32::INFINITY, 0, false);
    for axis in 0..3 {
        if d[axis].abs() > 1e-12 {
            let t = (if d[axis] > 0.0 { 1.0 } else { 0.0 } - origin[axis]) / d[axis];
            if t >= 0.0 && t < best.0 {
                best = (t, axis, d[axis] > 0.0);
            }
        }
    }
    (best.1, best.2, (origin + d * best.0).clamp(Vec3::ZERO, Vec3::ONE))
}

/// Where a ray from `origin` in block `block` of the level of `cells` lands: the block and the
/// point and face of the wall it meets (a ray always meets one: the level is closed).
pub fn land(cells: &[(i32, i32)], mut block: usize, origin: Vec3, d: Vec3) -> (usize, Face, Vec3) {
    let mut p = origin;
    loop {
        let (axis, positive, point) = leave(p, d);
        let (x, z) = cells[block];
        let step = if positive { 1 } else { -1 };
        let next = match axis {
            0 => cells.iter().position(|c| *c == (x + step, z)),
            2 => cells.iter().position(|c| *c == (x, z + step)),
            _ => None,
        };
        match next {
            Some(n) => {
                (block, p) = (n, point);
                p[axis] = if positive { 0.0 } else { 1.0 };
            }
            None => return (block, Face { axis, positive }, point),
        }
    }
}

/// Whether a point light at `light` (world: a block's cell plus its local point) is seen from
/// `x` in block `block`: the straight line between them stays inside the level's blocks.
pub fn sees(cells: &[(i32, i32)], block: usize, x: Vec3, light: Vec3) -> bool {
    let world = |b: usize, p: Vec3| Vec3::new(cells[b].0 as f32 + p.x, p.y, cells[b].1 as f32 + p.z);
    let from = world(block, x);
    let d = (light - from).normalize();
    let (hit_block, _, point) = land(cells, block, x, d);
    (world(hit_block, point) - from).length() >= (light - from).length() - 1e-4
}

/// The direct irradiance of a unit point light at `light` (world, in cells) on every block's
/// samples, seen through the level (an inverse square, not below 5 cm).
pub fn point_light(cells: &[(i32, i32)], samples: &[Samples], light: Vec3) -> Vec<DVector<f64>> {
    samples
        .iter()
        .enumerate()
        .map(|(block, own)| {
            DVector::from_iterator(
                own.len(),
                (0..own.len()).map(|i| {
                    let (_, x, n) = own.sample(i);
                    let to = light - Vec3::new(cells[block].0 as f32 + x.x, x.y, cells[block].1 as f32 + x.z);
                    let cos = n.dot(to.normalize());
                    match cos > 0.0 && sees(cells, block, x, light) {
                        true => (cos / to.length_squared().max(0.0025)) as f64,
                        false => 0.0,
                    }
                }),
            )
        })
        .collect()
}

/// Brute-force one bounce over a whole level: for every block's samples, the mean over
/// cosine rays of the direct light `l_d` (per block, its own samples) where each ray lands.
pub fn bounce(cells: &[(i32, i32)], samples: &[Samples], l_d: &[DVector<f64>], rays: u32) -> Vec<DVector<f64>> {
    (0..cells.len())
        .map(|block| {
            let own = &samples[block];
            DVector::from_iterator(
                own.len(),
                (0..own.len()).map(|i| {
                    let (_, origin, normal) = own.sample(i);
                    gather(cells, samples, l_d, (block, origin, normal), (block * 100_000 + i) as u32, rays)
                }),
            )
        })
        .collect()
}

/// The irradiance the radiosity `l_d` (per block, its own samples) gives a surface at local
/// point `origin` of block `block` facing `normal`: the mean over `rays` cosine rays (the
/// random stream `stream`) of `l_d` where each lands.
pub fn gather(
    cells: &[(i32, i32)],
    samples: &[Samples],
    l_d: &[DVector<f64>],
    (block, origin, normal): (usize, Vec3, Vec3),
    stream: u32,
    rays: u32,
) -> f64 {
    use relume_bake::sampling::{cosine_hemisphere, orthonormal_basis, PathSampler};
    let (t, b) = orthonormal_basis(normal);
    let mut sum = 0.0;
    for r in 0..rays {
        let u = PathSampler::new(7, stream, r).sobol4(0);
        let local = cosine_hemisphere(glam::Vec2::new(u[0], u[1]));
        let (hit, face, point) = land(cells, block, origin, t * local.x + b * local.y + normal * local.z);
        let slot = samples[hit].faces.iter().position(|f| *f == face).expect("a wall");
        sum += samples[hit].bilinear(slot, face.uv(point)).iter().map(|(j, w)| *w as f64 * l_d[hit][*j]).sum::<f64>();
    }
    sum / rays as f64
}
