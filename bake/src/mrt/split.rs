//! The scene's triangles split where a derived proxy's block boundaries cross them (vertical
//! planes through the lattice's edges, lines in plan), so that each piece lies in one block and
//! can be mapped onto one of its faces (a floor polygon under several blocks, a desk across a
//! boundary). The result is a `Tessellation` (plain data: each new vertex from its source
//! triangle's corners and weights), which the bake and the renderer apply alike.

use crate::scene::{Mesh, Scene};
use crate::tessellation::{TessellatedMesh, Tessellation};
use glam::DVec2;
use std::collections::HashMap;

/// A side of a plan cell: the inward unit normal n and d, a point p inside having n . p > d;
/// `id` names the plane, so that pieces cut by it on either side share their new vertices.
#[derive(Clone, Copy, Debug)]
pub struct Side {
    pub normal: DVec2,
    pub d: f64,
    pub id: usize,
}

/// The most pieces one triangle may be cut into (a guard against slivers that never settle).
const MOST_PIECES: usize = 4096;

/// `scene` split so that no piece of a triangle crosses a side of the cell its middle lies in
/// (`cell(p)`: that cell's sides, None outside every cell: the piece stays whole); None when no
/// triangle needed splitting. `tolerance` (metres): a corner this near a side counts as on it.
pub fn split(scene: &Scene, cell: &dyn Fn(DVec2) -> Option<[Side; 4]>, tolerance: f64) -> Option<Tessellation> {
    let meshes: Vec<(TessellatedMesh, bool)> = scene.meshes.iter().map(|m| split_mesh(m, cell, tolerance)).collect();
    meshes.iter().any(|(_, cut)| *cut).then(|| Tessellation { max_edge: 0.0, meshes: meshes.into_iter().map(|(m, _)| m).collect() })
}

/// A corner of a piece: its new vertex, its weights on the source triangle's corners, its plan
/// point.
#[derive(Clone, Copy)]
struct Corner {
    vertex: u32,
    weights: [f64; 3],
    plan: DVec2,
}

/// The new vertices of one mesh: the source vertices kept as they are, points cut on a source
/// edge shared by the triangles on both sides, points inside a triangle its own.
struct Vertices {
    out: TessellatedMesh,
    kept: HashMap<u32, u32>,
    on_edges: HashMap<(u32, u32, usize), u32>,
}

impl Vertices {
    fn kept(&mut self, v: u32) -> u32 {
        let out = &mut self.out;
        *self.kept.entry(v).or_insert_with(|| {
            out.sources.push(([v; 3], [0.0, 0.0]));
            out.sources.len() as u32 - 1
        })
    }

    /// The point at `weights` of triangle `t` made by cutting plane `plane`.
    fn cut(&mut self, t: [u32; 3], weights: [f64; 3], plane: usize) -> u32 {
        let zero: Vec<usize> = (0..3).filter(|&k| weights[k] == 0.0).collect();
        if let [k] = zero[..] {
            // On the source edge between the other two corners: keyed from its lower vertex.
            let (i, j) = ((k + 1) % 3, (k + 2) % 3);
            let (lo, hi, t_hi) = if t[i] < t[j] { (t[i], t[j], weights[j]) } else { (t[j], t[i], weights[i]) };
            let out = &mut self.out;
            return *self.on_edges.entry((lo, hi, plane)).or_insert_with(|| {
                out.sources.push(([lo, hi, lo], [t_hi as f32, 0.0]));
                out.sources.len() as u32 - 1
            });
        }
        self.out.sources.push((t, [weights[1] as f32, weights[2] as f32]));
        self.out.sources.len() as u32 - 1
    }
}

/// One mesh's triangles split; whether any was.
fn split_mesh(mesh: &Mesh, cell: &dyn Fn(DVec2) -> Option<[Side; 4]>, tolerance: f64) -> (TessellatedMesh, bool) {
    let mut v =
        Vertices { out: TessellatedMesh { sources: Vec::new(), indices: Vec::new() }, kept: HashMap::new(), on_edges: HashMap::new() };
    let plan = |i: u32| {
        let p = mesh.positions[i as usize].as_dvec3();
        DVec2::new(p.x, p.z)
    };
    let mut any = false;
    for t in mesh.indices.chunks_exact(3) {
        let t = [t[0], t[1], t[2]];
        let start: Vec<Corner> = (0..3)
            .map(|k| Corner { vertex: v.kept(t[k]), weights: std::array::from_fn(|j| (j == k) as u8 as f64), plan: plan(t[k]) })
            .collect();
        let mut pending = vec![start];
        let mut pieces = 0;
        while let Some(piece) = pending.pop() {
            pieces += 1;
            let middle = piece.iter().map(|c| c.plan).sum::<DVec2>() / piece.len() as f64;
            let crossing = cell(middle).and_then(|sides| {
                sides.into_iter().find(|s| {
                    let distances = piece.iter().map(|c| s.normal.dot(c.plan) - s.d);
                    distances.clone().any(|x| x < -tolerance) && distances.clone().any(|x| x > tolerance)
                })
            });
            match crossing {
                Some(side) if pieces < MOST_PIECES => {
                    any = true;
                    let (a, b) = cut(&piece, side, t, &mut v);
                    pending.extend([a, b].into_iter().filter(|p| p.len() >= 3));
                }
                _ => {
                    // A convex piece: a fan from its first corner, in the source's winding.
                    for k in 1..piece.len() - 1 {
                        v.out.indices.extend([piece[0].vertex, piece[k].vertex, piece[k + 1].vertex]);
                    }
                }
            }
        }
    }
    (v.out, any)
}

/// A convex piece cut by `side` into the part inside it and the part outside, in order.
fn cut(piece: &[Corner], side: Side, t: [u32; 3], v: &mut Vertices) -> (Vec<Corner>, Vec<Corner>) {
    let (mut inside, mut outside) = (Vec::new(), Vec::new());
    let distance = |c: &Corner| side.normal.dot(c.plan) - side.d;
    for (k, a) in piece.iter().enumerate() {
        let b = &piece[(k + 1) % piece.len()];
        let (da, db) = (distance(a), distance(b));
        if da >= 0.0 {
            inside.push(*a);
        }
        if da <= 0.0 {
            outside.push(*a);
        }
        if (da > 0.0 && db < 0.0) || (da < 0.0 && db > 0.0) {
            let s = da / (da - db);
            let weights = std::array::from_fn(|j| a.weights[j] + (b.weights[j] - a.weights[j]) * s);
            let corner = Corner { vertex: v.cut(t, weights, side.id), weights, plan: a.plan + (b.plan - a.plan) * s };
            inside.push(corner);
            outside.push(corner);
        }
    }
    (inside, outside)
}
