//! The perceptual metric: LDR FLIP (Andersson et al. 2020), NVIDIA's implementation through
//! the nv-flip crate, on the images as relume's PNGs show them.

use relume_bake::image::{tonemap_to_srgb8, Image};

/// Mean FLIP error in [0, 1] of `image` against `reference`, both tonemapped to sRGB8 at
/// `exposure`, at FLIP's default 67 pixels per degree.
pub(crate) fn mean_flip(image: &Image, reference: &Image, exposure: f32) -> f64 {
    let srgb = |image: &Image| -> Vec<u8> { image.pixels.iter().flat_map(|p| tonemap_to_srgb8(*p, exposure)).collect() };
    let test = nv_flip::FlipImageRgb8::with_data(image.width, image.height, &srgb(image));
    let reference = nv_flip::FlipImageRgb8::with_data(reference.width, reference.height, &srgb(reference));
    let error = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    nv_flip::FlipPool::from_image(&error).mean() as f64
}

/// The exposure that puts the reference's mean at 0.18 (middle grey), as the tests' pictures do.
pub(crate) fn exposure_for(reference: &Image) -> f32 {
    let mean = reference.pixels.iter().map(|p| p.element_sum() / 3.0).sum::<f32>() / reference.pixels.len().max(1) as f32;
    if mean > 0.0 && mean.is_finite() {
        0.18 / mean
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn flip_is_zero_for_equal_images_and_grows_with_the_difference() {
        let mut reference = Image::new(32, 32);
        for (i, p) in reference.pixels.iter_mut().enumerate() {
            *p = Vec3::splat((i % 32) as f32 / 32.0);
        }
        let exposure = exposure_for(&reference);
        let shifted = |by: f32| Image { pixels: reference.pixels.iter().map(|p| *p * by).collect(), ..reference.clone() };
        assert!(mean_flip(&reference, &reference, exposure) < 1e-6);
        let (small, large) = (mean_flip(&shifted(1.1), &reference, exposure), mean_flip(&shifted(2.0), &reference, exposure));
        assert!(small > 0.0 && large > small && large <= 1.0, "{small} {large}");
    }
}
