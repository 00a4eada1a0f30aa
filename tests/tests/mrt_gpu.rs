//! Modular radiance transfer's passes on the GPU against the CPU evaluator of the same tables
//! (`LevelData`), on `mrt-maze` with validation on: the direct light the GPU found at every
//! level sample is fed to the CPU, and b0, b, r, the indirect light, the un-padded light map
//! (its sample texels) and the padded one (every copy record) must agree, with the feedback
//! solved and off; texels no sample or record writes hold 0.

use glam::{Vec3, Vec4};
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
    let k_max = relume_bake::mrt::level_data::k_max(&dictionary);
    for feedback in [false, true] {
        let data = MrtData { dictionary: &dictionary, level: &level, feedback };
        let mut renderer = new_renderer(&ctx, &applied, &settings, &[&data]);
        let (direct, indirect) = frame(&mut renderer);
        assert!(direct.iter().filter(|e| e.max_element() > 0.0).count() > direct.len() / 20, "the light reaches the samples");
        let b0 = level.coefficients(&dictionary, &light(&level, &direct));
        let b = if feedback { level.fed_back(&dictionary, &b0) } else { b0.clone() };
        let r = level.received(&dictionary, &b);
        let per_block = |gpu: &[Vec3], cpu: &[Vec<Vec3>]| {
            let got: Vec<Vec3> = cpu.iter().enumerate().flat_map(|(i, c)| gpu[i * k_max..i * k_max + c.len()].to_vec()).collect();
            relative(&got, &cpu.concat())
        };
        let e_b0 = per_block(&rgb(&read_vec4s(&mut renderer, "mrt.b0").unwrap()), &b0);
        let e_b = per_block(&rgb(&read_vec4s(&mut renderer, "mrt.b").unwrap()), &b);
        let e_r = relative(&rgb(&read_vec4s(&mut renderer, "mrt.r").unwrap()), &r.concat());
        let e_indirect = relative(&indirect, &level.indirect(&dictionary, &direct, feedback));
        let map = read_vec4s(&mut renderer, "mrt.light_map").unwrap();
        let unpadded: Vec<Vec3> = level.samples.iter().map(|s| map[s.texel as usize].truncate()).collect();
        let e_unpadded = relative(&unpadded, &indirect);
        let mut written = vec![false; map.len()];
        level.samples.iter().for_each(|s| written[s.texel as usize] = true);
        level.copies.iter().for_each(|c| written[c[0] as usize] = true);
        let padded = level.copies.iter().all(|[to, from]| map[*to as usize] == map[*from as usize].truncate().extend(-1.0));
        let rest_zero = map.iter().zip(&written).all(|(t, w)| *w || *t == Vec4::ZERO);
        eprintln!(
            "GPU against CPU, feedback {feedback}: b0 {e_b0:.2e}, b {e_b:.2e}, r {e_r:.2e}, indirect {e_indirect:.2e}, un-padded light map {e_unpadded:.2e}"
        );
        assert!(e_b0 < 1e-4 && e_b < 1e-4 && e_r < 1e-4 && e_indirect < 1e-4, "b0 {e_b0:e}, b {e_b:e}, r {e_r:e}, indirect {e_indirect:e}");
        assert_eq!(e_unpadded, 0.0, "the light map's sample texels hold the indirect light");
        assert!(padded && rest_zero, "every copy record copies its source (padded {padded}); the rest is 0 ({rest_zero})");
        assert!(map.iter().all(|t| t.is_finite()));
    }
    assert_clean(ctx);
}

#[test]
fn a_level_without_its_solved_feedback_or_with_a_shape_the_dictionary_lacks_is_refused() {
    let scene = load_scene("mrt-cube");
    let (dictionary, _, level, applied) = mrt_quick_bake(&scene);
    let ctx = validated_context();
    let unsolved = LevelData { feedback: Vec::new(), ..level.clone() };
    let data = MrtData { dictionary: &dictionary, level: &unsolved, feedback: true };
    says(&refusal(try_new_renderer(&ctx, &applied, &RenderSettings::default(), &[&data])), &["mrt", "feedback holds 0 values"]);
    let mut other = level.clone();
    other.blocks[0].shape = 9;
    let data = MrtData { dictionary: &dictionary, level: &other, feedback: true };
    says(&refusal(try_new_renderer(&ctx, &applied, &RenderSettings::default(), &[&data])), &["mrt", "block 0's shape 9"]);
    assert_clean(ctx);
}

/// The scene's vertex indices (mesh by mesh, as the vertex buffer holds them) of mesh `mesh`.
fn vertex_range(scene: &relume_bake::scene::Scene, mesh: usize) -> std::ops::Range<usize> {
    let first: usize = scene.meshes[..mesh].iter().map(|m| m.positions.len()).sum();
    first..first + scene.meshes[mesh].positions.len()
}

#[test]
fn the_light_volume_and_the_dynamic_vertices_equal_the_cpu_evaluator_as_a_figure_moves() {
    let scene = load_scene("mrt-figures");
    let (dictionary, _, level, applied) = mrt_quick_bake(&scene);
    assert_eq!(level.dynamic.len(), 2, "the two figures are dynamic");
    let ctx = validated_context();
    let settings = RenderSettings { width: 64, height: 48, ..RenderSettings::default() };
    let data = MrtData { dictionary: &dictionary, level: &level, feedback: true };
    let mut renderer = new_renderer(&ctx, &applied, &settings, &[&data]);
    let mut moved = applied.clone();
    let mut before: Option<Vec<Vec4>> = None;
    // Where the scene has the first figure, then 1.8 m along the row (another block).
    for translation in [Vec3::ZERO, Vec3::new(-1.8, 0.0, 0.2)] {
        let figure = level.dynamic[0] as usize;
        renderer.set_mesh_translation(figure, translation).unwrap();
        moved.meshes[figure].positions = applied.meshes[figure].positions.iter().map(|p| *p + translation).collect();
        let (direct, _) = frame(&mut renderer);
        let b = level.fed_back(&dictionary, &level.coefficients(&dictionary, &light(&level, &direct)));
        let r = level.received(&dictionary, &b);
        let volume = level.volume(&dictionary, &b, &r);
        let gpu_volume = rgb(&read_vec4s(&mut renderer, "mrt.volume").unwrap());
        let e_volume = relative(&gpu_volume, &volume.concat());
        let vertex_light = read_vec4s(&mut renderer, "mrt.vertex_light").unwrap();
        let (mut gpu, mut cpu) = (Vec::new(), Vec::new());
        for &mesh in &level.dynamic {
            let m = &moved.meshes[mesh as usize];
            for (k, v) in vertex_range(&moved, mesh as usize).enumerate() {
                gpu.push(vertex_light[v]);
                cpu.push(level.volume_irradiance(&volume, m.positions[k], m.normals[k]));
            }
        }
        let e_vertices = relative(&rgb(&gpu), &cpu);
        let lit = cpu.iter().filter(|e| e.min_element() > 0.0).count();
        eprintln!(
            "light volume at {translation}: GPU against CPU {e_volume:.2e}, dynamic vertices {e_vertices:.2e}, {lit} of {} lit",
            cpu.len()
        );
        assert!(e_volume < 1e-4 && e_vertices < 1e-3, "volume {e_volume:e}, dynamic vertices {e_vertices:e}");
        assert!(lit > cpu.len() * 9 / 10, "the volume lights the figures: {lit} of {} vertices", cpu.len());
        assert!(gpu.iter().all(|v| v.w == 1.0), "dynamic vertices are marked");
        let unmarked =
            vertex_light.iter().enumerate().filter(|(v, _)| !level.dynamic.iter().any(|&m| vertex_range(&moved, m as usize).contains(v)));
        assert!(unmarked.clone().all(|(_, l)| *l == Vec4::ZERO), "the other vertices read the light map");
        if let Some(before) = before.replace(vertex_light.clone()) {
            let figure = vertex_range(&moved, level.dynamic[0] as usize);
            assert!(
                figure.clone().any(|v| (before[v] - vertex_light[v]).abs().max_element() > 1e-3),
                "the moved figure's light follows it"
            );
        }
    }
    drop(renderer);
    assert_clean(ctx);
}
