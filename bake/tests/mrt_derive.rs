//! Modular radiance transfer's block proxy derived from a scene that declares none: on the
//! shipped levels without their declaration, against what they declare.
#![cfg(feature = "baking")]

use relume_bake::bvh::SceneBvh;
use relume_bake::mrt::derive::derive;
use relume_bake::mrt::proxy::Proxy;
use relume_bake::scene::Scene;

fn load(name: &str) -> Scene {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.gltf"));
    relume_bake::gltf_load::load(&path).unwrap().scene
}

/// The scene without its `extras.relume.mrt`, derived, beside its declared proxy.
fn derived_and_declared(name: &str) -> (relume_bake::mrt::derive::Derived, Proxy) {
    let mut scene = load(name);
    let declared = Proxy::of(&scene).unwrap();
    scene.settings.blocks.remove("mrt");
    (derive(&scene, &SceneBvh::new(&scene)).unwrap(), declared)
}

/// A maze of grid cells (002 Table 3's levels) gives its grid back: the same blocks, the same
/// joins, every mesh on a block face, and a grid declaration.
#[test]
fn a_maze_models_derived_proxy_is_its_grid() {
    for name in ["mrt-cube", "mrt-corridor", "mrt-maze", "mrt-maze-large"] {
        let (derived, declared) = derived_and_declared(name);
        println!("{name}: {}", derived.declared);
        assert_eq!(derived.proxy.corners, declared.corners, "{name}");
        assert_eq!(derived.proxy.level(), declared.level(), "{name}");
        assert!(derived.dynamic.is_empty() && derived.split.is_none(), "{name}: {:?}", derived.dynamic);
        assert!(derived.declared.get("grid").is_some(), "{name}: {}", derived.declared);
    }
}

#[test]
fn the_caves_warped_blocks_are_found_on_its_walls() {
    let (derived, declared) = derived_and_declared("mrt-cave");
    println!("{}", derived.declared);
    println!(
        "derived {} blocks, declared {}; dynamic {:?}; split into {:?} vertices",
        derived.proxy.corners.len(),
        declared.corners.len(),
        derived.dynamic,
        derived.split.as_ref().map(|s| s.vertex_count())
    );
    let near = |p: glam::DVec3| declared.corners.iter().flatten().map(|q| q.distance(p)).fold(f64::INFINITY, f64::min);
    let worst = derived.proxy.corners.iter().flatten().map(|p| near(*p)).fold(0.0, f64::max);
    println!("largest distance of a derived corner from a declared one: {worst:.4} m");
    let mut d: Vec<f64> = derived.proxy.corners.iter().flatten().map(|p| near(*p)).collect();
    d.sort_by(f64::total_cmp);
    println!("{:?}", d.iter().map(|x| (x * 1000.0).round() / 1000.0).collect::<Vec<_>>());
}

/// What a derivation records (`extras.relume.mrt` as a scene would declare it) reads back as
/// the same blocks (to the f32 a scene's coordinates are read in) and joins: a user can paste it
/// into the scene and edit it.
#[test]
fn a_derived_proxy_declared_reads_back_as_itself() {
    for name in ["mrt-cave", "mrt-maze", "classroom", "cornell"] {
        let mut scene = load(name);
        scene.settings.blocks.remove("mrt");
        let derived = derive(&scene, &SceneBvh::new(&scene)).unwrap();
        scene.settings.blocks.insert("mrt".into(), derived.declared.clone());
        let declared = Proxy::of(&scene).unwrap();
        let close = declared.corners.iter().flatten().zip(derived.proxy.corners.iter().flatten()).all(|(a, b)| a.distance(*b) < 1e-5);
        assert!(close && declared.corners.len() == derived.proxy.corners.len(), "{name}");
        assert_eq!(declared.level(), derived.proxy.level(), "{name}");
    }
}

/// Cornell, which declares no proxy: one block on the room's walls (the published data's
/// walls lean a few millimetres; the tall and short blocks inside are furniture), every mesh
/// on its faces.
#[test]
fn cornell_is_one_block_on_its_walls() {
    let scene = load("cornell");
    let derived = derive(&scene, &SceneBvh::new(&scene)).unwrap();
    assert_eq!(derived.proxy.corners.len(), 1);
    assert!(derived.dynamic.is_empty(), "{:?}", derived.dynamic);
    let (lo, hi) = scene.settings.bounds;
    for c in derived.proxy.corners[0] {
        let c = c.as_vec3();
        assert!(c.cmpge(lo - 0.01).all() && c.cmple(hi + 0.01).all(), "{c} off the room {lo} .. {hi}");
    }
}

/// A flat scene (one floor, no height: a downloaded ground plane) is refused as a flat block,
/// not counted into a lattice of cells past `usize` (its rooms' height of 0 divided the floor).
#[test]
fn a_flat_scene_is_refused_as_one_flat_block() {
    use glam::Vec3;
    use relume_bake::testing;
    let floor = testing::square(Vec3::ZERO, Vec3::X, Vec3::Z, 2, 0);
    let camera = testing::look_at(Vec3::new(0.0, 2.0, 3.0), Vec3::ZERO, Vec3::Y, 0.8);
    let light = testing::point_light(Vec3::Y, Vec3::splat(10.0));
    let scene = testing::scene("flat", vec![floor], vec![testing::material("floor", Vec3::splat(0.5), Vec3::ZERO)], vec![light], camera);
    let Err(error) = derive(&scene, &SceneBvh::new(&scene)) else { panic!("a flat scene derived blocks") };
    assert!(error.contains("cell (0, 0)") && error.contains("flat") && error.contains("declare extras.relume.mrt"), "{error}");
}
