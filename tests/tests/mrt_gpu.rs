//! Modular radiance transfer's passes on the GPU against the CPU evaluator of the same tables
//! (`LevelData`), on `mrt-maze` with validation on: the direct light the GPU found at every
//! level sample is fed to the CPU, and b, r (one bounce), the summed indirect light (three
//! bounces), the un-padded light map (its sample texels) and the padded one (every copy
//! record) must agree; texels no sample or record writes hold 0.

use glam::{Vec3, Vec4};
use relume_bake::mrt::dictionary::Dictionary;
use relume_bake::mrt::level_data::LevelData;
use relume_renderer::techniques::mrt::MrtData;
use relume_renderer::{Headless, RenderSettings};
use relume_tests::*;

/// The largest difference between `gpu` and `cpu` over the largest magnitude of `cpu`.
fn relative(gpu: &[Vec3], cpu: &[Vec3]) -> f32 {
    assert_eq!(gpu.len(), cpu.len());
    let scale = cpu.iter().fold(0.0f32, |m, v| m.max(v.abs().max_element()));
    assert!(scale > 0.0, "all zero: the comparison would prove nothing");
    gpu.iter().zip(cpu).fold(0.0f32, |m, (g, c)| m.max((*g - *c).abs().max_element())) / scale
}

fn rgb(values: &[Vec4]) -> Vec<Vec3> {
    values.iter().map(|v| v.truncate()).collect()
}

fn frame(renderer: &mut Headless) -> (Vec<Vec3>, Vec<Vec3>) {
    renderer.render().expect("frame");
    (rgb(&read_vec4s(renderer, "mrt.direct").unwrap()), rgb(&read_vec4s(renderer, "mrt.indirect").unwrap()))
}

fn light(level: &LevelData, e: &[Vec3]) -> Vec<Vec3> {
    e.iter().zip(&level.samples).map(|(e, s)| *e * s.albedo).collect()
}

#[test]
fn the_passes_equal_the_cpu_evaluator_for_b_r_the_indirect_light_and_both_atlases() {
    let scene = load_scene("mrt-maze");
    let (dictionary, _, level, applied) = mrt_quick_bake(&scene);
    let ctx = validated_context();
    let settings = RenderSettings { width: 64, height: 48, ..RenderSettings::default() };
    let once = MrtData { dictionary: &dictionary, level: &level, bounces: 1 };
    let mut renderer = new_renderer(&ctx, &applied, &settings, &[&once]);
    let (direct, indirect) = frame(&mut renderer);
    assert!(direct.iter().filter(|e| e.max_element() > 0.0).count() > direct.len() / 20, "the light reaches the samples");
    let b = level.coefficients(&dictionary, &light(&level, &direct));
    let r = level.received(&dictionary, &b);
    let k_max = dictionary.blocks.iter().map(|d| d.modes).max().unwrap();
    let gpu_b = rgb(&read_vec4s(&mut renderer, "mrt.b").unwrap());
    let (mut got, mut want) = (Vec::new(), Vec::new());
    for (i, block) in b.iter().enumerate() {
        got.extend_from_slice(&gpu_b[i * k_max..i * k_max + block.len()]);
        want.extend_from_slice(block);
    }
    let e_b = relative(&got, &want);
    let e_r = relative(&rgb(&read_vec4s(&mut renderer, "mrt.r").unwrap()), &r.concat());
    let e_one = relative(&indirect, &level.response(&dictionary, &b, &r));
    eprintln!("GPU against CPU, one bounce: b {e_b:.2e}, r {e_r:.2e}, indirect {e_one:.2e}");
    assert!(e_b < 1e-4 && e_r < 1e-4 && e_one < 1e-4, "b {e_b:e}, r {e_r:e}, indirect {e_one:e}");
    drop(renderer);

    let thrice = MrtData { dictionary: &dictionary, level: &level, bounces: 3 };
    let mut renderer = new_renderer(&ctx, &applied, &settings, &[&thrice]);
    let (direct, indirect) = frame(&mut renderer);
    let e_three = relative(&indirect, &level.indirect(&dictionary, &direct, 3));
    let map = read_vec4s(&mut renderer, "mrt.light_map").unwrap();
    let unpadded: Vec<Vec3> = level.samples.iter().map(|s| map[s.texel as usize].truncate()).collect();
    let e_unpadded = relative(&unpadded, &indirect);
    let written: Vec<bool> = {
        let mut w = vec![false; map.len()];
        level.samples.iter().for_each(|s| w[s.texel as usize] = true);
        level.copies.iter().for_each(|c| w[c[0] as usize] = true);
        w
    };
    let padded_ok = level.copies.iter().all(|[to, from]| map[*to as usize] == map[*from as usize].truncate().extend(-1.0));
    let rest_zero = map.iter().zip(&written).all(|(t, w)| *w || *t == Vec4::ZERO);
    eprintln!("GPU against CPU, three bounces: indirect {e_three:.2e}, un-padded light map {e_unpadded:.2e}");
    assert!(e_three < 1e-4 && e_unpadded == 0.0, "indirect {e_three:e}, un-padded {e_unpadded:e}");
    assert!(padded_ok && rest_zero, "every copy record copies its source (padded {padded_ok}); the rest is 0 ({rest_zero})");
    assert!(map.iter().all(|t| t.is_finite()));
    drop(renderer);
    assert_clean(ctx);
}

#[test]
fn bounces_outside_one_to_four_are_refused_by_name() {
    let scene = load_scene("mrt-cube");
    let (dictionary, _, level, applied): (Dictionary, _, LevelData, _) = mrt_quick_bake(&scene);
    let ctx = validated_context();
    let none = MrtData { dictionary: &dictionary, level: &level, bounces: 0 };
    let error = refusal(try_new_renderer(&ctx, &applied, &RenderSettings::default(), &[&none]));
    says(&error, &["mrt", "0 bounces", "1..=4"]);
    assert_clean(ctx);
}
