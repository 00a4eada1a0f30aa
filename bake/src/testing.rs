//! Scenes built in code for analytic tests: a tessellated closed sphere, squares (a big
//! ground plane, an area light), a closed box, and the lights and camera to go with them.
//!
//! Every mesh here is flat shaded (each triangle has its own vertices, whose normals are the
//! face normal), so shading normals equal geometric normals and the analytic answers hold
//! exactly, independent of the tessellation. Orientation is enforced, not assumed: each
//! builder checks each triangle's winding against the side it must face and flips it if
//! needed.

use crate::environment::{Environment, EnvironmentSettings};
use crate::scene::{Camera, Light, LightKind, Material, Mesh, Scene};
use crate::settings::SceneSettings;
use glam::{DVec3, Mat4, Vec2, Vec3};
use std::path::PathBuf;

/// Which way a closed surface's front faces (and so its emission) point.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Facing {
    Outward,
    Inward,
}

/// A Lambertian material with constant albedo and emitted radiance.
pub fn material(name: &str, albedo: Vec3, emission: Vec3) -> Material {
    Material { name: name.to_string(), base_color: albedo.extend(1.0), base_color_texture: None, emission, phong: None }
}

/// A scene from parts; its `source` names it as built in code.
pub fn scene(name: &str, meshes: Vec<Mesh>, materials: Vec<Material>, lights: Vec<Light>, camera: Camera) -> Scene {
    let mut scene = Scene {
        source: PathBuf::from(format!("<built in code: {name}>")),
        meshes,
        materials,
        textures: Vec::new(),
        lights,
        environment: None,
        camera,
        settings: SceneSettings::defaults_for((Vec3::ZERO, Vec3::ONE)),
    };
    scene.settings = SceneSettings::defaults_for(scene.bounds());
    scene
}

/// A camera at `eye` looking at `target`, `up` roughly up, vertical field of view `yfov`.
/// `count` points spread over the cube [lo, hi]^3 by a fixed hash (the same at every call).
pub fn scattered_points(count: u32, lo: f32, hi: f32) -> Vec<Vec3> {
    (0..count)
        .map(|i| {
            let h = |k: u32| ((i.wrapping_mul(2_654_435_761) ^ k.wrapping_mul(40_503)) % 1000) as f32 / 1000.0;
            Vec3::new(h(1), h(2), h(3)) * (hi - lo) + Vec3::splat(lo)
        })
        .collect()
}

pub fn look_at(eye: Vec3, target: Vec3, up: Vec3, yfov: f32) -> Camera {
    // glTF cameras look down their local -Z with +Y up.
    let forward = (target - eye).normalize();
    let right = forward.cross(up).normalize();
    let camera_up = right.cross(forward);
    Camera {
        world_from_camera: Mat4::from_cols(right.extend(0.0), camera_up.extend(0.0), (-forward).extend(0.0), eye.extend(1.0)),
        yfov,
        znear: 0.01,
        zfar: 1.0e4,
    }
}

pub fn point_light(position: Vec3, intensity: Vec3) -> Light {
    Light { name: "point".to_string(), kind: LightKind::Point, intensity, range: None, position, direction: Vec3::NEG_Z }
}

pub fn spot_light(position: Vec3, direction: Vec3, intensity: Vec3, inner_cone: f32, outer_cone: f32) -> Light {
    Light {
        name: "spot".to_string(),
        kind: LightKind::Spot { inner_cone, outer_cone },
        intensity,
        range: None,
        position,
        direction: direction.normalize(),
    }
}

/// A flat-shaded mesh from a triangle soup; `facing` decides each triangle's winding: it
/// is flipped when its normal disagrees with `wanted(centroid)`.
fn soup(name: &str, triangles: &[[Vec3; 3]], material: usize, wanted: impl Fn(Vec3) -> Vec3) -> Mesh {
    let mut positions = Vec::with_capacity(triangles.len() * 3);
    let mut normals = Vec::with_capacity(triangles.len() * 3);
    for &[a, b, c] in triangles {
        let mut tri = [a, b, c];
        let n = (b - a).cross(c - a);
        if n.dot(wanted((a + b + c) / 3.0)) < 0.0 {
            tri.swap(1, 2);
        }
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
        positions.extend(tri);
        normals.extend([n; 3]);
    }
    let count = positions.len() as u32;
    Mesh {
        name: name.to_string(),
        uv0: Some(vec![Vec2::ZERO; positions.len()]),
        uv1: None,
        positions,
        normals,
        indices: (0..count).collect(),
        material,
    }
}

/// The unit icosphere: an icosahedron subdivided `subdivisions` times (20 * 4^n triangles),
/// in f64 so that the scene generator's meshes built on it keep their bytes. Vertices shared
/// by triangles are computed from the same numbers, so meshes made from it are closed.
pub fn icosphere(subdivisions: u32) -> Vec<[DVec3; 3]> {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    let v = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .map(|p| DVec3::from_array(p).normalize());
    #[rustfmt::skip]
    const FACES: [[usize; 3]; 20] = [
        [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11],
        [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
        [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9],
        [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
    ];
    let mut tris: Vec<[DVec3; 3]> = FACES.iter().map(|f| f.map(|i| v[i])).collect();
    for _ in 0..subdivisions {
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let (ab, bc, ca) = ((a + b).normalize(), (b + c).normalize(), (c + a).normalize());
            next.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        tris = next;
    }
    tris
}

/// A closed sphere: [`icosphere`] of `subdivisions`, vertices on the sphere.
pub fn sphere(center: Vec3, radius: f32, subdivisions: u32, facing: Facing, material: usize) -> Mesh {
    let tris: Vec<[Vec3; 3]> = icosphere(subdivisions).iter().map(|t| t.map(|p| center + p.as_vec3() * radius)).collect();
    let sign = if facing == Facing::Outward { 1.0 } else { -1.0 };
    soup("sphere", &tris, material, |c| (c - center) * sign)
}

/// A square centred at `center`, spanned by the half-edge vectors `u` and `v`, split into
/// `n` x `n` cells (two triangles each); its front faces the direction of `u x v`.
pub fn square(center: Vec3, u: Vec3, v: Vec3, n: u32, material: usize) -> Mesh {
    let normal = u.cross(v);
    let corner = |i: u32, j: u32| center + u * (2.0 * i as f32 / n as f32 - 1.0) + v * (2.0 * j as f32 / n as f32 - 1.0);
    let mut tris = Vec::with_capacity((2 * n * n) as usize);
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (corner(i, j), corner(i + 1, j), corner(i + 1, j + 1), corner(i, j + 1));
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
    }
    soup("square", &tris, material, |_| normal)
}

/// A closed axis-aligned box, each face split into `n` x `n` cells.
pub fn closed_box(min: Vec3, max: Vec3, n: u32, facing: Facing, material: usize) -> Mesh {
    let c = (min + max) * 0.5;
    let h = (max - min) * 0.5;
    let faces = [(Vec3::X, Vec3::Y, Vec3::Z), (Vec3::Y, Vec3::Z, Vec3::X), (Vec3::Z, Vec3::X, Vec3::Y)];
    let mut tris = Vec::new();
    for (axis, a, b) in faces {
        for side in [-1.0f32, 1.0] {
            let face = square(c + axis * h * side, a * h, b * h, n, 0);
            tris.extend(face.positions.chunks_exact(3).map(|t| [t[0], t[1], t[2]]));
        }
    }
    let sign = if facing == Facing::Outward { 1.0 } else { -1.0 };
    // Each face's wanted normal is the axis it lies across, pointing out of (or into) the box.
    soup("box", &tris, material, |p| {
        let d = (p - c) / h;
        let k = d.abs().max_position();
        let mut n = Vec3::ZERO;
        n[k] = d[k].signum() * sign;
        n
    })
}

/// Procedural environments (radiance by direction) for analytic tests and the generated
/// scenes: a sky brightening towards the zenith over a dim ground, with a small sun.
pub fn sky(sun_direction: Vec3, sun_radiance: Vec3, sun_radius_degrees: f32) -> impl Fn(Vec3) -> Vec3 {
    let sun = sun_direction.normalize();
    let cos_sun = sun_radius_degrees.to_radians().cos();
    move |d: Vec3| {
        let sky = if d.y >= 0.0 { Vec3::new(0.35, 0.5, 0.9).lerp(Vec3::new(0.9, 0.95, 1.0), 1.0 - d.y) } else { Vec3::splat(0.1) };
        if d.dot(sun) >= cos_sun {
            sun_radiance
        } else {
            sky
        }
    }
}

/// Two coloured area lights (a red one and a green one, 30 degrees square, 45 degrees up on
/// opposite sides) in a black environment: the paper's Fig. 14 lighting.
pub fn two_area_lights(radiance: f32) -> impl Fn(Vec3) -> Vec3 {
    move |d: Vec3| {
        let elevation = d.y.clamp(-1.0, 1.0).asin().to_degrees();
        let azimuth = d.x.atan2(-d.z).to_degrees();
        if !(30.0..=60.0).contains(&elevation) {
            Vec3::ZERO
        } else if (-15.0..=15.0).contains(&azimuth) {
            Vec3::new(radiance, 0.0, 0.0)
        } else if azimuth.abs() >= 165.0 {
            Vec3::new(0.0, radiance, 0.0)
        } else {
            Vec3::ZERO
        }
    }
}

/// An environment of `radiance` (a lat-long image of 512 x 256 resampled onto a cube of
/// `cube_face`).
pub fn environment(radiance: impl Fn(Vec3) -> Vec3, cube_face: u32) -> Environment {
    let settings = EnvironmentSettings { image: "built in code".into(), layer: None, intensity: 1.0, rotation_y_degrees: 0.0, cube_face };
    let image = crate::environment::lat_long_image(512, radiance);
    Environment::from_lat_long(&image, std::path::Path::new("<built in code>"), &settings).expect("a valid environment")
}

/// FIV's test scene: a ground square 40 m wide at y = 0 facing up, 16 x 16 cells (albedo
/// 0.5, mesh "ground"), black closed spheres (centre, radius) named "ball <k>", each an occluder of
/// `extras.relume.fiv`, lit only by the environment `radiance` on a cube of `cube_face`, seen
/// from above at an angle.
pub fn occluders_over_ground(balls: &[(Vec3, f32)], radiance: impl Fn(Vec3) -> Vec3, cube_face: u32) -> Scene {
    let mut meshes = vec![Mesh { name: "ground".into(), ..square(Vec3::ZERO, Vec3::X * 20.0, Vec3::NEG_Z * 20.0, 16, 0) }];
    for (k, (centre, radius)) in balls.iter().enumerate() {
        meshes.push(Mesh { name: format!("ball {k}"), ..sphere(*centre, *radius, 3, Facing::Outward, 1) });
    }
    let materials = vec![material("ground", Vec3::splat(0.5), Vec3::ZERO), material("black", Vec3::ZERO, Vec3::ZERO)];
    let mut s = scene("occluders over ground", meshes, materials, vec![], look_at(Vec3::new(0.0, 4.0, 4.0), Vec3::ZERO, Vec3::Y, 0.8));
    s.environment = Some(environment(radiance, cube_face));
    let names: Vec<String> = (0..balls.len()).map(|k| format!("ball {k}")).collect();
    s.settings.blocks.insert("fiv".into(), serde_json::json!({ "occluders": names }));
    s
}

/// A wave on a flat-shaded mesh: every vertex raised by `amplitude` sin(2 pi x / `wavelength`)
/// cos(2 pi z / `wavelength`), each triangle's normals its new face normal (front kept).
/// Positions and normals in the mesh's vertex order: a deforming receiver's next shape.
pub fn waved(mesh: &Mesh, amplitude: f32, wavelength: f32) -> (Vec<Vec3>, Vec<Vec3>) {
    let k = std::f32::consts::TAU / wavelength;
    let positions: Vec<Vec3> = mesh.positions.iter().map(|p| *p + Vec3::Y * amplitude * (k * p.x).sin() * (k * p.z).cos()).collect();
    let mut normals = mesh.normals.clone();
    for t in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let n = if n.dot(mesh.normals[t[0] as usize]) < 0.0 { -n } else { n };
        t.iter().for_each(|&i| normals[i as usize] = n);
    }
    (positions, normals)
}
