//! A flat quad split across two atlas charts shows no visible seam after padding.
//!
//! Scene A: a 2 m x 2 m white floor (albedo 1) made of two meshes, its halves x < 0 and
//! x > 0, so the atlas gives each its own chart (triangles of different meshes never share
//! one), with a closed 0.5 m box standing beside the seam line x = 0 so that the obscurance
//! W varies along and across the seam. Scene B: the same with the floor as one mesh, one
//! chart, no seam. Both are baked (obscurance, tau 0.2 m, L_max 0.6 m, 1024 rays a texel,
//! fixed seed) at 32 texels a metre and rendered from straight above with I_A = pi, beta = 0
//! and a light of zero intensity, so every floor pixel's radiance is albedo / pi * I_A * W = W:
//! the image is the obscurance as the renderer filters it.
//!
//! Both floors' texel grids start at x = -1 m with whole texels per metre, so the two atlases
//! put texel centres at the same floor points everywhere; the images differ only where A's
//! filter reaches past a chart's edge (the seam) and by the bake's noise (each texel's rays
//! are seeded by its index, which differs between the atlases).
//!
//! Measured along the seam (every image row whose two pixels either side of x = 0 see the
//! floor): the jump |I(right) - I(left)| in A against the same pixel pair's jump in B, and the
//! largest |A - B| over floor pixels away from silhouettes. Bounds:
//!
//! - max jump in A <= max jump in B + g * (1 texel - 1 pixel) + 0.01, g the largest slope of
//!   W across the seam (measured in B over 9 pixels, 6.7 cm; about 1.5 per metre here, the
//!   box 0.1 m beside the seam). Why the slope term: the padding copies each chart's edge
//!   texel into the gutter, so near the seam A's filter extrapolates W as a constant from the
//!   edge texel's centre, half a texel (1/64 m) inside each chart, where B interpolates
//!   between real neighbours. For W of slope g across the seam the step in A is g times one
//!   texel (1/32 m), in B g times one pixel (1.9 m / 256): measured 0.046 against 0.011, as
//!   predicted (a fixed allowance of 0.02 fails at 32 texels a metre for this reason; at 64
//!   the step would halve). The 0.01: two independent 1024-ray bakes of B (seeds 17 and 18)
//!   differ by at most 0.0076 anywhere in the image (rms 3e-4), and the seam compares two
//!   charts' independent estimates.
//! - max |A - B| over floor pixels <= 0.05: two estimates of the same W through the same texel
//!   grid, differing by the bake's noise (< 0.01) and, within half a texel of the seam, by the
//!   constant extrapolation above, g * (1/2 texel - 1/2 pixel) per side (0.018 here).
//!
//! What the bounds guard against is checked in the same test: scene A rendered with its
//! gutters left black (empty texels handed over as covered with W = 0, so the padding pass
//! leaves them alone) puts 38% of the seam pixels' bilinear weight on black texels (each seam
//! pixel is 0.38 texel from its edge texel's centre, towards the gutter): W drops to 0.62 W on both
//! sides of the seam, a dark line two pixels wide (|A - B| 0.38 at the seam, far past 0.05).
//! The line is symmetric, so the adjacent-pixel jump alone misses it (0.028): the |A - B|
//! bound is the one that catches missing padding. The jump bound catches padding that
//! extrapolates from farther inside the chart: with each floor chart's edge column replaced
//! by its inner neighbour (tried while writing this test, not kept), the step grows to three
//! texels' worth, jump 0.142 and |A - B| 0.086, and both bounds fail.

use glam::{Vec3, Vec4};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::obscurance::{bake_obscurance, ObscuranceSettings, Variant};
use relume_bake::scene::{Mesh, Scene};
use relume_bake::testing::{self, Facing};
use relume_bake::work::WorkOptions;
use relume_renderer::techniques::obscurance::ObscuranceData;
use relume_renderer::vk::Context;
use relume_renderer::{AtlasImage, RenderSettings};
use relume_tests::*;
use std::f32::consts::PI;
use std::sync::Arc;

const SIZE: u32 = 256;
const TEXEL_DENSITY: f32 = 32.0;
/// Half the floor's side seen by the image at the floor's height (the floor's is 1 m).
const HALF_VIEW: f32 = 0.95;
const EYE_HEIGHT: f32 = 3.0;

/// The largest difference two independent 1024-ray bakes may make at one pixel (0.0076
/// measured between seeds 17 and 18 of scene B).
const NOISE: f32 = 0.01;
const DIFFERENCE_BOUND: f32 = 0.05;

/// The floor quad (front +Y) from x = x0 to x1, z from -1 to 1, as one mesh of two triangles.
fn floor_part(x0: f32, x1: f32) -> Mesh {
    let centre = Vec3::new(0.5 * (x0 + x1), 0.0, 0.0);
    testing::square(centre, Vec3::X * 0.5 * (x1 - x0), -Vec3::Z, 1, 0)
}

/// The floor meshes, then the box; camera straight above the floor's centre, image right
/// +X, image top -Z; one point light of zero intensity (the image is the ambient term alone).
fn floor_and_box(name: &str, floor: Vec<Mesh>) -> Scene {
    let white = testing::material("white", Vec3::ONE, Vec3::ZERO);
    let block = testing::closed_box(Vec3::new(0.1, 0.0, -0.25), Vec3::new(0.6, 0.5, 0.25), 1, Facing::Outward, 0);
    let mut meshes = floor;
    meshes.push(block);
    let yfov = 2.0 * (HALF_VIEW / EYE_HEIGHT).atan();
    let camera = testing::look_at(Vec3::new(0.0, EYE_HEIGHT, 0.0), Vec3::ZERO, -Vec3::Z, yfov);
    let light = testing::point_light(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO);
    testing::scene(name, meshes, vec![white], vec![light], camera)
}

/// A scene baked: its atlas, the scene with uv1 (atlas applied) and the obscurance as the
/// renderer takes it (rgb W, alpha coverage).
struct Baked {
    atlas: Atlas,
    applied: Scene,
    texels: Vec<Vec4>,
}

fn bake(scene: &Scene) -> Baked {
    let atlas = Atlas::build(scene, &AtlasSettings { texel_density: TEXEL_DENSITY, ..AtlasSettings::default() }).expect("atlas");
    let settings = ObscuranceSettings {
        variant: Variant::Obscurance,
        tau: 0.2,
        l_max: 0.6,
        rays_per_texel: 1024,
        work: WorkOptions { seed: 17, ..WorkOptions::default() },
    };
    let map = bake_obscurance(scene, &SceneBvh::new(scene), &atlas, &settings).expect("bake");
    let texels = atlas.with_coverage(&map.values);
    let mut applied = scene.clone();
    atlas.apply_to(&mut applied);
    Baked { atlas, applied, texels }
}

/// The frame's linear radiance with I_A = pi, beta = 0, no shadows: albedo * W.
fn render_w(ctx: &Arc<Context>, scene: &Scene, obscurance: AtlasImage) -> Image {
    let settings =
        RenderSettings { width: SIZE, height: SIZE, shadows: false, ambient: Vec3::splat(PI), beta: 0.0, ..RenderSettings::default() };
    render(&mut new_renderer(ctx, scene, &settings, &[&ObscuranceData { obscurance }]))
}

/// The mesh every pixel's centre sees (CPU primary rays), None for the background.
fn pixel_meshes(scene: &Scene) -> Vec<Option<u32>> {
    primary_hits(scene, &SceneBvh::new(scene), SIZE, SIZE).iter().map(|h| h.map(|h| h.mesh)).collect()
}

fn at(image: &Image, x: u32, y: u32) -> f32 {
    image.pixels[(y * SIZE + x) as usize].x
}

/// Per seam row: (row, left column); the pixel at left + 1 is right of the seam.
fn seam_pairs(meshes_a: &[Option<u32>], floor_b: &[bool]) -> Vec<(u32, u32)> {
    let mut pairs = Vec::new();
    for y in 0..SIZE {
        for x in 0..SIZE - 1 {
            let (i, j) = ((y * SIZE + x) as usize, (y * SIZE + x + 1) as usize);
            if meshes_a[i] == Some(0) && meshes_a[j] == Some(1) && floor_b[i] && floor_b[j] {
                pairs.push((y, x));
            }
        }
    }
    pairs
}

/// Floor pixels whose 3 x 3 neighbourhood is floor too: away from the box's silhouette, where
/// the rasteriser and the CPU ray may disagree by a pixel.
fn interior(floor: &[bool]) -> Vec<bool> {
    let mut keep = vec![false; floor.len()];
    for y in 1..SIZE as i64 - 1 {
        for x in 1..SIZE as i64 - 1 {
            keep[(y * SIZE as i64 + x) as usize] = (-1..=1).all(|dy| (-1..=1).all(|dx| floor[((y + dy) * SIZE as i64 + x + dx) as usize]));
        }
    }
    keep
}

struct SeamStats {
    /// Largest jump across the seam and its row.
    max_jump: (f32, u32),
    /// Largest |A - B| at the seam pixels.
    max_seam_difference: f32,
}

fn seam_stats(a: &Image, b: &Image, pairs: &[(u32, u32)]) -> SeamStats {
    let mut max_jump = (0.0f32, 0);
    let mut max_seam_difference = 0.0f32;
    for &(y, x) in pairs {
        let jump = (at(a, x + 1, y) - at(a, x, y)).abs();
        if jump > max_jump.0 {
            max_jump = (jump, y);
        }
        for column in [x, x + 1] {
            max_seam_difference = max_seam_difference.max((at(a, column, y) - at(b, column, y)).abs());
        }
    }
    SeamStats { max_jump, max_seam_difference }
}

#[test]
fn a_flat_quad_split_across_two_charts_shows_no_visible_seam_after_padding() {
    let split = floor_and_box("split floor", vec![floor_part(-1.0, 0.0), floor_part(0.0, 1.0)]);
    let whole = floor_and_box("whole floor", vec![floor_part(-1.0, 1.0)]);
    let (a, b) = (bake(&split), bake(&whole));
    let charts_of = |baked: &Baked, mesh: u32| baked.atlas.charts.iter().filter(|c| c.mesh == mesh).count();
    assert_eq!((charts_of(&a, 0), charts_of(&a, 1)), (1, 1), "each floor half of A is one chart");
    assert_eq!(charts_of(&b, 0), 1, "B's floor is one chart");

    let ctx = validated_context();
    let image_a = render_w(&ctx, &a.applied, AtlasImage::new(a.atlas.layout(), &a.texels));
    let image_b = render_w(&ctx, &b.applied, AtlasImage::new(b.atlas.layout(), &b.texels));
    // A's gutters left black: empty texels handed over as covered (alpha 1) with W = 0, so
    // the padding pass, which fills only texels of alpha <= 0, leaves them as they are.
    let unpadded: Vec<Vec4> = a.texels.iter().map(|t| if t.w > 0.0 { *t } else { Vec4::new(0.0, 0.0, 0.0, 1.0) }).collect();
    let image_unpadded = render_w(&ctx, &a.applied, AtlasImage::new(a.atlas.layout(), &unpadded));
    assert_clean(ctx);

    let meshes_a = pixel_meshes(&split);
    let meshes_b = pixel_meshes(&whole);
    let floor_a: Vec<bool> = meshes_a.iter().map(|m| matches!(m, Some(0 | 1))).collect();
    let floor_b: Vec<bool> = meshes_b.iter().map(|m| *m == Some(0)).collect();
    let floor: Vec<bool> = floor_a.iter().zip(&floor_b).map(|(a, b)| *a && *b).collect();
    let keep = interior(&floor);
    assert!(meshes_a.iter().chain(&meshes_b).all(Option::is_some), "every pixel sees the floor or the box");

    let pairs = seam_pairs(&meshes_a, &floor_b);
    assert!(pairs.len() * 10 >= SIZE as usize * 9, "only {} of {SIZE} rows cross the seam on the floor", pairs.len());
    // The box must make W vary along the seam, or a constant W would hide any seam (W
    // there spans about [0.87, 1]).
    let seam_w: Vec<f32> = pairs.iter().map(|&(y, x)| at(&image_b, x, y)).collect();
    let (w_min, w_max) = seam_w.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), w| (lo.min(*w), hi.max(*w)));
    assert!(w_max - w_min > 0.1, "W along the seam spans only [{w_min}, {w_max}]");
    assert!(w_max <= 1.0 + 1e-4, "W above 1 ({w_max})");

    let seam_a = seam_stats(&image_a, &image_b, &pairs);
    let seam_b = seam_stats(&image_b, &image_b, &pairs);
    let seam_unpadded = seam_stats(&image_unpadded, &image_b, &pairs);
    let max_difference =
        (0..keep.len()).filter(|&i| keep[i]).map(|i| (image_a.pixels[i].x - image_b.pixels[i].x).abs()).fold(0.0f32, f32::max);
    let max_difference_unpadded =
        (0..keep.len()).filter(|&i| keep[i]).map(|i| (image_unpadded.pixels[i].x - image_b.pixels[i].x).abs()).fold(0.0f32, f32::max);
    // The slope of W across the seam in B, from 4 pixels left of the seam pair to 4 right.
    let pixel_metres = 2.0 * HALF_VIEW / SIZE as f32;
    let max_slope = pairs
        .iter()
        .filter(|&&(y, x)| x >= 4 && x + 5 < SIZE && (x - 4..=x + 5).all(|c| floor_b[(y * SIZE + c) as usize]))
        .map(|&(y, x)| (at(&image_b, x + 5, y) - at(&image_b, x - 4, y)).abs() / (9.0 * pixel_metres))
        .fold(0.0f32, f32::max);

    println!(
        "atlases: A {}x{}x{} ({} charts), B {}x{}x{} ({} charts); {} seam rows, W along the seam in [{w_min:.3}, {w_max:.3}], largest slope across it {max_slope:.3} per metre",
        a.atlas.width, a.atlas.height, a.atlas.pages, a.atlas.charts.len(), b.atlas.width, b.atlas.height, b.atlas.pages, b.atlas.charts.len(), pairs.len()
    );
    println!(
        "max jump across the seam: A {:.4} (row {}), B {:.4} (row {}), A with black gutters {:.4} (row {})",
        seam_a.max_jump.0, seam_a.max_jump.1, seam_b.max_jump.0, seam_b.max_jump.1, seam_unpadded.max_jump.0, seam_unpadded.max_jump.1
    );
    println!("max |A - B| at the seam pixels {:.4} (black gutters {:.4}); over {} floor pixels {max_difference:.4} (black gutters {max_difference_unpadded:.4})", seam_a.max_seam_difference, seam_unpadded.max_seam_difference, keep.iter().filter(|k| **k).count());

    let allowance = max_slope * (1.0 / TEXEL_DENSITY - pixel_metres) + NOISE;
    println!(
        "jump bound: B's {:.4} + slope {max_slope:.3} x (texel {:.4} m - pixel {pixel_metres:.4} m) + noise {NOISE} = {:.4}",
        seam_b.max_jump.0,
        1.0 / TEXEL_DENSITY,
        seam_b.max_jump.0 + allowance
    );
    assert!(
        seam_a.max_jump.0 <= seam_b.max_jump.0 + allowance,
        "a seam: jump {} across the chart border (row {}), {} in the one-chart render, allowed {allowance} more",
        seam_a.max_jump.0,
        seam_a.max_jump.1,
        seam_b.max_jump.0
    );
    assert!(max_difference <= DIFFERENCE_BOUND, "the split floor differs from the whole one by up to {max_difference}");
    // The test can fail: without padding the seam is plain.
    assert!(
        seam_unpadded.max_seam_difference > 4.0 * DIFFERENCE_BOUND,
        "black gutters should darken the seam by far more than the bound ({} at the seam)",
        seam_unpadded.max_seam_difference
    );
}
