//! Light path maps on the CPU: entry points and their densities, the transfers' clustered PCA
//! on real transfers (error monotone in C and D, exact at full D), determinism, the artifact
//! round trip and refusals.

use glam::Vec3;
use relume_bake::artifact::{Artifact, BakeOutput};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::SceneBvh;
use relume_bake::cpca;
use relume_bake::gltf_load;
use relume_bake::light_path_maps::*;
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use serde_json::json;
use std::path::PathBuf;

fn cornell() -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf");
    gltf_load::load(&path).unwrap().scene
}

fn settings(threads: usize) -> LightPathMapSettings {
    LightPathMapSettings {
        entry_points: 256,
        walks: 2,
        threshold: 0.05,
        max_depth: 64,
        work: WorkOptions { seed: 3, threads: Some(threads), ..WorkOptions::default() },
    }
}

struct Baked256 {
    atlas: Atlas,
    entries: EntryPoints,
    transfers: Transfers,
}

fn bake(scene: &Scene, threads: usize) -> Baked256 {
    let atlas = Atlas::build(scene, &AtlasSettings { texel_density: 24.0, ..Default::default() }).unwrap();
    let bvh = SceneBvh::new(scene);
    let region = LightPathMapsSceneSettings::of(scene).unwrap().region;
    let tests = test_points(scene, region.as_ref(), 3).unwrap();
    let entries = entry_points(scene, &bvh, tests, 256, 3).unwrap();
    let transfers = bake_transfers(scene, &bvh, &atlas, &entries.entries, &settings(threads)).unwrap();
    Baked256 { atlas, entries, transfers }
}

#[test]
fn entry_points_face_their_test_points_with_finite_densities() {
    let scene = cornell();
    let b = bake(&scene, 2);
    assert!(b.entries.entries.len() >= 256, "{} entry points", b.entries.entries.len());
    assert_eq!(b.entries.test_points.len(), 64);
    for e in &b.entries.entries {
        assert!(e.density.is_finite() && e.density > 0.0, "density {}", e.density);
        let seen = b.entries.test_points.iter().any(|y| (*y - e.point.position).dot(e.point.normal) > 0.0);
        assert!(seen, "an entry point faces away from every test point");
    }
}

#[test]
fn same_bytes_whatever_the_thread_count() {
    let scene = cornell();
    let (one, two) = (bake(&scene, 1), bake(&scene, 2));
    assert_eq!(one.transfers.values, two.transfers.values);
    assert!(one.transfers.values.iter().any(|v| v.max_element() > 0.0), "every transfer is zero");
}

#[test]
fn cpca_error_of_real_transfers_falls_with_clusters_and_basis_and_is_exact_at_full_basis() {
    let scene = cornell();
    let b = bake(&scene, 2);
    let cols = 3 * b.transfers.texels.len();
    let data: Vec<f32> = b.transfers.values.iter().flat_map(|v| v.to_array()).collect();
    let features: Vec<f32> =
        b.entries.entries.iter().flat_map(|e| e.point.position.to_array().into_iter().chain(e.point.normal.to_array())).collect();
    let counts = [1, 2, 4, 8, 16];
    let table = cpca::error_table(&data, cols, &features, 6, &counts, 6).unwrap();
    let error = |c: usize, d: usize| table.iter().find(|x| x.clusters == c && x.basis == d).unwrap().relative_error;
    for &c in &counts {
        for d in 1..=6 {
            assert!(
                error(c, d) <= error(c, d - 1) * (1.0 + 1e-6),
                "C = {c}: D = {d} error {} > D = {} error {}",
                error(c, d),
                d - 1,
                error(c, d - 1)
            );
        }
    }
    for pair in counts.windows(2) {
        for d in 0..=6 {
            assert!(error(pair[1], d) <= error(pair[0], d) * (1.0 + 1e-6), "D = {d}: C = {} worse than C = {}", pair[1], pair[0]);
        }
    }
    assert!(error(16, 2) < 0.9 * error(1, 0), "clustering and two eigen-textures barely help: {} vs {}", error(16, 2), error(1, 0));
    let fit = cpca::fit(&data, cols, &features, 6, 16, 0).unwrap();
    let largest = fit.clusters.iter().map(|c| c.members.len()).max().unwrap();
    let exact = cpca::fit(&data, cols, &features, 6, 16, largest).unwrap();
    assert!(exact.relative_error(&data) < 1e-4, "D = cluster size leaves {}", exact.relative_error(&data));
}

#[test]
fn compressed_transfer_reconstructs_what_the_fit_says() {
    let scene = cornell();
    let b = bake(&scene, 2);
    let n = b.atlas.texels.len();
    let irradiance: Vec<Vec3> = (0..b.entries.entries.len()).map(|e| Vec3::new(1.0, 0.5, 0.25) * (1 + e % 7) as f32).collect();
    let exact = b.transfers.irradiance(&irradiance, n);
    let none = compress(&b.transfers, &b.entries.entries, n, 0.0, Compression::None).unwrap();
    let from_none = reconstruct_with(&none.transfer, &b.entries.entries, &irradiance);
    assert!(max_relative(&from_none, &exact) < 1e-5, "uncompressed differs by {}", max_relative(&from_none, &exact));
    let fixed = compress(&b.transfers, &b.entries.entries, n, 0.0, Compression::Fixed { clusters: 8, basis: 2 }).unwrap();
    assert_eq!((fixed.clusters, fixed.basis, fixed.transfer.cluster_count()), (8, 2, 8));
    fixed.transfer.validate().unwrap();
    let budget = compress(&b.transfers, &b.entries.entries, n, 0.0, Compression::Budget(fixed.relative_error)).unwrap();
    assert!(budget.relative_error <= fixed.relative_error + 1e-9);
    assert!(budget.transfer.textures.len() <= fixed.transfer.textures.len() + fixed.transfer.weights.len());
}

/// The default budget searches only the sizes whose textures fit: with room for fewer textures
/// than its choice, it takes the most accurate size that fits (a larger error), and with room
/// for none it refuses, naming the memory limit.
#[test]
fn the_default_budget_chooses_within_the_textures_the_memory_leaves_room_for() {
    let scene = cornell();
    let b = bake(&scene, 2);
    let textures = |(c, d): (usize, usize)| c * (1 + d);
    let strict = Compression::BestWithin(1e-6);
    let free = sizes(&b.transfers, &b.entries.entries, strict, None).unwrap().unwrap();
    assert!(textures(free) > 4, "the search's most accurate size stores {free:?}");
    let bound = sizes(&b.transfers, &b.entries.entries, strict, Some(4)).unwrap().unwrap();
    assert!(textures(bound) <= 4 && textures(bound) >= 3, "{bound:?} within 4 textures");
    let error = |(clusters, basis)| {
        compress(&b.transfers, &b.entries.entries, b.atlas.texels.len(), 0.0, Compression::Fixed { clusters, basis })
            .unwrap()
            .relative_error
    };
    assert!(error(bound) > error(free), "fewer textures, yet no larger error: {} vs {}", error(bound), error(free));
    let none = sizes(&b.transfers, &b.entries.entries, strict, Some(0)).unwrap_err();
    assert!(none.contains("memory limit"), "{none}");
    // An explicit budget is not bent to fit: its choice is admitted or refused as it is.
    assert_eq!(sizes(&b.transfers, &b.entries.entries, Compression::Budget(1.0), Some(0)).unwrap(), Some((1, 0)));
}

/// sum_e I_e T~_e through the stored transfer, with I_e given in the bake's entry order.
fn reconstruct_with(t: &ClusteredTransfer, entries: &[BakedEntry], irradiance: &[Vec3]) -> Vec<Vec3> {
    let ordered: Vec<Vec3> = t.entry_points.iter().map(|p| irradiance[entries.iter().position(|e| e.point == *p).unwrap()]).collect();
    t.reconstruct(&t.cluster_sums(&ordered))
}

fn max_relative(a: &[Vec3], b: &[Vec3]) -> f32 {
    let scale = b.iter().map(|v| v.max_element()).fold(0.0, f32::max);
    a.iter().zip(b).map(|(x, y)| (*x - *y).abs().max_element() / scale).fold(0.0, f32::max)
}

#[test]
fn artifact_round_trip_keeps_the_transfer_and_refuses_a_corrupt_one() {
    let scene = cornell();
    let b = bake(&scene, 2);
    let n = b.atlas.texels.len();
    let compressed = compress(&b.transfers, &b.entries.entries, n, 0.01, Compression::Fixed { clusters: 4, basis: 2 }).unwrap();
    let dir = std::env::temp_dir().join(format!("relume-light-path-maps-artifact-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let layout = b.atlas.layout();
    let output = BakeOutput {
        method: "light-path-maps",
        scene: Some(&scene),
        parameters: json!({}),
        sections: vec![b.atlas.to_section().section(json!({})), section(&compressed.transfer, layout, json!({})).unwrap()],
        stats: json!({}),
    };
    output.write(&dir).unwrap();
    let read = read(&Artifact::read(&dir).unwrap(), &scene, layout).unwrap();
    assert_eq!(read, compressed.transfer);
    let bin = dir.join("light-path-maps.bin");
    let mut bytes = std::fs::read(&bin).unwrap();
    bytes[20] ^= 1;
    std::fs::write(&bin, bytes).unwrap();
    let error = Artifact::read(&dir).unwrap_err().to_string();
    assert!(error.contains("light-path-maps.bin") && error.contains("checksum"), "{error}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn refuses_impossible_settings_and_a_scene_with_nowhere_to_shoot_from() {
    let mut bad = settings(1);
    bad.entry_points = 0;
    assert!(bad.validate().unwrap_err().contains("entry points"));
    let mut bad = settings(1);
    bad.threshold = f32::NAN;
    assert!(bad.validate().unwrap_err().contains("threshold"));
    let mut scene = cornell();
    scene.lights.clear();
    let error = test_points(&scene, None, 0).unwrap_err();
    assert!(error.contains("cornell.gltf") && error.contains("light_path_maps.region"), "{error}");
}
