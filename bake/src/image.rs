//! Linear RGB float images, and their files: multi-layer EXR (exact) and tonemapped sRGB PNG.

use crate::outputs::{OutputError, Outputs};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// A linear-radiance RGB image, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image { width, height, pixels: vec![Vec3::ZERO; (width * height) as usize] }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width + x) as usize]
    }

    pub fn set(&mut self, x: u32, y: u32, value: Vec3) {
        self.pixels[(y * self.width + x) as usize] = value;
    }
}

/// Why an image file could not be read or written, naming the file.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: {message}")]
    Io { path: PathBuf, message: String },
    #[error("{path}: layer \"{layer}\" not found (the file has: {available}); name one of those")]
    MissingLayer { path: PathBuf, layer: String, available: String },
    #[error("{a} is {aw}x{ah} but {b} is {bw}x{bh}; compare images of the same size")]
    SizeMismatch { a: String, aw: u32, ah: u32, b: String, bw: u32, bh: u32 },
}

fn io_error(path: &Path, message: impl std::fmt::Display) -> ImageError {
    ImageError::Io { path: path.to_path_buf(), message: message.to_string() }
}

/// Pixels, row by row, `width` to a row: an image's or a slice's, written without a copy.
#[derive(Clone, Copy)]
struct LayerPixels<'a> {
    width: usize,
    pixels: &'a [Vec3],
}

impl exr::prelude::GetPixel for LayerPixels<'_> {
    type Pixel = (f32, f32, f32);
    fn get_pixel(&self, position: exr::prelude::Vec2<usize>) -> Self::Pixel {
        let p = self.pixels[position.y() * self.width + position.x()];
        (p.x, p.y, p.z)
    }
}

impl From<OutputError> for ImageError {
    fn from(e: OutputError) -> ImageError {
        ImageError::Io { path: e.path, message: e.message }
    }
}

/// Stages named RGB float layers (all the same size) as one EXR file, losslessly.
pub fn write_exr_layers(outputs: &mut Outputs, path: &Path, layers: &[(&str, &Image)]) -> Result<(), ImageError> {
    let Some((_, first)) = layers.first() else { return Err(io_error(path, "no layers to write")) };
    let views: Vec<_> =
        layers.iter().map(|(name, image)| (*name, LayerPixels { width: image.width as usize, pixels: &image.pixels })).collect();
    let bytes = encode(&views, (first.width as usize, first.height as usize)).map_err(|e| io_error(path, e))?;
    Ok(outputs.bytes(path, &bytes)?)
}

/// The bytes of an EXR file of one named RGB float layer, `width` pixels wide, losslessly.
pub fn encode_exr_layer(name: &str, width: u32, pixels: &[Vec3]) -> Result<Vec<u8>, String> {
    if width == 0 || !pixels.len().is_multiple_of(width as usize) {
        return Err(format!("{} pixels do not fill rows of {width}", pixels.len()));
    }
    let width = width as usize;
    encode(&[(name, LayerPixels { width, pixels })], (width, pixels.len() / width))
}

fn encode(layers: &[(&str, LayerPixels)], size: (usize, usize)) -> Result<Vec<u8>, String> {
    use exr::prelude::*;
    let exr_layers: Vec<_> = layers
        .iter()
        .map(|(name, pixels)| Layer::new(size, LayerAttributes::named(*name), Encoding::SMALL_LOSSLESS, SpecificChannels::rgb(*pixels)))
        .collect();
    let attributes = ImageAttributes::new(IntegerBounds::from_dimensions(size));
    let exr_image = exr::image::Image::from_layers(attributes, Layers::from_vec(exr_layers));
    let mut bytes = std::io::Cursor::new(Vec::new());
    exr_image.write().to_buffered(&mut bytes).map_err(|e| e.to_string())?;
    Ok(bytes.into_inner())
}

/// Reads every RGB layer of an EXR file, by name (an unnamed layer is called "rgb"),
/// streaming it from the file.
pub fn read_exr_layers(path: &Path) -> Result<Vec<(String, Image)>, ImageError> {
    crate::inputs::admit(path).map_err(|e| io_error(path, e))?;
    let open = || std::fs::File::open(path).map(std::io::BufReader::new).map_err(|e| io_error(path, format!("cannot read ({e})")));
    check_exr_size(open()?).map_err(|e| io_error(path, e))?;
    decode_exr_layers(open()?).map_err(|e| io_error(path, e))
}

/// Every RGB layer of the EXR file `reader` reads, by name (an unnamed layer is called "rgb").
fn decode_exr_layers(reader: impl std::io::Read + std::io::Seek + Send) -> Result<Vec<(String, Image)>, String> {
    use exr::prelude::*;
    type RgbImage = crate::image::Image;
    let file = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |resolution, _| RgbImage::new(resolution.width() as u32, resolution.height() as u32),
            |image: &mut RgbImage, position, (r, g, b): (f32, f32, f32)| {
                image.set(position.x() as u32, position.y() as u32, Vec3::new(r, g, b))
            },
        )
        .all_layers()
        .all_attributes()
        .from_buffered(reader)
        .map_err(|e| format!("not a readable RGB EXR file ({e})"))?;
    Ok(file
        .layer_data
        .into_iter()
        .map(|layer| {
            let name = layer.attributes.layer_name.map(|n| n.to_string());
            (name.unwrap_or_else(|| "rgb".into()), layer.channel_data.pixels)
        })
        .collect())
}

/// The largest image relume reads: 16384 x 16384, the renderer's own limit.
const MAX_PIXELS: usize = 16384 * 16384;

/// Refuses a file whose header claims a size no relume image has, before anything is
/// allocated for it (a corrupt header must not become a huge allocation or an overflow).
fn check_exr_size(reader: impl std::io::Read + std::io::Seek) -> Result<(), String> {
    let meta = exr::meta::MetaData::read_from_buffered(reader, false).map_err(|e| format!("not a readable RGB EXR file ({e})"))?;
    for header in meta.headers.iter() {
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        if w.checked_mul(h).is_none_or(|pixels| pixels > MAX_PIXELS) {
            return Err(format!(
                "a layer claims {w}x{h} pixels, more than relume reads (16384x16384); the file is corrupt or not one of relume's"
            ));
        }
    }
    Ok(())
}

fn pick_layer(layers: Vec<(String, Image)>, layer: Option<&str>) -> Result<Image, (String, String)> {
    let available = layers.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(", ");
    let found = match layer {
        Some(wanted) => layers.into_iter().find(|(n, _)| n == wanted),
        None => layers.into_iter().next(),
    };
    found.map(|(_, image)| image).ok_or_else(|| (layer.unwrap_or("(first)").to_string(), available))
}

/// Reads one layer of an EXR file: the named one, or the first when `layer` is None.
pub fn read_exr_layer(path: &Path, layer: Option<&str>) -> Result<Image, ImageError> {
    pick_layer(read_exr_layers(path)?, layer).map_err(|(layer, available)| ImageError::MissingLayer {
        path: path.to_path_buf(),
        layer,
        available,
    })
}

/// The display transform of every PNG relume writes, on the GPU (`tonemap.comp`) and here:
/// exposure, the ACES filmic fit of Narkowicz (2015) per channel, then the sRGB curve.
pub fn tonemap_to_srgb8(linear: Vec3, exposure: f32) -> [u8; 3] {
    let aces = |x: f32| {
        let x = (x * exposure).max(0.0);
        ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
    };
    let encode = |c: f32| (linear_to_srgb(aces(c)) * 255.0 + 0.5) as u8;
    [encode(linear.x), encode(linear.y), encode(linear.z)]
}

pub fn linear_to_srgb(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.040_45 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Stages 8-bit RGB pixels (row-major, top row first) as a PNG file.
pub fn write_png_rgb8(outputs: &mut Outputs, path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), ImageError> {
    Ok(outputs.file(path, |file| {
        let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer.write_image_data(rgb).map_err(|e| e.to_string())?;
        writer.finish().map_err(|e| e.to_string())
    })?)
}

/// Tonemaps a linear image (see [`tonemap_to_srgb8`]) and stages it as PNG.
pub fn write_png_tonemapped(outputs: &mut Outputs, path: &Path, image: &Image, exposure: f32) -> Result<(), ImageError> {
    let rgb: Vec<u8> = image.pixels.iter().flat_map(|p| tonemap_to_srgb8(*p, exposure)).collect();
    write_png_rgb8(outputs, path, image.width, image.height, &rgb)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_path(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("relume-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        dir.join(name)
    }

    fn gradient(width: u32, height: u32, scale: f32) -> Image {
        let mut image = Image::new(width, height);
        for y in 0..height {
            for x in 0..width {
                image.set(x, y, Vec3::new(x as f32, y as f32, 1.0 + x as f32 * y as f32) * scale);
            }
        }
        image
    }

    #[test]
    fn exr_layers_round_trip_exactly_and_deterministically() {
        let (a, b) = (gradient(7, 5, 0.1), gradient(7, 5, 1e3));
        let path = temp_path("round-trip.exr");
        let write = || {
            let mut outputs = Outputs::new();
            write_exr_layers(&mut outputs, &path, &[("direct", &a), ("combined", &b)]).unwrap();
            outputs.commit().unwrap();
        };
        write();
        let first = std::fs::read(&path).unwrap();
        write();
        assert_eq!(first, std::fs::read(&path).unwrap(), "same image, same bytes");
        assert_eq!(read_exr_layer(&path, Some("combined")).unwrap(), b);
        assert_eq!(read_exr_layer(&path, None).unwrap(), a);
        let missing = read_exr_layer(&path, Some("indirect")).unwrap_err().to_string();
        assert!(missing.contains("direct, combined"), "{missing}");
    }

    #[test]
    fn a_file_that_is_not_exr_is_refused_by_name() {
        let path = temp_path("garbage.exr");
        std::fs::write(&path, b"not an image").unwrap();
        let error = read_exr_layers(&path).unwrap_err().to_string();
        assert!(error.contains("garbage.exr") && error.contains("EXR"), "{error}");
    }

    #[test]
    fn the_display_transform_is_monotonic_and_srgb_encoded() {
        assert_eq!(tonemap_to_srgb8(Vec3::ZERO, 1.0), [0, 0, 0]);
        assert_eq!(tonemap_to_srgb8(Vec3::splat(1e6), 1.0), [255, 255, 255]);
        let levels: Vec<u8> = (0..50).map(|i| tonemap_to_srgb8(Vec3::splat(i as f32 * 0.1), 1.0)[0]).collect();
        assert!(levels.windows(2).all(|w| w[0] <= w[1]), "{levels:?}");
        for c in [0.0, 0.001, 0.2, 0.5, 1.0] {
            assert!((srgb_to_linear(linear_to_srgb(c)) - c).abs() < 1e-6);
        }
    }
}
