//! The GPU atlas padding pass against a brute-force CPU nearest fill: covered texels stay
//! bit for bit, every empty texel copies a covered texel within a texel of the nearest and
//! says how far it is, a layer without coverage stays empty, bad sizes are refused. Every
//! covered texel has an rgb of its own (its coordinates), so the texel a padded one copied
//! can be read off its colour.

use glam::{IVec2, Vec4};
use relume_renderer::atlas_image::GpuAtlasImage;
use relume_renderer::vk::{Access, Context, Tracker, VkResult};
use relume_renderer::AtlasImage;
use relume_tests::*;
use std::sync::Arc;

const WIDTH: u32 = 64;
const HEIGHT: u32 = 48;

/// The coverage of texel (x, y) of `layer` in the synthetic atlas image, 0 for empty. Layer 0:
/// a disc, a right triangle and one lone texel; layer 1: a one-texel-wide diagonal band and
/// a block in the corner. Coverages differ so that "unchanged" covers alpha too.
fn coverage(layer: u32, x: i32, y: i32) -> f32 {
    let disc = (x - 16).pow(2) + (y - 14).pow(2) <= 49;
    let triangle = x <= 60 && y >= 30 && (y - 30) * 24 <= (x - 36) * 14;
    let band = (20..50).contains(&x) && x - y == 10;
    let corner = x < 4 && y < 3;
    match layer {
        0 if disc => 1.0,
        0 if triangle => 0.5,
        0 if (x, y) == (3, 44) => 0.25,
        1 if band => 0.75,
        1 if corner => 1.0,
        _ => 0.0,
    }
}

/// Covered texels carry (x, y, layer + 1) as rgb; empty ones are zero.
fn synthetic_texels(layers: u32, coverage: impl Fn(u32, i32, i32) -> f32) -> Vec<Vec4> {
    let mut texels = Vec::new();
    for layer in 0..layers {
        for y in 0..HEIGHT as i32 {
            for x in 0..WIDTH as i32 {
                let alpha = coverage(layer, x, y);
                texels.push(if alpha > 0.0 { Vec4::new(x as f32, y as f32, (layer + 1) as f32, alpha) } else { Vec4::ZERO });
            }
        }
    }
    texels
}

fn index(layer: u32, p: IVec2) -> usize {
    (layer as usize * HEIGHT as usize + p.y as usize) * WIDTH as usize + p.x as usize
}

fn distance(a: IVec2, b: IVec2) -> f32 {
    ((a - b).length_squared() as f32).sqrt()
}

/// Checks one layer of a padded atlas image against its input; returns how many empty texels
/// copied an exactly nearest covered texel, and how many empty texels there were.
fn check_layer(layer: u32, input: &[Vec4], padded: &[Vec4]) -> (usize, usize) {
    let texels = || (0..HEIGHT as i32).flat_map(|y| (0..WIDTH as i32).map(move |x| IVec2::new(x, y)));
    let covered: Vec<IVec2> = texels().filter(|&p| input[index(layer, p)].w > 0.0).collect();
    let (mut exact, mut empty) = (0, 0);
    for p in texels() {
        let (before, after) = (input[index(layer, p)], padded[index(layer, p)]);
        if before.w > 0.0 {
            assert_eq!(
                before.to_array().map(f32::to_bits),
                after.to_array().map(f32::to_bits),
                "covered texel {p} of layer {layer} changed"
            );
            continue;
        }
        empty += 1;
        assert!(after.w < 0.0, "empty texel {p} of layer {layer} was not padded: {after}");
        let source = after.truncate().truncate().as_ivec2();
        let original = input[index(layer, source.clamp(IVec2::ZERO, IVec2::new(WIDTH as i32 - 1, HEIGHT as i32 - 1)))];
        assert!(
            original.w > 0.0 && original.truncate() == after.truncate(),
            "texel {p} of layer {layer} holds {after}, the rgb of no covered texel of its layer"
        );
        let copied = distance(p, source);
        assert!(
            (-after.w - copied).abs() <= 1e-5 * copied,
            "texel {p} of layer {layer}: alpha {} for a copy from {copied} texels away",
            after.w
        );
        let nearest = covered.iter().map(|&c| distance(p, c)).fold(f32::INFINITY, f32::min);
        assert!(copied <= nearest + 1.0, "texel {p} of layer {layer} copied from {copied} texels away; the nearest is {nearest}");
        exact += (copied == nearest) as usize;
    }
    (exact, empty)
}

fn upload(ctx: &Arc<Context>, width: u32, height: u32, pages: u32, texels: &[Vec4]) -> VkResult<GpuAtlasImage> {
    GpuAtlasImage::upload_blocking(ctx, "atlas image", &AtlasImage { width, height, pages, texels })
}

#[test]
fn padding_copies_a_nearest_covered_texel_into_every_empty_one() {
    let ctx = validated_context();
    let input = synthetic_texels(2, coverage);
    let image = upload(&ctx, WIDTH, HEIGHT, 2, &input).expect("upload");
    let padded = image.read_back_blocking().expect("read back");
    for layer in 0..2 {
        let (exact, empty) = check_layer(layer, &input, &padded);
        println!("layer {layer}: {exact} of {empty} empty texels copied an exactly nearest covered texel");
    }
    assert_eq!(image.read_back_blocking().expect("read back"), padded, "a read-back leaves the image as it was");
    let mut tracker = Tracker::default();
    image.register_state(&mut tracker);
    assert_eq!(tracker.state(&image.image), Access::FragmentSampled);
    drop(image);
    assert_clean(ctx);
}

#[test]
fn a_layer_without_coverage_stays_empty_and_layers_do_not_mix() {
    let ctx = validated_context();
    let lone_texel = |layer, x, y| if layer == 1 && (x, y) == (40, 7) { 1.0 } else { 0.0 };
    let input = synthetic_texels(2, lone_texel);
    let image = upload(&ctx, WIDTH, HEIGHT, 2, &input).expect("upload");
    let padded = image.read_back_blocking().expect("read back");
    let layer_size = (WIDTH * HEIGHT) as usize;
    assert!(padded[..layer_size].iter().all(|t| *t == Vec4::ZERO), "the layer without coverage changed");
    check_layer(1, &input, &padded);
    drop(image);
    assert_clean(ctx);
}

#[test]
fn impossible_sizes_are_refused_with_their_numbers() {
    let ctx = validated_context();
    let cases: [(u32, u32, u32, usize, &[&str]); 5] = [
        (0, 4, 1, 0, &["0x4"]),
        (4, 4, 0, 0, &["0 layers"]),
        (20000, 1, 1, 20000, &["20000x1"]),
        (4, 4, 1, 15, &["16 texels", "15 were given"]),
        (4, 4, 2, 16, &["32 texels", "16 were given"]),
    ];
    for (width, height, layers, count, expected) in cases {
        let texels = vec![Vec4::ONE; count];
        let message = match upload(&ctx, width, height, layers, &texels) {
            Ok(_) => panic!("{width}x{height}x{layers} with {count} texels was accepted"),
            Err(e) => e.to_string(),
        };
        for part in expected {
            assert!(message.contains(part), "\"{message}\" does not say \"{part}\"");
        }
    }
    assert_clean(ctx);
}
