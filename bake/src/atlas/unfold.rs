//! Charts unfolded onto their neighbours. 001 §3's charts are each one projection, so a box
//! is six charts, and a thin box (a desk's leg, a shelf's edge) is six slivers a texel or two
//! across, each paying its gutter all round: on classroom the gutters alone kept any packing
//! under 78 % (docs/BENCHMARKS.md, "Atlas utilization"). A chart whose shared edge has the
//! same length in its neighbour's plane can be turned about that edge into the neighbour's
//! plane without distortion (a rigid motion of its own mapping, mirrored where it would fold
//! back over it). It is, where the pair then packs into clearly fewer texels and overlaps
//! nothing. Large faces gain too little from it to be folded: their charts stay as 001 has
//! them.

use super::builder::{bounds_2d, signed_area_2d, texel_size, Adjacency, ChartMapping, OverlapGrid};
use crate::scene::Mesh;
use glam::{UVec2, Vec2};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The share of the smaller chart's packed texels (gutters included) that unfolding it and
/// its neighbour into one chart must save. A texel across a fold averages two faces, which
/// pays only where the gutters are a large part of a chart: at 0.2, two equal square charts
/// fold when they are at most four gutters across, and at the default 2-texel gutter the faces
/// of a 1 x 2 x 3 m box at 10 texels a metre (10 to 30 texels across) stay apart.
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
    pub limit: u32,
}

impl ChartCost {
    fn size(&self, corners: &[[Vec2; 3]]) -> UVec2 {
        let (lo, hi) = bounds_2d(corners.as_flattened());
        texel_size(hi - lo, self.density)
    }

    /// The faces' area in texels.
    fn area(&self, corners: &[[Vec2; 3]]) -> f32 {
        corners.iter().map(|c| signed_area_2d(*c).abs()).sum::<f32>() * self.density * self.density
    }

    fn packed(&self, size: UVec2) -> f32 {
        ((size.x + self.gutter) as f32) * ((size.y + self.gutter) as f32)
    }
}

/// Which admitted pair is folded first: the one saving the largest share of its smaller
/// chart, or the most texels. Neither is best everywhere (a thin panel folded strips first
/// can end as two halves no fold joins), so both are run and the cheaper kept.
#[derive(Clone, Copy)]
enum Order {
    Share,
    Texels,
}

/// What folding one chart onto another saves: its share of the smaller chart's packed texels
/// (the bar), and the texels.
#[derive(Clone, Copy)]
struct Saving {
    share: f32,
    texels: f32,
}

impl Saving {
    fn key(&self, order: Order) -> f32 {
        match order {
            Order::Share => self.share,
            Order::Texels => self.texels,
        }
    }
}

/// The layouts after unfolding, admitted pairs (those saving [`UNFOLD_SAVING`]) folded in
/// each [`Order`] until no queued chart has one left (each chart is queued at the start and
/// again when it grows); of the two results, the one whose charts pack into
/// fewer texels (the first on a tie). Ties within a run follow the charts' and triangles'
/// indices, so the result depends on nothing else.
pub fn unfold(mesh: &Mesh, adjacency: &Adjacency, layouts: Vec<Layout>, cost: ChartCost) -> Vec<Layout> {
    let packed = |layouts: &[Layout]| -> f32 { layouts.iter().map(|l| cost.packed(cost.size(&l.corners))).sum() };
    let by_share = unfold_in(mesh, adjacency, layouts.clone(), cost, Order::Share);
    let by_texels = unfold_in(mesh, adjacency, layouts, cost, Order::Texels);
    if packed(&by_texels) < packed(&by_share) {
        by_texels
    } else {
        by_share
    }
}

/// One run of [`unfold`]: the admitted pair first in `order`, one at a time.
fn unfold_in(mesh: &Mesh, adjacency: &Adjacency, mut layouts: Vec<Layout>, cost: ChartCost, order: Order) -> Vec<Layout> {
    let mut owner = vec![(0u32, 0u32); mesh.indices.len() / 3];
    for (c, layout) in layouts.iter().enumerate() {
        for (i, &t) in layout.triangles.iter().enumerate() {
            owner[t as usize] = (c as u32, i as u32);
        }
    }
    // Per chart, its faces' area and its packed texels, kept as charts grow.
    let mut extents: Vec<Extent> = layouts.iter().map(|l| Extent::of(&l.corners, cost)).collect();
    let mut alive = vec![true; layouts.len()];
    // A chart's entry is checked against what its neighbours are now when it comes up.
    let mut queue: BinaryHeap<(u32, Reverse<usize>)> = BinaryHeap::new();
    let key = |fold: &Option<Fold>| fold.as_ref().map(|f| f.saving.key(order).to_bits());
    for a in 0..layouts.len() {
        if let Some(k) = key(&best_fold(adjacency, &layouts, &extents, &owner, a, cost, order)) {
            queue.push((k, Reverse(a)));
        }
    }
    while let Some((k, Reverse(a))) = queue.pop() {
        if !alive[a] {
            continue;
        }
        let fold = best_fold(adjacency, &layouts, &extents, &owner, a, cost, order);
        let Some(now) = key(&fold) else { continue };
        if now != k {
            queue.push((now, Reverse(a)));
            continue;
        }
        let Fold { onto: b, corners, .. } = fold.expect("its key was read");
        let triangles = std::mem::take(&mut layouts[b].triangles);
        let start = layouts[a].triangles.len() as u32;
        for (i, &t) in triangles.iter().enumerate() {
            owner[t as usize] = (a as u32, start + i as u32);
        }
        let parts = layouts[b].parts;
        let target = &mut layouts[a];
        target.triangles.extend(triangles);
        target.corners.extend(corners);
        target.parts += parts;
        extents[a] = Extent::of(&layouts[a].corners, cost);
        alive[b] = false;
        // Only the merged chart is looked at again: also re-queuing its neighbours (a fold
        // onto the grown chart might be admitted from their side) changed no chart on the
        // scenes measured and doubled scale-10's atlas stage.
        if let Some(k) = key(&best_fold(adjacency, &layouts, &extents, &owner, a, cost, order)) {
            queue.push((k, Reverse(a)));
        }
    }
    layouts.into_iter().zip(alive).filter(|(_, alive)| *alive).map(|(layout, _)| layout).collect()
}

/// A chart's faces' area in texels and the texels it packs into, gutters included.
#[derive(Clone, Copy)]
struct Extent {
    area: f32,
    packed: f32,
}

impl Extent {
    fn of(corners: &[[Vec2; 3]], cost: ChartCost) -> Self {
        Extent { area: cost.area(corners), packed: cost.packed(cost.size(corners)) }
    }
}

/// A neighbour unfolded onto a chart: what it saves, which chart it is, and its corners
/// moved into the chart's plane.
struct Fold {
    saving: Saving,
    onto: usize,
    corners: Vec<[Vec2; 3]>,
}

/// The admitted neighbour of chart `a` that comes first in `order` when unfolded onto it.
fn best_fold(
    adjacency: &Adjacency,
    layouts: &[Layout],
    extents: &[Extent],
    owner: &[(u32, u32)],
    a: usize,
    cost: ChartCost,
    order: Order,
) -> Option<Fold> {
    let here = &layouts[a];
    let own = extents[a].packed;
    let mut grid: Option<OverlapGrid> = None;
    let mut best: Option<Fold> = None;
    for (i, &t) in here.triangles.iter().enumerate() {
        for (k, o, ok) in adjacency.shared_edges(t) {
            let (b, j) = owner[o as usize];
            let b = b as usize;
            if b == a || best.as_ref().is_some_and(|f| f.onto == b) {
                continue;
            }
            let there = &layouts[b];
            let theirs = extents[b].packed;
            // No rectangle holding both is smaller than a square of their areas: large charts
            // are turned away here before any corner is moved.
            let least = (extents[a].area + extents[b].area).sqrt() + cost.gutter as f32;
            if (own + theirs - least * least) / own.min(theirs) < UNFOLD_SAVING {
                continue;
            }
            let Some(motion) = Motion::along(adjacency, (t, k, here.corners[i]), (o, ok, there.corners[j as usize])) else {
                continue;
            };
            let moved: Vec<[Vec2; 3]> = there.corners.iter().map(|c| c.map(|p| motion.apply(p))).collect();
            let size = cost.size(&[here.corners.as_slice(), moved.as_slice()].concat());
            if size.max_element() > cost.limit {
                continue;
            }
            let texels = own + theirs - cost.packed(size);
            let saving = Saving { share: texels / own.min(theirs), texels };
            if saving.share < UNFOLD_SAVING || best.as_ref().is_some_and(|f| f.saving.key(order) >= saving.key(order)) {
                continue;
            }
            let grid = grid.get_or_insert_with(|| {
                let mut g = OverlapGrid::new(here.corners[0]);
                here.corners.iter().for_each(|c| g.insert(*c));
                g
            });
            if moved.iter().all(|c| !grid.overlaps(*c)) {
                best = Some(Fold { saving, onto: b, corners: moved });
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
