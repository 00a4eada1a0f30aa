//! Spot lights on light clouds of emission bands (004 §8's spherical-harmonic emission): a
//! light's coefficients against the brute-force projection of its cone, the gather's columns
//! against the isotropic bake's, and the closed sphere's analytic indirect light for a spot.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, CloudGrid, LightCloud, LightCloudBakeSettings, Weigher};
use relume_bake::scene::Scene;
use relume_bake::sh;
use relume_bake::testing::{look_at, material, point_light, scene, sphere, spot_light, Facing};
use relume_bake::work::WorkOptions;
use std::f64::consts::PI;

/// c_k = (1 / 4 pi) integral of the light's intensity pattern times e_k(w) = y_k(w) / y_0 over
/// the sphere, by a midpoint rule of 1,000 x 2,000 cells equal in solid angle.
fn projected(light: &relume_bake::scene::Light) -> [f64; sh::COEFFICIENTS] {
    let (bands, sectors) = (1000, 2000);
    let mut c = [0f64; sh::COEFFICIENTS];
    for i in 0..bands {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / bands as f64;
        for j in 0..sectors {
            let phi = 2.0 * PI * (j as f64 + 0.5) / sectors as f64;
            let r = (1.0 - z * z).sqrt();
            let w = Vec3::new((r * phi.cos()) as f32, z as f32, (r * phi.sin()) as f32);
            let (s, y) = (light.cone_attenuation(w) as f64, sh::eval(w));
            c.iter_mut().zip(y).for_each(|(c, yk)| *c += s * (yk / y[0]) as f64 / (bands * sectors) as f64);
        }
    }
    c
}

#[test]
fn a_lights_emission_coefficients_are_its_cones_projection() {
    assert_eq!(lc::emission(&point_light(Vec3::ZERO, Vec3::ONE), 16), {
        let mut c = [0.0; 16];
        c[0] = 1.0;
        c
    });
    for (direction, inner, outer) in
        [(Vec3::NEG_Y, 1.047, 1.222), (Vec3::new(0.3, -0.5, 0.8), 0.2, 0.35), (Vec3::X, 0.0, 1.5707), (Vec3::Z, 0.6, 0.61)]
    {
        let spot = spot_light(Vec3::ZERO, direction.normalize(), Vec3::ONE, inner, outer);
        let (exact, brute) = (lc::emission(&spot, 16), projected(&spot));
        for k in 0..16 {
            assert!(
                (exact[k] as f64 - brute[k]).abs() < 2e-4,
                "cone {inner}..{outer} towards {direction}: c_{k} {} against {}",
                exact[k],
                brute[k]
            );
        }
        // Only the first `count` are asked for.
        assert!(lc::emission(&spot, 4)[4..].iter().all(|&c| c == 0.0));
    }
}

const RHO: f32 = 0.5;

/// An inward sphere of albedo RHO and radius 1 about the origin.
fn sphere_scene() -> Scene {
    let m = material("wall", Vec3::splat(RHO), Vec3::ZERO);
    let camera = look_at(Vec3::new(0.0, 0.0, 0.5), Vec3::ZERO, Vec3::Y, 1.0);
    scene("sphere furnace", vec![sphere(Vec3::ZERO, 1.0, 3, Facing::Inward, 0)], vec![m], vec![point_light(Vec3::ZERO, Vec3::ONE)], camera)
}

fn bake(s: &Scene, emission: usize) -> LightCloud {
    let grid = CloudGrid { min: Vec3::splat(-0.6), max: Vec3::splat(0.6), counts: [2, 2, 2] };
    let settings = LightCloudBakeSettings {
        grid: Some(grid),
        directions: 0,
        samples: 32,
        emission,
        work: WorkOptions { seed: 5, ..WorkOptions::default() },
    };
    lc::bake(s, &SceneBvh::new(s), &settings).expect("bake")
}

/// With emission bands, each cloud light's first column is the isotropic bake's, bit for bit
/// (the same paths); inside a closed sphere every point sees every other with the same form
/// factor per area, so a spot's indirect light is its flux's share of the isotropic light's,
/// wherever it points, and what the higher functions add (light of no net flux) is noise.
#[test]
fn in_a_closed_sphere_a_spot_gives_its_fluxs_share_of_the_isotropic_light() {
    let s = sphere_scene();
    let (isotropic, banded) = (bake(&s, 1), bake(&s, 9));
    let (a, b) = (lc::Columns::new(&isotropic), lc::Columns::new(&banded));
    for v in 0..isotropic.vertex_count() {
        for j in 0..isotropic.lights.len() {
            assert_eq!(a.column(v, j), b.column(v, 9 * j), "vertex {v}, light {j}");
        }
    }
    let expected = RHO / (1.0 - RHO);
    let mut weigher = Weigher::new(banded.lights.len(), 1).unwrap().with_emission(9).unwrap();
    let mut weights = Vec::new();
    for direction in [Vec3::NEG_Y, Vec3::new(0.6, 0.0, 0.8), Vec3::Y] {
        let spot = spot_light(banded.lights[3], direction, Vec3::splat(2.0), 0.3, 0.5);
        weigher.weigh(&banded.lights, std::slice::from_ref(&spot), |_, _| true, &mut weights);
        let share = lc::emission(&spot, 1)[0];
        let e = banded.reconstruct(&weights);
        let mean = e.iter().map(|e| e.x as f64).sum::<f64>() / e.len() as f64;
        let answer = 2.0 * share as f64 * expected as f64;
        println!("spot towards {direction}: mean indirect {mean:.5}, the flux's share {answer:.5}");
        // Bar from the first measurement (within 1 %: the gather's noise at 32 paths).
        assert!((mean - answer).abs() < 0.03 * answer, "{mean} against {answer}");
    }
}
