//! Packing the atlas's charts into pages: skyline packing, bottom-left, in a few orders, at
//! several page widths, with and without turning charts a quarter; the smallest pages kept.

use super::builder::{AtlasSettings, Chart, FlatChart};
use glam::UVec2;

/// Skyline packing, bottom-left, in a few orders and at several page widths: sets each
/// chart's page and origin from the packing whose pages are smallest; returns the page width,
/// height and count. Every chart keeps `gutter` texels to its neighbours and to the page
/// border. (Shelf packing, before it, left 64 % of cornell's and classroom's atlases covered;
/// docs/BENCHMARKS.md, "Atlas utilization".)
pub(super) fn pack(charts: &mut [Chart], flat: &mut [FlatChart], settings: &AtlasSettings) -> (u32, u32, u32) {
    let g = settings.gutter;
    let sizes: Vec<UVec2> = charts.iter().map(|c| c.size + UVec2::splat(g)).collect();
    let area: u64 = sizes.iter().map(|s| s.x as u64 * s.y as u64).sum();
    // Turned, a chart needs only its shorter side across the page.
    let widest = |turn: bool| sizes.iter().map(|s| if turn { s.x.min(s.y) } else { s.x }).max().unwrap_or(1) + g;
    let width_for = |slack: f64, turn: bool| ((area as f64 * slack).sqrt().ceil() as u32).max(widest(turn)).min(settings.max_size);
    let orders: Vec<Vec<usize>> = PACKING_ORDERS.iter().map(|key| packing_order(&sizes, *key)).collect();
    let (order, packing) = [false, true]
        .into_iter()
        .flat_map(|turn| orders.iter().flat_map(move |order| PACKING_SLACKS.iter().map(move |&slack| (turn, order, slack))))
        .map(|(turn, order, slack)| {
            let sizes: Vec<UVec2> = order.iter().map(|&i| sizes[i]).collect();
            (order, skyline(&sizes, width_for(slack, turn), settings.max_size, g, turn))
        })
        .min_by_key(|(_, p)| (p.pages, p.pages as u64 * p.used.x.div_ceil(4) as u64 * p.used.y.div_ceil(4) as u64))
        .expect("at least one packing is tried");
    for (&i, &(page, origin, turned)) in order.iter().zip(&packing.places) {
        if turned {
            flat[i].turn();
        }
        charts[i].page = page;
        charts[i].origin = origin;
        charts[i].size = flat[i].size;
    }
    let round4 = |v: u32| v.div_ceil(4) * 4;
    (round4(packing.used.x.max(1)).min(settings.max_size), round4(packing.used.y.max(1)).min(settings.max_size), packing.pages)
}

/// The orders charts are packed in: tallest, largest or widest first.
const PACKING_ORDERS: [fn(UVec2) -> (u64, u64); 3] =
    [|s| (s.y as u64, s.x as u64), |s| (s.x as u64 * s.y as u64, s.y as u64), |s| (s.x as u64, s.y as u64)];

/// Chart indices by `key` falling, ties by index.
fn packing_order(sizes: &[UVec2], key: fn(UVec2) -> (u64, u64)) -> Vec<usize> {
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(key(sizes[i])), i));
    order
}

/// Page widths tried, as the square root of this times the charts' area with their gutters.
const PACKING_SLACKS: [f64; 16] = [1.0, 1.03, 1.06, 1.09, 1.12, 1.15, 1.2, 1.25, 1.3, 1.4, 1.5, 1.6, 1.75, 2.0, 2.5, 3.0];

struct Packing {
    /// Per chart (in packing order), its page, origin and whether it was turned a quarter.
    places: Vec<(u32, UVec2, bool)>,
    /// The extent used on any page, gutter included.
    used: UVec2,
    pages: u32,
}

/// Places rectangles of `sizes` (gutter included) in order on pages `width` wide and at most
/// `max_height` tall: each at the lowest point of the skyline where it fits, leftmost on ties;
/// with `turn`, in whichever of its two orientations leaves the skyline lower there.
fn skyline(sizes: &[UVec2], width: u32, max_height: u32, g: u32, turn: bool) -> Packing {
    // The skyline: (x, top) steps from the left border on, each running to the next step's x.
    let fresh = || vec![(g, g)];
    let (mut steps, mut page, mut used) = (fresh(), 0, UVec2::ZERO);
    let mut places = Vec::with_capacity(sizes.len());
    let best_fit = |steps: &[(u32, u32)], size: UVec2| {
        let turned = (turn && size.x != size.y).then(|| lowest_fit(steps, UVec2::new(size.y, size.x), width, max_height)).flatten();
        let upright = lowest_fit(steps, size, width, max_height);
        match (upright, turned) {
            (Some(u), Some(t)) if t.y + size.x < u.y + size.y => Some((t, true)),
            (None, Some(t)) => Some((t, true)),
            (u, _) => u.map(|u| (u, false)),
        }
    };
    for &size in sizes {
        let (place, turned) = match best_fit(&steps, size) {
            Some(fit) => fit,
            None => {
                (steps, page) = (fresh(), page + 1);
                best_fit(&steps, size).unwrap_or((UVec2::splat(g), false))
            }
        };
        let size = if turned { UVec2::new(size.y, size.x) } else { size };
        raise(&mut steps, place, size);
        used = used.max(place + size);
        places.push((page, place, turned));
    }
    Packing { places, used, pages: page + 1 }
}

/// The lowest origin at a step's x where `size` fits under `max_height` and within `width`.
fn lowest_fit(steps: &[(u32, u32)], size: UVec2, width: u32, max_height: u32) -> Option<UVec2> {
    let mut best: Option<UVec2> = None;
    for (i, &(x, _)) in steps.iter().enumerate() {
        if x + size.x > width {
            break;
        }
        let top = steps[i..].iter().take_while(|&&(sx, _)| sx < x + size.x).map(|&(_, t)| t).max().unwrap_or(0);
        if top + size.y <= max_height && best.is_none_or(|b| top < b.y) {
            best = Some(UVec2::new(x, top));
        }
    }
    best
}

/// The skyline after a rectangle of `size` is placed at `place`.
fn raise(steps: &mut Vec<(u32, u32)>, place: UVec2, size: UVec2) {
    let (left, right) = (place.x, place.x + size.x);
    let top_at = |steps: &[(u32, u32)], x: u32| steps.iter().take_while(|&&(sx, _)| sx <= x).last().map_or(0, |&(_, t)| t);
    let after = top_at(steps, right);
    steps.retain(|&(x, _)| x < left || x > right);
    let at = steps.partition_point(|&(x, _)| x < left);
    let mut insert = vec![(left, place.y + size.y)];
    if steps.get(at).is_none_or(|&(x, _)| x > right) {
        insert.push((right, after));
    }
    steps.splice(at..at, insert);
    steps.dedup_by(|b, a| a.1 == b.1);
}
