//! The light cloud's directions (a directional light, the sun through an opening): a
//! direction's gathered transfer is that of a point light so far off along it that its light is
//! parallel; light clustering never merges a direction; the section round-trips them; a user's
//! directional light stands on the nearest directions by angle, and is refused by a cloud with
//! none.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, CloudGrid, CloudWeight, LightCloud, LightCloudBakeSettings, Weigher};
use relume_bake::scene::{Light, LightKind, Scene};
use relume_bake::testing::{look_at, material, point_light, scene, square};
use relume_bake::work::WorkOptions;

/// A 2 x 2 m floor walled 1 m high, open to the sky.
fn open_box() -> Scene {
    let walls = [
        (Vec3::ZERO, Vec3::X, Vec3::NEG_Z),
        (Vec3::new(0.0, 0.5, -1.0), Vec3::X, Vec3::Y * 0.5),
        (Vec3::new(0.0, 0.5, 1.0), Vec3::Y * 0.5, Vec3::X),
        (Vec3::new(-1.0, 0.5, 0.0), Vec3::Y * 0.5, Vec3::Z),
        (Vec3::new(1.0, 0.5, 0.0), Vec3::Z, Vec3::Y * 0.5),
    ];
    let meshes = walls.iter().map(|&(c, u, v)| square(c, u, v, 4, 0)).collect();
    let camera = look_at(Vec3::new(0.0, 0.5, 0.9), Vec3::ZERO, Vec3::Y, 1.0);
    scene("open box", meshes, vec![material("wall", Vec3::splat(0.6), Vec3::ZERO)], vec![sun(Vec3::NEG_Y)], camera)
}

fn sun(direction: Vec3) -> Light {
    Light { name: "sun".into(), kind: LightKind::Directional, direction, ..point_light(Vec3::ZERO, Vec3::ONE) }
}

const DIRECTIONS: usize = 16;
/// The direction the test's far point light stands along (its light comes in at 36 degrees from
/// the zenith, onto the floor and one wall).
const ALONG: usize = 1;
/// The far point light's distance, metres.
const FAR: f32 = 1.0e4;

/// The open box's cloud: one point light FAR away against direction `ALONG`, and the 16
/// directions, with `emission` functions a light.
fn gathered(emission: usize) -> LightCloud {
    let s = open_box();
    let far = -lc::directions(DIRECTIONS)[ALONG] * FAR;
    let grid = CloudGrid { min: far - 0.01, max: far + 0.01, counts: [1, 1, 1] };
    let settings = LightCloudBakeSettings {
        grid: Some(grid),
        directions: DIRECTIONS,
        samples: 16,
        emission,
        work: WorkOptions { seed: 11, ..WorkOptions::default() },
    };
    lc::bake(&s, &SceneBvh::new(&s), &settings).expect("bake")
}

/// Parallel light is the limit of a point light's as it recedes: the direction's column equals
/// the far light's times its distance squared (same paths: the gather's random numbers are
/// the vertex's). The directions' other emission columns are zero, and directions from below
/// the floor give the floor nothing.
#[test]
fn a_direction_gathers_what_a_point_light_far_along_it_gives() {
    let cloud = gathered(4);
    assert_eq!((cloud.lights.len(), cloud.directions), (1 + DIRECTIONS, DIRECTIONS));
    assert!(cloud.is_direction(1) && !cloud.is_direction(0));
    let columns = lc::Columns::new(&cloud);
    let (mut worst, mut largest, mut difference, mut total) = (0f32, 0f32, 0f64, 0f64);
    for v in 0..cloud.vertex_count() {
        let (point, direction) = (columns.column(v, 0) * FAR * FAR, columns.column(v, 4 * (1 + ALONG)));
        worst = worst.max((point - direction).abs().max_element());
        largest = largest.max(direction.max_element());
        difference += (point - direction).abs().x as f64;
        total += direction.x as f64;
        for j in 1..=DIRECTIONS {
            assert!((1..4).all(|f| columns.column(v, 4 * j + f) == Vec3::ZERO), "vertex {v}, direction {j}");
        }
    }
    let relative = difference / total;
    println!("largest direction transfer {largest:.4} lux per lux; from the far point light's: largest difference {worst:.2e}, summed {relative:.2e} of the sum");
    assert!(largest > 0.05, "the sun's light bounces in the box: {largest}");
    assert!(relative < 1e-3, "{relative}");
}

/// Light clustering (two zones) keeps every direction in every zone, the zones' clouds are
/// valid, and the section reads back what was written.
#[test]
fn light_clustering_keeps_the_directions_and_the_section_round_trips() {
    use relume_bake::artifact::{Artifact, BakeOutput};
    let s = open_box();
    let cloud = gathered(1);
    let reduced =
        lc::reduce(&s, &SceneBvh::new(&s), &cloud, lc::Reduction { zones: 2, weights: Some((0.5, 20.0)), linkage: lc::Linkage::Complete })
            .unwrap();
    let reduced = reduced.cloud;
    assert_eq!((reduced.zone_count(), reduced.directions), (2, DIRECTIONS));
    for z in 0..2 {
        let tail = &reduced.lights[reduced.zone_light_range(z)];
        assert_eq!(&tail[tail.len() - DIRECTIONS..], &lc::directions(DIRECTIONS)[..]);
    }
    let compressed = lc::compress(&reduced, 4, lc::Vectors::Each(2), false).unwrap();
    let dir = std::env::temp_dir().join(format!("relume-light-cloud-directions-{}", std::process::id()));
    let sections = vec![lc::section(&compressed, serde_json::json!({}))];
    BakeOutput { method: "light-cloud", scene: Some(&s), parameters: serde_json::json!({}), sections, stats: serde_json::json!({}) }
        .write(&dir)
        .unwrap();
    assert_eq!(lc::read(&Artifact::read(&dir).unwrap(), &s).unwrap(), compressed);
    std::fs::remove_dir_all(&dir).unwrap();
    let mut uneven = compressed.clone();
    uneven.lights[0] = Vec3::new(0.0, 2.0, 0.0);
    uneven.directions = reduced.zone_light_range(0).len();
    assert!(uneven.validate().unwrap_err().contains("directions"), "zones that end differently are refused");
}

/// A cloud of points (a 2 x 2 x 2 grid) and 64 directions in one zone.
fn mixed_cloud() -> (Vec<Vec3>, Weigher) {
    let mut cloud = CloudGrid { min: Vec3::ZERO, max: Vec3::splat(2.0), counts: [2, 2, 2] }.points();
    cloud.extend(lc::directions(64));
    let weigher = Weigher::new(cloud.len(), 4).unwrap().with_directions(64, 3).unwrap();
    (cloud, weigher)
}

fn weigh(weigher: &mut Weigher, cloud: &[Vec3], lights: &[Light]) -> (usize, Vec<CloudWeight>) {
    let mut out = Vec::new();
    let unseen = weigher.weigh(cloud, lights, |_, _| true, &mut out);
    (unseen, out)
}

/// A directional light stands on the 3 directions nearest it, the nearest weighed most, its
/// weights summing to its illuminance and moving little as it turns a little; a point light
/// stands on points only; a cloud without directions sees no directional light.
#[test]
fn a_directional_light_stands_on_the_nearest_directions_by_angle() {
    let (cloud, mut weigher) = mixed_cloud();
    let lux = Vec3::new(3.0, 2.0, 1.0);
    let direction = Vec3::new(0.3, -1.0, 0.2).normalize();
    let (unseen, weights) = weigh(&mut weigher, &cloud, &[Light { intensity: lux, ..sun(direction) }]);
    assert_eq!((unseen, weights.len()), (0, 3), "{weights:?}");
    assert!(weights.iter().all(|w| w.column >= 8), "directions only: {weights:?}");
    let sum = weights.iter().fold(Vec3::ZERO, |s, w| s + w.weight);
    assert!((sum - lux).abs().max_element() < 1e-5, "{sum}");
    let nearest = (8..cloud.len()).max_by(|&a, &b| cloud[a].dot(direction).total_cmp(&cloud[b].dot(direction))).unwrap();
    let heaviest = weights.iter().max_by(|a, b| a.weight.x.total_cmp(&b.weight.x)).unwrap();
    assert_eq!(heaviest.column as usize, nearest);
    let turned = (direction + Vec3::new(0.002, 0.0, 0.0)).normalize();
    let (_, after) = weigh(&mut weigher, &cloud, &[Light { intensity: lux, ..sun(turned) }]);
    let moved = cloud_change(&weights, &after);
    assert!(moved < 0.05 * lux.x, "a 0.1 degree turn moved {moved} lux of weight");
    let (_, points) = weigh(&mut weigher, &cloud, &[point_light(Vec3::ONE, Vec3::ONE)]);
    assert!(!points.is_empty() && points.iter().all(|w| w.column < 8), "{points:?}");
    let mut without = Weigher::new(8, 4).unwrap();
    let (unseen, none) = weigh(&mut without, &cloud[..8], &[sun(direction)]);
    assert_eq!((unseen, none.len()), (1, 0));
    assert!(Weigher::new(8, 4).unwrap().with_directions(9, 3).is_err(), "more directions than lights");
    assert!(Weigher::new(72, 4).unwrap().with_directions(64, 0).is_err());
}

/// The total change of the red weights between two weighings.
fn cloud_change(before: &[CloudWeight], after: &[CloudWeight]) -> f32 {
    let at = |ws: &[CloudWeight], c: u32| ws.iter().find(|w| w.column == c).map_or(0.0, |w| w.weight.x);
    let columns: std::collections::BTreeSet<u32> = before.iter().chain(after).map(|w| w.column).collect();
    columns.iter().map(|&c| (at(before, c) - at(after, c)).abs()).sum()
}

/// A cloud without directions refuses a directional light by name, naming the flag; with
/// directions, or for point and spot lights, nothing is refused.
#[test]
fn a_cloud_without_directions_refuses_a_directional_light() {
    let lights = [point_light(Vec3::ZERO, Vec3::ONE), sun(Vec3::NEG_Y)];
    let e = lc::refuse_lights(&lights, 0).unwrap_err();
    assert!(e.contains("\"sun\" is a directional light") && e.contains("--directions"), "{e}");
    assert!(lc::refuse_lights(&lights, 64).is_ok() && lc::refuse_lights(&lights[..1], 0).is_ok());
}

/// The directions are unit vectors spread evenly: every one has a neighbour within 40 degrees
/// at 16 and within 20 at 128, the first points most nearly down, and they sum to almost
/// nothing.
#[test]
fn the_directions_cover_the_sphere() {
    for (count, spacing) in [(16usize, 40f32), (128, 20.0)] {
        let d = lc::directions(count);
        assert!(d.iter().all(|v| (v.length() - 1.0).abs() < 1e-5));
        assert!(d.iter().skip(1).all(|v| v.y > d[0].y));
        assert!(d.iter().fold(Vec3::ZERO, |s, v| s + *v).length() < 0.1 * count as f32);
        for probe in lc::directions(1000) {
            let nearest = d.iter().map(|v| v.dot(probe)).fold(-1f32, f32::max).acos().to_degrees();
            assert!(nearest < spacing, "{count}: {probe} is {nearest} degrees from every direction");
        }
    }
}
