//! Charts unfolded onto their neighbours. 001 §3's charts are each one projection, so a box
//! is six charts, and a thin box (a desk's leg, a shelf's edge) is six slivers a texel or two
//! across, each paying its gutter all round: on classroom the gutters alone kept any packing
//! under 78 % (docs/BENCHMARKS.md, "Atlas utilization"). A chart whose shared edge has the
//! same length in its neighbour's plane can be turned about that edge into the neighbour's
//! plane without distortion (a rigid motion of its own mapping, mirrored where it would fold
//! back over it). It is, where the pair then packs into clearly fewer texels and overlaps
//! nothing. Large faces gain too little from it to be folded: their charts stay as 001 has
//! them.

use super::builder::{bounds_2d, texel_size, Adjacency, ChartMapping, OverlapGrid};
use crate::scene::Mesh;
use glam::{UVec2, Vec2};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The share of the smaller chart's packed texels (gutters included) that unfolding it and
/// its neighbour into one chart must save. A texel across a fold averages two faces, which
/// pays only where the gutters are a large part of a chart: at 0.2, two equal square charts
/// fold when they are at most four gutters across, and the faces of a 1 x 2 x 3 m box at 10
/// texels a metre (10 to 30 texels across) stay apart.
const UNFOLD_SAVING: f32 = 0.2;

/// A chart laid flat in metres: its triangles with their corners in its plane.
#[derive(Clone, Debug)]
pub struct Layout {
    /// Triangle indices within the mesh.
    pub triangles: Vec<u32>,
    /// Per triangle, its corners in the chart's plane, metres.
    pub corners: Vec<[Vec2; 3]>,
    /// The mapping of the chart's first part.
    pub mapping: ChartMapping,
    /// How many of 001's charts were unfolded into this one (1: none).
    pub parts: u32,
}

/// How a chart's packed size is measured: texels per metre, the gutter and the largest
/// chart side a page takes.
#[derive(Clone, Copy)]
pub struct ChartCost {
    pub density: f32,
    pub gutter: u32,
    pub largest: u32,
}

impl ChartCost {
    fn size(&self, corners: &[[Vec2; 3]]) -> UVec2 {
        let (lo, hi) = bounds_2d(corners.as_flattened());
        texel_size(hi - lo, self.density)
    }

    fn packed(&self, size: UVec2) -> f32 {
        ((size.x + self.gutter) as f32) * ((size.y + self.gutter) as f32)
    }
}

/// The layouts after unfolding, the pair that saves most first, until no pair saves
/// [`UNFOLD_SAVING`]. Ties follow the charts' and triangles' indices, so the result depends
/// on nothing else.
pub fn unfold(mesh: &Mesh, adjacency: &Adjacency, mut layouts: Vec<Layout>, cost: ChartCost) -> Vec<Layout> {
    let mut owner = vec![(0u32, 0u32); mesh.indices.len() / 3];
    for (c, layout) in layouts.iter().enumerate() {
        for (i, &t) in layout.triangles.iter().enumerate() {
            owner[t as usize] = (c as u32, i as u32);
        }
    }
    let mut alive = vec![true; layouts.len()];
    // Best saving first; a chart's entry is checked against what its neighbours are now.
    let mut queue: BinaryHeap<(u32, Reverse<usize>)> = BinaryHeap::new();
    for a in 0..layouts.len() {
        if let Some((saving, _, _)) = best_fold(adjacency, &layouts, &owner, a, cost) {
            queue.push((saving.to_bits(), Reverse(a)));
        }
    }
    while let Some((saving, Reverse(a))) = queue.pop() {
        if !alive[a] {
            continue;
        }
        let Some((now, b, corners)) = best_fold(adjacency, &layouts, &owner, a, cost) else { continue };
        if now.to_bits() != saving {
            queue.push((now.to_bits(), Reverse(a)));
            continue;
        }
        let emptied = Layout { triangles: Vec::new(), corners: Vec::new(), ..layouts[b] };
        let other = std::mem::replace(&mut layouts[b], emptied);
        let start = layouts[a].triangles.len() as u32;
        for (i, &t) in other.triangles.iter().enumerate() {
            owner[t as usize] = (a as u32, start + i as u32);
        }
        let target = &mut layouts[a];
        target.triangles.extend(other.triangles);
        target.corners.extend(corners);
        target.parts += other.parts;
        alive[b] = false;
        if let Some((saving, _, _)) = best_fold(adjacency, &layouts, &owner, a, cost) {
            queue.push((saving.to_bits(), Reverse(a)));
        }
    }
    layouts.into_iter().zip(alive).filter(|(_, alive)| *alive).map(|(layout, _)| layout).collect()
}

/// The neighbour of chart `a` that saves most by being unfolded onto it: the saving (a share
/// of the smaller chart's packed texels), the neighbour, and its corners moved into `a`'s
/// plane.
fn best_fold(
    adjacency: &Adjacency,
    layouts: &[Layout],
    owner: &[(u32, u32)],
    a: usize,
    cost: ChartCost,
) -> Option<(f32, usize, Vec<[Vec2; 3]>)> {
    let here = &layouts[a];
    let own = cost.packed(cost.size(&here.corners));
    let mut grid: Option<OverlapGrid> = None;
    let mut best: Option<(f32, usize, Vec<[Vec2; 3]>)> = None;
    for (i, &t) in here.triangles.iter().enumerate() {
        for (k, o, ok) in adjacency.shared_edges(t) {
            let (b, j) = owner[o as usize];
            let b = b as usize;
            if b == a || best.as_ref().is_some_and(|(_, seen, _)| *seen == b) {
                continue;
            }
            let there = &layouts[b];
            let Some(motion) = Motion::along(adjacency, (t, k, here.corners[i]), (o, ok, there.corners[j as usize])) else {
                continue;
            };
            let moved: Vec<[Vec2; 3]> = there.corners.iter().map(|c| c.map(|p| motion.apply(p))).collect();
            let size = cost.size(&[here.corners.as_slice(), moved.as_slice()].concat());
            if size.max_element() > cost.largest {
                continue;
            }
            let theirs = cost.packed(cost.size(&there.corners));
            let saving = (own + theirs - cost.packed(size)) / own.min(theirs);
            if saving < UNFOLD_SAVING || best.as_ref().is_some_and(|(s, _, _)| *s >= saving) {
                continue;
            }
            let grid = grid.get_or_insert_with(|| {
                let mut g = OverlapGrid::new(here.corners[0]);
                here.corners.iter().for_each(|c| g.insert(*c));
                g
            });
            if moved.iter().all(|c| !grid.overlaps(*c)) {
                best = Some((saving, b, moved));
            }
        }
    }
    best
}

/// A rigid motion of the plane (a rotation and a translation, then a mirror about the hinge
/// where needed), taking one chart's side of a shared edge onto the other's.
struct Motion {
    rotation: Vec2,
    from: Vec2,
    to: Vec2,
    /// The hinge's direction, when the moved chart is mirrored about it.
    mirror: Option<Vec2>,
}

impl Motion {
    /// The motion taking triangle `o`'s edge `ok` (corners in its own chart) onto triangle
    /// `t`'s edge `k`, with `o` on the far side of it; none where the edge's lengths differ
    /// (one of the two mappings foreshortens it).
    fn along(adjacency: &Adjacency, (t, k, a): (u32, usize, [Vec2; 3]), (o, ok, b): (u32, usize, [Vec2; 3])) -> Option<Motion> {
        let (a0, a1) = (a[k], a[(k + 1) % 3]);
        let same_order = adjacency.same_point((t, k), (o, ok));
        let (b0, b1) = if same_order { (b[ok], b[(ok + 1) % 3]) } else { (b[(ok + 1) % 3], b[ok]) };
        let (da, db) = (a1 - a0, b1 - b0);
        let tolerance = 1e-4 * da.length() + 1e-6 * a0.abs().max(a1.abs()).max_element();
        if (da.length() - db.length()).abs() > tolerance || da.length() <= 0.0 {
            return None;
        }
        let rotation = Vec2::new(da.dot(db), db.perp_dot(da)).normalize();
        let mut motion = Motion { rotation, from: b0, to: a0, mirror: None };
        let side = |p: Vec2| da.perp_dot(p - a0);
        if side(a[(k + 2) % 3]) * side(motion.apply(b[(ok + 2) % 3])) > 0.0 {
            motion.mirror = Some(da.normalize());
        }
        Some(motion)
    }

    fn apply(&self, p: Vec2) -> Vec2 {
        let r = self.rotation.rotate(p - self.from);
        let r = match self.mirror {
            Some(u) => 2.0 * u.dot(r) * u - r,
            None => r,
        };
        self.to + r
    }
}
