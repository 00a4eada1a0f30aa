//! Zones and light clustering (004 §4.1-4.2): complete linkage keeps together only lights
//! whose metric is below 1 and stops when no groups can merge; single linkage keeps the
//! connected components of the pairs below 1; lights that do not see each
//! other never merge; identical responses merge and distinct ones do not; zones cut the lights
//! each keeps; the zoned, clustered transfer survives the section; the same bytes at any
//! thread count.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, CloudGrid, LightCloud, LightCloudBakeSettings, Linkage, Reduced, Reduction};
use relume_bake::scene::Scene;
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, sphere, Facing};
use relume_bake::work::WorkOptions;

fn gathered(s: &Scene, grid: CloudGrid, samples: u32) -> LightCloud {
    let settings = LightCloudBakeSettings {
        grid: Some(grid),
        directions: 0,
        samples,
        emission: 1,
        work: WorkOptions { seed: 3, ..WorkOptions::default() },
    };
    lc::bake(s, &SceneBvh::new(s), &settings).expect("bake")
}

fn reduce(s: &Scene, cloud: &LightCloud, zones: usize, weights: Option<(f32, f32)>) -> Reduced {
    lc::reduce(s, &SceneBvh::new(s), cloud, Reduction { zones, weights, linkage: Linkage::Complete }).expect("reduce")
}

/// A 4 m room split by a wall at x = 2 with a door-less gap nowhere: lights on either side
/// never see the other side.
fn two_rooms() -> Scene {
    let m = material("white", Vec3::splat(0.6), Vec3::ZERO);
    let room = closed_box(Vec3::ZERO, Vec3::new(4.0, 2.0, 2.0), 4, Facing::Inward, 0);
    let wall = closed_box(Vec3::new(1.95, 0.0, 0.0), Vec3::new(2.05, 2.0, 2.0), 2, Facing::Outward, 0);
    let camera = look_at(Vec3::new(1.0, 1.0, 1.0), Vec3::new(3.0, 1.0, 1.0), Vec3::Y, 1.0);
    scene("two rooms", vec![room, wall], vec![m], vec![point_light(Vec3::new(1.0, 1.0, 1.0), Vec3::ONE)], camera)
}

const ROOMS_GRID: CloudGrid = CloudGrid { min: Vec3::new(0.0, 0.0, 0.0), max: Vec3::new(4.0, 2.0, 2.0), counts: [8, 2, 2] };

/// A deterministic symmetric metric in [0, 2) with a zero diagonal.
fn random_metric(n: usize, seed: u64) -> Vec<f32> {
    let mut state = seed;
    let mut next = || {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32 * 2.0
    };
    let mut metric = vec![0f32; n * n];
    for j in 0..n {
        for k in j + 1..n {
            let value = next();
            metric[j * n + k] = value;
            metric[k * n + j] = value;
        }
    }
    metric
}

#[test]
fn complete_linkage_keeps_only_close_pairs_together_and_leaves_no_mergeable_groups() {
    for (n, seed) in [(40, 1), (60, 2), (25, 3)] {
        let metric = random_metric(n, seed);
        let groups = lc::link(n, &metric, Linkage::Complete);
        let mut all: Vec<u32> = groups.concat();
        all.sort_unstable();
        assert_eq!(all, (0..n as u32).collect::<Vec<_>>(), "the groups partition the lights");
        for g in &groups {
            for &a in g {
                for &b in g {
                    assert!(
                        a == b || metric[a as usize * n + b as usize] < 1.0,
                        "{a} and {b} share a group at {}",
                        metric[a as usize * n + b as usize]
                    );
                }
            }
        }
        // Complete linkage stops only when every two groups have a pair at 1 or more.
        for (i, g) in groups.iter().enumerate() {
            for h in &groups[i + 1..] {
                let far = g.iter().any(|&a| h.iter().any(|&b| metric[a as usize * n + b as usize] >= 1.0));
                assert!(far, "groups {g:?} and {h:?} could still merge");
            }
        }
        assert!(groups.len() < n && groups.len() > 1, "{n} lights in {} groups: the metric should merge some, not all", groups.len());
        assert_eq!(groups, lc::link(n, &metric, Linkage::Complete), "deterministic");
    }
}

/// Single linkage's groups are the connected components of the pairs below 1, found here by
/// a plain flood fill; a sparse metric (mostly far pairs) leaves several.
#[test]
fn single_linkage_keeps_the_components_of_the_close_pairs() {
    for (n, seed) in [(40, 4), (60, 5), (25, 6)] {
        let metric: Vec<f32> = random_metric(n, seed).into_iter().map(|m| if m < 0.04 { m * 10.0 } else { m + 1.0 }).collect();
        let mut component = vec![usize::MAX; n];
        for start in 0..n {
            if component[start] != usize::MAX {
                continue;
            }
            let mut stack = vec![start];
            component[start] = start;
            while let Some(j) = stack.pop() {
                for k in 0..n {
                    if k != j && metric[j * n + k] < 1.0 && component[k] == usize::MAX {
                        component[k] = start;
                        stack.push(k);
                    }
                }
            }
        }
        let mut expected: Vec<Vec<u32>> = Vec::new();
        for start in 0..n {
            let members: Vec<u32> = (0..n as u32).filter(|&j| component[j as usize] == start).collect();
            if !members.is_empty() {
                expected.push(members);
            }
        }
        let groups = lc::link(n, &metric, Linkage::Single);
        assert_eq!(groups, expected, "{n} lights");
        assert!(groups.len() < n && groups.len() > 1, "{n} lights in {} groups: the metric should merge some, not all", groups.len());
        let complete = lc::link(n, &metric, Linkage::Complete);
        assert!(complete.len() >= groups.len(), "complete linkage never keeps fewer groups: {} against {}", complete.len(), groups.len());
    }
}

/// With no weight on distance or response, eq. (9) is the visibility term alone: every light
/// merges with every light it sees and with none it does not.
#[test]
fn lights_that_do_not_see_each_other_never_merge() {
    let s = two_rooms();
    let cloud = gathered(&s, ROOMS_GRID, 1);
    assert_eq!(cloud.lights.len(), 32, "no grid point lies inside the wall");
    let reduced = reduce(&s, &cloud, 1, Some((0.0, 0.0)));
    let groups = &reduced.groups[0];
    assert_eq!(groups.len(), 2, "one light per room: {groups:?}");
    for g in groups {
        let left = cloud.lights[g[0] as usize].x < 2.0;
        assert!(g.iter().all(|&j| (cloud.lights[j as usize].x < 2.0) == left), "a group spans the wall: {g:?}");
    }
    for p in &reduced.cloud.lights {
        assert!((p.x - 1.0).abs() < 0.3 || (p.x - 3.0).abs() < 0.3, "a merged light at its room's mean: {p}");
    }
}

/// Inside the closed sphere every cloud light's transfer is the same up to the gather's noise:
/// with no weight on distance and a small one on response, the whole cloud merges into one
/// light at its mean, carrying the mean transfer; with a large weight on response, the noise
/// keeps every light apart.
#[test]
fn identical_responses_merge_into_one_light_with_the_mean_transfer() {
    let m = material("wall", Vec3::splat(0.5), Vec3::ZERO);
    let camera = look_at(Vec3::new(0.0, 0.0, 0.5), Vec3::ZERO, Vec3::Y, 1.0);
    let s = scene("sphere", vec![sphere(Vec3::ZERO, 1.0, 3, Facing::Inward, 0)], vec![m], vec![point_light(Vec3::ZERO, Vec3::ONE)], camera);
    let cloud = gathered(&s, CloudGrid { min: Vec3::splat(-0.6), max: Vec3::splat(0.6), counts: [2, 2, 2] }, 8);
    for zones in [1, 4] {
        let merged = reduce(&s, &cloud, zones, Some((0.0, 0.5)));
        assert_eq!(merged.cloud.zone_count(), zones);
        assert_eq!(merged.cloud.lights.len(), zones, "one light a zone: {:?}", merged.groups);
        assert!(merged.cloud.lights.iter().all(|p| p.length() < 1e-6), "at the cloud's mean: {:?}", merged.cloud.lights);
        let (before, after) = (lc::Columns::new(&cloud), lc::Columns::new(&merged.cloud));
        for v in 0..cloud.vertex_count() {
            let mean = (0..8).fold(Vec3::ZERO, |s, j| s + before.column(v, j)) / 8.0;
            let cluster = merged.cloud.assignment[v];
            // One light a zone: the vertex's zone's light is the zone's index.
            let zone = (0..zones).find(|&z| merged.cloud.zone_clusters[z + 1] > cluster).unwrap();
            assert!((after.column(v, zone) - mean).abs().max_element() < 1e-6, "vertex {v}");
        }
        assert!(merged.relative_error > 0.0 && merged.relative_error < 0.3, "the gather's noise: {}", merged.relative_error);
        let apart = reduce(&s, &cloud, zones, Some((0.0, 1e6)));
        assert_eq!(apart.cloud.lights.len(), 8 * zones);
        assert_eq!(apart.relative_error, 0.0);
    }
    // The distance weight alone, over a diagonal of 2 sqrt(3): with w1 = 4, lights 0.6 and 0.85
    // apart (an edge, a face's diagonal of the grid) may merge, 1.04 apart (opposite corners)
    // not: groups of at most four.
    let by_distance = reduce(&s, &cloud, 1, Some((4.0, 0.0)));
    assert!(by_distance.groups[0].len() > 1 && by_distance.groups[0].len() < 8, "{:?}", by_distance.groups);
}

/// 004 Fig. 3: a zone's metric is a maximum over fewer vertices, so zones keep fewer lights.
#[test]
fn zones_keep_fewer_lights_than_the_whole_scene() {
    let s = two_rooms();
    let cloud = gathered(&s, ROOMS_GRID, 8);
    let per_zone = |zones: usize| {
        let r = reduce(&s, &cloud, zones, Some((0.5, 8.0)));
        r.cloud.lights.len() as f64 / zones as f64
    };
    let (one, eight) = (per_zone(1), per_zone(8));
    println!("lights per zone: {one} in one zone, {eight} in eight");
    assert!(eight < one, "{eight} lights per zone in 8 zones against {one} in 1");
}

#[test]
fn zones_split_the_longest_axis_at_the_median() {
    // 100 points along x, jittered in y and z: four zones of 25 consecutive points.
    let points: Vec<Vec3> = (0..100).map(|i| Vec3::new(i as f32 * 0.1, (i % 3) as f32 * 0.01, (i % 5) as f32 * 0.01)).collect();
    let zones = lc::split_zones(&points, 4);
    assert_eq!(zones.len(), 4);
    let mut firsts: Vec<u32> = zones.iter().map(|z| z[0]).collect();
    firsts.sort_unstable();
    assert_eq!(firsts, [0, 25, 50, 75]);
    for z in &zones {
        assert_eq!(z.len(), 25);
        assert!(z.windows(2).all(|w| w[1] == w[0] + 1), "{z:?}");
    }
    assert_eq!(lc::split_zones(&points[..1], 4).len(), 1, "one point cannot be split");
}

/// A zoned, clustered, compressed transfer reads back as written; the same bytes at 1 and 2
/// threads.
#[test]
fn a_zoned_transfer_round_trips_and_is_the_same_at_any_thread_count() {
    use relume_bake::artifact::{Artifact, BakeOutput};
    use serde_json::json;
    let s = two_rooms();
    let cloud = gathered(&s, ROOMS_GRID, 2);
    let in_pool = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| lc::compress(&reduce(&s, &cloud, 3, Some((0.5, 8.0))).cloud, 6, lc::Vectors::Each(2), false).unwrap())
    };
    let zoned = in_pool(1);
    assert_eq!(zoned, in_pool(2));
    assert_eq!(zoned.zone_count(), 3);
    assert!(zoned.cluster_count() >= 3);
    let dir = std::env::temp_dir().join(format!("relume-light-clustering-{}", std::process::id()));
    let sections = vec![lc::section(&zoned, json!({}))];
    BakeOutput { method: "light-cloud", scene: Some(&s), parameters: json!({}), sections, stats: json!({}) }.write(&dir).unwrap();
    assert_eq!(lc::read(&Artifact::read(&dir).unwrap(), &s).unwrap(), zoned);
    // Zone starts out of order are refused, naming the file and the zones.
    let mut disordered = zoned.clone();
    disordered.zone_lights.swap(1, 2);
    let sections = vec![lc::section(&disordered, json!({}))];
    BakeOutput { method: "light-cloud", scene: Some(&s), parameters: json!({}), sections, stats: json!({}) }.write(&dir).unwrap();
    let error = lc::read(&Artifact::read(&dir).unwrap(), &s).unwrap_err().to_string();
    assert!(error.contains("light-cloud.bin") && error.contains("each zone needs lights and clusters"), "{error}");
    std::fs::remove_dir_all(&dir).unwrap();
}
