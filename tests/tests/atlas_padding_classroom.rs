//! After the GPU padding pass, no texel that bilinear filtering can read from any point of
//! any triangle of `classroom` is empty: the renderer never samples a gutter.

use glam::{Vec2, Vec4};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_renderer::atlas_image::GpuAtlasImage;
use relume_tests::*;

/// The four texels bilinear filtering reads at `uv1` (texel centres at (i + 0.5) / size,
/// clamped to the page), as indices into the page-major texel array.
fn bilinear_footprint(atlas: &Atlas, uv1: Vec2) -> [usize; 4] {
    let page = uv1.x.floor() as u32;
    let size = Vec2::new(atlas.width as f32, atlas.height as f32);
    let x = Vec2::new(uv1.x.fract(), uv1.y) * size - 0.5;
    let base = x.floor();
    let texel = |dx: f32, dy: f32| {
        let p = (base + Vec2::new(dx, dy)).clamp(Vec2::ZERO, size - 1.0);
        ((page * atlas.height + p.y as u32) * atlas.width + p.x as u32) as usize
    };
    [texel(0.0, 0.0), texel(1.0, 0.0), texel(0.0, 1.0), texel(1.0, 1.0)]
}

#[test]
fn every_texel_a_classroom_triangle_can_sample_is_filled_after_padding() {
    let scene = load_scene("classroom");
    let settings = AtlasSettings { texel_density: scene.settings.texel_density, ..Default::default() };
    let atlas = Atlas::build(&scene, &settings).unwrap();
    let texels: Vec<Vec4> = atlas.texels.iter().map(|t| (t.centre * 0.1).extend(t.coverage)).collect();
    let ctx = validated_context();
    let image = GpuAtlasImage::upload_blocking(&ctx, "atlas image", &atlas_image(&atlas, &texels)).expect("upload");
    let padded = image.read_back_blocking().expect("read back");
    drop(image);
    assert_clean(ctx);

    let empty_before = texels.iter().filter(|t| t.w == 0.0).count();
    let (mut sampled_empty, mut sampled_empty_before) = (0, 0);
    let mut checked = 0;
    for mesh in &atlas.meshes {
        for tri in mesh.indices.chunks_exact(3) {
            let corners = [0, 1, 2].map(|k| mesh.uv1[tri[k] as usize]);
            // Corners, edge points and interior points: 6 x 6 barycentric steps.
            for i in 0..=6 {
                for j in 0..=6 - i {
                    let (b1, b2) = (i as f32 / 6.0, j as f32 / 6.0);
                    let uv = corners[0] * (1.0 - b1 - b2) + corners[1] * b1 + corners[2] * b2;
                    for texel in bilinear_footprint(&atlas, uv) {
                        checked += 1;
                        sampled_empty += (padded[texel].w == 0.0) as u32;
                        sampled_empty_before += (texels[texel].w == 0.0) as u32;
                    }
                }
            }
        }
    }
    println!("{} triangles, {checked} bilinear reads, {sampled_empty_before} of them of empty texels before padding ({empty_before} empty texels)", scene.triangle_count());
    assert!(sampled_empty_before > 0, "without padding, bilinear reads at chart borders reach gutters");
    assert_eq!(sampled_empty, 0, "reads of empty texels after padding");
}
