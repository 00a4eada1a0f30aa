//! The environment light: the working cube's geometry, the lat-long resampling, the sampling
//! distribution, and the path tracer lit by it against closed forms.
#![cfg(feature = "baking")]

use glam::{Vec2, Vec3};
use relume_bake::bvh::SceneBvh;
use relume_bake::environment::{cube_coordinates, lat_long_image, Environment, EnvironmentSettings};
use relume_bake::image::Image;
use relume_bake::reference::{environment_irradiance, render_reference, ReferenceSettings};
use relume_bake::sampling::PathSampler;
use relume_bake::scene::Scene;
use relume_bake::testing::{look_at, material, scene, sky, sphere, square, two_area_lights, Facing};
use relume_bake::work::WorkOptions;
use std::f32::consts::PI;
use std::path::Path;

fn settings(cube_face: u32, rotation_y_degrees: f32) -> EnvironmentSettings {
    EnvironmentSettings { image: "test.exr".into(), layer: None, intensity: 1.0, rotation_y_degrees, cube_face }
}

fn environment(image: &Image, cube_face: u32) -> Environment {
    Environment::from_lat_long(image, Path::new("test.exr"), &settings(cube_face, 0.0)).unwrap()
}

#[test]
fn texels_tile_the_sphere_and_directions_find_their_texel() {
    let e = environment(&lat_long_image(64, |_| Vec3::ONE), 16);
    let total: f64 = e.solid_angle.iter().map(|&w| w as f64).sum();
    assert!((total - 4.0 * std::f64::consts::PI).abs() < 1e-4, "texels sum to {total}");
    for (texel, d) in e.direction.iter().enumerate() {
        assert_eq!(e.texel(*d).0, texel, "the centre of texel {texel} falls elsewhere");
    }
    // Vulkan's face order and orientation: +X is face 0, whose s grows towards -Z.
    assert_eq!(cube_coordinates(Vec3::X), (0, 0.0, 0.0));
    assert_eq!(cube_coordinates(Vec3::new(1.0, -0.25, -0.5)), (0, 0.5, 0.25));
    assert_eq!(cube_coordinates(Vec3::new(0.5, 1.0, 0.25)), (2, 0.5, 0.25));
    assert_eq!(cube_coordinates(Vec3::NEG_Z).0, 5);
}

#[test]
fn resampling_keeps_a_uniform_environment_uniform_and_puts_light_where_it_was() {
    let e = environment(&lat_long_image(256, |_| Vec3::new(0.5, 1.0, 2.0)), 32);
    assert!(e.radiance.iter().all(|l| (*l - Vec3::new(0.5, 1.0, 2.0)).abs().max_element() < 1e-6));
    // A sun in the direction the lat-long centre (u = 0.5, v = 0.5) looks: -Z.
    let sun = sky(Vec3::NEG_Z, Vec3::splat(1000.0), 6.0);
    let e = environment(&lat_long_image(512, sun), 32);
    assert!(e.radiance_towards(Vec3::NEG_Z).x > 900.0);
    assert!(e.radiance_towards(Vec3::Z).x < 1.0);
    // Turned 90 degrees about +Y (counter-clockwise from above), -Z goes to -X.
    let turned = Environment::from_lat_long(
        &lat_long_image(512, sky(Vec3::NEG_Z, Vec3::splat(1000.0), 6.0)),
        Path::new("t.exr"),
        &settings(32, 90.0),
    );
    assert!(turned.unwrap().radiance_towards(Vec3::NEG_X).x > 900.0);
    // Power is kept: the sun's share of the sphere's flux matches its solid angle.
    let power = |e: &Environment| e.radiance.iter().zip(&e.solid_angle).map(|(l, w)| l.x as f64 * *w as f64).sum::<f64>();
    let sun_only =
        environment(&lat_long_image(2048, |d| if d.dot(Vec3::NEG_Z) > 3f32.to_radians().cos() { Vec3::ONE } else { Vec3::ZERO }), 32);
    let cap = 2.0 * std::f64::consts::PI * (1.0 - 3f64.to_radians().cos());
    assert!((power(&sun_only) / cap - 1.0).abs() < 0.02, "sun flux {} against {cap}", power(&sun_only));
}

#[test]
fn refuses_images_that_are_not_lat_long_or_not_radiance() {
    let mut image = Image::new(30, 10);
    let error = Environment::from_lat_long(&image, Path::new("e.exr"), &settings(8, 0.0)).unwrap_err().to_string();
    assert!(error.contains("e.exr") && error.contains("30x10") && error.contains("lat-long"), "{error}");
    image = Image::new(20, 10);
    image.set(3, 4, Vec3::new(0.0, f32::NAN, 0.0));
    let error = Environment::from_lat_long(&image, Path::new("e.exr"), &settings(8, 0.0)).unwrap_err().to_string();
    assert!(error.contains("texel (3, 4)"), "{error}");
    image.set(3, 4, Vec3::new(0.0, -1.0, 0.0));
    let error = Environment::from_lat_long(&image, Path::new("e.exr"), &settings(8, 0.0)).unwrap_err().to_string();
    assert!(error.contains(">= 0"), "{error}");
    // Finite but past any light: 1e38 turned FIV's tables into NaN.
    image.set(3, 4, Vec3::new(0.0, 1e38, 0.0));
    let error = Environment::from_lat_long(&image, Path::new("e.exr"), &settings(8, 0.0)).unwrap_err().to_string();
    assert!(error.contains("texel (3, 4)") && error.contains("at most 1e9"), "{error}");
    // Compression ringing a hair below zero (Blender's probes go down to -0.0018) reads as 0.
    let mut noisy = lat_long_image(64, |_| Vec3::ONE);
    noisy.set(5, 5, Vec3::new(1.0, -4.5e-6, 1.0));
    let e = Environment::from_lat_long(&noisy, Path::new("e.exr"), &settings(8, 0.0)).unwrap();
    assert_eq!(e.clamped_texels, 1);
    assert!(e.radiance.iter().all(|l| l.min_element() >= 0.0));
}

#[test]
fn sampling_density_integrates_to_one_and_matches_what_is_drawn() {
    let e = environment(&lat_long_image(256, sky(Vec3::new(0.3, 0.8, -0.2), Vec3::splat(500.0), 2.0)), 16);
    // The pdf over the sphere, by quadrature on 4 x 4 cells per texel.
    let mut total = 0.0f64;
    let n = e.face;
    for texel in 0..e.radiance.len() {
        let (face, t, s) = (texel / (n * n) as usize, (texel as u32 / n) % n, texel as u32 % n);
        for j in 0..4 {
            for i in 0..4 {
                let edge = |c: u32, k: u32| 2.0 * (c as f64 + k as f64 / 4.0) / n as f64 - 1.0;
                let (a0, b0, a1, b1) = (edge(s, i), edge(t, j), edge(s, i + 1), edge(t, j + 1));
                let d = relume_bake::environment::face_point(face, ((a0 + a1) * 0.5) as f32, ((b0 + b1) * 0.5) as f32).normalize();
                total += e.pdf(d) as f64 * relume_bake::environment::face_rectangle_solid_angle(a0, b0, a1, b1);
            }
        }
    }
    assert!((total - 1.0).abs() < 1e-3, "the pdf integrates to {total}");
    // Each drawn direction carries the density pdf() gives it and the radiance of its texel.
    for k in 0..2000 {
        let sampler = PathSampler::new(7, k, 0);
        let (d, radiance, pdf) = e.sample(sampler.uniform_f64(0), Vec2::new(sampler.uniform(1), sampler.uniform(2))).unwrap();
        assert!(((pdf - e.pdf(d)) / pdf).abs() < 1e-3, "sample {k}: pdf {pdf} against {}", e.pdf(d));
        assert_eq!(radiance, e.radiance_towards(d));
    }
    assert!(environment(&lat_long_image(64, |_| Vec3::ZERO), 8).sample(0.5, Vec2::splat(0.5)).is_none());
}

/// A large square ground of albedo `albedo` at y = 0 (facing up), with `extra` meshes, lit
/// only by the environment `radiance`, seen from above.
fn ground_scene(albedo: f32, extra: Vec<relume_bake::scene::Mesh>, radiance: impl Fn(Vec3) -> Vec3) -> Scene {
    let mut meshes = vec![square(Vec3::ZERO, Vec3::X * 50.0, Vec3::NEG_Z * 50.0, 4, 0)];
    meshes.extend(extra);
    let materials = vec![material("ground", Vec3::splat(albedo), Vec3::ZERO), material("black", Vec3::ZERO, Vec3::ZERO)];
    let camera = look_at(Vec3::new(0.0, 3.0, 0.5), Vec3::ZERO, Vec3::Y, 0.5);
    let mut s = scene("environment ground", meshes, materials, vec![], camera);
    s.environment = Some(environment(&lat_long_image(512, radiance), 32));
    s
}

#[test]
fn uniform_environment_on_an_open_plane_gives_albedo_times_radiance() {
    let s = ground_scene(0.6, vec![], |_| Vec3::new(1.0, 2.0, 0.5));
    let bvh = SceneBvh::new(&s);
    let e = environment_irradiance(&s, &bvh, Vec3::new(0.3, 0.0, 0.2), Vec3::Y, 16);
    assert!((e / (PI * Vec3::new(1.0, 2.0, 0.5)) - 1.0).abs().max_element() < 1e-3, "irradiance {e}");
    let settings = ReferenceSettings {
        samples_per_pixel: 256,
        width: 8,
        height: 8,
        work: WorkOptions { seed: 3, ..WorkOptions::default() },
        ..Default::default()
    };
    let images = render_reference(&s, &bvh, &settings);
    assert_eq!(images.nonfinite_samples, 0);
    let mean = images.direct.pixels.iter().copied().sum::<Vec3>() / 64.0;
    let expected = 0.6 * Vec3::new(1.0, 2.0, 0.5);
    assert!((mean / expected - 1.0).abs().max_element() < 0.005, "mean {mean}, expected {expected}");
    // An open plane sees nothing of itself: no light bounces twice.
    assert!(images.indirect.pixels.iter().all(|p| *p == Vec3::ZERO));
}

#[test]
fn a_black_sphere_above_the_plane_takes_its_solid_angle_of_cosine_weighted_sky() {
    // Straight below a sphere of radius r at height D the cap it hides has sin^2 = (r / D)^2
    // of the cosine-weighted hemisphere: I = pi L (1 - (r / D)^2).
    for (r, height) in [(0.5f32, 1.0f32), (0.25, 1.0)] {
        let ball = sphere(Vec3::new(0.0, height, 0.0), r, 5, Facing::Outward, 1);
        let s = ground_scene(0.5, vec![ball], |_| Vec3::ONE);
        let bvh = SceneBvh::new(&s);
        let e = environment_irradiance(&s, &bvh, Vec3::ZERO, Vec3::Y, 16).x;
        let exact = PI * (1.0 - (r / height).powi(2));
        assert!((e / exact - 1.0).abs() < 0.005, "r/D = {}: {e} against {exact}", r / height);
    }
}

#[test]
fn path_tracer_direct_light_equals_the_quadrature_under_a_sky_with_a_sun_and_two_area_lights() {
    let ball = sphere(Vec3::new(0.2, 0.6, 0.0), 0.3, 3, Facing::Outward, 1);
    for radiance in
        [Box::new(sky(Vec3::new(0.4, 0.7, 0.3), Vec3::splat(300.0), 2.0)) as Box<dyn Fn(Vec3) -> Vec3>, Box::new(two_area_lights(5.0))]
    {
        let s = ground_scene(0.5, vec![ball.clone()], radiance);
        let bvh = SceneBvh::new(&s);
        let settings = ReferenceSettings {
            samples_per_pixel: 16384,
            width: 4,
            height: 4,
            pixel_centres: true,
            work: WorkOptions { seed: 5, ..WorkOptions::default() },
            ..Default::default()
        };
        let images = render_reference(&s, &bvh, &settings);
        // Summed over the pixels that see the ground, so the noise of the one-texel-wide sun
        // and the small red light averages down (about 2 % per pixel at this sample count).
        let (mut got, mut expected, mut ground) = (Vec3::ZERO, Vec3::ZERO, 0);
        for (x, y) in (0..4).flat_map(|y| (0..4).map(move |x| (x, y))) {
            let dir = s.camera.ray_direction(x as f32 + 0.5, y as f32 + 0.5, 4, 4);
            let hit = bvh.closest_hit(s.camera.position(), dir, f32::INFINITY).unwrap();
            if hit.material == 0 {
                got += images.direct.get(x, y);
                expected += 0.5 / PI * environment_irradiance(&s, &bvh, hit.position, Vec3::Y, 16);
                ground += 1;
            }
        }
        assert!(ground >= 8, "only {ground} pixels see the ground");
        let error = ((got - expected).abs() / expected.max_element()).max_element();
        assert!(error < 0.01, "{got} against {expected}");
    }
}

/// The unoccluded irradiance on normal `n` by the working cube's own quadrature: every texel's
/// radiance times its solid angle and the clamped cosine.
fn cube_irradiance(e: &Environment, n: Vec3) -> Vec3 {
    let terms = e.radiance.iter().zip(&e.direction).zip(&e.solid_angle);
    terms.map(|((l, d), w)| l.as_dvec3() * (n.dot(*d).max(0.0) as f64 * *w as f64)).sum::<glam::DVec3>().as_vec3()
}

/// The ambient methods' environment light: nine spherical-harmonic coefficients of the working
/// cube's radiance give its unoccluded irradiance exactly when the radiance has bands l <= 2
/// (the clamped cosine's higher bands meet nothing): at 500 normals within 5e-4 of the largest
/// irradiance (1.4e-4 measured: the cube's texels hold means, not point values); under the
/// procedural sky with its 2° sun, the truncation within 0.05 (0.030 measured).
#[test]
fn nine_coefficients_give_the_cubes_irradiance() {
    let normals: Vec<Vec3> = (0..500)
        .map(|i| {
            let (z, phi) = (1.0 - 2.0 * (i as f32 + 0.5) / 500.0, i as f32 * PI * (3.0 - 5f32.sqrt()));
            let r = (1.0 - z * z).sqrt();
            Vec3::new(r * phi.cos(), z, r * phi.sin())
        })
        .collect();
    let worst = |e: &Environment| {
        let c = e.radiance_sh();
        let scale = normals.iter().map(|&n| cube_irradiance(e, n).max_element()).fold(0.0, f32::max);
        let error =
            normals.iter().map(|&n| (relume_bake::sh::irradiance(&c, n) - cube_irradiance(e, n)).abs().max_element()).fold(0.0, f32::max);
        error / scale
    };
    let smooth =
        environment(&lat_long_image(256, |d| Vec3::new(1.0 + 0.5 * d.y, 0.8 + 0.3 * d.x * d.z, 0.6 + 0.2 * (d.z * d.z - d.x * d.x))), 32);
    let exact = worst(&smooth);
    let with_sun = worst(&environment(&lat_long_image(512, sky(Vec3::new(0.5, 0.8, -0.3), Vec3::splat(400.0), 2.0)), 32));
    println!("largest SH irradiance error, of the largest irradiance: smooth {exact:.2e}, sky with a sun {with_sun:.4}");
    assert!(exact < 5e-4, "{exact}");
    assert!(with_sun < 0.05, "{with_sun}");
}
