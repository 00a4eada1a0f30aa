//! The generated scenes: byte-identical regeneration, loading, stated settings, light levels,
//! furnished rooms' sizes, the wall-light variant.

use super::settings::*;
use super::*;
use glam::{Vec3, Vec4Swizzles};
use relume_bake::gltf_load;
use relume_bake::light_path_maps::{LightPathMapsSceneSettings, LightRegion};
use relume_bake::obscurance::ObscuranceSceneSettings;
use relume_bake::scene::{LightKind, Scene};

fn temp_dir(tag: &str) -> PathBuf {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map(|d| d.as_nanos()).unwrap_or(0);
    std::env::temp_dir().join(format!("relume-scenegen-{tag}-{}-{nanos}", std::process::id()))
}

fn load(dir: &Path, name: &str) -> Scene {
    let loaded = gltf_load::load(&dir.join(format!("{name}.gltf"))).unwrap_or_else(|e| panic!("{e}"));
    assert!(loaded.warnings.is_empty(), "{:?}", loaded.warnings);
    loaded.scene
}

/// Pixel-space NDC of a world point through the scene camera (square image).
fn ndc(scene: &Scene, p: Vec3) -> Vec3 {
    let clip = scene.camera.clip_from_world(1, 1) * p.extend(1.0);
    clip.xyz() / clip.w
}

#[test]
fn writes_identical_bytes_twice_and_matches_the_committed_scenes() {
    let (a, b) = (temp_dir("a"), temp_dir("b"));
    let files_a = write_all(&a).unwrap();
    let files_b = write_all(&b).unwrap();
    assert_eq!(files_a.len(), 2 * SCENE_NAMES.len() + ENVIRONMENT_NAMES.len());
    let committed = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    for (fa, fb) in files_a.iter().zip(&files_b) {
        let bytes = std::fs::read(fa).unwrap();
        assert_eq!(bytes, std::fs::read(fb).unwrap(), "{} differs between runs", fa.display());
        let name = fa.strip_prefix(&a).unwrap();
        let old = std::fs::read(committed.join(name)).unwrap_or_else(|_| panic!("scenes/{} is not committed", name.display()));
        assert!(old == bytes, "scenes/{} is out of date: run `relume scenes --out scenes/`", name.display());
    }
    let _ = std::fs::remove_dir_all(&a);
    let _ = std::fs::remove_dir_all(&b);
}

#[test]
fn generated_scenes_load() {
    let dir = temp_dir("load");
    write_all(&dir).unwrap();

    // Every scene: loads without warnings, has a light, and its stored normals agree
    // with its winding (flat shading, front faces counter-clockwise).
    for name in SCENE_NAMES {
        let scene = load(&dir, name);
        assert!(!scene.lights.is_empty() || scene.environment.is_some(), "{name}");
        for m in &scene.meshes {
            for tri in m.indices.chunks_exact(3) {
                let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| m.positions[i as usize]);
                let n = (b - a).cross(c - a).normalize();
                // The stored normal is the exact one of the triangle before its corners were
                // rounded to f32; rounding moves a corner by up to half an ulp of its
                // coordinates, which turns the face by about that over its smallest altitude
                // (the blobs of fiv-crowd-60, 4 m out, turn by up to 1e-5).
                let double_area = (b - a).cross(c - a).length();
                let longest = (b - a).length().max((c - b).length()).max((a - c).length());
                let rounding = [a, b, c].iter().map(|p| p.abs().max_element()).fold(0.0f32, f32::max) * f32::EPSILON;
                let tolerance = 1e-5 + 4.0 * rounding * longest / double_area;
                // A smooth mesh (shared vertices: fiv-garden's) has the loader's area-weighted
                // normals, which may only lean from the face, not turn from it.
                let smooth = m.positions.len() < m.indices.len();
                for i in tri {
                    let normal = m.normals[*i as usize];
                    let off = (n - normal).length();
                    assert!(
                        if smooth { n.dot(normal) > 0.5 } else { off < tolerance },
                        "{name}: {}: winding and normal disagree by {off} (tolerance {tolerance}, smooth {smooth})",
                        m.name
                    );
                }
            }
        }
    }

    let cornell = load(&dir, "cornell");
    // 5 room quads and 2 blocks of 5 quads, 2 triangles each.
    assert_eq!(cornell.triangle_count(), 30);
    assert_eq!(cornell.meshes.len(), 7);
    for block in ["ShortBlock", "TallBlock"] {
        let m = cornell.meshes.iter().find(|m| m.name == block).unwrap();
        assert_eq!(m.indices.len() / 3, 10, "{block}");
    }
    assert_eq!(cornell.lights.len(), 1);
    let light = &cornell.lights[0];
    assert!(matches!(light.kind, LightKind::Spot { .. }));
    assert!((light.direction - Vec3::NEG_Y).length() < 1e-6);
    assert!((cornell.camera.position() - Vec3::new(0.0, 0.273, 0.8)).length() < 1e-6);
    assert!((cornell.camera.yfov.to_degrees() - 39.31).abs() < 0.01);
    // Classic orientation: red wall on the left of the image, green on the right.
    let centre_of = |name: &str| {
        let m = cornell.meshes.iter().find(|m| m.name == name).unwrap();
        m.positions.iter().sum::<Vec3>() / m.positions.len() as f32
    };
    assert!(ndc(&cornell, centre_of("LeftWall")).x < -0.5);
    assert!(ndc(&cornell, centre_of("RightWall")).x > 0.5);
    assert_eq!(cornell.materials[cornell.meshes.iter().find(|m| m.name == "LeftWall").unwrap().material].name, "red");
    // Every room surface faces into the room, every block face away from its block.
    let room_centre = Vec3::new(0.0, 0.2744, -0.2796);
    for m in &cornell.meshes {
        let inward = !m.name.ends_with("Block");
        for tri in m.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| m.positions[i as usize]);
            let n = (b - a).cross(c - a).normalize();
            assert!((n - m.normals[tri[0] as usize]).length() < 1e-5, "{}: winding and normal disagree", m.name);
            let to_centre = room_centre - (a + b + c) / 3.0;
            if inward {
                assert!(n.dot(to_centre) > 0.0, "{} faces out of the room", m.name);
            }
        }
    }
    // The light is inside the room, under the ceiling.
    let (lo, hi) = cornell.bounds();
    assert!(light.position.cmpgt(lo).all() && light.position.cmplt(hi).all());

    for (name, occluder_triangles) in [("occluder-plane", 12), ("occluder-stacked", 24)] {
        let scene = load(&dir, name);
        assert_eq!(scene.triangle_count(), 2 + occluder_triangles, "{name}");
        assert_eq!(scene.lights.len(), 1);
        let light = &scene.lights[0];
        assert_eq!(light.kind, LightKind::Spot { inner_cone: 35f32.to_radians(), outer_cone: 45f32.to_radians() });
        // Every occluder lies straight under the light, between it and the ground.
        for m in scene.meshes.iter().filter(|m| m.name != "Ground") {
            let (lo, hi) = m.bounds();
            assert!(lo.x < 0.0 && hi.x > 0.0 && lo.z < 0.0 && hi.z > 0.0, "{name}: {} is not under the light", m.name);
            assert!(lo.y > 0.5 && hi.y < light.position.y, "{name}: {}", m.name);
            // The occluder and the shadow below it are in view.
            for p in [(lo + hi) * 0.5, Vec3::ZERO, Vec3::new(0.6, 0.0, 0.6), Vec3::new(-0.6, 0.0, -0.6)] {
                let q = ndc(&scene, p);
                assert!(q.x.abs() < 1.0 && q.y.abs() < 1.0 && q.z > 0.0 && q.z < 1.0, "{name}: {p} is out of view");
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Everything a scene's settings say: the shared keys and each method's block.
type Stated = (Vec3, f32, f32, ObscuranceSceneSettings, LightPathMapsSceneSettings);

fn stated(scene: &Scene) -> Stated {
    let s = &scene.settings;
    (s.ambient, s.beta, s.texel_density, ObscuranceSceneSettings::of(scene).unwrap(), LightPathMapsSceneSettings::of(scene).unwrap())
}

fn settings(s: Settings) -> Stated {
    let region = s.light_region.map(|(min, max, test_points)| LightRegion::Box {
        min: Vec3::from_array(min.map(|x| x as f32)),
        max: Vec3::from_array(max.map(|x| x as f32)),
        test_points,
    });
    (
        Vec3::from_array(s.ambient.map(|x| x as f32)),
        s.beta as f32,
        s.texel_density as f32,
        ObscuranceSceneSettings { tau: s.tau as f32, l_max: s.l_max as f32 },
        LightPathMapsSceneSettings { region, light_area: s.light_area as f32 },
    )
}

#[test]
fn every_scene_states_its_settings() {
    let dir = temp_dir("settings");
    write_all(&dir).unwrap();
    for (name, expected) in [
        ("cornell", CORNELL_SETTINGS),
        ("occluder-plane", OCCLUDER_SETTINGS),
        ("occluder-stacked", OCCLUDER_SETTINGS),
        ("table-chair", TABLE_CHAIR_SETTINGS),
        ("classroom", CLASSROOM_SETTINGS),
        ("cornell-wall-light", CORNELL_WALL_LIGHT_SETTINGS),
    ] {
        assert_eq!(stated(&load(&dir, name)), settings(expected), "{name}");
    }
    // The values the brief set, spelled out once rather than only through the constants.
    let table_chair = stated(&load(&dir, "table-chair"));
    assert_eq!((table_chair.2, table_chair.3.tau, table_chair.3.l_max), (24.0, 0.2, 0.6));
    let cornell = load(&dir, "cornell").settings;
    assert_eq!((cornell.ambient, cornell.beta, cornell.texel_density), (Vec3::ONE, 0.0, 128.0));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Nearest hit of a ray (Möller-Trumbore) on the meshes `keep` accepts: distance, mesh
/// name and the triangle.
fn cast_on(scene: &Scene, origin: Vec3, dir: Vec3, keep: impl Fn(&str) -> bool) -> Option<(f32, String, [Vec3; 3])> {
    let mut best: Option<(f32, String, [Vec3; 3])> = None;
    for m in scene.meshes.iter().filter(|m| keep(&m.name)) {
        for tri in m.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| m.positions[i as usize]);
            let (e1, e2) = (b - a, c - a);
            let p = dir.cross(e2);
            let det = e1.dot(p);
            if det.abs() < 1e-12 {
                continue;
            }
            let t_vec = origin - a;
            let u = t_vec.dot(p) / det;
            let q = t_vec.cross(e1);
            let v = dir.dot(q) / det;
            let t = e2.dot(q) / det;
            if u < 0.0 || v < 0.0 || u + v > 1.0 || t <= 1e-6 {
                continue;
            }
            if best.as_ref().is_none_or(|(d, _, _)| t < *d) {
                best = Some((t, m.name.clone(), [a, b, c]));
            }
        }
    }
    best
}

fn cast(scene: &Scene, origin: Vec3, dir: Vec3) -> Option<(f32, String, [Vec3; 3])> {
    cast_on(scene, origin, dir, |_| true)
}

/// The README's convention: the floor, ground or wall a light points straight at
/// receives pi lux there, from the front, as if no occluder stood in between.
#[test]
fn every_light_gives_the_surface_in_front_of_it_pi_lux() {
    let dir = temp_dir("pi-lux");
    write_all(&dir).unwrap();
    for name in SCENE_NAMES {
        let scene = load(&dir, name);
        for light in &scene.lights {
            let receiver = |mesh: &str| ROOM_SURFACES.contains(&mesh) || mesh == "Ground";
            let (t, hit, [a, b, c]) = cast_on(&scene, light.position, light.direction, receiver)
                .unwrap_or_else(|| panic!("{name}: {} points at nothing", light.name));
            let point = light.position + t * light.direction;
            let incident = light.incident(point);
            let n = (b - a).cross(c - a).normalize();
            let cosine = n.dot(incident.to_light);
            assert!(cosine > 0.99, "{name}: {} lights the back of {hit}", light.name);
            let e = incident.irradiance * cosine;
            assert!((e - Vec3::splat(std::f32::consts::PI)).abs().max_element() < 1e-3, "{name}: {} gives {hit} {e} lux", light.name);
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

const ROOM_SURFACES: [&str; 6] = ["Floor", "Ceiling", "BackWall", "FrontWall", "LeftWall", "RightWall"];

/// Room surfaces face the room's inside, every piece of furniture is a closed box facing
/// outward, no two boxes overlap, and everything (lights and camera too) is in the room.
fn check_furnished_room(scene: &Scene, name: &str, lo: Vec3, hi: Vec3) {
    let inside = [(lo + hi) * 0.5, lo + (hi - lo) * 0.1, lo + (hi - lo) * Vec3::new(0.9, 0.5, 0.2)];
    let mut boxes = Vec::new();
    for m in &scene.meshes {
        let triangles: Vec<[Vec3; 3]> = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]].map(|i| m.positions[i as usize])).collect();
        let (mlo, mhi) = m.bounds();
        assert!(mlo.cmpge(lo - 1e-5).all() && mhi.cmple(hi + 1e-5).all(), "{name}: {} leaves the room", m.name);
        if ROOM_SURFACES.contains(&m.name.as_str()) {
            for [a, b, c] in &triangles {
                let n = (*b - *a).cross(*c - *a);
                for p in inside {
                    assert!(n.dot(p - *a) > 0.0, "{name}: {} faces out", m.name);
                }
            }
            continue;
        }
        assert_eq!(triangles.len(), 12, "{name}: {}", m.name);
        let centre = (mlo + mhi) * 0.5;
        for [a, b, c] in &triangles {
            let n = (*b - *a).cross(*c - *a);
            assert!(n.dot((*a + *b + *c) / 3.0 - centre) > 0.0, "{name}: {} faces in", m.name);
        }
        // Closed and consistently wound: each directed edge once, and its reverse once.
        let key = |p: Vec3| p.to_array().map(f32::to_bits);
        let mut edges = std::collections::BTreeMap::new();
        for [a, b, c] in &triangles {
            for (p, q) in [(a, b), (b, c), (c, a)] {
                *edges.entry((key(*p), key(*q))).or_insert(0) += 1;
            }
        }
        for ((p, q), count) in &edges {
            assert_eq!(*count, 1, "{name}: {}: an edge used twice", m.name);
            assert_eq!(edges.get(&(*q, *p)), Some(&1), "{name}: {} is open", m.name);
        }
        boxes.push((m.name.clone(), mlo, mhi));
    }
    // Boxes may touch, never overlap (1 mm of slack for f32 corners).
    for (i, (na, alo, ahi)) in boxes.iter().enumerate() {
        for (nb, blo, bhi) in &boxes[i + 1..] {
            let overlap = ahi.min(*bhi) - alo.max(*blo);
            assert!(overlap.min_element() < 1e-3, "{name}: {na} and {nb} overlap");
        }
    }
    // Some furniture stands on the floor.
    assert!(boxes.iter().any(|(_, blo, _)| blo.y.abs() < 1e-6));
    for light in &scene.lights {
        assert!(light.position.cmpgt(lo).all() && light.position.cmplt(hi).all(), "{name}: {} is outside the room", light.name);
    }
    let eye = scene.camera.position();
    assert!(eye.cmpgt(lo).all() && eye.cmplt(hi).all(), "{name}: camera");
}

fn in_view(scene: &Scene, p: Vec3) -> bool {
    let q = ndc(scene, p);
    q.x.abs() < 1.0 && q.y.abs() < 1.0 && q.z > 0.0 && q.z < 1.0
}

fn centre(scene: &Scene, mesh: &str) -> Vec3 {
    let m = scene.meshes.iter().find(|m| m.name == mesh).unwrap_or_else(|| panic!("no mesh {mesh}"));
    let (lo, hi) = m.bounds();
    (lo + hi) * 0.5
}

#[test]
fn furnished_rooms_match_the_papers_sizes_and_face_the_right_way() {
    let dir = temp_dir("rooms");
    write_all(&dir).unwrap();
    for (name, paper_triangles) in [("table-chair", 180.0), ("classroom", 1244.0)] {
        let count = load(&dir, name).triangle_count() as f64;
        assert!((count / paper_triangles - 1.0).abs() <= 0.1, "{name}: {count} triangles, the paper's scene has {paper_triangles}");
    }

    let scene = load(&dir, "table-chair");
    assert_eq!(scene.triangle_count(), 180);
    check_furnished_room(&scene, "table-chair", Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0));
    assert_eq!(scene.meshes.len(), 6 + 5 + 6);
    // The camera sees the table, the chair, the floor and two walls.
    for mesh in ["TableTop", "TableLeg0", "ChairSeat", "ChairBack", "Floor", "BackWall", "RightWall"] {
        assert!(in_view(&scene, centre(&scene, mesh)), "table-chair: {mesh} is out of view");
    }
    // The chair is pushed under the table: seat below the top, overlapping it in z.
    let seat = scene.meshes.iter().find(|m| m.name == "ChairSeat").unwrap().bounds();
    let top = scene.meshes.iter().find(|m| m.name == "TableTop").unwrap().bounds();
    assert!(seat.1.y < top.0.y && seat.0.z < top.1.z && seat.1.z > top.1.z);

    let scene = load(&dir, "classroom");
    check_furnished_room(&scene, "classroom", Vec3::new(-4.0, 0.0, -3.5), Vec3::new(4.0, 3.0, 3.5));
    assert_eq!(scene.lights.len(), 3);
    let pairs = scene.meshes.iter().filter(|m| m.name.ends_with("Seat")).count();
    assert_eq!(pairs, 16);
    // From the back of the room: the blackboard, the teacher's desk and the front row.
    for mesh in ["Blackboard", "TeacherDeskTop", "Desk00Top", "Desk03Top", "Desk21Top", "BackWall"] {
        assert!(in_view(&scene, centre(&scene, mesh)), "classroom: {mesh} is out of view");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cornell_wall_light_is_cornell_lit_from_5_cm_off_the_red_wall() {
    let dir = temp_dir("wall-light");
    write_all(&dir).unwrap();
    let (cornell, scene) = (load(&dir, "cornell"), load(&dir, "cornell-wall-light"));
    assert_eq!(cornell.meshes.len(), scene.meshes.len());
    for (a, b) in cornell.meshes.iter().zip(&scene.meshes) {
        assert_eq!((&a.name, &a.positions), (&b.name, &b.positions));
    }
    assert_eq!(cornell.camera.world_from_camera, scene.camera.world_from_camera);
    assert_eq!(scene.lights.len(), 1);
    let light = &scene.lights[0];
    assert_eq!(light.kind, LightKind::Spot { inner_cone: 40f32.to_radians(), outer_cone: 50f32.to_radians() });
    let (t, hit, _) = cast(&scene, light.position, light.direction).unwrap();
    assert_eq!(hit, "LeftWall");
    assert!((t - 0.05).abs() < 1e-5, "{t}");
    // At mid height and mid depth.
    let aim = light.position + t * light.direction;
    assert!((aim.y - 0.2744).abs() < 1e-4 && (aim.z + 0.2796).abs() < 1e-4, "{aim}");
    // Its whole cone lands on the red wall: no direct light anywhere else.
    let (u, v) = light.direction.any_orthonormal_pair();
    for k in 0..16 {
        let phi = k as f32 * std::f32::consts::TAU / 16.0;
        let edge = 50f32.to_radians();
        let dir = (light.direction * edge.cos() + (u * phi.cos() + v * phi.sin()) * edge.sin()).normalize();
        let (_, hit, _) = cast(&scene, light.position, dir).unwrap();
        assert_eq!(hit, "LeftWall", "cone edge at {k}/16 of a turn");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The scale scene grows with its bays alone: each bay adds its sixteen instanced desk and
/// chair pairs (648 triangles each) and one light, alternately a spot and a point light; every
/// triangle faces out of its box (the pairs) or into the hall (the shell), so the bakes see
/// closed furniture in a closed hall.
#[test]
fn the_scale_scene_grows_by_bays_of_instanced_furniture_and_lights() {
    let dir = temp_dir("scale");
    let mut furniture = Vec::new();
    for bays in [1u32, 2] {
        write_scale(&dir, bays, false).unwrap();
        let scene = load(&dir, &format!("scale-{bays}"));
        let pairs: Vec<_> = scene.meshes.iter().filter(|m| m.name.starts_with("Pair")).collect();
        assert_eq!(pairs.len() as u32, 16 * bays * bays);
        assert!(pairs.iter().all(|m| m.indices.len() == 3 * 648), "a pair is 6 boxes of 6 faces of 3 x 3 cells");
        furniture.push(pairs.iter().map(|m| m.indices.len() / 3).sum::<usize>());
        let spots = scene.lights.iter().filter(|l| matches!(l.kind, LightKind::Spot { .. })).count() as u32;
        assert_eq!((scene.lights.len() as u32, spots), (bays * bays, (bays * bays).div_ceil(2)));
        // Signed volume: positive for closed boxes facing out, minus the hall's for its shell.
        let volume = |name: &str| -> f32 {
            let mesh = scene.meshes.iter().find(|m| m.name == name).unwrap();
            mesh.indices
                .chunks_exact(3)
                .map(|t| mesh.positions[t[0] as usize].dot(mesh.positions[t[1] as usize].cross(mesh.positions[t[2] as usize])) / 6.0)
                .sum()
        };
        let pair = volume(&pairs[0].name.clone());
        assert!(pair > 0.02 && pair < 0.05, "a pair's boxes face out: volume {pair}");
        let side = 8.0 * bays as f32;
        let shell: f32 = ["Floor", "Ceiling", "BackWall", "FrontWall", "LeftWall", "RightWall"].into_iter().map(volume).sum();
        assert!((shell + side * side * 3.0).abs() < 1e-3 * side * side * 3.0, "the shell faces in: volume {shell}");
    }
    assert_eq!(furniture, [16 * 648, 64 * 648]);
    std::fs::remove_dir_all(&dir).ok();
    assert!(write_scale(&temp_dir("scale-refused"), 0, false).unwrap_err().to_string().contains("--scale 0: give 1..=32"));
}

/// The open hall is the hall less its ceiling, under the sky, and FIV finds its occluders in it
/// alone: every desk and chair pair (closed, though a chair's seat and front panel share an edge), of
/// one shape, so one table.
#[test]
fn the_open_scale_scene_is_the_hall_under_the_sky_with_the_pairs_as_occluders() {
    let dir = temp_dir("scale-sky");
    let written = write_scale(&dir, 2, true).unwrap();
    assert!(written.iter().any(|p| p.ends_with("envs/sky.exr")), "{written:?}");
    let scene = load(&dir, "scale-2-sky");
    assert!(scene.environment.is_some());
    assert!(scene.meshes.iter().all(|m| m.name != "Ceiling"));
    assert_eq!(scene.meshes.len(), 5 + 64);
    let fiv = relume_bake::fiv::FivSceneSettings::of(&scene).unwrap();
    assert!(fiv.derived && fiv.occluders.len() == 64 && fiv.occluders.iter().all(|name| name.starts_with("Pair")), "{:?}", fiv.occluders);
    assert_eq!(relume_bake::fiv::occluder_types(&scene, &fiv).unwrap().len(), 1);
    std::fs::remove_dir_all(&dir).ok();
}
