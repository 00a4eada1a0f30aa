//! The tessellation per-vertex methods bake on: the same surfaces in smaller triangles, welded
//! where the source's vertices are equal, and its section read back exactly and refused when
//! it does not fit the scene.
#![cfg(feature = "baking")]

use relume_bake::artifact::{Artifact, BakeOutput};
use relume_bake::scene::{Mesh, Scene};
use relume_bake::tessellation::{self, Tessellation};
use serde_json::json;
use std::collections::HashMap;
use std::path::Path;

fn cornell() -> Scene {
    relume_bake::gltf_load::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/cornell.gltf")).unwrap().scene
}

fn area(mesh: &Mesh) -> f64 {
    mesh.indices
        .chunks_exact(3)
        .map(|t| {
            let p = |k: usize| mesh.positions[t[k] as usize].as_dvec3();
            0.5 * (p(1) - p(0)).cross(p(2) - p(0)).length()
        })
        .sum()
}

/// Edges used by one triangle only, by their vertex indices.
fn open_edges(mesh: &Mesh) -> usize {
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in mesh.indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    edges.values().filter(|&&n| n == 1).count()
}

/// Cornell's flat-shaded walls (two triangles of six vertices each) split to edges of at most
/// 5 cm: the same area, the same plane, every vertex shared by its neighbours (a wall's
/// only open edges are its border), normals and winding kept, no edge longer than asked.
#[test]
fn flat_meshes_become_welded_grids_of_the_same_surfaces() {
    let scene = cornell();
    assert!(tessellation::flat_shaded(&scene));
    let t = Tessellation::new(&scene, 0.05).unwrap();
    let fine = t.apply(&scene);
    assert!(!tessellation::flat_shaded(&fine));
    for (before, after) in scene.meshes.iter().zip(&fine.meshes) {
        assert!((area(before) - area(after)).abs() < 1e-5 * area(before), "{}: area {} against {}", before.name, area(after), area(before));
        for tri in after.indices.chunks_exact(3) {
            let p = |k: usize| after.positions[tri[k] as usize];
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                assert!(p(a).distance(p(b)) <= 0.05 * 1.0001, "{}: an edge of {}", after.name, p(a).distance(p(b)));
            }
            // The winding faces the way the vertex normals do, as in the source.
            let n = (p(1) - p(0)).cross(p(2) - p(0));
            assert!(n.dot(after.normals[tri[0] as usize]) > 0.0, "{}: a triangle turned over", after.name);
        }
        // Every new vertex lies on a plane of the source mesh (each face is flat).
        for (&p, &n) in after.positions.iter().zip(&after.normals) {
            let on = before.positions.iter().zip(&before.normals).any(|(q, m)| m.dot(n) > 0.9999 && (p - *q).dot(*m).abs() < 1e-5);
            assert!(on, "{}: {p} off the source's faces", after.name);
        }
    }
    // A single wall: the rectangle's border only (a grid of k x k squares has 4k border edges).
    let floor = &fine.meshes[0];
    let k = (open_edges(floor) / 4) as f32;
    assert!(
        k >= 10.0 && floor.positions.len() == ((k + 1.0) * (k + 1.0)) as usize,
        "{} vertices, {} open edges",
        floor.positions.len(),
        open_edges(floor)
    );
    // Asked for edges no shorter than the meshes', the tessellation only welds.
    let welded = Tessellation::new(&scene, 10.0).unwrap().apply(&scene);
    assert_eq!(welded.meshes[0].positions.len(), 4, "a quad's two triangles share two vertices");
    assert_eq!(welded.triangle_count(), scene.triangle_count());
}

#[test]
fn the_section_reads_back_and_is_refused_for_another_scene_or_when_corrupt() {
    let scene = cornell();
    let t = Tessellation::new(&scene, 0.1).unwrap();
    let dir = std::env::temp_dir().join(format!("relume-tessellation-{}", std::process::id()));
    let write = |dir: &Path, t: &Tessellation| {
        let output = BakeOutput {
            method: "test",
            scene: Some(&scene),
            parameters: json!({}),
            sections: vec![tessellation::section(t)],
            stats: json!({}),
        };
        output.write(dir).unwrap();
    };
    write(&dir, &t);
    let artifact = Artifact::read(&dir).unwrap();
    assert_eq!(tessellation::read(&artifact, &scene).unwrap(), Some(t.clone()));
    let mut other = scene.clone();
    other.meshes[0].positions[0].x += 0.01;
    let refused = tessellation::read(&artifact, &other).err().expect("refused").to_string();
    assert!(refused.contains("tessellation") && refused.contains("bake"), "{refused}");
    let mut bad = t.clone();
    bad.meshes[2].sources[5].0[1] = 999;
    write(&dir, &bad);
    let refused = tessellation::read(&Artifact::read(&dir).unwrap(), &scene).err().expect("refused").to_string();
    assert!(refused.contains("mesh 2's vertex 5") && refused.contains("bake"), "{refused}");
    let mut bad = t.clone();
    bad.meshes[1].indices[0] = 1 << 20;
    write(&dir, &bad);
    let refused = tessellation::read(&Artifact::read(&dir).unwrap(), &scene).err().expect("refused").to_string();
    assert!(refused.contains("mesh 1's indices"), "{refused}");
    std::fs::remove_dir_all(&dir).ok();
    // A scene's edges would make too many vertices: refused with the fix.
    let refused = Tessellation::new(&scene, 1e-4).err().expect("refused");
    assert!(refused.contains("--max-edge"), "{refused}");
}
