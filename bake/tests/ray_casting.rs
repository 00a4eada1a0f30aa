//! The ray set `relume rays` times, and (with the `embree` feature) Embree against relume's
//! BVH on the same triangles and rays: the yardstick must trace the same scene.

use relume_bake::bvh::SceneBvh;
use relume_bake::ray_bench::{ray_set, time_rays, RaySet};
use relume_bake::scene::Scene;
use relume_bake::tessellation::Tessellation;
use std::path::Path;

fn shipped(name: &str) -> Scene {
    relume_bake::gltf_load::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.gltf"))).unwrap().scene
}

fn set_at(scene: &Scene, threads: usize) -> RaySet {
    let bvh = SceneBvh::new(scene);
    relume_bake::work::with_threads(Some(threads), || ray_set(scene, &bvh, 24, 16, 3, 7))
}

/// The set is seeded per pixel: the same rays at any thread count, and every path of a closed
/// room meets a wall at each bounce (a camera ray per pixel, then one ray a bounce).
#[test]
fn the_ray_set_is_the_same_at_one_and_two_threads_and_a_closed_room_keeps_its_paths() {
    let scene = shipped("glossy-enclosure");
    let (one, two) = (set_at(&scene, 1), set_at(&scene, 2));
    assert_eq!(one.closest, two.closest);
    assert_eq!(one.shadow, two.shadow);
    assert_eq!(one.closest.len(), 24 * 16 * 4, "the room is closed: no path ends early");
    let most = 24 * 16 * 4 * scene.local_lights().count();
    assert!(one.shadow.len() > most / 4 && one.shadow.len() <= most, "at most one shadow ray a hit and light: {}", one.shadow.len());
    let bvh = SceneBvh::new(&scene);
    let (closest, shadow) = time_rays(&bvh, &one, Some(2), 1);
    assert_eq!(closest.hits, closest.rays, "every ray in a closed room hits");
    assert!(shadow.hits > 0 && shadow.hits < shadow.rays, "some hits are lit, some shadowed: {}", shadow.hits);
}

/// Subdividing changes the triangles, not the surfaces: the same rays hit at the same
/// distances (to rounding) in the scene split 4 x 4.
#[test]
fn a_subdivided_scene_answers_the_same_rays_alike() {
    let scene = shipped("classroom");
    let fine = Tessellation::uniform(&scene, 4).unwrap().apply(&scene);
    assert_eq!(fine.triangle_count(), 16 * scene.triangle_count());
    let (coarse_bvh, fine_bvh) = (SceneBvh::new(&scene), SceneBvh::new(&fine));
    let set = ray_set(&scene, &coarse_bvh, 32, 24, 2, 1);
    let (closest, shadow) = relume_bake::ray_bench::agreement(&coarse_bvh, &fine_bvh, &set, 1e-4);
    let share = |n: usize, of: usize| n as f64 / of as f64;
    assert!(share(closest, set.closest.len()) > 0.999, "{closest} of {} closest hits alike", set.closest.len());
    assert!(share(shadow, set.shadow.len()) > 0.999, "{shadow} of {} shadow rays alike", set.shadow.len());
}

/// Embree traces the same triangles: it answers all but a few rays (those along shared edges,
/// which either side may take) as relume's BVH does.
#[cfg(feature = "embree")]
#[test]
fn embree_and_relume_answer_the_same_rays_alike() {
    use relume_bake::embree::EmbreeScene;
    for name in ["cornell", "glossy-enclosure"] {
        let scene = shipped(name);
        let bvh = SceneBvh::new(&scene);
        let embree = EmbreeScene::new(&scene, Some(2)).unwrap();
        let set = ray_set(&scene, &bvh, 48, 32, 3, 3);
        let (closest, shadow) = relume_bake::ray_bench::agreement(&bvh, &embree, &set, 1e-4);
        assert!(closest as f64 >= 0.999 * set.closest.len() as f64, "{name}: {closest} of {} closest hits alike", set.closest.len());
        assert!(shadow as f64 >= 0.999 * set.shadow.len() as f64, "{name}: {shadow} of {} shadow rays alike", set.shadow.len());
    }
}
