//! The lightmap atlas (Iones et al. 2003 §3): charts never share a texel, every triangle
//! is covered, texel geometry is right on flat faces, pages split as asked, and the patch
//! count can be targeted.
#![cfg(feature = "baking")]

use glam::{Vec2, Vec3};
use relume_bake::atlas::{mesh_offsets, Atlas, AtlasError, AtlasSettings, ChartMapping};
use relume_bake::sampling::{uniform_triangle, PathSampler};
use relume_bake::scene::{Mesh, Scene};
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, sphere, square, Facing};

fn build_scene(meshes: Vec<Mesh>) -> Scene {
    let camera = look_at(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, Vec3::Y, 1.0);
    let lights = vec![point_light(Vec3::new(0.0, 3.0, 0.0), Vec3::ONE)];
    scene("atlas test", meshes, vec![material("grey", Vec3::splat(0.5), Vec3::ZERO)], lights, camera)
}

fn mixed_scene() -> Scene {
    build_scene(vec![
        sphere(Vec3::new(0.0, 1.0, 0.0), 0.7, 3, Facing::Outward, 0),
        closed_box(Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0), 3, Facing::Inward, 0),
        closed_box(Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.5, 0.4, 1.6), 1, Facing::Outward, 0),
    ])
}

fn settings(density: f32) -> AtlasSettings {
    AtlasSettings { texel_density: density, ..Default::default() }
}

/// Random points on every triangle (by area), with the triangle's chart, mapped through uv1.
fn sample_uv1(scene: &Scene, atlas: &Atlas, per_triangle: u32) -> Vec<(u32, u32, Vec2)> {
    let mut chart_of = std::collections::HashMap::new();
    for (c, chart) in atlas.charts.iter().enumerate() {
        for &t in &chart.triangles {
            chart_of.insert((chart.mesh, t), c as u32);
        }
    }
    let offsets = mesh_offsets(scene);
    let mut out = Vec::new();
    for (m, mesh) in atlas.meshes.iter().enumerate() {
        for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
            let id = offsets[m] + t as u32;
            for i in 0..per_triangle {
                let s = PathSampler::new(1, id, i).sobol4(0);
                let w = uniform_triangle(Vec2::new(s[0], s[1]));
                let uv = mesh.uv1[tri[0] as usize] * w.x + mesh.uv1[tri[1] as usize] * w.y + mesh.uv1[tri[2] as usize] * w.z;
                out.push((id, chart_of[&(m as u32, t as u32)], uv));
            }
        }
    }
    out
}

/// Every point of every triangle maps through uv1 to a covered texel, and no texel holds two
/// charts (each covered texel belongs to the chart of its own triangle).
fn assert_charts_own_their_texels(scene: &Scene, atlas: &Atlas) {
    assert!(atlas.too_small.is_empty(), "{:?}", atlas.too_small);
    let mut owner = vec![u32::MAX; atlas.texels.len()];
    for (triangle, chart, uv) in sample_uv1(scene, atlas, 64) {
        let texel = atlas.texel_at(uv).unwrap_or_else(|| panic!("triangle {triangle}: uv1 {uv} is off the atlas"));
        assert!(atlas.texels[texel].coverage > 0.0, "triangle {triangle}: uv1 {uv} lands on an empty texel");
        assert!(owner[texel] == u32::MAX || owner[texel] == chart, "texel {texel} holds charts {} and {chart}", owner[texel]);
        owner[texel] = chart;
    }
    let offsets = mesh_offsets(scene);
    for (i, texel) in atlas.texels.iter().enumerate().filter(|(_, t)| t.coverage > 0.0) {
        let mesh = offsets.iter().rposition(|&o| o <= texel.triangle).unwrap();
        let local = texel.triangle - offsets[mesh];
        let chart = atlas.charts.iter().position(|c| c.mesh == mesh as u32 && c.triangles.contains(&local)).unwrap() as u32;
        assert!(owner[i] == u32::MAX || owner[i] == chart, "texel {i}");
    }
}

#[test]
fn no_texel_is_shared_by_two_charts_and_every_triangle_is_covered() {
    let scene = mixed_scene();
    let atlas = Atlas::build(&scene, &settings(24.0)).unwrap();
    assert_charts_own_their_texels(&scene, &atlas);
    println!(
        "charts {}, pages {}, {}x{}, utilization {:.3}",
        atlas.charts.len(),
        atlas.pages,
        atlas.width,
        atlas.height,
        atlas.utilization()
    );
}

/// A desk's leg, 5 cm square and a metre tall at 16 texels a metre: its six faces, under a
/// texel to 16 texels across, are unfolded into fewer charts than faces, laid flat without
/// stretching (the coverage is the surface's area in texels), and still own their texels.
#[test]
fn a_thin_box_is_unfolded_into_fewer_charts_without_distortion() {
    let scene = build_scene(vec![closed_box(Vec3::ZERO, Vec3::new(0.05, 1.0, 0.05), 2, Facing::Outward, 0)]);
    let atlas = Atlas::build(&scene, &settings(16.0)).unwrap();
    assert!(atlas.charts.len() < 6, "{} charts", atlas.charts.len());
    assert_eq!(atlas.charts.iter().map(|c| c.parts).sum::<u32>(), 6);
    let coverage: f32 = atlas.texels.iter().map(|t| t.coverage).sum();
    let area = (4.0 * 0.05 * 1.0 + 2.0 * 0.05 * 0.05) * 16.0 * 16.0;
    assert!((coverage - area).abs() < 1e-3 * area, "{coverage} vs {area}");
    assert_charts_own_their_texels(&scene, &atlas);
}

/// `mesh` with its vertices welded by position (one index per point, as an indexed file
/// stores a smooth or shared-corner mesh).
fn welded(mesh: &Mesh) -> Mesh {
    let mut index = std::collections::HashMap::new();
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let indices = mesh
        .indices
        .iter()
        .map(|&i| {
            let p = mesh.positions[i as usize];
            *index.entry(p.to_array().map(f32::to_bits)).or_insert_with(|| {
                positions.push(p);
                normals.push(mesh.normals[i as usize]);
                positions.len() as u32 - 1
            })
        })
        .collect();
    Mesh { positions, normals, uv0: None, uv1: None, indices, ..mesh.clone() }
}

/// The same leg with its corners shared by index: unfolding its sides into a strip puts a
/// corner vertex at two places of one chart (the strip's two ends), and each place keeps its
/// own uv1, so every triangle's uv1 has its own area in texels.
#[test]
fn a_welded_box_unfolds_with_a_uv1_for_each_place_of_a_vertex() {
    let scene = build_scene(vec![welded(&closed_box(Vec3::ZERO, Vec3::new(0.05, 1.0, 0.05), 1, Facing::Outward, 0))]);
    assert_eq!(scene.meshes[0].positions.len(), 8);
    let density = 16.0;
    let atlas = Atlas::build(&scene, &settings(density)).unwrap();
    assert!(atlas.charts.iter().any(|c| c.parts > 2), "{:?}", atlas.charts.iter().map(|c| c.parts).collect::<Vec<_>>());
    let page = Vec2::new(atlas.width as f32, atlas.height as f32);
    let mesh = &atlas.meshes[0];
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let uv = [0, 1, 2].map(|k| mesh.uv1[tri[k] as usize] * page);
        let texels = 0.5 * (uv[1] - uv[0]).perp_dot(uv[2] - uv[0]).abs();
        let p = [0, 1, 2].map(|k| scene.meshes[0].positions[mesh.source_vertex[tri[k] as usize] as usize]);
        let world = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() * density * density;
        assert!((texels - world).abs() < 1e-3 * world, "triangle {t}: {texels} texels in uv1, {world} on the surface");
    }
    assert_charts_own_their_texels(&scene, &atlas);
}

#[test]
fn a_box_gets_one_chart_per_face_projected_on_its_axis() {
    let scene = build_scene(vec![closed_box(Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0), 2, Facing::Outward, 0)]);
    let atlas = Atlas::build(&scene, &settings(10.0)).unwrap();
    assert_eq!(atlas.charts.len(), 6);
    for chart in &atlas.charts {
        assert_eq!(chart.triangles.len(), 8);
        assert!(matches!(chart.mapping, ChartMapping::Projection { .. }));
    }
    // Faces are whole texels at this density: coverage sums to the area in texels.
    let coverage: f32 = atlas.texels.iter().map(|t| t.coverage).sum();
    let area = 2.0 * (1.0 * 2.0 + 2.0 * 3.0 + 1.0 * 3.0) * 100.0;
    assert!((coverage - area).abs() < 1e-2 * area, "{coverage} vs {area}");
}

#[test]
fn texel_geometry_of_a_flat_square_lies_on_it() {
    let scene = build_scene(vec![square(Vec3::new(0.0, 0.5, 0.0), Vec3::X * 0.7, Vec3::NEG_Z * 0.7, 3, 0)]);
    let atlas = Atlas::build(&scene, &settings(13.0)).unwrap();
    assert_eq!(atlas.charts.len(), 1);
    for (i, t) in atlas.texels.iter().enumerate().filter(|(_, t)| t.coverage > 0.0) {
        assert!(
            (t.centre.y - 0.5).abs() < 1e-5 && t.centre.x.abs() <= 0.7 + 1e-5 && t.centre.z.abs() <= 0.7 + 1e-5,
            "texel {i}: {:?}",
            t.centre
        );
        assert!((t.normal - Vec3::Y).length() < 1e-5, "texel {i}: {:?}", t.normal);
        let piece_area: f32 = atlas.pieces_of(i).iter().map(|p| p.area).sum();
        assert!((piece_area - t.coverage / 169.0).abs() < 1e-6, "texel {i}: pieces {piece_area}, coverage {}", t.coverage);
    }
}

#[test]
fn a_continuous_uv0_makes_one_chart_in_uv_space() {
    let scene = build_scene(vec![{
        let mut m = square(Vec3::ZERO, Vec3::X, Vec3::NEG_Z, 4, 0);
        m.uv0 = Some(m.positions.iter().map(|p| Vec2::new(p.x * 0.5 + 0.5, p.z * 0.5 + 0.5)).collect());
        m
    }]);
    let atlas = Atlas::build(&scene, &settings(16.0)).unwrap();
    assert_eq!(atlas.charts.len(), 1);
    let ChartMapping::Uv0 { scale } = atlas.charts[0].mapping else { panic!("{:?}", atlas.charts[0].mapping) };
    assert!((scale - 2.0).abs() < 1e-4, "uv0 spans 2 m per unit: {scale}");
}

#[test]
fn charts_beyond_one_page_go_to_more_pages_and_a_chart_too_large_is_refused() {
    let scene = mixed_scene();
    let small = AtlasSettings { max_size: 128, ..settings(24.0) };
    let atlas = Atlas::build(&scene, &small).unwrap();
    assert!(atlas.pages > 1, "{} pages", atlas.pages);
    assert!(atlas.width <= 128 && atlas.height <= 128);
    assert!(sample_uv1(&scene, &atlas, 8).iter().all(|(_, _, uv)| atlas.texel_at(*uv).is_some_and(|t| atlas.texels[t].coverage > 0.0)));
    let error = Atlas::build(&scene, &AtlasSettings { max_size: 64, ..settings(200.0) }).unwrap_err();
    assert!(matches!(error, AtlasError::ChartTooLarge { .. }));
    assert!(error.to_string().contains("lower the texel density"), "{error}");
}

#[test]
fn the_patch_count_can_be_targeted() {
    let scene = mixed_scene();
    for target in [2_000u32, 15_000] {
        let atlas = Atlas::build_for_patch_count(&scene, &AtlasSettings::default(), target).unwrap();
        let covered = atlas.covered_texels() as f32;
        assert!((covered / target as f32 - 1.0).abs() < 0.03, "{covered} for {target}");
    }
}

#[test]
fn the_atlas_is_deterministic_and_bad_settings_are_refused() {
    let scene = mixed_scene();
    let a = Atlas::build(&scene, &settings(20.0)).unwrap();
    let b = Atlas::build(&scene, &settings(20.0)).unwrap();
    assert_eq!(a.texels, b.texels);
    assert_eq!(a.meshes, b.meshes);
    for bad in
        [AtlasSettings { gutter: 0, ..settings(20.0) }, settings(f32::NAN), AtlasSettings { discontinuity_angle: 2.0, ..settings(20.0) }]
    {
        assert!(matches!(Atlas::build(&scene, &bad), Err(AtlasError::Settings(_))));
    }
}

/// `mesh` with every triangle split into four at its edges' midpoints, `levels` times, each
/// triangle keeping vertices of its own (as a flat-shaded file has them); a midpoint depends
/// only on its edge's two ends, so neighbours' new vertices coincide bit for bit.
fn midpoint_subdivided(mesh: &Mesh, levels: u32) -> Mesh {
    let mut triangles: Vec<[usize; 3]> = mesh.indices.chunks_exact(3).map(|t| [t[0] as usize, t[1] as usize, t[2] as usize]).collect();
    let (mut positions, mut normals) = (mesh.positions.clone(), mesh.normals.clone());
    for _ in 0..levels {
        let mut next = Vec::with_capacity(4 * triangles.len());
        for [a, b, c] in triangles {
            let mut mid = |p: usize, q: usize| {
                positions.push((positions[p] + positions[q]) * 0.5);
                normals.push(normals[p]);
                positions.len() - 1
            };
            let (ab, bc, ca) = (mid(a, b), mid(b, c), mid(c, a));
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        triangles = next;
    }
    let indices = triangles.iter().flat_map(|t| t.map(|v| v as u32)).collect();
    Mesh { positions, normals, uv0: None, uv1: None, indices, ..mesh.clone() }
}

/// Chart segmentation sees surfaces, not triangles: classroom and table-chair with every
/// triangle split 16 ways (and 64 ways for table-chair) keep their charts and their covered
/// texels (to the texels that tiny triangles' rounding touches at a chart's border).
#[test]
fn a_scene_and_its_midpoint_subdivided_copy_get_the_same_charts() {
    for (name, levels) in [("classroom", 2), ("table-chair", 3)] {
        let scene = relume_bake::gltf_load::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.gltf")))
            .unwrap()
            .scene;
        let fine = Scene { meshes: scene.meshes.iter().map(|m| midpoint_subdivided(m, levels)).collect(), ..scene.clone() };
        assert_eq!(fine.triangle_count(), scene.triangle_count() << (2 * levels));
        let settings = AtlasSettings { texel_density: scene.settings.texel_density, ..AtlasSettings::default() };
        let (coarse, subdivided) = (Atlas::build(&scene, &settings).unwrap(), Atlas::build(&fine, &settings).unwrap());
        assert_eq!(subdivided.charts.len(), coarse.charts.len(), "{name}: charts");
        let (a, b) = (coarse.covered_texels() as f64, subdivided.covered_texels() as f64);
        assert!((b / a - 1.0).abs() < 0.01, "{name}: {a} covered texels, {b} subdivided");
    }
}
