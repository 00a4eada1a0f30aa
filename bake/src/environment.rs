//! A distant environment light: an HDR lat-long image of the radiance arriving from every
//! direction, resampled into a working cube of 6 x n x n texels, piecewise constant per texel.
//! The working cube is what Michael & Chrysanthou (003) §4 sum over ("all 6144 texels" of a
//! 6 x 32 x 32 cube), and the path tracer lights by the same cube, so the reference and the
//! method see one environment (docs/FORMATS.md "Environment").
//!
//! Texel order is Vulkan's cube-map face table (faces +X, -X, +Y, -Y, +Z, -Z; s right, t
//! down), so a texel index here is the texel the GPU reads for the same direction.

use crate::image::{read_exr_layer, Image};
use crate::settings::{as_object, known_keys, number};
use glam::{Mat3, Vec2, Vec3};
use serde_json::Value;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// Cube faces per side the scene may ask for: coarser has too few sources for a sun, finer
/// makes every FIV table sum over more texels than the paper's 6144 for no visible gain.
pub const CUBE_FACE_RANGE: std::ops::RangeInclusive<u32> = 8..=256;

/// The scene's `extras.relume.environment` block, as written.
#[derive(Clone, Debug, PartialEq)]
pub struct EnvironmentSettings {
    /// The lat-long EXR, relative to the glTF file.
    pub image: PathBuf,
    /// The EXR layer to read; the first when None.
    pub layer: Option<String>,
    /// Scales every texel's radiance.
    pub intensity: f32,
    /// Turns the environment about +Y (counter-clockwise seen from above).
    pub rotation_y_degrees: f32,
    /// Texels along a side of each face of the working cube.
    pub cube_face: u32,
}

const KEY: &str = "extras.relume.environment";

impl EnvironmentSettings {
    pub fn from_json(value: &Value) -> Result<Self, String> {
        let block = as_object(value, KEY)?;
        known_keys(block, KEY, &["image", "layer", "intensity", "rotation_y_degrees", "cube_face"])?;
        let image = match block.get("image").and_then(Value::as_str) {
            Some(path) if !path.is_empty() => PathBuf::from(path),
            _ => return Err(format!("{KEY}.image must name the lat-long EXR file (a path relative to the glTF file)")),
        };
        let layer = match block.get("layer") {
            None | Some(Value::Null) => None,
            Some(Value::String(name)) => Some(name.clone()),
            Some(_) => return Err(format!("{KEY}.layer must be a layer name or null (the first layer)")),
        };
        let read = |key: &str, default: f32| block.get(key).map_or(Ok(default), |v| number(v, &format!("{KEY}.{key}")));
        let cube_face = match block.get("cube_face") {
            None => 32,
            Some(v) => v.as_u64().filter(|n| *n <= 256 && CUBE_FACE_RANGE.contains(&(*n as u32))).ok_or_else(|| {
                format!("{KEY}.cube_face must be a whole number in {}..={}", CUBE_FACE_RANGE.start(), CUBE_FACE_RANGE.end())
            })? as u32,
        };
        let settings = EnvironmentSettings {
            image,
            layer,
            intensity: read("intensity", 1.0)?,
            rotation_y_degrees: read("rotation_y_degrees", 0.0)?,
            cube_face,
        };
        if !(settings.intensity.is_finite() && (0.0..=crate::scene::MAX_LIGHT).contains(&settings.intensity)) {
            return Err(format!("{KEY}.intensity must be in 0..=1e9"));
        }
        if !settings.rotation_y_degrees.is_finite() {
            return Err(format!("{KEY}.rotation_y_degrees must be finite"));
        }
        Ok(settings)
    }
}

/// The working cube: radiance, direction and solid angle per texel, and the distribution
/// the path tracer samples texels from.
#[derive(Clone, Debug)]
pub struct Environment {
    /// The image it was made from (named in errors).
    pub source: PathBuf,
    /// Texels along a side of a face.
    pub face: u32,
    /// Radiance per texel, index (face * n + t) * n + s.
    pub radiance: Vec<Vec3>,
    /// Unit direction through each texel's centre.
    pub direction: Vec<Vec3>,
    /// Exact solid angle of each texel (they sum to 4 pi).
    pub solid_angle: Vec<f32>,
    /// Cumulative selection probability, proportional to luminance times solid angle; empty
    /// when the environment is black.
    cdf: Vec<f64>,
    /// Selection probability per texel (the differences of `cdf`).
    select: Vec<f32>,
    /// Texels of the image a hair below zero (within [`NEGATIVE_TOLERANCE`]), read as 0.
    pub clamped_texels: usize,
}

/// How far below zero a texel may be, relative to the image's mean radiance, and still be
/// read (as 0) rather than refused: lossy compression's ringing, not negative light (every
/// probe of Debian's blender-data loads within it).
pub const NEGATIVE_TOLERANCE: f64 = 0.02;

/// The direction through point (a, b) in [-1, 1]^2 of cube face `face` (not normalised):
/// the inverse of Vulkan's face table (sc, tc, ma).
pub fn face_point(face: usize, a: f32, b: f32) -> Vec3 {
    match face {
        0 => Vec3::new(1.0, -b, -a),
        1 => Vec3::new(-1.0, -b, a),
        2 => Vec3::new(a, 1.0, b),
        3 => Vec3::new(a, -1.0, -b),
        4 => Vec3::new(a, -b, 1.0),
        _ => Vec3::new(-a, -b, -1.0),
    }
}

/// The face a direction leaves through and its (a, b) in [-1, 1]^2 on it (Vulkan's table;
/// ties go to x, then y).
pub fn cube_coordinates(d: Vec3) -> (usize, f32, f32) {
    let m = d.abs();
    let (face, sc, tc, ma) = if m.x >= m.y && m.x >= m.z {
        if d.x >= 0.0 {
            (0, -d.z, -d.y, m.x)
        } else {
            (1, d.z, -d.y, m.x)
        }
    } else if m.y >= m.z {
        if d.y >= 0.0 {
            (2, d.x, d.z, m.y)
        } else {
            (3, d.x, -d.z, m.y)
        }
    } else if d.z >= 0.0 {
        (4, d.x, -d.y, m.z)
    } else {
        (5, -d.x, -d.y, m.z)
    };
    (face, sc / ma, tc / ma)
}

/// Solid angle of the rectangle [x0, x1] x [y0, y1] on a cube face at unit distance.
pub fn face_rectangle_solid_angle(x0: f64, y0: f64, x1: f64, y1: f64) -> f64 {
    let corner = |x: f64, y: f64| (x * y).atan2((x * x + y * y + 1.0).sqrt());
    corner(x1, y1) - corner(x0, y1) - corner(x1, y0) + corner(x0, y0)
}

impl Environment {
    /// Reads the environment a scene at `scene_file` declares, or says what is wrong with it
    /// (the message names the file and the key; the caller adds the scene).
    pub fn load(settings: &EnvironmentSettings, scene_file: &Path) -> Result<Environment, EnvironmentError> {
        let path = scene_file.parent().unwrap_or(Path::new("")).join(&settings.image);
        if !path.is_file() {
            return Err(EnvironmentError::NotFound(path));
        }
        let image = read_exr_layer(&path, settings.layer.as_deref()).map_err(|e| EnvironmentError::Unreadable(e.to_string()))?;
        Self::from_lat_long(&image, &path, settings)
    }

    /// Resamples a lat-long image (width = 2 x height, u = 0.5 + atan2(x, -z) / 2 pi,
    /// v = acos(y) / pi) into the working cube.
    pub fn from_lat_long(image: &Image, source: &Path, settings: &EnvironmentSettings) -> Result<Environment, EnvironmentError> {
        let bad = |problem: String| EnvironmentError::Invalid { path: source.to_path_buf(), problem };
        if image.width != 2 * image.height || image.height == 0 {
            return Err(bad(format!("is {}x{}, not a lat-long image (width must be twice the height)", image.width, image.height)));
        }
        // Lossily compressed probes ring a little below zero next to bright texels (down to
        // -0.0018 in Blender's studio lights); those read as 0 and are counted, anything more
        // negative is refused.
        let finite_mean =
            image.pixels.iter().filter(|p| p.is_finite()).map(|p| p.max_element().max(0.0) as f64).sum::<f64>() / image.pixels.len() as f64;
        let tolerance = -(NEGATIVE_TOLERANCE * finite_mean) as f32;
        let too_bright = |p: &Vec3| p.max_element() * settings.intensity > crate::scene::MAX_LIGHT;
        if let Some(i) = image.pixels.iter().position(|p| !p.is_finite() || p.min_element() < tolerance || too_bright(p)) {
            let (x, y) = (i as u32 % image.width, i as u32 / image.width);
            let problem =
                format!("texel ({x}, {y}) is {} (radiance times the intensity must be finite, >= 0 and at most 1e9)", image.pixels[i]);
            return Err(bad(problem));
        }
        let clamped_texels = image.pixels.iter().filter(|p| p.min_element() < 0.0).count();
        let n = settings.cube_face;
        let turn = Mat3::from_rotation_y(-settings.rotation_y_degrees.to_radians());
        let lookup = |d: Vec3| lat_long_texel(image, turn * d).max(Vec3::ZERO) * settings.intensity;
        // Enough sub-samples per texel to visit every lat-long texel it covers (8 x 8 at least).
        let sub = (image.width / (4 * n)).max(8);
        let texels = 6 * (n * n) as usize;
        let (mut radiance, mut direction, mut solid_angle) =
            (Vec::with_capacity(texels), Vec::with_capacity(texels), Vec::with_capacity(texels));
        for texel in 0..texels {
            let (face, s, t) = (texel / (n * n) as usize, texel as u32 % n, (texel as u32 / n) % n);
            let edge = |i: u32| 2.0 * i as f64 / n as f64 - 1.0;
            solid_angle.push(face_rectangle_solid_angle(edge(s), edge(t), edge(s + 1), edge(t + 1)) as f32);
            let centre = |i: u32, f: f32| (2.0 * (i as f32 + f) / n as f32) - 1.0;
            direction.push(face_point(face, centre(s, 0.5), centre(t, 0.5)).normalize());
            // Area-weighted: each sub-sample counts with its solid angle, dA / (1 + a^2 + b^2)^1.5.
            let (mut sum, mut weights) = (Vec3::ZERO, 0.0f32);
            for j in 0..sub {
                for i in 0..sub {
                    let (a, b) = (centre(s, (i as f32 + 0.5) / sub as f32), centre(t, (j as f32 + 0.5) / sub as f32));
                    let weight = (1.0 + a * a + b * b).powf(-1.5);
                    sum += lookup(face_point(face, a, b).normalize()) * weight;
                    weights += weight;
                }
            }
            radiance.push(sum / weights);
        }
        Ok(Environment { clamped_texels, ..Environment::new(source.to_path_buf(), n, radiance, direction, solid_angle) })
    }

    fn new(source: PathBuf, face: u32, radiance: Vec<Vec3>, direction: Vec<Vec3>, solid_angle: Vec<f32>) -> Environment {
        let power: Vec<f64> = radiance.iter().zip(&solid_angle).map(|(l, w)| luminance(*l) as f64 * *w as f64).collect();
        let total: f64 = power.iter().sum();
        let (mut cdf, mut select) = (Vec::new(), vec![0.0f32; power.len()]);
        if total > 0.0 {
            let mut running = 0.0;
            cdf = power
                .iter()
                .map(|p| {
                    running += p / total;
                    running
                })
                .collect();
            *cdf.last_mut().expect("a cube has texels") = 1.0;
            for (i, s) in select.iter_mut().enumerate() {
                *s = (cdf[i] - if i == 0 { 0.0 } else { cdf[i - 1] }) as f32;
            }
        }
        Environment { source, face, radiance, direction, solid_angle, cdf, select, clamped_texels: 0 }
    }

    /// The radiance's spherical-harmonic coefficients of bands l <= 2 (`crate::sh`), summed
    /// over the working cube's texels by their solid angles: with `sh::irradiance`, the
    /// unoccluded irradiance the environment gives a surface of any normal (Ramamoorthi &
    /// Hanrahan 2001), the ambient light of the ambient methods on a scene lit by one. Exact
    /// for radiance of bands l <= 2; a sun rings (docs/BENCHMARKS.md measures how much).
    pub fn radiance_sh(&self) -> [Vec3; crate::sh::IRRADIANCE_COEFFICIENTS] {
        let mut sums = [glam::DVec3::ZERO; crate::sh::IRRADIANCE_COEFFICIENTS];
        for ((l, d), w) in self.radiance.iter().zip(&self.direction).zip(&self.solid_angle) {
            let y = crate::sh::eval(*d);
            for (sum, y) in sums.iter_mut().zip(y) {
                *sum += l.as_dvec3() * (y as f64 * *w as f64);
            }
        }
        sums.map(|s| s.as_vec3())
    }

    /// Whether any texel is lit (a black environment lights nothing and is never sampled).
    pub fn is_lit(&self) -> bool {
        !self.cdf.is_empty()
    }

    /// The texel a direction falls in and its (a, b) on the face.
    pub fn texel(&self, d: Vec3) -> (usize, f32, f32) {
        let (face, a, b) = cube_coordinates(d);
        let n = self.face as f32;
        let index = |x: f32| (((x + 1.0) * 0.5 * n) as u32).min(self.face - 1) as usize;
        ((face * self.face as usize + index(b)) * self.face as usize + index(a), a, b)
    }

    /// Radiance arriving from direction `d` (piecewise constant per texel).
    pub fn radiance_towards(&self, d: Vec3) -> Vec3 {
        self.radiance[self.texel(d).0]
    }

    /// Solid-angle density with which [`Environment::sample`] picks direction `d`.
    pub fn pdf(&self, d: Vec3) -> f32 {
        let (texel, a, b) = self.texel(d);
        self.texel_pdf(texel, a, b)
    }

    /// A texel is picked with its selection probability, then a point uniform on its square
    /// of the face: pdf = p_t (1 + a^2 + b^2)^1.5 / (2 / n)^2 (spec fiv.md C3).
    fn texel_pdf(&self, texel: usize, a: f32, b: f32) -> f32 {
        let side = 2.0 / self.face as f32;
        self.select[texel] * (1.0 + a * a + b * b).powf(1.5) / (side * side)
    }

    /// A direction drawn in proportion to luminance times solid angle, with its radiance and
    /// solid-angle pdf; None for a black environment. `pick` chooses the texel, `u` the point in it.
    pub fn sample(&self, pick: f64, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if self.cdf.is_empty() {
            return None;
        }
        let texel = self.cdf.partition_point(|&c| c <= pick).min(self.cdf.len() - 1);
        let n = self.face as usize;
        let (face, t, s) = (texel / (n * n), (texel / n) % n, texel % n);
        let a = 2.0 * (s as f32 + u.x) / n as f32 - 1.0;
        let b = 2.0 * (t as f32 + u.y) / n as f32 - 1.0;
        let pdf = self.texel_pdf(texel, a, b);
        (pdf > 0.0).then(|| (face_point(face, a, b).normalize(), self.radiance[texel], pdf))
    }
}

/// The unit direction at lat-long coordinates (u, v) in [0, 1]^2: the inverse of the mapping
/// [`Environment::from_lat_long`] reads by.
pub fn lat_long_direction(u: f32, v: f32) -> Vec3 {
    let (theta, phi) = (v * std::f32::consts::PI, (u - 0.5) * std::f32::consts::TAU);
    Vec3::new(theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos())
}

/// A lat-long image of `width` x `width / 2` texels, each the radiance `f` gives for the
/// direction through its centre.
pub fn lat_long_image(width: u32, f: impl Fn(Vec3) -> Vec3) -> Image {
    let mut image = Image::new(width, width / 2);
    for y in 0..image.height {
        for x in 0..width {
            let (u, v) = ((x as f32 + 0.5) / width as f32, (y as f32 + 0.5) / image.height as f32);
            image.set(x, y, f(lat_long_direction(u, v)));
        }
    }
    image
}

/// The lat-long texel a direction falls in (nearest: the image is piecewise constant too).
fn lat_long_texel(image: &Image, d: Vec3) -> Vec3 {
    let u = 0.5 + d.x.atan2(-d.z) as f64 / (2.0 * PI);
    let v = (d.y.clamp(-1.0, 1.0) as f64).acos() / PI;
    let x = ((u * image.width as f64).floor() as i64).rem_euclid(image.width as i64) as u32;
    let y = ((v * image.height as f64) as u32).min(image.height - 1);
    image.get(x, y)
}

/// Rec. 709 luminance, the weight of a texel's colour in its selection probability.
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Why an environment could not be used.
#[derive(Clone, Debug)]
pub enum EnvironmentError {
    NotFound(PathBuf),
    Unreadable(String),
    Invalid { path: PathBuf, problem: String },
}

impl std::fmt::Display for EnvironmentError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EnvironmentError::NotFound(path) => write!(f, "{}: file not found", path.display()),
            EnvironmentError::Unreadable(message) => write!(f, "{message}"),
            EnvironmentError::Invalid { path, problem } => write!(f, "{}: {problem}", path.display()),
        }
    }
}
