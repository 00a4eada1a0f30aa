//! A level of modular radiance transfer on the CPU (no GPU): the stored tables evaluate as the
//! level's transfer does (the CPU oracle of the GPU passes is right); the padded atlas: every
//! bilinear read of every mapped triangle reads a written texel, a seam between connected
//! blocks reads the same from both sides, a crease clamps to its own edge; a warped level's
//! samples lie on its triangles, and a level turned as warped blocks bakes the same tables;
//! refusals of geometry off the blocks and of a level made with another dictionary.

use glam::{Quat, Vec2, Vec3, Vec4};
use nalgebra::DVector;
use relume_bake::artifact::{Artifact, BakeOutput};
use relume_bake::mrt::dictionary::{self, Dictionary};
use relume_bake::mrt::evaluate::LevelTransfer;
use relume_bake::mrt::level_data;
use relume_bake::mrt::map::Mapped;
use relume_bake::mrt::proxy::Proxy;
use relume_bake::mrt::{Face, Samples};
use relume_tests::*;

#[test]
fn the_stored_tables_evaluate_as_the_level_transfer() {
    let scene = load_scene("mrt-maze");
    let (dictionary, mapped, level, _) = mrt_quick_bake(&scene);
    let proxy = Proxy::of(&scene).unwrap();
    let blocks = proxy.level();
    let (operators, interfaces) = dictionary.operators();
    let transfer = LevelTransfer::new(&blocks, &operators, &interfaces, 8).unwrap();
    // A grey light falling off from one corner: every block lit, unevenly.
    let light: Vec<f32> = mapped.samples.iter().map(|s| 1.0 / (1.0 + s.position.length_squared())).collect();
    let mut at = 0;
    let per_block: Vec<DVector<f64>> = (0..blocks.len())
        .map(|b| {
            let n = Samples::new(blocks.shape(b), dictionary.settings.samples_per_face).len();
            at += n;
            DVector::from_iterator(n, light[at - n..at].iter().map(|&v| v as f64))
        })
        .collect();
    let expected: Vec<f64> =
        transfer.indirect(&operators, &interfaces, &per_block).unwrap().iter().flat_map(|v| v.iter().copied()).collect();
    let got = level.bounce(&dictionary, &light.iter().map(|&v| Vec3::splat(v)).collect::<Vec<_>>());
    let scale = expected.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = got.iter().zip(&expected).map(|(g, e)| (g.x as f64 - e).abs().max((g.z as f64 - e).abs())).fold(0.0, f64::max) / scale;
    assert!(scale > 0.0 && worst < 1e-5, "the tables' bounce against LevelTransfer: worst {worst:e} of the largest value");
    assert_eq!(level.receivers.len(), 26, "11 blocks with 13 openings between them: 26 receivers");
}

/// §7.3's feedback iterated bounce by bounce (b <- b0 + K b, as from frame to frame) converges
/// to the solved fixed point the level stores.
#[test]
fn the_feedback_iterated_converges_to_the_solved_fixed_point() {
    let scene = load_scene("mrt-maze");
    let (dictionary, mapped, level, _) = mrt_quick_bake(&scene);
    let direct: Vec<Vec3> = mapped.samples.iter().map(|s| Vec3::new(1.0, 0.5, 0.25) / (1.0 + s.position.length_squared())).collect();
    let solved = level.indirect(&dictionary, &direct, true);
    let mut total = vec![Vec3::ZERO; direct.len()];
    let (mut changes, mut light) = (Vec::new(), direct.iter().zip(&level.samples).map(|(e, s)| *e * s.albedo).collect::<Vec<_>>());
    for _ in 0..200 {
        let e = level.bounce(&dictionary, &light);
        total.iter_mut().zip(&e).for_each(|(t, e)| *t += *e);
        changes.push(e.iter().map(|v| v.abs().max_element()).fold(0.0, f32::max));
        light = e.iter().zip(&level.samples).map(|(e, s)| *e * s.albedo).collect();
    }
    let scale = solved.iter().map(|v| v.max_element()).fold(0.0, f32::max);
    let gap = solved.iter().zip(&total).map(|(s, t)| (*s - *t).abs().max_element()).fold(0.0, f32::max) / scale;
    eprintln!(
        "feedback: the last bounce's largest value {:.2e} of the total's {scale:.3}; iterated against solved {gap:.2e}",
        changes[199]
    );
    assert!(changes[199] < 1e-3 * scale && gap < 1e-4, "bounce 200 adds {:e}; iterated and solved differ by {gap:e}", changes[199]);
    let first = level.indirect(&dictionary, &direct, false);
    assert!(solved.iter().zip(&first).all(|(s, f)| s.cmpge(*f - 1e-6).all()), "more bounces never take light away");
}

/// The light map after the padding, on the CPU: each sample texel `value(position)`, each
/// copy record's texel its source's, alpha 1 written, 0 not.
fn padded(mapped: &Mapped, value: impl Fn(Vec3) -> f32) -> Vec<Vec4> {
    let mut texels = vec![Vec4::ZERO; mapped.layout.texel_count()];
    for s in &mapped.samples {
        texels[s.texel as usize] = Vec4::new(value(s.position), 0.0, 0.0, 1.0);
    }
    for [to, from] in &mapped.copies {
        texels[*to as usize] = texels[*from as usize];
    }
    texels
}

/// The lighting pass's bilinear read at uv1 (clamped to the page), and the texels it reads.
fn read(texels: &[Vec4], width: u32, height: u32, uv: Vec2) -> (f32, [usize; 4]) {
    let p = uv * Vec2::new(width as f32, height as f32) - 0.5;
    let (x0, y0) = (p.x.floor(), p.y.floor());
    let (fx, fy) = (p.x - x0, p.y - y0);
    let at = |x: f32, y: f32| (y.clamp(0.0, height as f32 - 1.0) as usize) * width as usize + x.clamp(0.0, width as f32 - 1.0) as usize;
    let idx = [at(x0, y0), at(x0 + 1.0, y0), at(x0, y0 + 1.0), at(x0 + 1.0, y0 + 1.0)];
    let w = [(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy];
    (idx.iter().zip(w).map(|(i, w)| texels[*i].x * w).sum(), idx)
}

#[test]
fn every_bilinear_read_of_every_mapped_triangle_reads_a_written_texel() {
    let scene = load_scene("mrt-maze");
    let (_, mapped, level, applied) = mrt_quick_bake(&scene);
    let texels = padded(&mapped, |p| p.x);
    let (w, h) = (level.layout.width, level.layout.height);
    let mut reads = 0;
    for mesh in &applied.meshes {
        let uv1 = mesh.uv1.as_ref().expect("mapped");
        for tri in mesh.indices.chunks_exact(3) {
            let corners = [0, 1, 2].map(|k| uv1[tri[k] as usize]);
            // The corners, the edges' midpoints and the centroid.
            let points = [
                corners[0],
                corners[1],
                corners[2],
                (corners[0] + corners[1]) / 2.0,
                (corners[1] + corners[2]) / 2.0,
                (corners[0] + corners[2]) / 2.0,
                (corners[0] + corners[1] + corners[2]) / 3.0,
            ];
            for p in points {
                let (value, texels_read) = read(&texels, w, h, p);
                assert!(value.is_finite() && texels_read.iter().all(|&t| texels[t].w == 1.0), "a read at {p} touches an unwritten texel");
                reads += 1;
            }
        }
    }
    assert!(reads > 100, "{reads} reads");
}

#[test]
fn a_seam_reads_the_same_from_both_sides_and_a_crease_clamps_to_its_own_edge() {
    let scene = load_scene("mrt-maze");
    let (dictionary, mapped, level, _) = mrt_quick_bake(&scene);
    // A value that differs across every texel, so a wrong copy cannot hide.
    let texels = padded(&mapped, |p| (3.1 * p.x).sin() + (1.7 * p.z).cos() + 0.3 * p.y);
    let (w, h) = (level.layout.width, level.layout.height);
    let blocks = Proxy::of(&scene).unwrap().level();
    let floor = Face { axis: 1, positive: false };
    let read_at = |block: usize, face: Face, uv: Vec2| read(&texels, w, h, mapped.tiles.uv1_of(block, face, uv).expect("a present face")).0;
    let (mut seams, mut creases) = (0, 0);
    for b in 0..blocks.len() {
        // Seams: the floor across each opening (x and z).
        for axis in [0, 2] {
            let Some(n) = blocks.neighbour(b, Face { axis, positive: true }) else { continue };
            // Along the seam up to half a texel from its ends: a seam ending at a concave
            // corner (a wall on one side) cannot read the same from both sides there, because
            // the corner texel would have to be both tiles' clamped wall edge (map.rs).
            let half = 0.5 / dictionary.settings.samples_per_face as f32;
            for k in 0..=20 {
                let t = half + (1.0 - 2.0 * half) * k as f32 / 20.0;
                // The floor's (u, v) are (x, z): the far edge here is the near edge there.
                let (here, there) = if axis == 0 { (Vec2::new(1.0, t), Vec2::new(0.0, t)) } else { (Vec2::new(t, 1.0), Vec2::new(t, 0.0)) };
                let (a, c) = (read_at(b, floor, here), read_at(n, floor, there));
                assert!((a - c).abs() < 1e-5, "block {b} to {n}: {a} against {c} at {here}");
                seams += 1;
            }
        }
        // Creases: every face of the block read within half a texel of a closed edge equals
        // the bilinear read of its own samples only (clamped at their outer centres).
        let own = Samples::new(blocks.shape(b), dictionary.settings.samples_per_face);
        let first: usize = (0..b).map(|a| Samples::new(blocks.shape(a), own.grid).len()).sum();
        for (slot, &face) in own.faces.iter().enumerate() {
            for k in 0..=10 {
                let t = k as f32 / 10.0;
                for uv in [Vec2::new(t, 0.0), Vec2::new(t, 1.0), Vec2::new(0.0, t), Vec2::new(1.0, t)] {
                    if crosses_a_seam(&blocks, b, face, uv) {
                        continue;
                    }
                    let expected: f32 =
                        own.bilinear(slot, uv).iter().map(|(j, wt)| wt * texels[mapped.samples[first + j].texel as usize].x).sum();
                    let got = read_at(b, face, uv);
                    assert!((got - expected).abs() < 1e-5, "block {b} face {face:?} at {uv}: {got} against its own edge's {expected}");
                    creases += 1;
                }
            }
        }
    }
    assert!(seams >= 13 * 21 && creases > 500, "{seams} seam reads, {creases} crease reads");
}

/// Whether (u, v) on the edge of `face` of `block` lies on an edge shared with a connected
/// block's same face (a seam).
fn crosses_a_seam(blocks: &relume_bake::mrt::level::Level, block: usize, face: Face, uv: Vec2) -> bool {
    let (a, b) = face.tangents();
    [(a, uv.x), (b, uv.y)].into_iter().any(|(axis, t)| {
        let edge = if t <= 0.0 {
            Some(false)
        } else if t >= 1.0 {
            Some(true)
        } else {
            None
        };
        edge.is_some_and(|positive| blocks.neighbour(block, Face { axis, positive }).is_some_and(|n| !blocks.shape(n).is_open(face)))
    })
}

#[test]
fn the_warped_caves_samples_lie_on_the_triangles_they_light_facing_as_they_do() {
    let scene = load_scene("mrt-cave");
    let (_, mapped, _, _) = mrt_quick_bake(&scene);
    let triangles: Vec<[Vec3; 3]> = scene
        .meshes
        .iter()
        .flat_map(|m| m.indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| m.positions[t[k] as usize])).collect::<Vec<_>>())
        .collect();
    let mut covered = 0;
    for sample in &mapped.samples {
        let texel = &mapped.texels[sample.texel as usize];
        assert_eq!(texel.coverage, 1.0, "every sample of a cave face is covered by the face's geometry");
        let [a, b, c] = triangles[texel.triangle as usize];
        let normal = (b - a).cross(c - a).normalize();
        let off = (sample.position - a).dot(normal).abs();
        assert!(off < 1e-4, "sample at {} stands {off} m off the plane of its triangle", sample.position);
        assert!(sample.normal.dot(normal) > 0.9999, "sample normal {} against its triangle's {normal}", sample.normal);
        covered += 1;
    }
    assert_eq!(covered, (19 * 6 - 42) * 64, "19 blocks' faces less their 42 openings, 8^2 samples each");
}

#[test]
fn a_level_turned_a_quarter_about_the_vertical_and_declared_as_warped_blocks_bakes_the_same_tables() {
    let scene = load_scene("mrt-maze");
    let (dictionary, _, level, _) = mrt_quick_bake(&scene);
    let turn = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let mut turned = scene.clone();
    for mesh in &mut turned.meshes {
        mesh.positions.iter_mut().for_each(|p| *p = turn * *p);
        mesh.normals.iter_mut().for_each(|n| *n = turn * *n);
    }
    // The grid's blocks by their corners, turned with the scene: each keeps its corner order,
    // so its local +x now runs along world -z.
    let blocks: Vec<serde_json::Value> = Proxy::of(&scene)
        .unwrap()
        .corners
        .iter()
        .map(|c| serde_json::json!({ "corners": c.iter().map(|p| (turn * p.as_vec3()).to_array()).collect::<Vec<_>>() }))
        .collect();
    turned.settings.blocks.insert("mrt".into(), serde_json::json!({ "blocks": blocks }));
    let (_, turned_level) = relume_bake::mrt::baker::bake_level(&turned, &dictionary, 8).unwrap();
    assert_eq!(turned_level.blocks, level.blocks);
    assert_eq!(turned_level.receivers, level.receivers);
    assert_eq!(turned_level.copies, level.copies);
    assert_eq!(turned_level.feedback, level.feedback);
    for (i, (a, b)) in level.samples.iter().zip(&turned_level.samples).enumerate() {
        assert_eq!((a.albedo, a.texel), (b.albedo, b.texel), "sample {i}");
        assert!((turn * a.position).distance(b.position) < 1e-5, "sample {i} at {} against {}", a.position, b.position);
        assert!((turn * a.normal).distance(b.normal) < 1e-5, "sample {i} facing {} against {}", a.normal, b.normal);
    }
}

#[test]
fn geometry_off_the_blocks_and_a_level_of_another_dictionary_are_refused() {
    let mut scene = load_scene("mrt-cube");
    // The floor moved a block's side along x: it stands in no block.
    for p in &mut scene.meshes[0].positions {
        p.x += 2.0;
    }
    let (dictionary, ..) = mrt_quick_bake(&load_scene("mrt-cube"));
    let error = relume_bake::mrt::baker::bake_level(&scene, &dictionary, 8).err().expect("refused");
    says(&error, &["mesh \"Floor\" triangle 0", "in no block", "extras.relume.mrt"]);
    // A floor triangle across two blocks' faces.
    let mut scene = load_scene("mrt-corridor");
    let floor = scene.meshes.iter_mut().find(|m| m.name == "Floor").unwrap();
    floor.positions[0].x += 2.5;
    let error = relume_bake::mrt::baker::bake_level(&scene, &dictionary, 8).err().expect("refused");
    says(&error, &["mesh \"Floor\" triangle", "reaches past the face", "split the geometry"]);
    // A dynamic mesh the scene lacks.
    let mut scene = load_scene("mrt-figures");
    scene.settings.blocks["mrt"]["dynamic"] = serde_json::json!(["Figure", "Nobody"]);
    let error = relume_bake::mrt::baker::bake_level(&scene, &dictionary, 8).err().expect("refused");
    says(&error, &["extras.relume.mrt.dynamic", "\"Nobody\"", "no mesh of the scene"]);
    // A level read with a dictionary other than the one it was made with.
    let scene = load_scene("mrt-cube");
    let (_, _, level, _) = mrt_quick_bake(&scene);
    let other = Dictionary {
        blocks: {
            let mut b = dictionary.blocks.clone();
            b[0].u_b[0] += 1.0;
            b
        },
        ..dictionary.clone()
    };
    let error = level_refusal(&scene, &other, level_data::section(&level, serde_json::json!({})), "other");
    says(&error, &["mrt-level.bin", "made with the dictionary", "bake the level again"]);
}

/// Why `level` (a section) is refused when read from an artifact beside `dictionary`'s.
fn level_refusal(scene: &relume_bake::scene::Scene, dictionary: &Dictionary, level: relume_bake::artifact::Section, case: &str) -> String {
    let dir = std::env::temp_dir().join(format!("relume-mrt-level-{case}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let sections = vec![dictionary::section(dictionary, serde_json::json!({})), level];
    BakeOutput { method: "mrt", scene: Some(scene), parameters: serde_json::json!({}), sections, stats: serde_json::json!({}) }
        .write(&dir)
        .unwrap();
    let artifact = Artifact::read(&dir).unwrap();
    let (read, checksum) = dictionary::read(&artifact, None).unwrap();
    let error = level_data::read(&artifact, scene, &read, &checksum).unwrap_err().to_string();
    let _ = std::fs::remove_dir_all(&dir);
    error
}

/// A level file cut short, naming a shape the dictionary lacks, or naming one sample twice is
/// refused with the file and the item, never read.
#[test]
fn a_corrupt_level_is_refused_by_item() {
    let scene = load_scene("mrt-cube");
    let (dictionary, _, level, _) = mrt_quick_bake(&scene);
    let good = level_data::section(&level, serde_json::json!({})).files[0].1.clone();
    // Magic, the checksum's length and characters, the layout, the four counts: the first
    // block's shape.
    let shape_at = 8 + 4 + 4 * level.dictionary.len() + 12 + 16;
    let mut other_shape = good.clone();
    other_shape[shape_at..shape_at + 4].copy_from_slice(&9u32.to_le_bytes());
    let mut turned = good.clone();
    turned[shape_at + 4..shape_at + 8].copy_from_slice(&7u32.to_le_bytes());
    let mut twice = good.clone();
    let first_row = shape_at + 12;
    let second = twice[first_row + 4..first_row + 8].to_vec();
    twice[first_row..first_row + 4].copy_from_slice(&second);
    for (bytes, named) in [
        // The cube's tail: its block's corners (96 bytes) and no dynamic meshes (4).
        (good[..good.len() - 107].to_vec(), "the feedback"),
        (good[..good.len() - 7].to_vec(), "a block's corners"),
        (other_shape, "block 0 has shape 9; the dictionary has 6"),
        (turned, "7 quarter turns"),
        (twice, "which another row names too"),
    ] {
        let mut section = level_data::section(&level, serde_json::json!({}));
        section.files[0].1 = bytes;
        says(&level_refusal(&scene, &dictionary, section, "corrupt"), &["mrt-level.bin", named]);
    }
    // Tables no bake makes, written as they are: a receiver entering through a block's top,
    // dynamic meshes out of order.
    let corridor = load_scene("mrt-corridor");
    let (_, level) = relume_bake::mrt::baker::bake_level(&corridor, &dictionary, 8).unwrap();
    let mut through_the_top = level.clone();
    through_the_top.receivers[0].entry = Face::ALL[3];
    let mut unordered = level.clone();
    unordered.dynamic = vec![1, 0];
    for (bad, named) in [(through_the_top, "receiver 0"), (unordered, "2 dynamic meshes, not ascending")] {
        let section = level_data::section(&bad, serde_json::json!({}));
        says(&level_refusal(&corridor, &dictionary, section, "tables"), &["mrt-level.bin", named]);
    }
}

/// The level's tables, the solved feedback included, are the same bytes at 1 and 2 threads.
#[test]
fn a_level_is_the_same_bytes_at_one_and_two_threads() {
    let scene = load_scene("mrt-maze");
    let (dictionary, _, level, _) = mrt_quick_bake(&scene);
    let one = relume_bake::work::with_threads(Some(1), || relume_bake::mrt::baker::bake_level(&scene, &dictionary, 8).unwrap().1);
    let bytes = |l: &relume_bake::mrt::level_data::LevelData| level_data::section(l, serde_json::json!({})).files[0].1.clone();
    assert!(bytes(&one) == bytes(&level), "the level differs between 1 and 2 threads");
}
