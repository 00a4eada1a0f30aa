//! Materials (base colour and its PNG texture, emission) and their textures, decoded on first
//! use so that unused materials and images are neither decoded nor refused.

use super::files::read_uri;
use super::{default_material, quoted_name, Ctx, ErrorKind, Loader, SceneError};
use crate::image::srgb_to_linear;
use crate::scene::{Material, Phong, Texture};
use glam::{Vec3, Vec4};
use std::borrow::Cow;

/// The largest Phong exponent: the lobe's normalisation (n + 2) / 2 pi times cos^n is then
/// still finite (at 1e30 it was infinity times zero), and a lobe of 1e6 is a mirror already.
const MAX_EXPONENT: f32 = 1e6;

/// The material's glossy lobe, `extras.relume.phong {specular, exponent}` (specular one number
/// or rgb), refused unless rho_d + rho_s <= 1 per channel (rho_d the base colour factor: a
/// texture, at most 1, only lowers it) and the exponent is in 0..=1e6.
fn phong(ctx: Ctx, item: &str, extras: &gltf::json::Extras, base: Vec3) -> Result<Option<Phong>, SceneError> {
    let Some(raw) = extras else { return Ok(None) };
    let value: serde_json::Value = serde_json::from_str(raw.get()).unwrap_or_default();
    let block = &value["relume"]["phong"];
    if block.is_null() {
        return Ok(None);
    }
    let item = format!("{item} extras.relume.phong");
    let fix = "give {\"specular\": rho_s (a number or [r, g, b]), \"exponent\": e in 0..=1e6} with base colour + specular <= 1";
    let number = |v: &serde_json::Value| v.as_f64().map(|v| v as f32).filter(|v| v.is_finite());
    let specular = match &block["specular"] {
        serde_json::Value::Array(a) if a.len() == 3 => a.iter().map(number).collect::<Option<Vec<f32>>>().map(|v| Vec3::from_slice(&v)),
        v => number(v).map(Vec3::splat),
    };
    let (Some(specular), Some(exponent)) = (specular, number(&block["exponent"])) else {
        return Err(ctx.fail(ErrorKind::Invalid, item, "needs a finite specular and exponent", fix));
    };
    if specular.min_element() < 0.0 || !(0.0..=MAX_EXPONENT).contains(&exponent) || (base + specular).max_element() > 1.0 {
        let problem = format!(
            "specular {specular} with base colour {base} and exponent {exponent} would make light, is negative or is an exponent past 1e6"
        );
        return Err(ctx.fail(ErrorKind::Invalid, item, problem, fix));
    }
    Ok(Some(Phong { specular, exponent }))
}

impl Loader<'_> {
    pub(super) fn material_for(&mut self, primitive: &gltf::Primitive, item: &str) -> Result<usize, SceneError> {
        let gm = primitive.material();
        let Some(index) = gm.index() else {
            return Ok(*self.default_material.get_or_insert_with(|| {
                self.scene.materials.push(default_material());
                self.scene.materials.len() - 1
            }));
        };
        if let Some(Some(m)) = self.material_map.get(index) {
            return Ok(*m);
        }
        let ctx = self.ctx;
        let mat_item = quoted_name("material", gm.name(), index);
        let pbr = gm.pbr_metallic_roughness();
        let base_color = Vec4::from(pbr.base_color_factor());
        let strength = gm.emissive_strength().unwrap_or(1.0);
        let emission = Vec3::from(gm.emissive_factor()) * strength;
        if !base_color.is_finite() || base_color.min_element() < 0.0 || !emission.is_finite() || emission.min_element() < 0.0 {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                mat_item,
                format!("baseColorFactor {base_color} or emission {emission} is negative or not finite"),
                "use finite, non-negative factors",
            ));
        }
        if emission.max_element() > crate::scene::MAX_LIGHT {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                mat_item,
                format!("emission {emission} (emissiveFactor times KHR_materials_emissive_strength) exceeds 1e9"),
                "give an emission of at most 1e9",
            ));
        }
        // The factor alone would make the texture's dark parts glow as its bright ones do.
        let emission = match gm.emissive_texture() {
            Some(_) if emission != Vec3::ZERO => {
                let message =
                    "emissiveTexture is not read, so the material's emission is left out (a scene it alone lit takes the default rig)";
                self.warnings.push(ctx.warning(&mat_item, message));
                Vec3::ZERO
            }
            _ => emission,
        };
        let base_color_texture = match pbr.base_color_texture() {
            None => None,
            Some(info) => {
                if info.tex_coord() != 0 {
                    return Err(ctx.fail(
                        ErrorKind::Unsupported,
                        format!("{item}: {mat_item}"),
                        format!("baseColorTexture uses TEXCOORD_{}", info.tex_coord()),
                        "relume samples base colour with TEXCOORD_0; set the texture's texCoord to 0",
                    ));
                }
                Some(self.texture_for(&info.texture().source(), &mat_item)?)
            }
        };
        let phong = phong(ctx, &mat_item, gm.extras(), base_color.truncate())?;
        let name = gm.name().map(str::to_string).unwrap_or_else(|| format!("material {index}"));
        self.scene.materials.push(Material { name, base_color, base_color_texture, emission, phong });
        let m = self.scene.materials.len() - 1;
        if let Some(slot) = self.material_map.get_mut(index) {
            *slot = Some(m);
        }
        Ok(m)
    }

    pub(super) fn texture_for(&mut self, image: &gltf::Image, mat_item: &str) -> Result<usize, SceneError> {
        if let Some(Some(t)) = self.image_map.get(image.index()) {
            return Ok(*t);
        }
        let ctx = self.ctx;
        let image_item = format!("{mat_item}: {}", quoted_name("image", image.name(), image.index()));
        let (bytes, name): (Cow<[u8]>, String) = match image.source() {
            gltf::image::Source::View { view, .. } => {
                let data: &[u8] = self.buffers.get(view.buffer().index()).map(|b| b.as_ref()).unwrap_or(&[]);
                let range = view.offset()..view.offset().saturating_add(view.length());
                let Some(bytes) = data.get(range.clone()) else {
                    return Err(ctx.fail(
                        ErrorKind::Buffer,
                        image_item,
                        format!("its bufferView {} (bytes {range:?}) reaches past its buffer ({} bytes)", view.index(), data.len()),
                        "fix the bufferView",
                    ));
                };
                (Cow::Borrowed(bytes), image.name().map(str::to_string).unwrap_or_else(|| format!("image {}", image.index())))
            }
            gltf::image::Source::Uri { uri, .. } => {
                let bytes = read_uri(ctx, &image_item, uri)?;
                let name = image.name().map(str::to_string).unwrap_or_else(|| {
                    if uri.starts_with("data:") {
                        format!("image {}", image.index())
                    } else {
                        uri.to_string()
                    }
                });
                (Cow::Owned(bytes), name)
            }
        };
        let texture = decode_png(ctx, &image_item, &bytes, name)?;
        self.scene.textures.push(texture);
        let t = self.scene.textures.len() - 1;
        if let Some(slot) = self.image_map.get_mut(image.index()) {
            *slot = Some(t);
        }
        Ok(t)
    }
}

/// Decodes a PNG base-colour image to linear RGBA (sRGB transfer undone on rgb; alpha is
/// linear already). Other formats are refused by their signature, whatever the mimeType says.
pub(super) fn decode_png(ctx: Ctx, item: &str, bytes: &[u8], name: String) -> Result<Texture, SceneError> {
    if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        return Err(ctx.fail(ErrorKind::Unsupported, item, "is a JPEG image", "convert the image to PNG"));
    }
    if !bytes.starts_with(&[0x89, b'P', b'N', b'G', 0x0D, 0x0A, 0x1A, 0x0A]) {
        return Err(ctx.fail(ErrorKind::Unsupported, item, "is not a PNG image", "convert the image to PNG"));
    }
    let bad = |e: png::DecodingError| ctx.fail(ErrorKind::Image, item, format!("cannot decode the PNG: {e}"), "re-save the image as PNG");
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    // Palette to RGB, tRNS to alpha, low bit depths to 8; 16-bit stays 16-bit.
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(bad)?;
    let (width, height) = (reader.info().width, reader.info().height);
    // Checked against the header before anything is allocated, so a small file that claims
    // a huge image is refused, not a failed allocation.
    if u64::from(width) * u64::from(height) > ctx.max_texture_pixels {
        return Err(ctx.fail(
            ErrorKind::Image,
            item,
            format!("its header says {width} x {height} pixels, more than the limit of {} pixels", ctx.max_texture_pixels),
            "downscale the image, or raise the limit with --max-texture-pixels",
        ));
    }
    let Some(size) = reader.output_buffer_size() else {
        return Err(ctx.fail(ErrorKind::Image, item, "the PNG is too large", "use a smaller image"));
    };
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(bad)?;
    let channels = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => {
            return Err(ctx.fail(ErrorKind::Image, item, "the PNG palette was not expanded", "re-save the image as RGB(A) PNG"))
        }
    };
    let bytes_per_sample = if info.bit_depth == png::BitDepth::Sixteen { 2 } else { 1 };
    let (width, height) = (info.width, info.height);
    let lut: Vec<f32> = (0..256).map(|v| srgb_to_linear(v as f32 / 255.0)).collect();
    let sample = |row: &[u8], i: usize| -> f32 {
        if bytes_per_sample == 2 {
            u16::from_be_bytes([row[2 * i], row[2 * i + 1]]) as f32 / 65535.0
        } else {
            row[i] as f32 / 255.0
        }
    };
    let mut texels = Vec::with_capacity(width as usize * height as usize);
    for y in 0..height as usize {
        let row_start = y * info.line_size;
        let Some(row) = buf.get(row_start..row_start + info.line_size) else {
            return Err(ctx.fail(ErrorKind::Image, item, "the decoded PNG is shorter than its size", "re-save the image"));
        };
        for x in 0..width as usize {
            let s = |c: usize| sample(row, x * channels + c);
            let to_linear = |v: f32| {
                if bytes_per_sample == 1 {
                    lut[(v * 255.0).round() as usize & 255]
                } else {
                    srgb_to_linear(v)
                }
            };
            let (rgb, a) = match channels {
                1 => (Vec3::splat(s(0)), 1.0),
                2 => (Vec3::splat(s(0)), s(1)),
                3 => (Vec3::new(s(0), s(1), s(2)), 1.0),
                _ => (Vec3::new(s(0), s(1), s(2)), s(3)),
            };
            texels.push(Vec4::new(to_linear(rgb.x), to_linear(rgb.y), to_linear(rgb.z), a));
        }
    }
    Ok(Texture { name, width, height, texels })
}
