//! A cloud baked zone by zone (004 §4.2, one zone's gather in memory at a time): the same
//! cloud as the whole gather reduced and compressed at once, whether the zones' rows wait in
//! memory or in a scratch file.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, CloudGrid, LightCloudBakeSettings, Reduction, ZoneRows, ZoneSettings};
use relume_bake::scene::Scene;
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, Facing};
use relume_bake::work::WorkOptions;
use serde_json::json;

/// A 4 m room with a pillar, lit by a point light.
fn room() -> Scene {
    let m = material("white", Vec3::splat(0.6), Vec3::ZERO);
    let room = closed_box(Vec3::ZERO, Vec3::new(4.0, 2.0, 2.0), 6, Facing::Inward, 0);
    let pillar = closed_box(Vec3::new(1.8, 0.0, 0.8), Vec3::new(2.2, 2.0, 1.2), 2, Facing::Outward, 0);
    let camera = look_at(Vec3::new(1.0, 1.0, 1.0), Vec3::new(3.0, 1.0, 1.0), Vec3::Y, 1.0);
    scene("room", vec![room, pillar], vec![m], vec![point_light(Vec3::new(1.0, 1.0, 1.0), Vec3::ONE)], camera)
}

fn bytes(cloud: &lc::LightCloud) -> Vec<(String, Vec<u8>)> {
    lc::section(cloud, json!({})).files
}

/// A gathered cloud of `directions` directions besides the grid, reduced into `zones` zones.
fn settings(directions: usize) -> LightCloudBakeSettings {
    LightCloudBakeSettings {
        grid: Some(CloudGrid { min: Vec3::new(0.2, 0.2, 0.2), max: Vec3::new(3.8, 1.8, 1.8), counts: [6, 2, 2] }),
        directions,
        samples: 8,
        emission: 1,
        work: WorkOptions { seed: 5, ..WorkOptions::default() },
    }
}

/// Light clustering merges some lights, compressed with D vectors each or shared, uncompressed,
/// without light clustering, with directions: every way the same bytes as the whole cloud.
#[test]
fn a_cloud_baked_zone_by_zone_is_the_whole_cloud_reduced_and_compressed() {
    let s = room();
    let bvh = SceneBvh::new(&s);
    let cases = [
        (0, Some((0.5, 2.0)), Some((6, lc::Vectors::Each(2)))),
        (0, Some((0.5, 2.0)), Some((6, lc::Vectors::Shared(2)))),
        (0, Some((0.5, 2.0)), None),
        (8, Some((0.5, 2.0)), Some((6, lc::Vectors::Each(2)))),
        (0, None, Some((6, lc::Vectors::Each(3)))),
    ];
    for (directions, weights, compression) in cases {
        let case = format!("{directions} directions, weights {weights:?}, {compression:?}");
        let settings = settings(directions);
        let reduction = Reduction { zones: 5, weights, linkage: lc::Linkage::Complete };
        let gathered = lc::bake(&s, &bvh, &settings).unwrap();
        let reduced = lc::reduce(&s, &bvh, &gathered, reduction).unwrap();
        let whole = compression.map(|(c, v)| lc::compress(&reduced.cloud, c, v, false).unwrap());
        if weights.is_some() {
            let kept = (reduced.cloud.lights.len(), 5 * gathered.lights.len());
            assert!(kept.0 < kept.1, "{case}: light clustering merged some lights: {kept:?}");
        }

        let gatherer = lc::Gatherer::new(&s, &bvh, &settings).unwrap();
        let zones = lc::split_zones(&lc::vertex_positions(&s), reduction.zones);
        let zone_settings = ZoneSettings { reduction, compression, variance_components: None };
        for spill in [false, true] {
            let mut store = ZoneRows::new(spill).unwrap();
            let (taken, scale) = lc::gather_zones(&gatherer, &zones, settings.samples, &mut store).unwrap();
            assert_eq!((taken, scale), (8, gathered.terms.iter().fold(0f32, |m, &x| m.max(x))), "{case}");
            let shape = gatherer.shape(taken, Vec::new());
            let zoned = lc::reduce_zones(&s, &bvh, &shape, (&zones, store, scale), &zone_settings, false).unwrap();
            let expected = whole.as_ref().unwrap_or(&reduced.cloud);
            assert!(bytes(&zoned.cloud) == bytes(expected), "{case}: zone by zone (scratch file: {spill}) differs from the whole cloud");
            let clustering = (zoned.clustering_error, reduced.relative_error);
            assert!((clustering.0 - clustering.1).abs() < 1e-12, "{case}: {clustering:?}");
            let error = whole.as_ref().map_or(0.0, |w| lc::relative_error(&reduced.cloud, w));
            assert!((zoned.error - error).abs() < 1e-12, "{case}: {} against {error}", zoned.error);
        }
    }
}
