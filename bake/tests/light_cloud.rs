//! The light-cloud bake (004): the cloud, the gather against the closed sphere's analytic
//! indirect light, the weights of §6.1 (sum, continuity, the stored column at a cloud point,
//! visibility), determinism, and the refusals.
#![cfg(feature = "baking")]

use glam::Vec3;
use relume_bake::bvh::SceneBvh;
use relume_bake::light_cloud::{self as lc, CloudGrid, CloudWeight, LightCloud, LightCloudBakeSettings, Weigher};
use relume_bake::scene::{Light, Scene};
use relume_bake::testing::{closed_box, look_at, material, point_light, scene, sphere, Facing};
use relume_bake::work::WorkOptions;

const RHO: f32 = 0.5;
const RADIUS: f32 = 1.0;

/// An inward-facing sphere of albedo RHO and radius RADIUS about the origin, 5,120 facets.
fn sphere_scene() -> Scene {
    let m = material("wall", Vec3::splat(RHO), Vec3::ZERO);
    let camera = look_at(Vec3::new(0.0, 0.0, 0.5), Vec3::ZERO, Vec3::Y, 1.0);
    scene(
        "sphere furnace",
        vec![sphere(Vec3::ZERO, RADIUS, 4, Facing::Inward, 0)],
        vec![m],
        vec![point_light(Vec3::ZERO, Vec3::ONE)],
        camera,
    )
}

fn bake(s: &Scene, grid: CloudGrid, samples: u32, threads: Option<usize>) -> LightCloud {
    let settings = LightCloudBakeSettings {
        grid: Some(grid),
        directions: 0,
        samples,
        emission: 1,
        work: WorkOptions { seed: 7, threads, ..WorkOptions::default() },
    };
    lc::bake(s, &SceneBvh::new(s), &settings).expect("bake")
}

/// Inside a closed sphere every point receives rho I / (R^2 (1 - rho)) of indirect
/// irradiance from an isotropic light of I cd anywhere inside: the first bounce spreads
/// rho 4 pi I evenly over 4 pi R^2 (every patch sees every other with the same form factor
/// per area), and each further bounce multiplies by rho (spec light-clouds.md D3, as
/// irradiance).
#[test]
fn inside_a_closed_sphere_every_column_is_the_analytic_indirect_irradiance() {
    let s = sphere_scene();
    let grid = CloudGrid { min: Vec3::splat(-0.6), max: Vec3::splat(0.6), counts: [2, 2, 2] };
    let cloud = bake(&s, grid, 64, None);
    assert_eq!(cloud.lights.len(), 8, "no grid point lies inside closed geometry");
    let expected = RHO / (RADIUS * RADIUS * (1.0 - RHO));
    let (vertices, columns) = (cloud.vertex_count(), lc::Columns::new(&cloud));
    for j in 0..cloud.lights.len() {
        let values: Vec<f32> = (0..vertices).map(|v| columns.column(v, j).x).collect();
        let mean = values.iter().map(|&x| x as f64).sum::<f64>() / vertices as f64;
        let rms = (values.iter().map(|&x| (x as f64 - expected as f64).powi(2)).sum::<f64>() / vertices as f64).sqrt();
        println!("light {j} at {}: mean {mean:.4}, rms about the answer {rms:.4} (answer {expected})", cloud.lights[j]);
        assert!((mean - expected as f64).abs() < 0.02 * expected as f64, "light {j}: mean {mean} against {expected}");
        // Bars from the first measurement (64 paths a vertex): means within 0.2 %, rms 6.4 %,
        // the gather's noise (the facets' departure from the sphere is below it).
        assert!(rms < 0.08 * expected as f64, "light {j}: per-vertex rms {rms} against {expected}");
    }
    // Any weights standing in for a light of total intensity 3 cd: 3 times the answer.
    let mut weigher = Weigher::new(cloud.lights.len(), 4).unwrap();
    let mut weights = Vec::new();
    for k in 0..20 {
        let t = k as f32 / 20.0;
        let position = Vec3::new(0.5 * (7.0 * t).sin(), 0.5 * (3.0 * t).cos(), 0.6 * t - 0.3);
        weigher.weigh(&cloud.lights, &[point_light(position, Vec3::splat(3.0))], |_, _| true, &mut weights);
        let e = cloud.reconstruct(&weights);
        let mean = e.iter().map(|e| e.y as f64).sum::<f64>() / e.len() as f64;
        assert!((mean - 3.0 * expected as f64).abs() < 0.02 * 3.0 * expected as f64, "reconstruction {k}: mean {mean}");
    }
}

fn grid_cloud() -> Vec<Vec3> {
    CloudGrid { min: Vec3::ZERO, max: Vec3::splat(4.0), counts: [4, 4, 4] }.points()
}

fn weigh(weigher: &mut Weigher, cloud: &[Vec3], lights: &[Light]) -> Vec<CloudWeight> {
    let mut out = Vec::new();
    weigher.weigh(cloud, lights, |_, _| true, &mut out);
    out
}

#[test]
fn weights_sum_to_each_lights_intensity_and_add_over_lights() {
    let cloud = grid_cloud();
    for m in [1, 2, 4, 8, 16] {
        let mut weigher = Weigher::new(cloud.len(), m).unwrap();
        // A cloud point (ties at distance 1 all round), a cell centre of the cloud's grid
        // (eight ties) and an ordinary point.
        for p in [Vec3::splat(1.5), Vec3::splat(2.0), Vec3::new(0.3, 2.9, 1.7)] {
            let intensity = Vec3::new(2.0, 0.5, 0.0);
            let w = weigh(&mut weigher, &cloud, &[point_light(p, intensity)]);
            let sum = w.iter().fold(Vec3::ZERO, |s, w| s + w.weight);
            assert!((sum - intensity).abs().max_element() < 1e-6, "m {m} at {p}: sum {sum}");
            assert!(w.len() <= m && w.iter().all(|w| w.weight.is_finite() && w.weight.cmpge(Vec3::ZERO).all()), "m {m} at {p}: {w:?}");
        }
        let two = [point_light(Vec3::splat(0.7), Vec3::ONE), point_light(Vec3::new(3.1, 0.2, 2.2), Vec3::splat(2.0))];
        let sum = weigh(&mut weigher, &cloud, &two).iter().fold(Vec3::ZERO, |s, w| s + w.weight);
        assert!((sum - Vec3::splat(3.0)).abs().max_element() < 1e-5, "m {m}, two lights: {sum}");
    }
}

/// The largest change of any weight between consecutive positions along a path sampled every
/// `step` metres: for continuous weights it shrinks with the step (by about 10x for 10x).
fn largest_jump(m: usize, step: f32) -> f32 {
    let cloud = grid_cloud();
    let mut weigher = Weigher::new(cloud.len(), m).unwrap();
    let (a, b) = (Vec3::new(0.2, 0.6, 1.1), Vec3::new(3.6, 3.3, 2.4));
    let steps = ((b - a).length() / step) as usize;
    let mut previous = vec![0f32; cloud.len()];
    let mut worst = 0f32;
    for k in 0..=steps {
        let p = a + (b - a).normalize() * (k as f32 * step);
        let mut dense = vec![0f32; cloud.len()];
        for w in weigh(&mut weigher, &cloud, &[point_light(p, Vec3::ONE)]) {
            dense[w.column as usize] = w.weight.x;
        }
        if k > 0 {
            worst = worst.max(dense.iter().zip(&previous).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max));
        }
        previous = dense;
    }
    worst
}

#[test]
fn weights_have_no_jumps_as_a_light_moves() {
    for m in [2, 4, 8] {
        let (coarse, fine) = (largest_jump(m, 1e-3), largest_jump(m, 1e-4));
        println!("m {m}: largest weight change {coarse:.2e} per mm, {fine:.2e} per 0.1 mm");
        assert!(fine < coarse / 5.0, "m {m}: {coarse} then {fine}: a jump");
    }
}

#[test]
fn with_one_nearest_a_light_at_a_cloud_point_takes_its_column() {
    let s = sphere_scene();
    let cloud = bake(&s, CloudGrid { min: Vec3::splat(-0.6), max: Vec3::splat(0.6), counts: [2, 2, 2] }, 2, Some(1));
    let (mut weigher, columns) = (Weigher::new(cloud.lights.len(), 1).unwrap(), lc::Columns::new(&cloud));
    for j in 0..cloud.lights.len() {
        let e = cloud.reconstruct(&weigh(&mut weigher, &cloud.lights, &[point_light(cloud.lights[j], Vec3::splat(2.0))]));
        for (v, e) in e.iter().enumerate() {
            assert!((*e - 2.0 * columns.column(v, j)).abs().max_element() <= 1e-6 * e.max_element().max(1.0), "light {j}, vertex {v}");
        }
    }
}

/// Cloud lights hidden from the user's light take no weight; a light that sees none adds
/// nothing and is counted.
#[test]
fn hidden_cloud_lights_take_no_weight() {
    let cloud = grid_cloud();
    let mut weigher = Weigher::new(cloud.len(), 8).unwrap();
    let mut out = Vec::new();
    // A wall at x = 2: only cloud lights on the light's side are visible.
    let unseen = weigher.weigh(&cloud, &[point_light(Vec3::new(1.9, 2.0, 2.0), Vec3::ONE)], |a, b| (a.x < 2.0) == (b.x < 2.0), &mut out);
    assert_eq!(unseen, 0);
    assert!(!out.is_empty() && out.iter().all(|w| cloud[w.column as usize].x < 2.0), "{out:?}");
    let unseen = weigher.weigh(&cloud, &[point_light(Vec3::ONE, Vec3::ONE)], |_, _| false, &mut out);
    assert_eq!((unseen, out.len()), (1, 0));
}

#[test]
fn an_m_out_of_range_is_refused() {
    assert!(Weigher::new(10, 0).is_err() && Weigher::new(10, 17).is_err());
}

/// A room with a closed block in it: grid points inside the block are dropped, and a grid
/// wholly inside closed geometry is refused naming the grid.
#[test]
fn cloud_points_inside_closed_geometry_are_dropped() {
    let m = material("white", Vec3::splat(0.5), Vec3::ZERO);
    let room = closed_box(Vec3::ZERO, Vec3::splat(4.0), 2, Facing::Inward, 0);
    let block = closed_box(Vec3::splat(0.2), Vec3::new(1.9, 3.8, 3.8), 2, Facing::Outward, 0);
    let camera = look_at(Vec3::splat(3.0), Vec3::ZERO, Vec3::Y, 1.0);
    let s = scene("room with block", vec![room, block], vec![m], vec![point_light(Vec3::splat(3.0), Vec3::ONE)], camera);
    let bvh = SceneBvh::new(&s);
    let grid = CloudGrid { min: Vec3::ZERO, max: Vec3::splat(4.0), counts: [4, 2, 2] };
    let points = lc::cloud_points(&bvh, &grid);
    assert_eq!(points.len(), 8);
    assert!(points.iter().all(|p| p.x > 2.0), "{points:?}");
    let inside = CloudGrid { min: Vec3::splat(0.5), max: Vec3::splat(1.5), counts: [2, 2, 2] };
    let settings = LightCloudBakeSettings { grid: Some(inside), directions: 0, samples: 1, emission: 1, work: WorkOptions::default() };
    let e = lc::bake(&s, &bvh, &settings).unwrap_err();
    assert!(e.contains("inside closed geometry") && e.contains("light_cloud.grid"), "{e}");
}

#[test]
fn the_bake_is_the_same_at_any_thread_count() {
    let s = sphere_scene();
    let grid = CloudGrid { min: Vec3::splat(-0.5), max: Vec3::splat(0.5), counts: [3, 1, 1] };
    assert_eq!(bake(&s, grid.clone(), 9, Some(1)), bake(&s, grid, 9, Some(2)));
}

/// 004 §5: the clustered PCA's error falls as vectors are added, and a basis as long as the
/// rows (3 x 8 values) reproduces every column; the same vectors shared out by eigenvalue
/// (Sloan et al. 2003) lose no more, and less where the clusters' spectra differ (the
/// sphere's are alike; half its rows varied in every direction make them differ); the GPU's sums-then-vertices order equals weighing the
/// reconstructed columns, with D the same for every cluster or not.
#[test]
fn compression_error_falls_with_vectors_and_vanishes_at_full_rank() {
    let s = sphere_scene();
    let cloud = bake(&s, CloudGrid { min: Vec3::splat(-0.6), max: Vec3::splat(0.6), counts: [2, 2, 2] }, 4, None);
    let errors: Vec<f64> = [0, 1, 2, 4, 8, 24]
        .iter()
        .map(|&d| lc::relative_error(&cloud, &lc::compress(&cloud, 4, lc::Vectors::Each(d), false).expect("compress")))
        .collect();
    println!("relative error with 0, 1, 2, 4, 8, 24 vectors: {errors:?}");
    assert!(errors.windows(2).all(|w| w[1] <= w[0] + 1e-9), "{errors:?}");
    assert!(errors[0] > 0.01 && errors[5] < 1e-5, "{errors:?}");
    let mut uneven = cloud.clone();
    let row = uneven.per_light() * uneven.lights.len();
    // Rows of one half of the sphere vary in every direction, the other half's as gathered.
    for (v, x) in uneven.terms.chunks_exact_mut(row).enumerate().filter(|(v, _)| s.meshes[0].positions[*v].y > 0.0) {
        x.iter_mut().enumerate().for_each(|(j, t)| *t *= 1.0 + 0.8 * (1.7 * j as f32 + 0.3 * v as f32).sin());
    }
    let mut gains = Vec::new();
    for (data, d) in [(&cloud, 1), (&cloud, 2), (&cloud, 4), (&uneven, 1), (&uneven, 2), (&uneven, 4)] {
        let each = lc::relative_error(data, &lc::compress(data, 4, lc::Vectors::Each(d), false).unwrap());
        let shared = lc::compress(data, 4, lc::Vectors::Shared(d), false).unwrap();
        let error = lc::relative_error(data, &shared);
        println!("D = {d}: {:?} vectors shared, relative error {error:.5} against {each:.5}", shared.vectors);
        assert_eq!(shared.vectors.iter().sum::<u32>() as usize, d * shared.cluster_count());
        assert!(error <= each + 1e-6, "D = {d} shared: {error} against {each} for the same each");
        if std::ptr::eq(data, &uneven) {
            gains.push(each - error);
        }
    }
    assert!(gains.iter().any(|&g| g > 0.01 * errors[0]), "sharing gained nothing on uneven clusters: {gains:?}");
    let mut weigher = Weigher::new(cloud.lights.len(), 4).unwrap();
    let weights = weigh(&mut weigher, &cloud.lights, &[point_light(Vec3::new(0.1, 0.2, -0.1), Vec3::new(1.0, 2.0, 3.0))]);
    for vectors in [lc::Vectors::Each(2), lc::Vectors::Shared(2)] {
        let compressed = lc::compress(&cloud, 4, vectors, false).unwrap();
        let columns = lc::Columns::new(&compressed);
        for (v, e) in compressed.reconstruct(&weights).iter().enumerate() {
            let direct = weights.iter().fold(Vec3::ZERO, |sum, w| sum + columns.column(v, w.column as usize) * w.weight).max(Vec3::ZERO);
            assert!(
                (*e - direct).abs().max_element() < 1e-5 * direct.max_element().max(1.0),
                "{vectors:?}, vertex {v}: {e} against {direct}"
            );
        }
        assert!(lc::compress(&compressed, 4, vectors, false).is_err(), "a compressed cloud is refused");
    }
}

/// The section reads back what was written, uncompressed and clustered, and refuses what a
/// bake never makes: a negative uncompressed value, a non-finite term, a vertex in a cluster
/// that does not exist; and a cloud baked for other vertices.
#[test]
fn the_section_round_trips_and_refuses_values_out_of_range() {
    use relume_bake::artifact::{Artifact, BakeOutput};
    use serde_json::json;
    let s = sphere_scene();
    let cloud = bake(&s, CloudGrid { min: Vec3::splat(-0.5), max: Vec3::splat(0.5), counts: [2, 1, 1] }, 1, None);
    let dir = std::env::temp_dir().join(format!("relume-light-cloud-section-{}", std::process::id()));
    let read = |cloud: &LightCloud, scene: &Scene| {
        let sections = vec![lc::section(cloud, json!({}))];
        BakeOutput { method: "light-cloud", scene: Some(&s), parameters: json!({}), sections, stats: json!({}) }.write(&dir).unwrap();
        lc::read(&Artifact::read(&dir).unwrap(), scene).map_err(|e| e.to_string())
    };
    let compressed = lc::compress(&cloud, 3, lc::Vectors::Each(2), false).unwrap();
    assert_eq!(read(&cloud, &s).unwrap(), cloud);
    assert_eq!(read(&compressed, &s).unwrap(), compressed);
    let shared = lc::compress(&cloud, 3, lc::Vectors::Shared(1), false).unwrap();
    assert_eq!(read(&shared, &s).unwrap(), shared);
    let mut short = shared.clone();
    short.coords.pop();
    let error = read(&short, &s).unwrap_err();
    assert!(error.contains("light-cloud.bin") && error.contains("the coordinates"), "{error}");
    let mut negative = cloud.clone();
    negative.terms[7] = -0.25;
    let error = read(&negative, &s).unwrap_err();
    assert!(error.contains("light-cloud.bin") && error.contains("transfer value 7") && error.contains(">= 0"), "{error}");
    let mut nan = compressed.clone();
    nan.terms[4] = f32::NAN;
    assert!(read(&nan, &s).unwrap_err().contains("must be finite"));
    let mut stray = compressed.clone();
    let clusters = stray.cluster_count();
    stray.assignment[10] = clusters as u32;
    let error = read(&stray, &s).unwrap_err();
    assert!(error.contains(&format!("vertex 10 is in cluster {clusters}, of {clusters}")), "{error}");
    let mut other = s.clone();
    other.meshes[0].positions.push(Vec3::ZERO);
    other.meshes[0].normals.push(Vec3::Y);
    assert!(read(&cloud, &other).unwrap_err().contains("scene"), "another scene is refused");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Spec light-clouds.md B5: a door closes between a moving light and half the cloud (cloud
/// lights at x < 2 drop out of sight once the light passes y = 2). Cut after cut, their weights
/// vanish in one step; moving continuously at 60 frames a second with a 0.25 s fade, no
/// frame's change is more than a fraction of that, the weights still sum to the intensity, and
/// once the light stands still for the fade they equal the settled weights.
#[test]
fn a_fade_spreads_a_visibility_change_over_its_duration() {
    let cloud = grid_cloud();
    let visible = |a: Vec3, b: Vec3| !(b.x < 2.0 && a.y > 2.0);
    let intensity = Vec3::new(1.0, 2.0, 0.5);
    let path: Vec<Vec3> = (0..=60).map(|k| Vec3::new(2.1, 1.7 + 0.01 * k as f32, 1.9)).collect();
    let dense = |weights: &[CloudWeight]| {
        let mut d = vec![0f32; cloud.len()];
        weights.iter().for_each(|w| d[w.column as usize] = w.weight.y);
        d
    };
    let largest_step = |fade: f32, continuous: bool| {
        let mut weigher = Weigher::new(cloud.len(), 8).unwrap().with_fade(fade).unwrap();
        let (mut out, mut previous, mut worst) = (Vec::new(), None::<Vec<f32>>, 0f32);
        for (k, &p) in path.iter().enumerate() {
            let elapsed = (continuous && k > 0).then_some(1.0 / 60.0);
            weigher.weigh_after(&cloud, &[point_light(p, intensity)], visible, elapsed, &mut out);
            let sum = out.iter().fold(Vec3::ZERO, |s, w| s + w.weight);
            assert!((sum - intensity).abs().max_element() < 1e-5, "fade {fade}, step {k}: sum {sum}");
            let now = dense(&out);
            if let Some(before) = &previous {
                worst = worst.max(now.iter().zip(before).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max));
            }
            previous = Some(now);
        }
        worst
    };
    let (cut, faded) = (largest_step(0.25, false), largest_step(0.25, true));
    println!("largest weight change a frame: {cut:.4} by cuts, {faded:.4} fading over 0.25 s");
    assert!(faded < 0.25 * cut, "fading: {faded} against {cut}");
    assert_eq!(largest_step(0.0, true), cut, "no fade: continuous moves are cuts");
    // Standing still past the fade: the settled weights.
    let end = point_light(*path.last().unwrap(), intensity);
    let mut weigher = Weigher::new(cloud.len(), 8).unwrap().with_fade(0.25).unwrap();
    let mut out = Vec::new();
    weigher.weigh_after(&cloud, &[point_light(path[0], intensity)], visible, None, &mut out);
    weigher.weigh_after(&cloud, std::slice::from_ref(&end), visible, Some(1.0 / 60.0), &mut out);
    let mut settled = Vec::new();
    Weigher::new(cloud.len(), 8).unwrap().weigh(&cloud, std::slice::from_ref(&end), visible, &mut settled);
    assert_ne!(dense(&out), dense(&settled), "one frame after the door closed, the hidden lights still fade");
    for _ in 0..15 {
        weigher.weigh_after(&cloud, std::slice::from_ref(&end), visible, Some(1.0 / 60.0), &mut out);
    }
    let (now, settled) = (dense(&out), dense(&settled));
    assert!(now.iter().zip(&settled).all(|(a, b)| (a - b).abs() < 1e-6), "after the fade: {now:?} against {settled:?}");
    assert!(Weigher::new(4, 2).unwrap().with_fade(f32::NAN).is_err() && Weigher::new(4, 2).unwrap().with_fade(-1.0).is_err());
}

/// A glossy scene stores exitant radiance in 16 spherical harmonics (spec light-clouds.md B10).
/// The closed sphere's material opts into the glossy lobe with no specular part, so its
/// exitant radiance is the Lambertian rho / pi E in every direction: the fitted coefficients
/// must give the analytic answer towards the normal and 60 degrees off it, on average over the
/// vertices within 2 %, as the irradiance did.
#[test]
fn a_glossy_scene_stores_exitant_radiance_in_sixteen_harmonics() {
    use relume_bake::scene::Phong;
    use relume_bake::sh;
    let mut s = sphere_scene();
    s.materials[0].phong = Some(Phong { specular: Vec3::ZERO, exponent: 12.0 });
    let cloud = bake(&s, CloudGrid { min: Vec3::splat(-0.6), max: Vec3::splat(0.6), counts: [2, 2, 2] }, 32, None);
    assert_eq!(cloud.coefficients, sh::COEFFICIENTS);
    let expected = RHO / std::f32::consts::PI * RHO / (RADIUS * RADIUS * (1.0 - RHO));
    let (normals, columns) = (s.meshes[0].normals.clone(), lc::Columns::new(&cloud));
    for j in 0..cloud.lights.len() {
        for tilt in [0.0f32, 60.0] {
            let mut sum = 0f64;
            for (v, &n) in normals.iter().enumerate() {
                let (t, _) = relume_bake::sampling::orthonormal_basis(n);
                let wo = n * tilt.to_radians().cos() + t * tilt.to_radians().sin();
                let y = sh::eval(wo);
                sum += (0..sh::COEFFICIENTS).map(|k| columns.coefficient(v, j, k).y * y[k]).sum::<f32>() as f64;
            }
            let mean = sum / normals.len() as f64;
            assert!((mean - expected as f64).abs() < 0.02 * expected as f64, "light {j}, {tilt} degrees: {mean} against {expected}");
        }
    }
}

/// 004 Fig. 5's statistic: each component's share of the clusters' variance lies in [0, 1] and
/// falls; the sphere's 8 cloud lights give rows of rank 8 at most (one value a light for the
/// direct light, and grey walls make the indirect light's rgb equal), so 8 components hold all
/// the variance of both and the rest none.
#[test]
fn explained_variance_shares_fall_and_sum_to_one_at_full_rank() {
    let s = sphere_scene();
    let cloud = bake(&s, CloudGrid { min: Vec3::splat(-0.6), max: Vec3::splat(0.6), counts: [2, 2, 2] }, 4, None);
    let compressed = lc::compress(&cloud, 4, lc::Vectors::Each(2), false).unwrap();
    let shares = lc::explained_variance(&s, &SceneBvh::new(&s), &cloud, &compressed, 12);
    println!("indirect {:?}\ndirect {:?}", shares.indirect, shares.direct);
    for (name, values) in [("indirect", &shares.indirect), ("direct", &shares.direct)] {
        assert_eq!(values.len(), 12);
        assert!(values.iter().all(|&v| (0.0..=1.0).contains(&v)), "{name}: {values:?}");
        assert!(values.windows(2).all(|w| w[1] <= w[0] + 1e-12), "{name} does not fall: {values:?}");
        assert!((values[..8].iter().sum::<f64>() - 1.0).abs() < 1e-6, "{name}: 8 components miss variance: {values:?}");
        assert!(values[8..].iter().all(|&v| v < 1e-6), "{name}: variance past rank 8: {values:?}");
    }
}
