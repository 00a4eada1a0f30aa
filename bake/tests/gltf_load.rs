//! The glTF loader against the committed generated scenes (`scenes/`, written by
//! `relume scenes`) and against broken copies of them made here, one defect each.

use glam::{Mat3, Mat4, Quat, Vec3};
use relume_bake::environment::lat_long_image;
use relume_bake::gltf_load::{self, CameraOverride, ErrorKind};
use relume_bake::image::{self, Image};
use relume_bake::scene::LightKind;
use serde_json::{json, Value};
use std::path::Path;

mod gltf_support;
use gltf_support::*;

#[test]
fn cornell_box_loads() {
    let loaded = load_ok(&scenes_dir().join("cornell.gltf"));
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    let s = &loaded.scene;
    assert_eq!(s.triangle_count(), 30);
    assert_eq!(mesh(s, "ShortBlock").indices.len(), 30);
    assert_eq!(mesh(s, "TallBlock").indices.len(), 30);
    assert_eq!(s.lights.len(), 1);
    let LightKind::Spot { inner_cone, outer_cone } = s.lights[0].kind else { panic!("not a spot light") };
    assert!(inner_cone < outer_cone && outer_cone <= std::f32::consts::FRAC_PI_2);
    assert!((s.lights[0].direction - Vec3::NEG_Y).length() < 1e-6);
    assert!((s.camera.position() - Vec3::new(0.0, 0.273, 0.8)).length() < 1e-6);
    assert!((s.camera.yfov - 2.0 * (12.5f32 / 35.0).atan()).abs() < 1e-6);
    assert!(s.camera.znear > 0.0 && s.camera.zfar > 1.4);
    let (lo, hi) = s.bounds();
    assert!((hi.y - 0.5488).abs() < 1e-6 && lo.y.abs() < 1e-6 && (lo.z + 0.5592).abs() < 1e-6);
    let red = &s.materials[mesh(s, "LeftWall").material];
    assert!((red.base_color.truncate() - Vec3::new(0.63, 0.065, 0.05)).length() < 1e-6);
    for m in &s.meshes {
        assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-5));
    }
}

#[test]
fn occluder_scenes_load() {
    for (name, triangles, occluders) in [("occluder-plane", 14, 1), ("occluder-stacked", 26, 2)] {
        let loaded = load_ok(&scenes_dir().join(format!("{name}.gltf")));
        assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
        let s = &loaded.scene;
        assert_eq!(s.triangle_count(), triangles, "{name}");
        assert_eq!(s.meshes.len(), 1 + occluders);
        assert!(matches!(s.lights[0].kind, LightKind::Spot { .. }));
        let (lo, hi) = mesh(s, "Ground").positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| (l.min(*p), h.max(*p)));
        assert_eq!((lo, hi), (Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 0.0, 2.0)));
        // The camera looks down at the scene.
        let forward = s.camera.world_from_camera.transform_vector3(Vec3::NEG_Z);
        assert!(forward.y < -0.2, "{name}: camera does not look down");
    }
    // The box: a unit cube scaled by 0.5 and lifted by 1 in its node: 0.75..1.25 m.
    let s = load_ok(&scenes_dir().join("occluder-plane.gltf")).scene;
    let b = mesh(&s, "Box");
    let (lo, hi) = b.positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| (l.min(*p), h.max(*p)));
    assert_eq!((lo, hi), (Vec3::new(-0.25, 0.75, -0.25), Vec3::new(0.25, 1.25, 0.25)));
}

#[test]
fn glb_loads_identically_to_gltf() {
    let dir = temp_dir("glb");
    for name in ["cornell", "occluder-stacked"] {
        let (json, bin) = read_scene(name);
        let glb = dir.join(format!("{name}.glb"));
        std::fs::write(&glb, to_glb(&json, &bin)).unwrap();
        let from_gltf = load_ok(&scenes_dir().join(format!("{name}.gltf"))).scene;
        let from_glb = load_ok(&glb).scene;
        assert_same_scene(&from_gltf, &from_glb);
    }
}

#[test]
fn data_uri_buffer_loads_identically() {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let (mut json, bin) = read_scene("occluder-plane");
    let mut encoded = String::new();
    for chunk in bin.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                encoded.push(ALPHABET[(n >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                encoded.push('=');
            }
        }
    }
    json["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{encoded}"));
    let dir = temp_dir("datauri");
    let path = dir.join("embedded.gltf");
    std::fs::write(&path, serde_json::to_vec(&json).unwrap()).unwrap();
    assert_same_scene(&load_ok(&scenes_dir().join("occluder-plane.gltf")).scene, &load_ok(&path).scene);
}

// --- transforms ------------------------------------------------------------------------------

/// The Box node of occluder-plane given a transform; returns the Box mesh.
fn box_with_transform(dir: &Path, tag: &str, transform: Value) -> relume_bake::scene::Mesh {
    let (mut json, bin) = read_scene("occluder-plane");
    let nodes = json["nodes"].as_array_mut().unwrap();
    let node = nodes.iter_mut().find(|n| n["name"] == "Box").unwrap().as_object_mut().unwrap();
    for key in ["translation", "rotation", "scale", "matrix"] {
        node.remove(key);
    }
    for (k, v) in transform.as_object().unwrap() {
        node.insert(k.clone(), v.clone());
    }
    let path = write_scene(dir, &format!("box-{tag}"), &json, Some(&bin));
    mesh(&load_ok(&path).scene, "Box").clone()
}

#[test]
fn node_transforms_move_positions_and_normals() {
    let dir = temp_dir("transform");
    let raw = box_with_transform(&dir, "raw", json!({}));
    let rotation = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    let (t, s) = (Vec3::new(1.0, 2.0, -3.0), Vec3::new(2.0, 0.5, 1.5));
    let trs = Mat4::from_scale_rotation_translation(s, rotation, t);
    let moved =
        box_with_transform(&dir, "trs", json!({ "translation": t.to_array(), "rotation": rotation.to_array(), "scale": s.to_array() }));
    let normal_matrix = Mat3::from_mat4(trs).inverse().transpose();
    assert_eq!(raw.indices, moved.indices);
    for i in 0..raw.positions.len() {
        assert!((trs.transform_point3(raw.positions[i]) - moved.positions[i]).length() < 1e-5);
        let expected = (normal_matrix * raw.normals[i]).normalize();
        assert!((expected - moved.normals[i]).length() < 1e-5, "normal {i}: {expected} vs {}", moved.normals[i]);
    }
    // A parent's transform composes with the child's: the same TRS given as a column-major
    // matrix on a new parent node.
    let (mut json, bin) = read_scene("occluder-plane");
    let box_index = json["nodes"].as_array().unwrap().iter().position(|n| n["name"] == "Box").unwrap();
    json["nodes"][box_index].as_object_mut().unwrap().retain(|k, _| k == "name" || k == "mesh");
    json["nodes"].as_array_mut().unwrap().push(json!({ "name": "Parent", "matrix": trs.to_cols_array(), "children": [box_index] }));
    let parent = json["nodes"].as_array().unwrap().len() - 1;
    let roots = json["scenes"][0]["nodes"].as_array_mut().unwrap();
    roots.retain(|n| n.as_u64() != Some(box_index as u64));
    roots.push(json!(parent));
    let path = write_scene(&dir, "parented", &json, Some(&bin));
    let parented = mesh(&load_ok(&path).scene, "Box").clone();
    for i in 0..raw.positions.len() {
        assert!((parented.positions[i] - moved.positions[i]).length() < 1e-5);
        assert!((parented.normals[i] - moved.normals[i]).length() < 1e-5);
    }
}

#[test]
fn mirroring_transform_flips_winding() {
    let dir = temp_dir("mirror");
    let mirrored = box_with_transform(&dir, "mirror", json!({ "scale": [-1.0, 1.0, 1.0] }));
    for tri in mirrored.indices.chunks_exact(3) {
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| mirrored.positions[i as usize]);
        let geometric = (b - a).cross(c - a).normalize();
        // Still outward (the cube is centred on the origin) and agreeing with the normals.
        assert!(geometric.dot((a + b + c) / 3.0) > 0.0);
        assert!((geometric - mirrored.normals[tri[0] as usize]).length() < 1e-5);
    }
}

// --- cameras ---------------------------------------------------------------------------------

#[test]
fn camera_defaults_and_override() {
    let dir = temp_dir("camera");
    let (mut json, bin) = read_scene("occluder-plane");
    // No camera: a default one frames the scene.
    let nodes = json["nodes"].as_array_mut().unwrap();
    let cam = nodes.iter().position(|n| n.get("camera").is_some()).unwrap();
    let mut no_camera = json.clone();
    no_camera["nodes"][cam].as_object_mut().unwrap().remove("camera");
    let loaded = load_ok(&write_scene(&dir, "nocam", &no_camera, Some(&bin)));
    assert!(loaded.warnings.iter().any(|w| w.contains("default")));
    let s = &loaded.scene;
    let (lo, hi) = s.bounds();
    let view = s.camera.clip_from_world(1, 1);
    for corner in [lo, hi, Vec3::new(lo.x, hi.y, lo.z), Vec3::new(hi.x, lo.y, hi.z)] {
        let clip = view * corner.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        assert!(ndc.x.abs() <= 1.0 && ndc.y.abs() <= 1.0 && ndc.z > 0.0 && ndc.z < 1.0, "{corner} out of view: {ndc}");
    }
    // Infinite far plane (zfar absent) becomes finite and beyond the scene.
    json["cameras"][0]["perspective"].as_object_mut().unwrap().remove("zfar");
    let s = load_ok(&write_scene(&dir, "infinite", &json, Some(&bin))).scene;
    assert!(s.camera.zfar.is_finite() && s.camera.zfar > 7.0);
    // Override from the command line.
    let o = CameraOverride::parse("eye=0,5,0.001; target=0,0,0; yfov=30").unwrap();
    let s = gltf_load::load_with_camera(&scenes_dir().join("occluder-plane.gltf"), Some(&o)).unwrap().scene;
    assert!((s.camera.position() - Vec3::new(0.0, 5.0, 0.001)).length() < 1e-6);
    assert!((s.camera.yfov - 30f32.to_radians()).abs() < 1e-6);
    assert!(s.camera.world_from_camera.transform_vector3(Vec3::NEG_Z).y < -0.99);
}

// --- refusals ----------------------------------------------------------------------------------

#[test]
fn missing_file() {
    let path = temp_dir("missing").join("nothing.gltf");
    let e = load_err(&path);
    assert_eq!(e.kind, ErrorKind::NotFound);
    assert!(e.to_string().contains("not found"));
}

#[test]
fn missing_bin() {
    let dir = temp_dir("nobin");
    let (json, _) = read_scene("occluder-plane");
    let e = load_err(&write_scene(&dir, "occluder-plane", &json, None));
    assert_eq!(e.kind, ErrorKind::NotFound);
    let line = e.to_string();
    assert!(line.contains("buffer 0 (\"occluder-plane.bin\")") && line.contains("fix the uri"), "{line}");
}

#[test]
fn truncated_bin() {
    let dir = temp_dir("truncated");
    let (json, bin) = read_scene("occluder-plane");
    let e = load_err(&write_scene(&dir, "occluder-plane", &json, Some(&bin[..bin.len() - 10])));
    assert_eq!(e.kind, ErrorKind::Buffer);
    let line = e.to_string();
    assert!(line.contains(&format!("has {} bytes but the buffer's byteLength is {}", bin.len() - 10, bin.len())), "{line}");
}

#[test]
fn accessor_past_its_buffer_view() {
    let dir = temp_dir("accessor");
    let (mut json, bin) = read_scene("occluder-plane");
    json["accessors"][0]["count"] = json!(7);
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::Accessor);
    assert!(e.to_string().contains("mesh \"Ground\" primitive 0: POSITION accessor 0"), "{e}");
}

#[test]
fn nan_position() {
    let dir = temp_dir("nan");
    let (json, mut bin) = read_scene("occluder-plane");
    // Vertex 2's y of the Ground mesh (accessor 0).
    let at = accessor_offset(&json, 0) + 2 * 12 + 4;
    bin[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::NonFinite);
    let line = e.to_string();
    assert!(line.contains("mesh \"Ground\" primitive 0: vertex 2 has a non-finite POSITION"), "{line}");
}

#[test]
fn index_out_of_range() {
    let dir = temp_dir("index");
    let (json, mut bin) = read_scene("occluder-plane");
    let indices = json["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize;
    let at = accessor_offset(&json, indices) + 4;
    bin[at..at + 4].copy_from_slice(&17u32.to_le_bytes());
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::IndexOutOfRange);
    let line = e.to_string();
    assert!(
        line.ends_with("mesh \"Ground\" primitive 0: index 17 (at position 1) out of range (6 vertices); fix the indices accessor"),
        "{line}"
    );
}

#[test]
fn index_count_not_a_multiple_of_three() {
    let dir = temp_dir("count");
    let (mut json, bin) = read_scene("occluder-plane");
    let indices = json["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize;
    json["accessors"][indices]["count"] = json!(5);
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::NotTriangles);
    assert!(e.to_string().contains("index count 5 is not a multiple of 3"));
}

#[test]
fn non_triangle_mode_refused() {
    let dir = temp_dir("mode");
    let (mut json, bin) = read_scene("occluder-plane");
    json["meshes"][0]["primitives"][0]["mode"] = json!(1);
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::NotTriangles);
}

/// Each triangle of `mesh` as its corners' positions, turned so the smallest comes first: the
/// same triangle with the same winding, whichever vertices carry it.
fn turned(mesh: &relume_bake::scene::Mesh) -> Vec<[[u32; 3]; 3]> {
    let corner = |i: u32| mesh.positions[i as usize].to_array().map(f32::to_bits);
    let mut triangles: Vec<[[u32; 3]; 3]> = mesh
        .indices
        .chunks_exact(3)
        .map(|t| {
            let c = [corner(t[0]), corner(t[1]), corner(t[2])];
            let first = (0..3).min_by_key(|&k| c[k]).unwrap();
            [c[first], c[(first + 1) % 3], c[(first + 2) % 3]]
        })
        .collect();
    triangles.sort();
    triangles
}

#[test]
fn triangle_strips_and_fans_read_as_the_same_triangles() {
    let dir = temp_dir("strips");
    let (json, bin) = read_scene("occluder-plane");
    let listed = load_ok(&write_scene(&dir, "list", &json, Some(&bin)));
    let ground = mesh(&listed.scene, "Ground");
    let at = accessor_offset(&json, json["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize);
    let list: Vec<u32> = (0..6).map(|k| u32::from_le_bytes(bin[at + 4 * k..at + 4 * k + 4].try_into().unwrap())).collect();
    // The ground quad as two triangles (w u v) and one with the edge v-u and a vertex d: the
    // strip w u v d and the fan v w u d make the same two triangles with the same winding.
    let at_vertex = |i: u32| ground.positions[i as usize];
    let (first, second) = (&list[..3], &list[3..]);
    let shared = |i: u32| second.iter().any(|&j| at_vertex(j) == at_vertex(i));
    let lone = (0..3).find(|&k| !shared(first[k])).expect("the two triangles share an edge");
    let [w, u, v] = [first[lone], first[(lone + 1) % 3], first[(lone + 2) % 3]];
    let d = *second.iter().find(|&&j| at_vertex(j) != at_vertex(u) && at_vertex(j) != at_vertex(v)).expect("a vertex off the edge");
    for (mode, order) in [(5, [w, u, v, d]), (6, [v, w, u, d])] {
        let mut json = json.clone();
        let mut bin = bin.clone();
        let offset = bin.len();
        bin.extend(order.iter().flat_map(|i| i.to_le_bytes()));
        let views = json["bufferViews"].as_array_mut().unwrap();
        views.push(serde_json::json!({ "buffer": 0, "byteOffset": offset, "byteLength": 16 }));
        let view = views.len() - 1;
        let accessors = json["accessors"].as_array_mut().unwrap();
        accessors.push(serde_json::json!({ "bufferView": view, "componentType": 5125, "count": 4, "type": "SCALAR" }));
        json["meshes"][0]["primitives"][0]["indices"] = json!(accessors.len() - 1);
        json["meshes"][0]["primitives"][0]["mode"] = json!(mode);
        json["buffers"][0]["byteLength"] = json!(bin.len());
        let loaded = load_ok(&write_scene(&dir, &format!("mode{mode}"), &json, Some(&bin)));
        let other = mesh(&loaded.scene, "Ground");
        assert_eq!(other.indices.len(), 6, "mode {mode}: two triangles");
        assert_eq!(turned(other), turned(ground), "mode {mode}: the triangles differ");
        assert!(loaded.warnings.is_empty(), "mode {mode}: {:?}", loaded.warnings);
    }
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let dir = temp_dir("degenerate");
    let (json, mut bin) = read_scene("occluder-plane");
    // Ground triangle 1: all three indices 3.
    let indices = json["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize;
    let at = accessor_offset(&json, indices) + 12;
    for k in 0..3 {
        bin[at + 4 * k..at + 4 * k + 4].copy_from_slice(&3u32.to_le_bytes());
    }
    let loaded = load_ok(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(loaded.scene.triangle_count(), 13);
    assert_eq!(loaded.warnings.len(), 1);
    assert!(
        loaded.warnings[0].contains("mesh \"Ground\" primitive 0: dropped 1 degenerate (zero-area) triangles of 2"),
        "{}",
        loaded.warnings[0]
    );
}

#[test]
fn missing_normals_are_computed() {
    let dir = temp_dir("normals");
    let (mut json, bin) = read_scene("occluder-plane");
    for m in json["meshes"].as_array_mut().unwrap() {
        m["primitives"][0]["attributes"].as_object_mut().unwrap().remove("NORMAL");
    }
    let without = load_ok(&write_scene(&dir, "x", &json, Some(&bin))).scene;
    let with = load_ok(&scenes_dir().join("occluder-plane.gltf")).scene;
    for (a, b) in without.meshes.iter().zip(&with.meshes) {
        for (na, nb) in a.normals.iter().zip(&b.normals) {
            // Flat-shaded input: each vertex belongs to one triangle, so the computed normal
            // is that face's normal.
            assert!((*na - *nb).length() < 1e-5);
        }
    }
}

#[test]
fn no_light() {
    let dir = temp_dir("nolight");
    let (mut json, bin) = read_scene("occluder-plane");
    for n in json["nodes"].as_array_mut().unwrap() {
        n.as_object_mut().unwrap().remove("extensions");
    }
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::NoLight);
    assert!(e.to_string().ends_with("scene \"occluder-plane\": has no light; add a KHR_lights_punctual light, an emissive material, an environment (extras.relume.environment) or an ambient light (extras.relume.ambient), or give a lights file (--lights)"), "{e}");
    // An emissive material is light enough.
    json["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_materials_emissive_strength"]);
    json["materials"][1]["emissiveFactor"] = json!([1.0, 0.5, 0.25]);
    json["materials"][1]["extensions"] = json!({ "KHR_materials_emissive_strength": { "emissiveStrength": 4.0 } });
    let s = load_ok(&write_scene(&dir, "y", &json, Some(&bin))).scene;
    assert!(s.lights.is_empty());
    assert_eq!(s.materials[mesh(&s, "Box").material].emission, Vec3::new(4.0, 2.0, 1.0));
}

#[test]
fn an_environment_is_light_enough_and_a_bad_one_is_refused_by_name() {
    let dir = temp_dir("environment");
    let (mut json, bin) = read_scene("occluder-plane");
    for n in json["nodes"].as_array_mut().unwrap() {
        n.as_object_mut().unwrap().remove("extensions");
    }
    std::fs::create_dir_all(dir.join("envs")).unwrap();
    let write = |name: &str, image: &Image| {
        let mut outputs = relume_bake::outputs::Outputs::new();
        image::write_exr_layers(&mut outputs, &dir.join("envs").join(name), &[("rgb", image)]).unwrap();
        outputs.commit().unwrap();
    };
    write("sky.exr", &lat_long_image(64, |d| Vec3::splat(d.y.max(0.0))));
    json["scenes"][0]["extras"]["relume"]["environment"] = json!({ "image": "envs/sky.exr", "intensity": 2.0, "cube_face": 8 });
    let s = load_ok(&write_scene(&dir, "lit", &json, Some(&bin))).scene;
    let environment = s.environment.expect("the environment is loaded");
    assert_eq!(environment.face, 8);
    assert!((environment.radiance_towards(Vec3::Y).y - 2.0).abs() < 0.1);

    let mut refused = |image: &str, expected: &str| {
        json["scenes"][0]["extras"]["relume"]["environment"]["image"] = json!(image);
        let e = load_err(&write_scene(&dir, "bad", &json, Some(&bin))).to_string();
        assert!(e.contains("extras.relume.environment") && e.contains(expected), "{e}");
    };
    refused("envs/missing.exr", "missing.exr: file not found");
    write("square.exr", &Image::new(16, 16));
    refused("envs/square.exr", "16x16, not a lat-long image");
    let mut nan = Image::new(16, 8);
    nan.set(5, 2, Vec3::splat(f32::NAN));
    write("nan.exr", &nan);
    refused("envs/nan.exr", "texel (5, 2)");
    std::fs::write(dir.join("envs/text.exr"), b"not an exr").unwrap();
    refused("envs/text.exr", "not a readable RGB EXR");
}

#[test]
fn empty_scene() {
    let dir = temp_dir("empty");
    let (mut json, bin) = read_scene("occluder-plane");
    for n in json["nodes"].as_array_mut().unwrap() {
        n.as_object_mut().unwrap().remove("mesh");
    }
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::Empty);
    assert!(e.to_string().contains("has no triangles"));
}

#[test]
fn bad_json_and_bad_spot_cone() {
    let dir = temp_dir("json");
    let path = dir.join("broken.gltf");
    std::fs::write(&path, b"{ \"asset\": { \"version\": \"2.0\" }, ").unwrap();
    assert_eq!(load_err(&path).kind, ErrorKind::Parse);
    let (mut json, bin) = read_scene("occluder-plane");
    json["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"]["innerConeAngle"] = json!(1.0);
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert_eq!(e.kind, ErrorKind::Invalid);
    assert!(e.to_string().contains("innerConeAngle < outerConeAngle"));
}

#[test]
fn spot_cone_defaults_follow_the_extension() {
    let dir = temp_dir("cone");
    let (mut json, bin) = read_scene("occluder-plane");
    json["extensions"]["KHR_lights_punctual"]["lights"][0]["spot"] = json!({});
    let s = load_ok(&write_scene(&dir, "x", &json, Some(&bin))).scene;
    assert_eq!(s.lights[0].kind, LightKind::Spot { inner_cone: 0.0, outer_cone: std::f32::consts::FRAC_PI_4 });
}

#[test]
fn point_and_directional_lights() {
    let dir = temp_dir("lights");
    let (mut json, bin) = read_scene("occluder-plane");
    json["extensions"]["KHR_lights_punctual"]["lights"] = json!([
        { "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 2.0, "range": 10.0 },
        { "type": "directional", "intensity": 3.0 },
    ]);
    let nodes = json["nodes"].as_array_mut().unwrap();
    nodes.push(
        json!({ "name": "Sun", "rotation": [-0.70710677, 0.0, 0.0, 0.70710677], "extensions": { "KHR_lights_punctual": { "light": 1 } } }),
    );
    let sun = nodes.len() - 1;
    json["scenes"][0]["nodes"].as_array_mut().unwrap().push(json!(sun));
    let s = load_ok(&write_scene(&dir, "x", &json, Some(&bin))).scene;
    assert_eq!(s.lights.len(), 2);
    assert_eq!(s.lights[0].kind, LightKind::Point);
    assert_eq!(s.lights[0].intensity, Vec3::new(2.0, 1.0, 0.5));
    assert_eq!(s.lights[0].range, Some(10.0));
    assert_eq!(s.lights[0].position, Vec3::new(0.0, 3.0, 0.0));
    assert_eq!(s.lights[1].kind, LightKind::Directional);
    assert!((s.lights[1].direction - Vec3::NEG_Y).length() < 1e-6);
}

#[test]
fn png_base_color_texture_is_decoded_to_linear() {
    let dir = temp_dir("texture");
    // A 2x1 RGB PNG: sRGB 255,0,0 and 128,128,128.
    let mut png_bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png_bytes, 2, 1);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        writer.write_image_data(&[255, 0, 0, 128, 128, 128]).unwrap();
    }
    std::fs::write(dir.join("tex.png"), &png_bytes).unwrap();
    let (mut json, bin) = read_scene("occluder-plane");
    json["images"] = json!([{ "uri": "tex.png" }]);
    json["textures"] = json!([{ "source": 0 }]);
    json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({ "index": 0 });
    // Without TEXCOORD_0 the texture cannot be sampled: refused.
    let e = load_err(&write_scene(&dir, "x", &json, Some(&bin)));
    assert!(e.to_string().contains("has no TEXCOORD_0"), "{e}");
    // Give the ground uv0 from a new accessor appended to the buffer.
    let mut bin = bin;
    let offset = bin.len();
    for i in 0..6 {
        bin.extend_from_slice(&(i as f32 * 0.1).to_le_bytes());
        bin.extend_from_slice(&0.5f32.to_le_bytes());
    }
    json["buffers"][0]["byteLength"] = json!(bin.len());
    json["bufferViews"].as_array_mut().unwrap().push(json!({ "buffer": 0, "byteOffset": offset, "byteLength": 48 }));
    let view = json["bufferViews"].as_array().unwrap().len() - 1;
    json["accessors"].as_array_mut().unwrap().push(json!({ "bufferView": view, "componentType": 5126, "count": 6, "type": "VEC2" }));
    let acc = json["accessors"].as_array().unwrap().len() - 1;
    json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(acc);
    let s = load_ok(&write_scene(&dir, "y", &json, Some(&bin))).scene;
    assert_eq!(s.textures.len(), 1);
    let t = &s.textures[0];
    assert_eq!((t.width, t.height), (2, 1));
    assert_eq!(t.texels[0], glam::Vec4::new(1.0, 0.0, 0.0, 1.0));
    assert!((t.texels[1].x - 0.2158605).abs() < 1e-5);
    let ground = mesh(&s, "Ground");
    assert_eq!(s.materials[ground.material].base_color_texture, Some(0));
    assert!((ground.uv0.as_ref().unwrap()[1] - glam::Vec2::new(0.1, 0.5)).length() < 1e-6);
    // The pixel limit is the caller's: this 2 x 1 image passes a limit of 2, not one of 1.
    let limited = |pixels| {
        gltf_load::load_with_options(
            &dir.join("y.gltf"),
            &gltf_load::LoadOptions { max_texture_pixels: Some(pixels), ..Default::default() },
        )
    };
    assert!(limited(2).is_ok());
    let Err(e) = limited(1) else { panic!("a 2-pixel texture passed a limit of 1") };
    let e = e.to_string();
    assert!(e.contains("2 x 1 pixels") && e.contains("limit of 1 pixels") && e.contains("--max-texture-pixels"), "{e}");
    // JPEG is refused by its signature.
    std::fs::write(dir.join("tex.png"), [0xFF, 0xD8, 0xFF, 0xE0, 0, 0]).unwrap();
    let e = load_err(&dir.join("y.gltf"));
    assert_eq!(e.kind, ErrorKind::Unsupported);
    assert!(e.to_string().contains("JPEG"));
    // A small PNG whose header claims 100000 x 100000 pixels is refused before anything is
    // allocated (30 GB would abort the process).
    let mut bomb = png_bytes.clone();
    bomb[16..20].copy_from_slice(&100_000u32.to_be_bytes());
    bomb[20..24].copy_from_slice(&100_000u32.to_be_bytes());
    let crc = crc32(&bomb[12..29]);
    bomb[29..33].copy_from_slice(&crc.to_be_bytes());
    std::fs::write(dir.join("tex.png"), &bomb).unwrap();
    let e = load_err(&dir.join("y.gltf"));
    assert!(e.to_string().contains("100000 x 100000") && e.to_string().contains("limit of 67108864"), "{e}");
}

#[test]
fn files_outside_the_scenes_folder_are_read_only_when_allowed() {
    let dir = temp_dir("outside");
    let inner = dir.join("scene");
    std::fs::create_dir_all(inner.join("sub")).unwrap();
    let (mut json, bin) = read_scene("occluder-plane");
    std::fs::write(dir.join("outside.bin"), &bin).unwrap();
    for uri in ["../outside.bin", "sub/../../outside.bin"] {
        json["buffers"][0]["uri"] = json!(uri);
        let path = write_scene(&inner, "x", &json, None);
        let e = load_err(&path);
        assert!(e.to_string().contains("outside the scene's folder") && e.to_string().contains("--allow-outside-files"), "{e}");
        let options = gltf_load::LoadOptions { outside_files: true, ..Default::default() };
        assert_eq!(gltf_load::load_with_options(&path, &options).unwrap().scene.meshes.len(), 2);
    }
    // Inside its folder, a path through .. is fine.
    std::fs::write(inner.join("in.bin"), &bin).unwrap();
    json["buffers"][0]["uri"] = json!("sub/../in.bin");
    assert_eq!(load_ok(&write_scene(&inner, "y", &json, None)).scene.meshes.len(), 2);
}

/// The CRC-32 of PNG chunks (ISO 3309), bit by bit.
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 == 1 { (crc >> 1) ^ 0xEDB8_8320 } else { crc >> 1 };
        }
    }
    !crc
}

/// Corrupted and truncated files are refused (or loaded), never a panic.
#[test]
fn damaged_files_never_panic() {
    let dir = temp_dir("fuzz");
    let (json, bin) = read_scene("occluder-stacked");
    let glb = to_glb(&json, &bin);
    let path = dir.join("fuzz.glb");
    let mut state = 0x2545_F491_4F6C_DD1Du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for round in 0..600 {
        let mut bytes = glb.clone();
        match round % 3 {
            0 => bytes.truncate(next() as usize % glb.len()),
            1 => {
                for _ in 0..1 + next() % 4 {
                    let at = next() as usize % bytes.len();
                    bytes[at] = next() as u8;
                }
            }
            _ => {
                // Damage the binary chunk only, where JSON parsing cannot catch it.
                let json_len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
                let start = 20 + json_len + 8;
                for _ in 0..1 + next() % 8 {
                    let at = start + next() as usize % (glb.len() - start);
                    bytes[at] = next() as u8;
                }
            }
        }
        std::fs::write(&path, &bytes).unwrap();
        if let Err(e) = gltf_load::load(&path) {
            assert!(!e.to_string().contains('\n'));
        }
    }
}

/// Numbers changed at random in the JSON (still valid JSON, wrong values) are refused or
/// loaded, never a panic; and a node cycle is refused.
#[test]
fn damaged_json_never_panics() {
    let dir = temp_dir("fuzzjson");
    let (json, bin) = read_scene("occluder-stacked");
    let text = serde_json::to_string(&json).unwrap();
    std::fs::write(dir.join("occluder-stacked.bin"), &bin).unwrap();
    let path = dir.join("fuzz.gltf");
    let digits: Vec<usize> = text.bytes().enumerate().filter(|(_, b)| b.is_ascii_digit()).map(|(i, _)| i).collect();
    let mut state = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    for _ in 0..400 {
        let mut bytes = text.clone().into_bytes();
        for _ in 0..1 + next() % 3 {
            let at = digits[next() as usize % digits.len()];
            bytes[at] = b"0123456789"[next() as usize % 10];
        }
        std::fs::write(&path, &bytes).unwrap();
        if let Err(e) = gltf_load::load(&path) {
            assert!(!e.to_string().contains('\n'));
        }
    }
    let mut cyclic = json.clone();
    cyclic["nodes"][0]["children"] = json!([1]);
    cyclic["nodes"][1]["children"] = json!([0]);
    let e = load_err(&write_scene(&dir, "cycle", &cyclic, None));
    assert!(matches!(e.kind, ErrorKind::Invalid | ErrorKind::Parse), "{e}");
}
