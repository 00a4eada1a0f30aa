//! Obscurance against closed forms (Iones et al. 2003 §4; Umenhoffer et al. §3.3): a point
//! under a hemisphere, an open plane, ambient occlusion in a right-angle corner, and the
//! spectral variant's colour bleeding and 0/0 rule.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::SceneBvh;
use relume_bake::obscurance::{bake_obscurance, point_obscurance, ObscuranceMap, ObscuranceSettings, Variant};
use relume_bake::scene::Scene;
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, sphere, square, Facing};
use relume_bake::work::WorkOptions;
use std::f32::consts::PI;
use std::time::Duration;

fn settings(variant: Variant, tau: f32, l_max: f32, rays: u32) -> ObscuranceSettings {
    ObscuranceSettings { variant, tau, l_max, rays_per_texel: rays, work: WorkOptions { seed: 7, ..WorkOptions::default() } }
}

fn build(name: &str, meshes: Vec<relume_bake::scene::Mesh>, albedos: &[Vec3]) -> Scene {
    let materials = albedos.iter().enumerate().map(|(i, a)| material(&format!("m{i}"), *a, Vec3::ZERO)).collect();
    let camera = look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0);
    scene(name, meshes, materials, vec![point_light(Vec3::new(0.0, 0.5, 0.0), Vec3::ONE)], camera)
}

fn bake(scene: &Scene, density: f32, s: &ObscuranceSettings) -> (Atlas, ObscuranceMap) {
    let atlas = Atlas::build(scene, &AtlasSettings { texel_density: density, ..Default::default() }).unwrap();
    let map = bake_obscurance(scene, &SceneBvh::new(scene), &atlas, s).unwrap();
    (atlas, map)
}

/// Covered texels of one mesh (by triangle id range) and their values.
fn mesh_values(scene: &Scene, atlas: &Atlas, map: &ObscuranceMap, mesh: usize) -> Vec<Vec3> {
    let offsets = relume_bake::atlas::mesh_offsets(scene);
    let range = offsets[mesh]..offsets[mesh] + (scene.meshes[mesh].indices.len() / 3) as u32;
    atlas.texels.iter().zip(&map.values).filter(|(t, _)| t.coverage > 0.0 && range.contains(&t.triangle)).map(|(_, v)| *v).collect()
}

/// `settings` with its work options changed by `change`.
fn with_work(mut settings: ObscuranceSettings, change: impl FnOnce(&mut WorkOptions)) -> ObscuranceSettings {
    change(&mut settings.work);
    settings
}

#[test]
fn centre_of_a_closed_hemisphere_has_w_equal_to_rho_of_the_radius() {
    let radius = 1.0;
    let dome = sphere(Vec3::ZERO, radius, 5, Facing::Inward, 0);
    // A small patch at the centre of the base, facing into the dome.
    let base = square(Vec3::ZERO, Vec3::X * 0.01, Vec3::NEG_Z * 0.01, 1, 0);
    let scene = build("hemisphere", vec![dome, base], &[Vec3::splat(0.5)]);
    let s = settings(Variant::Obscurance, 0.5, 10.0, 1024);
    let expected = 1.0 - (-radius / s.tau).exp();
    let at_centre = point_obscurance(&scene, &SceneBvh::new(&scene), &s, Vec3::ZERO, Vec3::Y, 1024);
    assert!((at_centre.x / expected - 1.0).abs() < 0.01, "W = {at_centre}, rho(R) = {expected}");
    // Every dome ray is about R long, so a few rays per texel pin W down.
    let (atlas, map) = bake(&scene, 50.0, &ObscuranceSettings { rays_per_texel: 16, ..s });
    let patch = mesh_values(&scene, &atlas, &map, 1);
    assert!(!patch.is_empty());
    for w in patch {
        assert!((w.x / expected - 1.0).abs() < 0.01, "patch W = {w}, rho(R) = {expected}");
    }
}

#[test]
fn a_point_on_an_open_plane_is_fully_open() {
    let plane = square(Vec3::ZERO, Vec3::X * 10.0, Vec3::NEG_Z * 10.0, 4, 0);
    let scene = build("plane", vec![plane], &[Vec3::splat(0.5)]);
    for variant in [Variant::Obscurance, Variant::AmbientOcclusion, Variant::Spectral] {
        let (_, map) = bake(&scene, 2.0, &settings(variant, 0.3, 1.0, 64));
        assert!(map.values.iter().all(|v| *v == Vec3::ONE || *v == Vec3::ZERO), "{variant:?}");
        assert!(map.values.contains(&Vec3::ONE));
    }
}

/// A point on a floor at distance d from an infinite wall: with cosine-distributed
/// directions the wall blocks exactly those whose horizontal component towards it exceeds
/// a = d / L_max, a cosine-weighted share of (acos a - a sqrt(1 - a^2)) / pi.
#[test]
fn ambient_occlusion_in_a_right_angle_corner_matches_its_closed_form() {
    let wall = square(Vec3::new(0.0, 500.0, 0.0), Vec3::Y * 500.0, Vec3::Z * 500.0, 1, 0);
    let floor = square(Vec3::new(-500.0, 0.0, 0.0), Vec3::X * 500.0, Vec3::NEG_Z * 500.0, 1, 0);
    let scene = build("corner", vec![wall, floor], &[Vec3::splat(0.5)]);
    let bvh = SceneBvh::new(&scene);
    let s = settings(Variant::AmbientOcclusion, 1.0, 1.0, 4096);
    for d in [0.1f32, 0.5, 0.9] {
        let a = d / s.l_max;
        let expected = 1.0 - (a.acos() - a * (1.0 - a * a).sqrt()) / PI;
        let ao = point_obscurance(&scene, &bvh, &s, Vec3::new(-d, 0.0, 0.0), Vec3::Y, 4096);
        assert!((ao.x - expected).abs() < 0.005, "d = {d}: AO {} expected {expected}", ao.x);
    }
}

fn room(albedos: &[Vec3]) -> Scene {
    let walls = closed_box(Vec3::splat(-1.0), Vec3::splat(1.0), 2, Facing::Inward, 0);
    let block = closed_box(Vec3::new(-0.3, -0.95, -0.3), Vec3::new(0.3, -0.4, 0.3), 1, Facing::Outward, 1);
    build("room", vec![walls, block], albedos)
}

#[test]
fn spectral_obscurance_with_one_albedo_everywhere_is_the_scalar_obscurance() {
    let scene = room(&[Vec3::splat(0.6), Vec3::splat(0.6)]);
    let (_, scalar) = bake(&scene, 8.0, &settings(Variant::Obscurance, 0.3, 1.0, 64));
    let (_, spectral) = bake(&scene, 8.0, &settings(Variant::Spectral, 0.3, 1.0, 64));
    for (a, b) in scalar.values.iter().zip(&spectral.values) {
        assert!((*a - *b).abs().max_element() < 1e-5, "{a} vs {b}");
    }
}

#[test]
fn spectral_obscurance_bleeds_colour_and_takes_zero_over_zero_as_zero() {
    // No blue anywhere: the closed (box-bounded) directions give 0/0 in blue, counted 0.
    // The red block makes the floor around it redder than the walls far from it.
    let scene = room(&[Vec3::new(0.5, 0.5, 0.0), Vec3::new(0.9, 0.1, 0.0)]);
    let s = settings(Variant::Spectral, 0.3, 100.0, 64);
    let (atlas, map) = bake(&scene, 8.0, &s);
    let covered: Vec<Vec3> = atlas.texels.iter().zip(&map.values).filter(|(t, _)| t.coverage > 0.0).map(|(_, v)| *v).collect();
    assert!(covered.iter().all(|v| v.z == 0.0 && v.x > 0.0), "the room is closed: every blue value must be 0");
    let floor_near_block = point_obscurance(&scene, &SceneBvh::new(&scene), &s, Vec3::new(0.4, -1.0, 0.0), Vec3::Y, 1024);
    assert!(floor_near_block.x > floor_near_block.y * 1.05, "no red bleeding: {floor_near_block}");
}

#[test]
fn the_bake_is_deterministic_across_thread_counts_and_honours_its_time_limit() {
    let scene = room(&[Vec3::splat(0.6), Vec3::splat(0.3)]);
    let one = bake(&scene, 8.0, &with_work(settings(Variant::Obscurance, 0.3, 1.0, 64), |w| w.threads = Some(1))).1;
    let two = bake(&scene, 8.0, &with_work(settings(Variant::Obscurance, 0.3, 1.0, 64), |w| w.threads = Some(2))).1;
    assert_eq!(one.values, two.values);
    let limited = bake(&scene, 8.0, &with_work(settings(Variant::Obscurance, 0.3, 1.0, 1024), |w| w.time_limit = Some(Duration::ZERO))).1;
    assert_eq!(limited.rays_per_texel, 32, "one whole pass, then the limit");
}

#[test]
fn impossible_parameters_are_refused() {
    let scene = room(&[Vec3::splat(0.6), Vec3::splat(0.3)]);
    let atlas = Atlas::build(&scene, &AtlasSettings::default()).unwrap();
    let bvh = SceneBvh::new(&scene);
    for (s, word) in [
        (settings(Variant::Obscurance, 0.0, 1.0, 8), "tau"),
        (settings(Variant::Obscurance, 0.3, f32::NAN, 8), "l_max"),
        (settings(Variant::Obscurance, 0.3, 1.0, 0), "rays"),
    ] {
        let error = bake_obscurance(&scene, &bvh, &atlas, &s).unwrap_err();
        assert!(error.contains(word), "{error}");
    }
}
