//! Error metrics between a method's image and the reference, defined once for all of relume.
//!
//! RMSE is taken over every channel of every pixel. NRMSE is that RMSE divided by the RMS of
//! the reference over the same values: `sqrt(sum (a - r)^2 / sum r^2)`. It is pooled over the
//! channels rather than averaged per channel so that a channel the reference barely lights
//! (the blue of a red wall) cannot dominate it. docs/METRICS.md states the same.

use crate::image::{Image, ImageError};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ErrorStats {
    pub rmse: f64,
    pub nrmse: f64,
    /// Pixels of the method image that hold a NaN or an infinity (any is a failure).
    pub non_finite_pixels: usize,
    /// Pixels the reference leaves black (an umbra, in a direct layer).
    pub dark_pixels: usize,
    /// Light the image puts where the reference is black: the mean channel value over those
    /// pixels, relative to the reference RMS. Shadow light-bleeding shows here.
    pub dark_leak: f64,
}

fn check_sizes(image: &Image, reference: &Image) -> Result<(), ImageError> {
    if (image.width, image.height) == (reference.width, reference.height) {
        return Ok(());
    }
    Err(ImageError::SizeMismatch {
        a: "the image".into(),
        aw: image.width,
        ah: image.height,
        b: "the reference".into(),
        bw: reference.width,
        bh: reference.height,
    })
}

/// Side of the pixel blocks flicker averages over: popping is spatially coherent, the
/// reference's Monte Carlo noise is not, and averaging 4 x 4 blocks cuts the noise 4 times.
const FLICKER_BLOCK: u32 = 4;

/// Popping between consecutive frames (docs/BENCH.md): the part of the method's
/// frame-to-frame change that the reference does not have, averaged over blocks of pixels, RMS
/// over blocks and channels, relative to the RMS of the reference's blocks. The four images
/// are of one size (the caller's).
pub fn flicker(before: &Image, after: &Image, reference_before: &Image, reference_after: &Image) -> f64 {
    let change = |i: usize| (after.pixels[i] - before.pixels[i]) - (reference_after.pixels[i] - reference_before.pixels[i]);
    let (changes, reference) =
        (block_means(after.width, after.height, change), block_means(after.width, after.height, |i| reference_after.pixels[i]));
    let squares = |blocks: &[Vec3]| blocks.iter().map(|b| b.length_squared() as f64).sum::<f64>();
    let reference = squares(&reference);
    if reference > 0.0 {
        (squares(&changes) / reference).sqrt()
    } else {
        0.0
    }
}

/// The mean of `value(pixel index)` over each FLICKER_BLOCK square (partial at the edges).
fn block_means(width: u32, height: u32, value: impl Fn(usize) -> Vec3) -> Vec<Vec3> {
    let mut blocks = Vec::new();
    for by in (0..height).step_by(FLICKER_BLOCK as usize) {
        for bx in (0..width).step_by(FLICKER_BLOCK as usize) {
            let pixels: Vec<usize> = (by..(by + FLICKER_BLOCK).min(height))
                .flat_map(|y| (bx..(bx + FLICKER_BLOCK).min(width)).map(move |x| (y * width + x) as usize))
                .collect();
            blocks.push(pixels.iter().map(|&i| value(i)).sum::<Vec3>() / pixels.len() as f32);
        }
    }
    blocks
}

/// RMSE and NRMSE of `image` against `reference`; non-finite pixels are counted, not summed.
pub fn compare(image: &Image, reference: &Image) -> Result<ErrorStats, ImageError> {
    check_sizes(image, reference)?;
    let (mut squared_error, mut squared_reference, mut values) = (0.0f64, 0.0f64, 0usize);
    let (mut non_finite_pixels, mut dark_pixels, mut dark_light) = (0, 0, 0.0f64);
    for (a, r) in image.pixels.iter().zip(&reference.pixels) {
        if !a.is_finite() {
            non_finite_pixels += 1;
            continue;
        }
        if *r == Vec3::ZERO {
            dark_pixels += 1;
            dark_light += a.as_dvec3().element_sum() / 3.0;
        }
        let d = (*a - *r).as_dvec3();
        squared_error += d.length_squared();
        squared_reference += r.as_dvec3().length_squared();
        values += 3;
    }
    let rmse = (squared_error / values.max(1) as f64).sqrt();
    let reference_rms = (squared_reference / values.max(1) as f64).sqrt();
    let relative = |x: f64| if reference_rms > 0.0 { x / reference_rms } else { f64::INFINITY };
    let dark_leak = relative(dark_light / dark_pixels.max(1) as f64);
    Ok(ErrorStats { rmse, nrmse: relative(rmse), non_finite_pixels, dark_pixels, dark_leak })
}

/// [`compare`] over the pixels `mask` keeps (a receiver's pixels, say), the others left out
/// of both sums.
pub fn compare_masked(image: &Image, reference: &Image, mask: &[bool]) -> Result<ErrorStats, ImageError> {
    check_sizes(image, reference)?;
    if mask.len() != reference.pixels.len() {
        let (a, b) = ("the mask".to_string(), "the reference".to_string());
        return Err(ImageError::SizeMismatch { a, aw: mask.len() as u32, ah: 1, b, bw: reference.width, bh: reference.height });
    }
    let keep = |source: &Image| Image {
        pixels: source.pixels.iter().zip(mask).filter(|(_, keep)| **keep).map(|(p, _)| *p).collect(),
        width: mask.iter().filter(|k| **k).count() as u32,
        height: 1,
    };
    compare(&keep(image), &keep(reference))
}

/// The scale s that makes `base + s * unit` closest to `reference` in the least-squares
/// sense (over every channel of every pixel): how much of a term a method should add to come
/// nearest the truth. 0 when `unit` is black.
pub fn best_scale(base: &Image, unit: &Image, reference: &Image) -> Result<f64, ImageError> {
    check_sizes(base, reference)?;
    check_sizes(unit, reference)?;
    let (mut numerator, mut denominator) = (0.0f64, 0.0f64);
    for ((b, u), r) in base.pixels.iter().zip(&unit.pixels).zip(&reference.pixels) {
        let (b, u, r) = (b.as_dvec3(), u.as_dvec3(), r.as_dvec3());
        numerator += (r - b).dot(u);
        denominator += u.length_squared();
    }
    Ok(if denominator > 0.0 { numerator / denominator } else { 0.0 })
}

/// `a - b`, pixel by pixel: a method's indirect part is its image minus its direct light.
pub fn difference(a: &Image, b: &Image) -> Result<Image, ImageError> {
    add_scaled(a, b, -1.0)
}

/// `base + scale * unit`, pixel by pixel.
pub fn add_scaled(base: &Image, unit: &Image, scale: f32) -> Result<Image, ImageError> {
    check_sizes(base, unit)?;
    let pixels = base.pixels.iter().zip(&unit.pixels).map(|(b, u)| *b + *u * scale).collect();
    Ok(Image { width: base.width, height: base.height, pixels })
}

/// A false-colour picture of the per-pixel error: the mean absolute channel error divided by
/// the reference's RMS, from black (0) through blue, cyan, green and yellow to red (>= `scale`).
/// Non-finite pixels are magenta.
pub fn false_colour(image: &Image, reference: &Image, scale: f32) -> Result<Vec<u8>, ImageError> {
    check_sizes(image, reference)?;
    let rms = (reference.pixels.iter().map(|r| r.length_squared() as f64).sum::<f64>() / (3 * reference.pixels.len()).max(1) as f64)
        .sqrt()
        .max(f64::MIN_POSITIVE) as f32;
    Ok(image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .flat_map(|(a, r)| {
            if !a.is_finite() {
                return [255, 0, 255];
            }
            let error = (*a - *r).abs().element_sum() / 3.0 / rms;
            heat_ramp((error / scale).clamp(0.0, 1.0))
        })
        .collect())
}

fn heat_ramp(t: f32) -> [u8; 3] {
    const STOPS: [Vec3; 6] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
    ];
    let x = t * (STOPS.len() - 1) as f32;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let c = STOPS[i].lerp(STOPS[i + 1], x - i as f32) * 255.0 + 0.5;
    [c.x as u8, c.y as u8, c.z as u8]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(value: Vec3) -> Image {
        Image { width: 2, height: 2, pixels: vec![value; 4] }
    }

    #[test]
    fn flicker_counts_only_change_the_reference_lacks() {
        let image = |v: f32| Image { width: 2, height: 1, pixels: vec![Vec3::splat(v); 2] };
        assert_eq!(flicker(&image(1.0), &image(2.0), &image(1.0), &image(2.0)), 0.0);
        let popped = flicker(&image(1.0), &image(3.0), &image(1.0), &image(2.0));
        assert!((popped - 0.5).abs() < 1e-9, "{popped}");
    }

    #[test]
    fn the_best_scale_recovers_a_known_mixture() {
        let base = flat(Vec3::new(1.0, 0.5, 0.2));
        let unit = Image { width: 2, height: 2, pixels: vec![Vec3::ONE, Vec3::X, Vec3::Y, Vec3::Z] };
        let reference = add_scaled(&base, &unit, 0.37).unwrap();
        assert!((best_scale(&base, &unit, &reference).unwrap() - 0.37).abs() < 1e-6);
        assert_eq!(best_scale(&base, &flat(Vec3::ZERO), &reference).unwrap(), 0.0);
    }

    #[test]
    fn identical_images_have_zero_error() {
        let a = flat(Vec3::new(0.2, 0.5, 1.0));
        assert_eq!(compare(&a, &a).unwrap().nrmse, 0.0);
    }

    #[test]
    fn a_uniform_ten_percent_offset_has_nrmse_one_tenth() {
        let r = flat(Vec3::splat(2.0));
        let stats = compare(&flat(Vec3::splat(2.2)), &r).unwrap();
        assert!((stats.nrmse - 0.1).abs() < 1e-6, "{stats:?}");
        assert!((stats.rmse - 0.2).abs() < 1e-6, "{stats:?}");
    }

    #[test]
    fn non_finite_pixels_are_counted_not_averaged() {
        let mut a = flat(Vec3::ONE);
        a.pixels[1] = Vec3::new(f32::NAN, 0.0, 0.0);
        let stats = compare(&a, &flat(Vec3::ONE)).unwrap();
        assert_eq!(stats.non_finite_pixels, 1);
        assert_eq!(stats.nrmse, 0.0);
    }

    #[test]
    fn light_where_the_reference_is_black_is_measured() {
        let mut r = flat(Vec3::splat(2.0));
        r.pixels[0] = Vec3::ZERO;
        let mut a = r.clone();
        a.pixels[0] = Vec3::splat(0.5);
        let stats = compare(&a, &r).unwrap();
        assert_eq!(stats.dark_pixels, 1);
        let reference_rms = (3.0f64 * 4.0 / 4.0).sqrt();
        assert!((stats.dark_leak - 0.5 / reference_rms).abs() < 1e-9, "{stats:?}");
    }

    #[test]
    fn sizes_must_match() {
        let small = Image::new(1, 1);
        assert!(compare(&small, &flat(Vec3::ONE)).is_err());
    }

    #[test]
    fn false_colour_marks_large_error_red_and_nan_magenta() {
        let mut a = flat(Vec3::splat(100.0));
        a.pixels[0] = Vec3::ONE;
        a.pixels[3] = Vec3::splat(f32::INFINITY);
        let rgb = false_colour(&a, &flat(Vec3::ONE), 0.5).unwrap();
        assert_eq!(&rgb[0..3], &[0, 0, 0]);
        assert_eq!(&rgb[3..6], &[255, 0, 0]);
        assert_eq!(&rgb[9..12], &[255, 0, 255]);
    }
}
