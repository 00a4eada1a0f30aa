//! Analytic tests of the reference path tracer: cases whose exact answer is known, so a
//! failure means the tracer (or its BVH, sampling or light transport) is wrong.
#![cfg(feature = "baking")]

use glam::{Vec2, Vec3};
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::reference::{direct_irradiance, radiance_by_bounce, render_reference, ReferenceImages, ReferenceSettings, TRACED_LIGHTS};
use relume_bake::sampling::PathSampler;
use relume_bake::scene::{Camera, Light, Mesh, Scene};
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, sphere, spot_light, square, Facing};
use relume_bake::work::WorkOptions;
use std::f32::consts::{FRAC_PI_2, PI};
use std::time::Duration;

fn mean(image: &Image) -> Vec3 {
    image.pixels.iter().copied().sum::<Vec3>() / image.pixels.len() as f32
}

fn relative_error(actual: Vec3, expected: Vec3) -> f32 {
    ((actual - expected).abs() / expected.abs()).max_element()
}

fn render(scene: &Scene, settings: &ReferenceSettings) -> ReferenceImages {
    let bvh = SceneBvh::new(scene);
    let images = render_reference(scene, &bvh, settings);
    assert_eq!(images.nonfinite_samples, 0, "non-finite samples");
    for i in 0..images.combined.pixels.len() {
        assert_eq!(
            images.combined.pixels[i],
            images.direct.pixels[i] + images.indirect.pixels[i],
            "combined is not direct + indirect at pixel {i}"
        );
    }
    images
}

/// The point where the ray through pixel (x, y)'s centre meets the plane y = 0.
fn ground_point(camera: &Camera, x: u32, y: u32, width: u32, height: u32) -> Option<Vec3> {
    let dir = camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, width, height);
    let origin = camera.position();
    (dir.y < 0.0).then(|| origin + dir * (-origin.y / dir.y))
}

// ---------------------------------------------------------------------------------------
// Furnace: inside a closed sphere whose walls all have albedo a and emit Le towards the
// inside, the radiance is Le / (1 - a) in every direction (L = Le + a L, since every
// direction sees the same wall). Tests emission, MIS between emitter sampling and BSDF
// sampling (every wall is an emitter), Russian roulette and the bounce limit.

fn furnace(albedo: f32, emission: Vec3, size: u32, samples: u32, pixel_tolerance: f32) {
    // Inward faces: the front face (and so the emission) points to the centre.
    let mesh = sphere(Vec3::new(0.3, -0.2, 0.1), 2.0, 3, Facing::Inward, 0);
    let s = scene(
        "furnace",
        vec![mesh],
        vec![material("wall", Vec3::splat(albedo), emission)],
        vec![],
        look_at(Vec3::new(0.5, 0.0, 0.2), Vec3::new(1.0, 0.3, -1.0), Vec3::Y, FRAC_PI_2),
    );
    let settings = ReferenceSettings {
        samples_per_pixel: samples,
        width: size,
        height: size,
        work: WorkOptions { seed: 1, ..WorkOptions::default() },
        ..Default::default()
    };
    let images = render(&s, &settings);
    let expected = emission / (1.0 - albedo);
    let m = mean(&images.combined);
    // The image mean's standard error is about 0.1 % at these sample counts.
    assert!(relative_error(m, expected) < 0.005, "furnace a={albedo}: mean {m}, expected {expected}");
    // Direct: Le seen plus one bounce of the uniform irradiance pi Le: Le (1 + a).
    let d = mean(&images.direct);
    let expected_direct = emission * (1.0 + albedo);
    assert!(relative_error(d, expected_direct) < 0.005, "direct {d}, expected {expected_direct}");
    let worst = images.combined.pixels.iter().map(|&p| relative_error(p, expected)).fold(0.0f32, f32::max);
    assert!(worst < pixel_tolerance, "furnace a={albedo}: worst pixel off by {worst}");
}

#[test]
fn emitters_emit_from_their_front_face_only() {
    // The same sphere facing outward: from inside every wall shows its back, so no light.
    let mesh = sphere(Vec3::ZERO, 2.0, 2, Facing::Outward, 0);
    let s = scene(
        "inside out",
        vec![mesh],
        vec![material("wall", Vec3::splat(0.5), Vec3::ONE)],
        vec![],
        look_at(Vec3::ZERO, Vec3::X, Vec3::Y, FRAC_PI_2),
    );
    let settings = ReferenceSettings { samples_per_pixel: 16, width: 8, height: 8, ..Default::default() };
    assert!(render(&s, &settings).combined.pixels.iter().all(|&p| p == Vec3::ZERO));
    // Seen from outside, the front faces show exactly their emission: a convex surface sees
    // nothing of itself, so nothing is reflected.
    let outside = scene(
        "outside",
        vec![sphere(Vec3::ZERO, 2.0, 2, Facing::Outward, 0)],
        vec![material("wall", Vec3::splat(0.5), Vec3::ONE)],
        vec![],
        look_at(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, Vec3::Y, 0.2),
    );
    let image = render(&outside, &settings);
    assert_eq!(image.combined.get(4, 4), Vec3::ONE);
}

// Pixel tolerances are about five times the per-pixel noise measured at these sample counts
// (0.7 % and 0.9 %). The noise is mostly Russian roulette's: in a furnace every surviving
// path keeps throughput 1 and stops with probability 1 - a per bounce.

#[test]
fn furnace_albedo_half() {
    furnace(0.5, Vec3::new(1.0, 0.5, 2.0), 16, 1024, 0.035);
}

#[test]
fn furnace_albedo_080() {
    furnace(0.8, Vec3::new(0.2, 1.0, 0.6), 8, 4096, 0.045);
}

// ---------------------------------------------------------------------------------------
// Point light over a large plane: irradiance I cos(theta) / r^2, outgoing radiance
// albedo / pi times that, and nothing else (a plane cannot light itself).

fn plane_scene(albedo: f32, lights: Vec<relume_bake::scene::Light>, camera: Camera) -> Scene {
    // 1000 m square at y = 0 facing +Y (X x -Z = +Y).
    let ground = square(Vec3::ZERO, Vec3::X * 500.0, Vec3::NEG_Z * 500.0, 4, 0);
    scene("plane", vec![ground], vec![material("ground", Vec3::splat(albedo), Vec3::ZERO)], lights, camera)
}

#[test]
fn point_light_over_plane() {
    let light_pos = Vec3::new(1.0, 3.0, -2.0);
    let intensity = Vec3::new(100.0, 50.0, 25.0);
    let camera = look_at(Vec3::new(0.0, 8.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 70f32.to_radians());
    let albedo = 0.6;
    let plane = plane_scene(albedo, vec![point_light(light_pos, intensity)], camera);
    let bvh = SceneBvh::new(&plane);
    let analytic = |p: Vec3| {
        let r = light_pos - p;
        intensity * (r.y / r.length()) / r.length_squared()
    };

    // Irradiance at points near and far (up to 300 m), through the shadow-ray path.
    for i in 0..400 {
        let sampler = PathSampler::new(99, i, 0);
        let radius = 300.0 * sampler.uniform(0).powi(3);
        let angle = 2.0 * PI * sampler.uniform(1);
        let p = Vec3::new(radius * angle.cos(), 0.0, radius * angle.sin());
        let e = direct_irradiance(&plane, &bvh, p, Vec3::Y);
        let expected = analytic(p);
        assert!(relative_error(e, expected) < 0.005, "at {p}: {e}, expected {expected}");
    }
    // A receiver facing away from the light gets nothing.
    assert_eq!(direct_irradiance(&plane, &bvh, Vec3::new(0.0, 0.0, 0.0), Vec3::NEG_Y), Vec3::ZERO);

    // The rendered direct layer at pixel centres: albedo / pi times the irradiance, exactly
    // (one sample suffices: no randomness reaches a point light's contribution).
    let (w, h) = (32, 24);
    let settings = ReferenceSettings { samples_per_pixel: 2, width: w, height: h, pixel_centres: true, ..Default::default() };
    let images = render(&plane, &settings);
    for y in 0..h {
        for x in 0..w {
            let p = ground_point(&plane.camera, x, y, w, h).expect("camera looks down");
            let expected = analytic(p) * (albedo / PI);
            let got = images.direct.get(x, y);
            assert!(relative_error(got, expected) < 0.005, "pixel ({x}, {y}): {got}, expected {expected}");
            assert_eq!(images.indirect.get(x, y), Vec3::ZERO, "a lone plane lit itself at ({x}, {y})");
        }
    }
}

#[test]
fn shadow_rays_see_occluders() {
    // A 1 m square blocker at 1.5 m between a point light at 3 m and the ground below it.
    let light_pos = Vec3::new(0.0, 3.0, 0.0);
    let camera = look_at(Vec3::new(0.0, 8.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 1.0);
    let mut s = plane_scene(0.5, vec![point_light(light_pos, Vec3::splat(10.0))], camera);
    s.meshes.push(square(Vec3::new(0.0, 1.5, 0.0), Vec3::X * 0.5, Vec3::NEG_Z * 0.5, 1, 0));
    let bvh = SceneBvh::new(&s);
    assert_eq!(direct_irradiance(&s, &bvh, Vec3::ZERO, Vec3::Y), Vec3::ZERO);
    assert_eq!(direct_irradiance(&s, &bvh, Vec3::new(0.9, 0.0, 0.9), Vec3::Y), Vec3::ZERO);
    // Outside the shadow (the umbra reaches 1 m from the centre).
    assert!(direct_irradiance(&s, &bvh, Vec3::new(1.5, 0.0, 0.0), Vec3::Y).x > 0.0);
    // Rendered: ground in the umbra is black unless shadows are off (the debug mode);
    // ground outside it is lit as the analytic point light says. The camera at 8 m sees
    // past the blocker to ground farther than 0.5 * 8 / 6.5 = 0.62 m from the axis (per
    // axis); the umbra reaches 1 m.
    let (w, h) = (33, 33);
    let settings = ReferenceSettings { samples_per_pixel: 1, width: w, height: h, pixel_centres: true, ..Default::default() };
    let shadowed = render(&s, &settings);
    let unshadowed = render(&s, &ReferenceSettings { shadows: false, ..settings });
    let (mut umbra, mut lit) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let p = ground_point(&s.camera, x, y, w, h).unwrap();
            let reach = p.x.abs().max(p.z.abs());
            let expected = direct_irradiance(&s, &bvh, p, Vec3::Y) * (0.5 / PI);
            if (0.7..0.95).contains(&reach) {
                umbra += 1;
                assert_eq!(shadowed.direct.get(x, y), Vec3::ZERO, "({x}, {y}) is in the umbra");
                assert_eq!(expected, Vec3::ZERO);
                let unblocked = point_light(light_pos, Vec3::splat(10.0)).incident(p);
                let e = unblocked.irradiance * unblocked.to_light.y * (0.5 / PI);
                assert!(relative_error(unshadowed.direct.get(x, y), e) < 0.005);
            } else if reach > 1.05 {
                lit += 1;
                assert!(expected.x > 0.0);
                assert!(relative_error(shadowed.direct.get(x, y), expected) < 0.005);
            }
        }
    }
    assert!(umbra > 10 && lit > 100, "{umbra} pixels in the umbra, {lit} lit");
}

/// Many lights (more than `TRACED_LIGHTS`) are sampled at each vertex from the light grid:
/// with coloured point and spot lights and an occluder, the mean is still the sum over every
/// light (bars at about twice the first measurement: 0.21 % over the image, the worst pixel off by 0.23
/// of the mean pixel; at 8,192 samples 0.06 % and 0.058, as an unbiased estimate's noise falls).
#[test]
fn many_lights_are_sampled_without_bias() {
    let count = TRACED_LIGHTS as u32 * 3;
    let lights: Vec<Light> = (0..count)
        .map(|i| {
            let a = i as f32 * 2.4;
            let at = Vec3::new(3.0 * a.cos(), 1.0 + (i % 5) as f32 * 0.7, 3.0 * a.sin());
            let colour = Vec3::new(1.0 + (i % 3) as f32, 2.0, 1.0 + (i % 4) as f32);
            match i % 3 {
                0 => spot_light(at, Vec3::new(-at.x, -at.y, -at.z * 0.5), colour * 4.0, 0.2, 0.5),
                _ => point_light(at, colour),
            }
        })
        .collect();
    let camera = look_at(Vec3::new(0.0, 8.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 1.2);
    let mut s = plane_scene(0.5, lights, camera);
    s.meshes.push(square(Vec3::new(0.5, 0.6, 0.0), Vec3::X * 0.8, Vec3::NEG_Z * 0.8, 1, 0));
    let (w, h) = (24, 24);
    let settings = ReferenceSettings { samples_per_pixel: 512, width: w, height: h, pixel_centres: true, ..Default::default() };
    let images = render(&s, &settings);
    let bvh = SceneBvh::new(&s);
    // The sum over every light at the surface each pixel's centre sees (the ground or the
    // occluder's top: both face up).
    let pixels: Vec<(Vec3, Vec3)> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let hit = bvh.closest_hit(s.camera.position(), s.camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, w, h), f32::INFINITY);
            let e = direct_irradiance(&s, &bvh, hit.expect("every pixel sees the ground").position, Vec3::Y) * (0.5 / PI);
            (images.direct.get(x, y), e)
        })
        .collect();
    let (got, want) = pixels.iter().fold((Vec3::ZERO, Vec3::ZERO), |(g, e), p| (g + p.0, e + p.1));
    let mean = want / pixels.len() as f32;
    // Off by a share of the mean pixel: dim pixels' noise is not their relative error.
    let worst = pixels.iter().map(|(g, e)| ((*g - *e).abs() / mean).max_element()).fold(0.0f32, f32::max);
    eprintln!("many lights, 512 samples: image {got} against {want}, worst pixel off by {worst} of the mean pixel");
    assert!(relative_error(got, want) < 0.004 && worst < 0.5, "image {got} against {want}; worst pixel off by {worst}");
}

// ---------------------------------------------------------------------------------------

#[test]
fn spot_light_cone() {
    let light_pos = Vec3::new(0.0, 4.0, 0.0);
    let (inner, outer) = (15f32.to_radians(), 25f32.to_radians());
    let intensity = Vec3::splat(200.0);
    let camera = look_at(Vec3::new(0.0, 6.0, 0.0), Vec3::ZERO, Vec3::NEG_Z, 80f32.to_radians());
    let albedo = 0.5;
    let s = plane_scene(albedo, vec![spot_light(light_pos, Vec3::NEG_Y, intensity, inner, outer)], camera);
    let (w, h) = (40, 40);
    let settings = ReferenceSettings { samples_per_pixel: 1, width: w, height: h, pixel_centres: true, ..Default::default() };
    let images = render(&s, &settings);
    let (mut outside, mut inside) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let p = ground_point(&s.camera, x, y, w, h).unwrap();
            let to_point = (p - light_pos).normalize();
            let angle = to_point.dot(Vec3::NEG_Y).clamp(-1.0, 1.0).acos();
            let got = images.combined.get(x, y);
            if angle > outer + 1e-3 {
                assert_eq!(got, Vec3::ZERO, "pixel ({x}, {y}) at {}° is outside the cone", angle.to_degrees());
                outside += 1;
            } else if angle < inner - 1e-3 {
                let r2 = (light_pos - p).length_squared();
                let expected = intensity * (albedo / PI) * angle.cos() / r2;
                assert!(relative_error(got, expected) < 0.005, "pixel ({x}, {y}): {got}, expected {expected}");
                inside += 1;
            }
        }
    }
    assert!(outside > 100 && inside > 50, "the view must cover both: {outside} outside, {inside} inside");
}

// ---------------------------------------------------------------------------------------
// A square area light over a plane: irradiance from the view factor of a parallel
// rectangle. For a rectangle of sides a, b, parallel to a receiving point at height h with
// the normal through one corner, F = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2))
// + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))], X = a/h, Y = b/h; any placement follows by adding
// and subtracting corner rectangles. E = pi Le F. Exercises emitter sampling and MIS.

fn corner_factor(x: f32, y: f32, h: f32) -> f64 {
    let (a, b) = ((x.abs() / h) as f64, (y.abs() / h) as f64);
    let f = (a / (1.0 + a * a).sqrt() * (b / (1.0 + a * a).sqrt()).atan() + b / (1.0 + b * b).sqrt() * (a / (1.0 + b * b).sqrt()).atan())
        / (2.0 * std::f64::consts::PI);
    f * (x.signum() * y.signum()) as f64
}

fn rectangle_factor(p: Vec3, lo: Vec2, hi: Vec2, h: f32) -> f64 {
    let (x0, x1, z0, z1) = (lo.x - p.x, hi.x - p.x, lo.y - p.z, hi.y - p.z);
    corner_factor(x1, z1, h) - corner_factor(x0, z1, h) - corner_factor(x1, z0, h) + corner_factor(x0, z0, h)
}

/// `pixel_tolerance` is 4 to 5 times the per-pixel noise measured at 2048 samples.
fn area_light_over_plane(half: f32, height: f32, samples: u32, pixel_tolerance: f32) {
    let le = Vec3::new(2.0, 1.0, 0.5);
    let albedo = 0.5;
    let ground = square(Vec3::ZERO, Vec3::X * 100.0, Vec3::NEG_Z * 100.0, 2, 0);
    // Facing down (Z x X = +Y, so X x Z = -Y); black, so nothing reflects off it.
    let lamp = square(Vec3::new(0.0, height, 0.0), Vec3::X * half, Vec3::Z * half, 2, 1);
    let camera = look_at(Vec3::new(0.0, 0.5 * height, 0.0), Vec3::ZERO, Vec3::NEG_Z, 100f32.to_radians());
    let s = scene(
        "area light",
        vec![ground, lamp],
        vec![material("ground", Vec3::splat(albedo), Vec3::ZERO), material("lamp", Vec3::ZERO, le)],
        vec![],
        camera,
    );
    let (w, h) = (12, 12);
    let settings = ReferenceSettings {
        samples_per_pixel: samples,
        width: w,
        height: h,
        pixel_centres: true,
        work: WorkOptions { seed: 7, ..WorkOptions::default() },
        ..Default::default()
    };
    let images = render(&s, &settings);
    let (mut sum_got, mut sum_expected) = (Vec3::ZERO, Vec3::ZERO);
    let mut worst = 0.0f32;
    for y in 0..h {
        for x in 0..w {
            let p = ground_point(&s.camera, x, y, w, h).unwrap();
            let f = rectangle_factor(p, Vec2::splat(-half), Vec2::splat(half), height) as f32;
            let expected = le * (PI * f) * (albedo / PI);
            let got = images.direct.get(x, y);
            worst = worst.max(relative_error(got, expected));
            sum_got += got;
            sum_expected += expected;
            assert_eq!(images.indirect.get(x, y), Vec3::ZERO);
        }
    }
    assert!(relative_error(sum_got, sum_expected) < 0.002, "mean {sum_got} vs {sum_expected}");
    assert!(worst < pixel_tolerance, "worst pixel off by {worst}");
}

#[test]
fn small_area_light_over_plane() {
    // Light sampling dominates.
    area_light_over_plane(0.25, 2.0, 2048, 0.012);
}

#[test]
fn large_area_light_over_plane() {
    // BSDF sampling dominates.
    area_light_over_plane(20.0, 1.0, 2048, 0.012);
}

#[test]
fn medium_area_light_over_plane() {
    // Both strategies matter.
    area_light_over_plane(1.0, 1.0, 2048, 0.025);
}

// ---------------------------------------------------------------------------------------
// Energy: in a closed white box every reflection keeps the fraction a of the light, so the
// radiance arriving after k + 1 bounces is below that after k, by about a.

#[test]
fn energy_decreases_by_bounce() {
    let albedo = 0.7;
    let walls = closed_box(Vec3::splat(-1.0), Vec3::splat(1.0), 2, Facing::Inward, 0);
    let s = scene(
        "white box",
        vec![walls],
        vec![material("white", Vec3::splat(albedo), Vec3::ZERO)],
        vec![point_light(Vec3::new(0.2, 0.3, -0.1), Vec3::splat(5.0))],
        look_at(Vec3::new(0.8, 0.8, 0.8), Vec3::splat(-1.0), Vec3::Y, 100f32.to_radians()),
    );
    let bvh = SceneBvh::new(&s);
    let settings = ReferenceSettings { samples_per_pixel: 64, width: 16, height: 16, ..Default::default() };
    let by_bounce = radiance_by_bounce(&s, &bvh, &settings, 8);
    assert_eq!(by_bounce.len(), 9);
    assert_eq!(by_bounce[0], Vec3::ZERO, "no emitter is in view");
    for k in 1..=6 {
        let ratio = by_bounce[k + 1].x / by_bounce[k].x;
        assert!(by_bounce[k + 1].x < by_bounce[k].x, "bounce {} brighter than {k}", k + 1);
        assert!((0.8 * albedo..1.08 * albedo).contains(&ratio), "bounce {k} -> {}: ratio {ratio}", k + 1);
    }
    // The per-bounce sums add up to the rendered image.
    let images = render(&s, &settings);
    let total: Vec3 = radiance_by_bounce(&s, &bvh, &settings, settings.max_bounces).iter().copied().sum();
    assert!(relative_error(mean(&images.combined), total) < 1e-4);
    assert!(relative_error(mean(&images.direct), by_bounce[0] + by_bounce[1]) < 1e-4);
}

// ---------------------------------------------------------------------------------------

fn busy_scene() -> Scene {
    // A box with a sphere, a square area light on the ceiling and a point light.
    let walls = closed_box(Vec3::splat(-1.0), Vec3::splat(1.0), 2, Facing::Inward, 0);
    let ball = sphere(Vec3::new(0.2, -0.5, 0.1), 0.4, 2, Facing::Outward, 1);
    let lamp = square(Vec3::new(0.0, 0.99, 0.0), Vec3::X * 0.3, Vec3::Z * 0.3, 1, 2);
    scene(
        "busy",
        vec![walls, ball, lamp],
        vec![
            material("wall", Vec3::new(0.7, 0.6, 0.5), Vec3::ZERO),
            material("ball", Vec3::new(0.2, 0.5, 0.8), Vec3::ZERO),
            material("lamp", Vec3::splat(0.5), Vec3::splat(5.0)),
        ],
        vec![point_light(Vec3::new(-0.5, 0.5, 0.5), Vec3::splat(2.0))],
        look_at(Vec3::new(0.0, 0.0, 0.95), Vec3::new(0.0, -0.2, 0.0), Vec3::Y, 1.3),
    )
}

fn bits(image: &Image) -> Vec<u32> {
    image.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect()
}

#[test]
fn deterministic_across_thread_counts() {
    let s = busy_scene();
    let settings = ReferenceSettings {
        samples_per_pixel: 8,
        width: 24,
        height: 16,
        work: WorkOptions { seed: 42, threads: Some(1), ..WorkOptions::default() },
        ..Default::default()
    };
    let one = render(&s, &settings);
    let two = render(&s, &ReferenceSettings { work: WorkOptions { threads: Some(2), ..settings.work }, ..settings.clone() });
    assert_eq!(bits(&one.direct), bits(&two.direct));
    assert_eq!(bits(&one.indirect), bits(&two.indirect));
    assert_eq!(bits(&one.combined), bits(&two.combined));
    assert!(mean(&one.indirect).x > 0.0 && mean(&one.direct).x > 0.0);
    let other = render(&s, &ReferenceSettings { work: WorkOptions { seed: 43, ..settings.work }, ..settings.clone() });
    assert_ne!(bits(&one.combined), bits(&other.combined));
}

#[test]
fn time_limit_stops_at_whole_passes() {
    let s = busy_scene();
    let settings = ReferenceSettings {
        samples_per_pixel: 1_000_000,
        work: WorkOptions { time_limit: Some(Duration::from_millis(200)), ..WorkOptions::default() },
        width: 16,
        height: 12,
        ..Default::default()
    };
    let limited = render(&s, &settings);
    let taken = limited.samples_per_pixel;
    assert!(taken >= 1 && taken < settings.samples_per_pixel, "took {taken}");
    // The same image as asking for exactly that many samples.
    let exact =
        render(&s, &ReferenceSettings { samples_per_pixel: taken, work: WorkOptions { time_limit: None, ..settings.work }, ..settings });
    assert_eq!(bits(&limited.combined), bits(&exact.combined));
}

// ---------------------------------------------------------------------------------------
// The BVH against brute force: same closest triangle, same distance, same barycentrics.

fn random_soup(count: u32) -> Mesh {
    let mut tris = Vec::new();
    for i in 0..count {
        let s = PathSampler::new(3, i, 0);
        let c = Vec3::new(s.uniform(0), s.uniform(1), s.uniform(2)) * 10.0 - 5.0;
        let e = |d: u32| Vec3::new(s.uniform(d), s.uniform(d + 1), s.uniform(d + 2)) - 0.5;
        tris.push([c + e(3), c + e(6), c + e(9)]);
    }
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let normals = tris.iter().flat_map(|t| [(t[1] - t[0]).cross(t[2] - t[0]).normalize(); 3]).collect();
    let uv0 = Some(positions.iter().map(|p| Vec2::new(p.x, p.y)).collect());
    Mesh { name: "soup".into(), indices: (0..positions.len() as u32).collect(), positions, normals, uv0, uv1: None, material: 0 }
}

/// Möller-Trumbore in f64, independent of the BVH's own test.
fn brute_force(mesh: &Mesh, o: Vec3, d: Vec3) -> Option<(f64, usize)> {
    let (o, d) = (o.as_dvec3(), d.as_dvec3());
    let mut best: Option<(f64, usize)> = None;
    for (i, t) in mesh.positions.chunks_exact(3).enumerate() {
        let (v0, v1, v2) = (t[0].as_dvec3(), t[1].as_dvec3(), t[2].as_dvec3());
        let (e1, e2) = (v1 - v0, v2 - v0);
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-12 {
            continue;
        }
        let s = o - v0;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        let dist = e2.dot(q) / det;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && dist > 0.0 && best.is_none_or(|b| dist < b.0) {
            best = Some((dist, i));
        }
    }
    best
}

#[test]
fn bvh_matches_brute_force() {
    let mesh = random_soup(600);
    let mut s = scene("soup", vec![], vec![material("m", Vec3::ONE, Vec3::ZERO)], vec![], look_at(Vec3::Z, Vec3::ZERO, Vec3::Y, 1.0));
    // Two meshes, so the flattened and per-mesh indices differ.
    let mut first = mesh.clone();
    first.positions.truncate(300 * 3);
    first.normals.truncate(300 * 3);
    first.uv0.as_mut().unwrap().truncate(300 * 3);
    first.indices.truncate(300 * 3);
    let mut second = mesh.clone();
    second.indices = second.indices[300 * 3..].to_vec();
    s.meshes = vec![first, second];
    let bvh = SceneBvh::new(&s);
    assert_eq!(bvh.triangle_count(), 600);
    let mut hits = 0;
    for i in 0..3000 {
        let r = PathSampler::new(5, i, 0);
        let o = Vec3::new(r.uniform(0), r.uniform(1), r.uniform(2)) * 14.0 - 7.0;
        let target = Vec3::new(r.uniform(3), r.uniform(4), r.uniform(5)) * 8.0 - 4.0;
        let d = (target - o).normalize();
        let expected = brute_force(&mesh, o, d);
        let got = bvh.closest_hit(o, d, f32::INFINITY);
        assert_eq!(got.is_some(), expected.is_some(), "ray {i}");
        assert_eq!(bvh.occluded(o, d, f32::INFINITY), expected.is_some(), "ray {i}");
        if let (Some(hit), Some((t, tri))) = (got, expected) {
            hits += 1;
            assert!((hit.t as f64 - t).abs() < 1e-4 * t.max(1.0), "ray {i}: t {} vs {t}", hit.t);
            let flat = bvh.primitive_index(hit.mesh as usize, hit.triangle as usize);
            assert_eq!(flat, hit.primitive);
            assert_eq!(hit.primitive as usize, tri, "ray {i}");
            assert!((hit.position - (o + d * hit.t)).length() < 1e-4 * hit.t.max(1.0));
            assert!((hit.uv0 - Vec2::new(hit.position.x, hit.position.y)).length() < 1e-4 * hit.t.max(1.0));
            assert!(!bvh.occluded(o, d, hit.t * 0.999));
            assert!(bvh.closest_hit(o, d, hit.t * 0.999).is_none());
        }
    }
    assert!(hits > 1000, "only {hits} rays hit");
}
