//! glTF 2.0 in: `.gltf` (external `.bin` files or `data:` URIs) and `.glb`, flattened into a
//! [`Scene`] of world-space triangle meshes.
//!
//! Why not `gltf::import`: it stops at the first problem with a message that names neither
//! the item nor a fix, and it decodes every image (JPEG included) whether or not a material
//! uses it. Here the `gltf` crate only parses and validates the JSON; buffers, accessors and
//! images are read by this module with checked arithmetic, so that every way a file can be
//! wrong is refused with one line that names the file, the item and the fix
//! ([`SceneError`]), and no input can make the loader panic.
//!
//! What is read: the default scene's node tree (world matrices, normals by the
//! inverse-transpose, winding flipped under mirroring transforms); triangle-list primitives
//! with POSITION, NORMAL (computed when absent), TEXCOORD_0, TEXCOORD_1 and indices;
//! baseColorFactor, baseColorTexture (PNG), emissiveFactor × KHR_materials_emissive_strength;
//! KHR_lights_punctual lights; the first perspective camera. Everything else in the file
//! (metallic-roughness, normal maps, skins, morph targets, animations) is ignored: relume's
//! methods are Lambertian and static.

use crate::image::srgb_to_linear;
use crate::scene::{Camera, Light, LightKind, Material, Mesh, Scene, Texture};
use crate::settings::SceneSettings;
use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use std::borrow::Cow;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

/// A loaded scene and what the loader changed in it without refusing the file.
///
/// Warnings are returned rather than printed because the loader is a library: the CLI shows
/// them, a test can assert on them, an integrator can log them its own way.
#[derive(Clone, Debug)]
pub struct Loaded {
    pub scene: Scene,
    /// One line each, in the same `file: item: what; why` form as errors, e.g. the number
    /// of degenerate (zero-area) triangles dropped from a primitive.
    pub warnings: Vec<String>,
}

/// Which rule a file broke, for callers (and tests) that react to a kind of error;
/// the message is in [`SceneError`]'s other fields.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file (or a file it names) does not exist.
    NotFound,
    /// The file exists but could not be read.
    Io,
    /// Not parseable: JSON syntax, GLB container, or glTF schema validation.
    Parse,
    /// A buffer is missing, shorter than its byteLength, or a bufferView reaches past it.
    Buffer,
    /// An accessor reads past its bufferView, has the wrong type, or is sparse.
    Accessor,
    /// A NaN or infinite position, normal, texture coordinate or transform.
    NonFinite,
    /// An index refers past the vertex count.
    IndexOutOfRange,
    /// A primitive is not a triangle list (wrong mode, or an index count not a multiple of 3).
    NotTriangles,
    /// A glTF feature relume does not read (JPEG, sparse accessors, texCoord 1 for base colour).
    Unsupported,
    /// A value outside its valid range: light cones, camera planes, node hierarchy.
    Invalid,
    /// An image could not be decoded.
    Image,
    /// The scene has no punctual light and no emissive material.
    NoLight,
    /// The default scene has no triangles.
    Empty,
}

/// Why a scene file was refused. Its `Display` is one line:
/// `scenes/x.gltf: mesh "Floor" primitive 0: index 17 out of range (12 vertices); fix the indices accessor`
/// (`item` is left out when the problem concerns the whole file).
#[derive(Clone, Debug)]
pub struct SceneError {
    pub path: PathBuf,
    pub kind: ErrorKind,
    /// The glTF item at fault, e.g. `mesh "Floor" primitive 0`, `buffer 0 ("x.bin")`; may be empty.
    pub item: String,
    /// What is wrong.
    pub problem: String,
    /// What to do about it.
    pub fix: String,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // One line, whatever the wrapped messages (serde, io, png) contain.
        let line = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
        write!(f, "{}: ", self.path.display())?;
        if !self.item.is_empty() {
            write!(f, "{}: ", line(&self.item))?;
        }
        write!(f, "{}; {}", line(&self.problem), line(&self.fix))
    }
}

impl std::error::Error for SceneError {}

/// A camera given on the command line instead of the file's: eye, target, up and vertical
/// field of view. Constructed only through [`CameraOverride::new`] or the parser, which
/// check it, so that [`CameraOverride::camera`] cannot fail.
///
/// Syntax: `eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]`, spaces allowed around items;
/// `up` defaults to `0,1,0` (glTF's Y up) and `yfov` to 45 degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraOverride {
    eye: Vec3,
    target: Vec3,
    up: Vec3,
    yfov_degrees: f32,
}

/// Why a camera override was refused (one line, with the syntax as the fix).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("camera \"{input}\": {problem}; write it as eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]")]
pub struct CameraOverrideError {
    pub input: String,
    pub problem: String,
}

impl CameraOverride {
    pub const DEFAULT_YFOV_DEGREES: f32 = 45.0;

    pub fn new(eye: Vec3, target: Vec3, up: Vec3, yfov_degrees: f32) -> Result<Self, CameraOverrideError> {
        let fail = |problem: String| CameraOverrideError {
            input: format!(
                "eye={},{},{};target={},{},{};up={},{},{};yfov={}",
                eye.x, eye.y, eye.z, target.x, target.y, target.z, up.x, up.y, up.z, yfov_degrees
            ),
            problem,
        };
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(fail("eye, target and up must be finite numbers".into()));
        }
        let forward = target - eye;
        if forward.length() <= 1e-6 * eye.length().max(1.0) {
            return Err(fail("eye and target are the same point, so there is no view direction".into()));
        }
        if forward.normalize().cross(up.normalize_or_zero()).length() < 1e-4 {
            return Err(fail("up is zero or parallel to the view direction (target - eye)".into()));
        }
        if !(yfov_degrees > 0.0 && yfov_degrees < 180.0) {
            return Err(fail(format!("yfov {yfov_degrees} is not between 0 and 180 degrees")));
        }
        Ok(CameraOverride { eye, target, up, yfov_degrees })
    }

    /// Parses `eye=x,y,z;target=x,y,z[;up=x,y,z][;yfov=degrees]` (see the type's docs).
    pub fn parse(text: &str) -> Result<Self, CameraOverrideError> {
        text.parse()
    }

    pub fn eye(&self) -> Vec3 {
        self.eye
    }
    pub fn target(&self) -> Vec3 {
        self.target
    }
    pub fn up(&self) -> Vec3 {
        self.up
    }
    pub fn yfov_degrees(&self) -> f32 {
        self.yfov_degrees
    }

    /// The camera, with clip planes chosen from the scene bounds so that the whole scene
    /// lies between them (the CLI has no way to know good planes; the bounds do).
    pub fn camera(&self, scene_bounds: (Vec3, Vec3)) -> Camera {
        let world_from_camera = look_at(self.eye, self.target, self.up);
        let (znear, zfar) = clip_planes(self.eye, scene_bounds);
        Camera { world_from_camera, yfov: self.yfov_degrees.to_radians(), znear, zfar }
    }
}

impl FromStr for CameraOverride {
    type Err = CameraOverrideError;

    fn from_str(text: &str) -> Result<Self, Self::Err> {
        let fail = |problem: String| CameraOverrideError { input: text.to_string(), problem };
        let vec3 = |key: &str, value: &str| -> Result<Vec3, CameraOverrideError> {
            let parts: Vec<&str> = value.split(',').map(str::trim).collect();
            let numbers: Vec<f32> = parts.iter().filter_map(|p| p.parse().ok()).collect();
            if parts.len() != 3 || numbers.len() != 3 {
                return Err(fail(format!("{key} needs three numbers x,y,z, got \"{value}\"")));
            }
            Ok(Vec3::new(numbers[0], numbers[1], numbers[2]))
        };
        let (mut eye, mut target, mut up, mut yfov) = (None, None, None, None);
        for item in text.split(';').map(str::trim).filter(|s| !s.is_empty()) {
            let Some((key, value)) = item.split_once('=') else {
                return Err(fail(format!("\"{item}\" is not key=value")));
            };
            let (key, value) = (key.trim(), value.trim());
            let slot_taken = match key {
                "eye" => eye.replace(vec3(key, value)?).is_some(),
                "target" => target.replace(vec3(key, value)?).is_some(),
                "up" => up.replace(vec3(key, value)?).is_some(),
                "yfov" => {
                    let degrees: f32 = value.parse().map_err(|_| fail(format!("yfov needs a number of degrees, got \"{value}\"")))?;
                    yfov.replace(degrees).is_some()
                }
                _ => return Err(fail(format!("unknown key \"{key}\" (keys: eye, target, up, yfov)"))),
            };
            if slot_taken {
                return Err(fail(format!("{key} is given twice")));
            }
        }
        let eye = eye.ok_or_else(|| fail("eye is missing".into()))?;
        let target = target.ok_or_else(|| fail("target is missing".into()))?;
        CameraOverride::new(eye, target, up.unwrap_or(Vec3::Y), yfov.unwrap_or(Self::DEFAULT_YFOV_DEGREES)).map_err(|e| fail(e.problem))
    }
}

/// Loads a scene with the camera the file gives (or a default one framing the scene).
pub fn load(path: &Path) -> Result<Loaded, SceneError> {
    load_with_camera(path, None)
}

/// Loads a scene; `camera`, when given, replaces the file's camera.
pub fn load_with_camera(path: &Path, camera: Option<&CameraOverride>) -> Result<Loaded, SceneError> {
    let bytes = std::fs::read(path).map_err(|e| {
        let err = Ctx { path };
        if e.kind() == std::io::ErrorKind::NotFound {
            err.fail(
                ErrorKind::NotFound,
                "",
                "file not found",
                "check the path (`relume scenes --out scenes/` writes the generated scenes)",
            )
        } else {
            err.fail(ErrorKind::Io, "", format!("cannot read the file: {e}"), "check its permissions")
        }
    })?;
    Loader::new(path, &bytes)?.load(camera)
}

// ---------------------------------------------------------------------------------------------

/// Builds errors and warnings that name the file.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    path: &'a Path,
}

impl Ctx<'_> {
    fn fail(&self, kind: ErrorKind, item: impl Into<String>, problem: impl Into<String>, fix: impl Into<String>) -> SceneError {
        SceneError { path: self.path.to_path_buf(), kind, item: item.into(), problem: problem.into(), fix: fix.into() }
    }

    fn warning(&self, item: &str, message: &str) -> String {
        format!("{}: {item}: {message}", self.path.display())
    }
}

struct Loader<'a> {
    ctx: Ctx<'a>,
    document: gltf::Document,
    buffers: Vec<Cow<'a, [u8]>>,
    scene: Scene,
    warnings: Vec<String>,
    /// glTF material index -> index in `scene.materials`, filled on first use so that
    /// unused materials (and their images) are neither decoded nor refused.
    material_map: Vec<Option<usize>>,
    default_material: Option<usize>,
    /// glTF image index -> index in `scene.textures`.
    image_map: Vec<Option<usize>>,
}

/// The glTF default material: white base colour, no emission.
fn default_material() -> Material {
    Material { name: "default".into(), base_color: Vec4::ONE, base_color_texture: None, emission: Vec3::ZERO }
}

fn quoted_name(kind: &str, name: Option<&str>, index: usize) -> String {
    match name {
        Some(n) if !n.is_empty() => format!("{kind} \"{n}\""),
        _ => format!("{kind} {index}"),
    }
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// Splits a .glb into its JSON chunk and optional BIN chunk. Done here rather than by the
/// gltf crate because its GLB reader subtracts from the header length unchecked (a
/// malformed header would panic in debug builds) and its errors do not say which part is bad.
fn split_glb<'b>(ctx: Ctx, bytes: &'b [u8]) -> Result<(&'b [u8], Option<&'b [u8]>), SceneError> {
    let bad =
        |problem: String| ctx.fail(ErrorKind::Parse, "GLB container", problem, "re-export the .glb; the file is damaged or truncated");
    let version = u32_at(bytes, 4).ok_or_else(|| bad(format!("the header needs 12 bytes, the file has {}", bytes.len())))?;
    let length = u32_at(bytes, 8).ok_or_else(|| bad(format!("the header needs 12 bytes, the file has {}", bytes.len())))? as usize;
    if version != 2 {
        return Err(ctx.fail(
            ErrorKind::Unsupported,
            "GLB container",
            format!("version {version}"),
            "relume reads glTF 2.0; convert the file",
        ));
    }
    if length > bytes.len() || length < 12 {
        return Err(bad(format!("the header says {length} bytes, the file has {}", bytes.len())));
    }
    let bytes = &bytes[..length];
    // (chunk type, chunk data, offset of the next chunk)
    type Chunk<'c> = Option<(u32, &'c [u8], usize)>;
    let chunk = |at: usize, name: &str| -> Result<Chunk<'b>, SceneError> {
        if at >= bytes.len() {
            return Ok(None);
        }
        let (Some(len), Some(ty)) = (u32_at(bytes, at), u32_at(bytes, at + 4)) else {
            return Err(bad(format!("the {name} chunk header is cut off at byte {at}")));
        };
        let start = at + 8;
        let end = start.checked_add(len as usize).filter(|&e| e <= bytes.len());
        let Some(end) = end else {
            return Err(bad(format!("the {name} chunk says {len} bytes, only {} follow", bytes.len() - start)));
        };
        Ok(Some((ty, &bytes[start..end], end)))
    };
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    let Some((ty, json, next)) = chunk(12, "JSON")? else {
        return Err(bad("there is no JSON chunk".into()));
    };
    if ty != JSON {
        return Err(bad(format!("the first chunk has type 0x{ty:08x}, not JSON")));
    }
    let bin = match chunk(next, "BIN")? {
        Some((BIN, data, _)) => Some(data),
        // Unknown chunks after the JSON chunk must be ignored (glTF 2.0 §4.4.3.3).
        _ => None,
    };
    Ok((json, bin))
}

impl<'a> Loader<'a> {
    fn new(path: &'a Path, bytes: &'a [u8]) -> Result<Self, SceneError> {
        let ctx = Ctx { path };
        let (json, blob) = if bytes.starts_with(b"glTF") { split_glb(ctx, bytes)? } else { (bytes, None) };
        let root = gltf::json::deserialize::from_slice::<gltf::json::Root>(json).map_err(|e| {
            ctx.fail(
                ErrorKind::Parse,
                "",
                format!("not valid glTF JSON: {e}"),
                "fix the JSON at that line and column, or re-export the file",
            )
        })?;
        // gltf-json's validation indexes the POSITION accessor without a bounds check; an
        // out-of-range one would panic inside it, so it is refused here first.
        for (m, mesh) in root.meshes.iter().enumerate() {
            for (p, primitive) in mesh.primitives.iter().enumerate() {
                for (semantic, accessor) in &primitive.attributes {
                    if accessor.value() >= root.accessors.len() {
                        let semantic = match semantic {
                            gltf::json::validation::Checked::Valid(s) => s.to_string(),
                            gltf::json::validation::Checked::Invalid => "an attribute".to_string(),
                        };
                        return Err(ctx.fail(
                            ErrorKind::Parse,
                            format!("{} primitive {p}", quoted_name("mesh", mesh.name.as_deref(), m)),
                            format!("{semantic} refers to accessor {} but the file has {}", accessor.value(), root.accessors.len()),
                            "fix the attribute's accessor index",
                        ));
                    }
                }
            }
        }
        let document = gltf::Document::from_json(root).map_err(|e| match e {
            gltf::Error::Validation(errors) => {
                let list: Vec<String> = errors.iter().take(5).map(|(p, e)| format!("{p}: {e}")).collect();
                let more = if errors.len() > 5 { format!(" (and {} more)", errors.len() - 5) } else { String::new() };
                ctx.fail(ErrorKind::Parse, "", format!("not valid glTF 2.0: {}{more}", list.join(", ")), "fix those fields")
            }
            other => ctx.fail(ErrorKind::Parse, "", format!("not valid glTF: {other}"), "fix the file or re-export it"),
        })?;
        let buffers = load_buffers(ctx, &document, blob)?;
        let material_map = vec![None; document.materials().len()];
        let image_map = vec![None; document.images().len()];
        let placeholder_camera = Camera { world_from_camera: Mat4::IDENTITY, yfov: 1.0, znear: 0.1, zfar: 100.0 };
        Ok(Loader {
            ctx,
            document,
            buffers,
            scene: Scene {
                source: path.to_path_buf(),
                meshes: Vec::new(),
                materials: Vec::new(),
                textures: Vec::new(),
                lights: Vec::new(),
                camera: placeholder_camera,
                settings: SceneSettings::defaults_for((Vec3::ZERO, Vec3::ONE)),
            },
            warnings: Vec::new(),
            material_map,
            default_material: None,
            image_map,
        })
    }

    fn load(mut self, camera_override: Option<&CameraOverride>) -> Result<Loaded, SceneError> {
        let ctx = self.ctx;
        let document = self.document.clone();
        let Some(gltf_scene) = document.default_scene().or_else(|| document.scenes().next()) else {
            return Err(ctx.fail(ErrorKind::Empty, "", "the file has no scene", "add a scene whose nodes hold the meshes"));
        };
        let scene_item = quoted_name("scene", gltf_scene.name(), gltf_scene.index());

        // Depth-first, pre-order, children in file order: the order meshes and lights appear
        // in the Scene (and the camera that counts as "first") is the file's order.
        let mut visited = vec![false; document.nodes().len()];
        let mut stack: Vec<(gltf::Node, Mat4)> = gltf_scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect();
        stack.reverse();
        let mut camera_node: Option<(Perspective, Mat4, String)> = None;
        while let Some((node, parent)) = stack.pop() {
            let node_item = quoted_name("node", node.name(), node.index());
            match visited.get_mut(node.index()) {
                Some(seen) if !*seen => *seen = true,
                _ => {
                    return Err(ctx.fail(
                        ErrorKind::Invalid,
                        node_item,
                        "is reached twice from the scene (a cycle, or a node with two parents)",
                        "make the node hierarchy a tree: give each node at most one parent",
                    ))
                }
            }
            let local = Mat4::from_cols_array_2d(&node.transform().matrix());
            let world = parent * local;
            if !world.is_finite() {
                return Err(ctx.fail(
                    ErrorKind::NonFinite,
                    node_item,
                    "its world transform is not finite (NaN or infinite)",
                    "fix the node's (or a parent's) matrix, translation, rotation or scale",
                ));
            }
            if let Some(mesh) = node.mesh() {
                for primitive in mesh.primitives() {
                    if let Some(m) = self.load_primitive(node.name(), &mesh, &primitive, world)? {
                        self.scene.meshes.push(m);
                    }
                }
            }
            if let Some(light) = node.light() {
                let l = self.convert_light(&light, &node, world)?;
                self.scene.lights.push(l);
            }
            if let Some(cam) = node.camera() {
                let cam_item = quoted_name("camera", cam.name(), cam.index());
                match cam.projection() {
                    gltf::camera::Projection::Perspective(p) if camera_node.is_none() => {
                        camera_node = Some((
                            Perspective { yfov: p.yfov(), znear: p.znear(), zfar: p.zfar() },
                            world,
                            format!("{node_item} {cam_item}"),
                        ));
                    }
                    gltf::camera::Projection::Perspective(_) => {}
                    gltf::camera::Projection::Orthographic(_) => {
                        self.warnings.push(ctx.warning(&cam_item, "orthographic camera ignored (relume renders perspective views)"));
                    }
                }
            }
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, world));
            }
        }

        if self.scene.meshes.is_empty() {
            return Err(ctx.fail(ErrorKind::Empty, scene_item, "has no triangles", "add meshes with triangles to the scene's nodes"));
        }
        let bounds = self.scene.bounds();
        let defaults = SceneSettings::defaults_for(bounds);
        self.scene.settings = match gltf_scene.extras() {
            Some(raw) => serde_json::from_str(raw.get())
                .map_err(|e| e.to_string())
                .and_then(|extras| SceneSettings::from_extras(&extras, defaults))
                .map_err(|problem| {
                    ctx.fail(ErrorKind::Invalid, scene_item.clone(), problem, "fix the scene's extras.relume block (docs/FORMATS.md)")
                })?,
            None => defaults,
        };
        let emissive = self.scene.materials.iter().any(|m| m.emission.max_element() > 0.0);
        if self.scene.lights.is_empty() && !emissive && self.scene.settings.ambient.max_element() <= 0.0 {
            return Err(ctx.fail(
                ErrorKind::NoLight,
                scene_item,
                "has no light",
                "add a KHR_lights_punctual light, an emissive material or an ambient light (extras.relume.ambient)",
            ));
        }

        self.scene.camera = match (camera_override, camera_node) {
            (Some(o), _) => o.camera(bounds),
            (None, Some((p, world, item))) => perspective_camera(ctx, &item, &p, world, bounds)?,
            (None, None) => {
                self.warnings.push(ctx.warning(&scene_item, "no perspective camera; using a default one that frames the scene"));
                framing_camera(bounds)
            }
        };
        Ok(Loaded { scene: self.scene, warnings: self.warnings })
    }

    fn load_primitive(
        &mut self,
        node_name: Option<&str>,
        mesh: &gltf::Mesh,
        primitive: &gltf::Primitive,
        world: Mat4,
    ) -> Result<Option<Mesh>, SceneError> {
        let ctx = self.ctx;
        let mesh_item = quoted_name("mesh", mesh.name(), mesh.index());
        let item = format!("{mesh_item} primitive {}", primitive.index());
        // Named after the node (instances of one glTF mesh are told apart), else the mesh.
        let base = node_name
            .filter(|n| !n.is_empty())
            .or(mesh.name().filter(|n| !n.is_empty()))
            .map(str::to_string)
            .unwrap_or_else(|| format!("mesh {}", mesh.index()));
        let name = match mesh.primitives().len() {
            1 => base,
            _ => format!("{base} primitive {}", primitive.index()),
        };
        if primitive.mode() != gltf::mesh::Mode::Triangles {
            return Err(ctx.fail(
                ErrorKind::NotTriangles,
                item,
                format!("mode {:?} is not a triangle list", primitive.mode()),
                "export the mesh as triangles (mode 4)",
            ));
        }

        let Some(position_accessor) = primitive.get(&gltf::Semantic::Positions) else {
            return Err(ctx.fail(ErrorKind::Accessor, item, "has no POSITION attribute", "add a POSITION accessor"));
        };
        let positions: Vec<Vec3> =
            self.read_vectors::<3>(&item, "POSITION", &position_accessor, false)?.into_iter().map(Vec3::from).collect();
        let vertex_count = positions.len();
        check_finite(ctx, &item, "POSITION", positions.iter().map(|p| p.to_array()))?;

        let normals_in: Option<Vec<Vec3>> = match primitive.get(&gltf::Semantic::Normals) {
            Some(a) => {
                let n: Vec<Vec3> = self.read_vectors::<3>(&item, "NORMAL", &a, false)?.into_iter().map(Vec3::from).collect();
                self.check_count(&item, "NORMAL", n.len(), vertex_count)?;
                check_finite(ctx, &item, "NORMAL", n.iter().map(|v| v.to_array()))?;
                Some(n)
            }
            None => None,
        };
        let mut uvs: [Option<Vec<Vec2>>; 2] = [None, None];
        for (set, slot) in uvs.iter_mut().enumerate() {
            if let Some(a) = primitive.get(&gltf::Semantic::TexCoords(set as u32)) {
                let what = format!("TEXCOORD_{set}");
                let uv: Vec<Vec2> = self.read_vectors::<2>(&item, &what, &a, true)?.into_iter().map(Vec2::from).collect();
                self.check_count(&item, &what, uv.len(), vertex_count)?;
                check_finite(ctx, &item, &what, uv.iter().map(|v| v.to_array()))?;
                *slot = Some(uv);
            }
        }
        let [uv0, uv1] = uvs;

        let mut indices: Vec<u32> = match primitive.indices() {
            Some(a) => self.read_indices(&item, &a)?,
            None => {
                let n = u32::try_from(vertex_count).map_err(|_| {
                    ctx.fail(
                        ErrorKind::Accessor,
                        item.clone(),
                        format!("{vertex_count} vertices without indices"),
                        "split the mesh below 2^32 vertices",
                    )
                })?;
                (0..n).collect()
            }
        };
        if !indices.len().is_multiple_of(3) {
            let what = if primitive.indices().is_some() { "index" } else { "vertex (no indices)" };
            return Err(ctx.fail(
                ErrorKind::NotTriangles,
                item,
                format!("{what} count {} is not a multiple of 3", indices.len()),
                "a triangle list needs three indices per triangle; fix the indices accessor count",
            ));
        }
        if let Some((at, &bad)) = indices.iter().enumerate().find(|(_, &i)| i as usize >= vertex_count) {
            return Err(ctx.fail(
                ErrorKind::IndexOutOfRange,
                item,
                format!("index {bad} (at position {at}) out of range ({vertex_count} vertices)"),
                "fix the indices accessor",
            ));
        }

        // World space. Normals go through the inverse-transpose, computed as the cofactor
        // matrix (columns b×c, c×a, a×b) so that singular scales do not divide by zero; the
        // sign of the determinant keeps its orientation, and a mirroring transform (negative
        // determinant) flips the winding so the front face stays the one the normals face.
        let world_positions: Vec<Vec3> = positions.iter().map(|&p| world.transform_point3(p)).collect();
        if let Some(v) = world_positions.iter().position(|p| !p.is_finite()) {
            return Err(ctx.fail(
                ErrorKind::NonFinite,
                item,
                format!("vertex {v} is not finite after the node transform"),
                "fix the node transform's scale or the POSITION data's magnitude",
            ));
        }
        let linear = Mat3::from_mat4(world);
        let det = linear.determinant();
        let cofactor =
            Mat3::from_cols(linear.y_axis.cross(linear.z_axis), linear.z_axis.cross(linear.x_axis), linear.x_axis.cross(linear.y_axis));
        let normal_matrix = if det < 0.0 { -cofactor } else { cofactor };
        if det < 0.0 {
            for tri in indices.chunks_exact_mut(3) {
                tri.swap(1, 2);
            }
        }

        // Drop zero-area triangles: they carry no light, and they make a BVH, a lightmap
        // rasteriser and per-face normals divide by zero. Relative to the longest edge, so
        // that the test does not depend on the scene's scale.
        let before = indices.len() / 3;
        let mut kept = Vec::with_capacity(indices.len());
        for tri in indices.chunks_exact(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| world_positions[i as usize]);
            let area2 = (b - a).cross(c - a).length();
            let longest = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
            if area2 > 1e-7 * longest && area2 > 0.0 {
                kept.extend_from_slice(tri);
            }
        }
        let dropped = before - kept.len() / 3;
        if dropped > 0 {
            self.warnings.push(ctx.warning(&item, &format!("dropped {dropped} degenerate (zero-area) triangles of {before}")));
        }
        if kept.is_empty() {
            self.warnings.push(ctx.warning(&item, "has no triangles left; primitive skipped"));
            return Ok(None);
        }
        let indices = kept;

        // Area-weighted vertex normals (the unnormalised cross product is twice the area),
        // used where the file has none, or where its normal vanishes under the transform.
        let mut geometric = vec![Vec3::ZERO; vertex_count];
        let mut normals: Vec<Vec3> = match &normals_in {
            Some(n) => n.iter().map(|&v| (normal_matrix * v).normalize_or_zero()).collect(),
            None => vec![Vec3::ZERO; vertex_count],
        };
        if normals.contains(&Vec3::ZERO) {
            for tri in indices.chunks_exact(3) {
                let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| world_positions[i as usize]);
                let face = (b - a).cross(c - a);
                for &i in tri {
                    geometric[i as usize] += face;
                }
            }
            for (n, g) in normals.iter_mut().zip(&geometric) {
                if *n == Vec3::ZERO {
                    // A vertex no kept triangle uses gets any unit normal: nothing reads it.
                    *n = g.normalize_or(Vec3::Y);
                }
            }
        }

        let material = self.material_for(primitive, &item)?;
        if self.scene.materials[material].base_color_texture.is_some() && uv0.is_none() {
            return Err(ctx.fail(
                ErrorKind::Accessor,
                item,
                format!(
                    "its material \"{}\" has a baseColorTexture but the primitive has no TEXCOORD_0",
                    self.scene.materials[material].name
                ),
                "add TEXCOORD_0 to the primitive or remove the texture from the material",
            ));
        }

        Ok(Some(Mesh { name, positions: world_positions, normals, uv0, uv1, indices, material }))
    }

    fn check_count(&self, item: &str, what: &str, count: usize, vertex_count: usize) -> Result<(), SceneError> {
        if count != vertex_count {
            return Err(self.ctx.fail(
                ErrorKind::Accessor,
                item,
                format!("{what} has {count} elements but POSITION has {vertex_count}"),
                format!("give {what} one element per vertex"),
            ));
        }
        Ok(())
    }

    /// The bytes an accessor reads, checked: (buffer data, first byte, stride, element size).
    fn accessor_span(
        &self,
        item: &str,
        what: &str,
        accessor: &gltf::Accessor,
        element_size: usize,
    ) -> Result<(&[u8], usize, usize), SceneError> {
        let ctx = self.ctx;
        let acc_item = format!("{item}: {what} accessor {}", accessor.index());
        if accessor.sparse().is_some() {
            return Err(ctx.fail(ErrorKind::Unsupported, acc_item, "is sparse", "export without sparse accessors"));
        }
        let Some(view) = accessor.view() else {
            return Err(ctx.fail(
                ErrorKind::Accessor,
                acc_item,
                "has no bufferView",
                "point the accessor at a bufferView holding its data",
            ));
        };
        let buffer = view.buffer();
        let data: &[u8] = self.buffers.get(buffer.index()).map(|b| b.as_ref()).unwrap_or(&[]);
        let view_end = view.offset().checked_add(view.length());
        match view_end {
            Some(end) if end <= data.len() => {}
            _ => {
                return Err(ctx.fail(
                    ErrorKind::Buffer,
                    format!("bufferView {}", view.index()),
                    format!(
                        "bytes {}..{} reach past the end of buffer {} ({} bytes)",
                        view.offset(),
                        view.offset() as u128 + view.length() as u128,
                        buffer.index(),
                        data.len()
                    ),
                    "fix the bufferView's byteOffset and byteLength, or the buffer",
                ))
            }
        }
        let stride = view.stride().unwrap_or(element_size);
        if stride < element_size {
            return Err(ctx.fail(
                ErrorKind::Accessor,
                acc_item,
                format!("bufferView {} has byteStride {stride}, less than the {element_size}-byte element", view.index()),
                "fix the bufferView's byteStride",
            ));
        }
        let count = accessor.count();
        let start = view.offset().checked_add(accessor.offset());
        let end = match count {
            0 => start,
            n => start.and_then(|s| stride.checked_mul(n - 1).and_then(|x| x.checked_add(s))).and_then(|x| x.checked_add(element_size)),
        };
        let view_end = view.offset() + view.length();
        match (start, end) {
            (Some(s), Some(e)) if e <= view_end => Ok((data, s, stride)),
            _ => Err(ctx.fail(
                ErrorKind::Accessor,
                acc_item,
                format!(
                    "{count} elements of {element_size} bytes (stride {stride}) from byteOffset {} read past the end of bufferView {} ({} bytes)",
                    accessor.offset(),
                    view.index(),
                    view.length()
                ),
                "fix the accessor's count or byteOffset, or the bufferView's byteLength",
            )),
        }
    }

    /// Reads a float vector attribute. `normalized_ok` admits normalized unsigned bytes and
    /// shorts, which glTF allows for texture coordinates.
    fn read_vectors<const N: usize>(
        &self,
        item: &str,
        what: &str,
        accessor: &gltf::Accessor,
        normalized_ok: bool,
    ) -> Result<Vec<[f32; N]>, SceneError> {
        use gltf::accessor::{DataType, Dimensions};
        let dims = match accessor.dimensions() {
            Dimensions::Vec2 => 2,
            Dimensions::Vec3 => 3,
            Dimensions::Vec4 => 4,
            _ => 0,
        };
        let ty = accessor.data_type();
        let ok_type = ty == DataType::F32 || (normalized_ok && accessor.normalized() && matches!(ty, DataType::U8 | DataType::U16));
        if dims != N || !ok_type {
            let allowed = if normalized_ok { "float, or normalized unsigned byte/short" } else { "float" };
            return Err(self.ctx.fail(
                ErrorKind::Accessor,
                format!("{item}: {what} accessor {}", accessor.index()),
                format!("is {:?} {:?}{}", accessor.dimensions(), ty, if accessor.normalized() { " normalized" } else { "" }),
                format!("{what} must be VEC{N} of {allowed}"),
            ));
        }
        let size = ty.size();
        let (data, start, stride) = self.accessor_span(item, what, accessor, size * N)?;
        let mut out = Vec::with_capacity(accessor.count());
        for e in 0..accessor.count() {
            let base = start + e * stride;
            let mut v = [0.0f32; N];
            for (c, slot) in v.iter_mut().enumerate() {
                let at = base + c * size;
                // In range: accessor_span checked the last element's end.
                let b = &data[at..at + size];
                *slot = match ty {
                    DataType::U8 => b[0] as f32 / 255.0,
                    DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as f32 / 65535.0,
                    _ => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
                };
            }
            out.push(v);
        }
        Ok(out)
    }

    fn read_indices(&self, item: &str, accessor: &gltf::Accessor) -> Result<Vec<u32>, SceneError> {
        use gltf::accessor::{DataType, Dimensions};
        let ty = accessor.data_type();
        if accessor.dimensions() != Dimensions::Scalar || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32) {
            return Err(self.ctx.fail(
                ErrorKind::Accessor,
                format!("{item}: indices accessor {}", accessor.index()),
                format!("is {:?} {:?}", accessor.dimensions(), ty),
                "indices must be SCALAR unsigned byte, short or int",
            ));
        }
        let size = ty.size();
        let (data, start, stride) = self.accessor_span(item, "indices", accessor, size)?;
        let mut out = Vec::with_capacity(accessor.count());
        for e in 0..accessor.count() {
            let at = start + e * stride;
            let b = &data[at..at + size];
            out.push(match ty {
                DataType::U8 => b[0] as u32,
                DataType::U16 => u16::from_le_bytes([b[0], b[1]]) as u32,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            });
        }
        Ok(out)
    }

    fn material_for(&mut self, primitive: &gltf::Primitive, item: &str) -> Result<usize, SceneError> {
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
        if gm.emissive_texture().is_some() {
            self.warnings.push(ctx.warning(&mat_item, "emissiveTexture ignored (relume uses emissiveFactor only)"));
        }
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
        let name = gm.name().map(str::to_string).unwrap_or_else(|| format!("material {index}"));
        self.scene.materials.push(Material { name, base_color, base_color_texture, emission });
        let m = self.scene.materials.len() - 1;
        if let Some(slot) = self.material_map.get_mut(index) {
            *slot = Some(m);
        }
        Ok(m)
    }

    fn texture_for(&mut self, image: &gltf::Image, mat_item: &str) -> Result<usize, SceneError> {
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

    fn convert_light(&self, light: &gltf::khr_lights_punctual::Light, node: &gltf::Node, world: Mat4) -> Result<Light, SceneError> {
        use gltf::khr_lights_punctual::Kind;
        let ctx = self.ctx;
        let item = format!("{} light {}", quoted_name("node", node.name(), node.index()), light.index());
        let color = Vec3::from(light.color());
        let intensity = light.intensity();
        if !color.is_finite() || color.min_element() < 0.0 || !intensity.is_finite() || intensity < 0.0 {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                item,
                format!("color {color} or intensity {intensity} is negative or not finite"),
                "use a finite, non-negative color and intensity",
            ));
        }
        let kind = match light.kind() {
            Kind::Directional => LightKind::Directional,
            Kind::Point => LightKind::Point,
            Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                // Allow for outerConeAngle written as a rounded pi/2.
                let outer = if outer_cone_angle > std::f32::consts::FRAC_PI_2 && outer_cone_angle < std::f32::consts::FRAC_PI_2 + 1e-5 {
                    std::f32::consts::FRAC_PI_2
                } else {
                    outer_cone_angle
                };
                if !(inner_cone_angle >= 0.0 && inner_cone_angle < outer && outer <= std::f32::consts::FRAC_PI_2) {
                    return Err(ctx.fail(
                        ErrorKind::Invalid,
                        item,
                        format!("spot cone angles inner {inner_cone_angle} outer {outer_cone_angle} rad"),
                        "KHR_lights_punctual needs 0 <= innerConeAngle < outerConeAngle <= pi/2",
                    ));
                }
                LightKind::Spot { inner_cone: inner_cone_angle, outer_cone: outer }
            }
        };
        let range = light.range();
        if let Some(r) = range {
            if !(r.is_finite() && r > 0.0) {
                return Err(ctx.fail(
                    ErrorKind::Invalid,
                    item,
                    format!("range {r}"),
                    "range must be a positive number (or absent for no limit)",
                ));
            }
        }
        let direction = (-world.z_axis.truncate()).normalize_or_zero();
        if direction == Vec3::ZERO && kind != LightKind::Point {
            return Err(ctx.fail(
                ErrorKind::Invalid,
                item,
                "the node transform collapses the light's -Z axis (zero scale)",
                "give the light's node a non-zero scale",
            ));
        }
        let name = light.name().or(node.name()).map(str::to_string).unwrap_or_else(|| format!("light {}", light.index()));
        Ok(Light {
            name,
            kind,
            intensity: color * intensity,
            range,
            position: world.w_axis.truncate(),
            direction: if direction == Vec3::ZERO { Vec3::NEG_Z } else { direction },
        })
    }
}

fn check_finite<const N: usize>(ctx: Ctx, item: &str, what: &str, values: impl Iterator<Item = [f32; N]>) -> Result<(), SceneError> {
    for (v, value) in values.enumerate() {
        if value.iter().any(|c| !c.is_finite()) {
            return Err(ctx.fail(
                ErrorKind::NonFinite,
                item,
                format!("vertex {v} has a non-finite {what} {value:?}"),
                format!("fix the {what} data (NaN or infinity in the buffer)"),
            ));
        }
    }
    Ok(())
}

/// A glTF perspective camera's parameters (zfar absent means infinite).
struct Perspective {
    yfov: f32,
    znear: f32,
    zfar: Option<f32>,
}

/// The file's camera, with any scale removed from its node matrix (Gram-Schmidt on the
/// -Z and +Y axes, so a scaled or slightly sheared node still gives a rigid view).
fn perspective_camera(ctx: Ctx, item: &str, p: &Perspective, world: Mat4, bounds: (Vec3, Vec3)) -> Result<Camera, SceneError> {
    let back = world.z_axis.truncate().normalize_or_zero();
    let up = (world.y_axis.truncate() - back * back.dot(world.y_axis.truncate())).normalize_or_zero();
    if back == Vec3::ZERO || up == Vec3::ZERO {
        return Err(ctx.fail(
            ErrorKind::Invalid,
            item,
            "the node transform collapses the camera's axes (zero scale)",
            "give the camera's node a non-zero scale",
        ));
    }
    let right = up.cross(back);
    let eye = world.w_axis.truncate();
    let world_from_camera = Mat4::from_cols(right.extend(0.0), up.extend(0.0), back.extend(0.0), eye.extend(1.0));
    let (yfov, znear) = (p.yfov, p.znear);
    if !(yfov > 0.0 && yfov < std::f32::consts::PI) {
        return Err(ctx.fail(ErrorKind::Invalid, item, format!("yfov {yfov} rad"), "yfov must be between 0 and pi radians"));
    }
    if !(znear > 0.0 && znear.is_finite()) {
        return Err(ctx.fail(ErrorKind::Invalid, item, format!("znear {znear}"), "znear must be a positive number"));
    }
    // An infinite far plane (zfar absent) becomes a finite one that holds the whole scene,
    // because the renderer's projection and depth buffer need one.
    let zfar = match p.zfar {
        Some(f) => f,
        None => clip_planes(eye, bounds).1.max(znear * 2.0),
    };
    if !(zfar > znear && zfar.is_finite()) {
        return Err(ctx.fail(ErrorKind::Invalid, item, format!("zfar {zfar} is not beyond znear {znear}"), "make zfar larger than znear"));
    }
    Ok(Camera { world_from_camera, yfov, znear, zfar })
}

/// A right-handed view from `eye` to `target`: the camera looks down its -Z, +Y up.
fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let forward = (target - eye).normalize();
    let right = forward.cross(up).normalize();
    let true_up = right.cross(forward);
    Mat4::from_cols(right.extend(0.0), true_up.extend(0.0), (-forward).extend(0.0), eye.extend(1.0))
}

/// Near and far planes that hold the whole box as seen from `eye`: far beyond its farthest
/// corner, near at half the distance to the box (never below far / 10^4, which keeps depth
/// precision usable when the eye is inside the box).
fn clip_planes(eye: Vec3, (lo, hi): (Vec3, Vec3)) -> (f32, f32) {
    let farthest = (0..8)
        .map(|i| {
            let corner =
                Vec3::new(if i & 1 == 0 { lo.x } else { hi.x }, if i & 2 == 0 { lo.y } else { hi.y }, if i & 4 == 0 { lo.z } else { hi.z });
            (corner - eye).length()
        })
        .fold(0.0f32, f32::max);
    let far = (farthest * 1.1).max(1e-3);
    let nearest = (eye.clamp(lo, hi) - eye).length();
    let near = (nearest * 0.5).max(far * 1e-4);
    (near, far)
}

/// A camera for files without one: 45 degrees vertical, looking at the bounds' centre from
/// the +Z side and 20 degrees above, far enough that the bounding sphere fits the height.
fn framing_camera(bounds: (Vec3, Vec3)) -> Camera {
    let (lo, hi) = bounds;
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let yfov = 45f32.to_radians();
    let distance = radius / (yfov * 0.5).sin();
    let elevation = 20f32.to_radians();
    let eye = centre + Vec3::new(0.0, elevation.sin(), elevation.cos()) * distance;
    let (znear, zfar) = clip_planes(eye, bounds);
    Camera { world_from_camera: look_at(eye, centre, Vec3::Y), yfov, znear, zfar }
}

fn load_buffers<'b>(ctx: Ctx, document: &gltf::Document, blob: Option<&'b [u8]>) -> Result<Vec<Cow<'b, [u8]>>, SceneError> {
    let mut out = Vec::with_capacity(document.buffers().len());
    for buffer in document.buffers() {
        let (data, label): (Cow<[u8]>, String) = match buffer.source() {
            gltf::buffer::Source::Bin => match blob {
                Some(b) if buffer.index() == 0 => (Cow::Borrowed(b), "the GLB BIN chunk".to_string()),
                _ => {
                    return Err(ctx.fail(
                        ErrorKind::Buffer,
                        format!("buffer {}", buffer.index()),
                        "has no uri and there is no GLB BIN chunk for it",
                        "give the buffer a uri (a .bin file next to the .gltf), or save the scene as .glb",
                    ))
                }
            },
            gltf::buffer::Source::Uri(uri) => {
                let item = format!("buffer {} (\"{}\")", buffer.index(), short_uri(uri));
                (Cow::Owned(read_uri(ctx, &item, uri)?), format!("\"{}\"", short_uri(uri)))
            }
        };
        if data.len() < buffer.length() {
            return Err(ctx.fail(
                ErrorKind::Buffer,
                format!("buffer {}", buffer.index()),
                format!("{label} has {} bytes but the buffer's byteLength is {}", data.len(), buffer.length()),
                "the data is truncated: re-export the scene (or regenerate it), or fix byteLength",
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// A URI for messages: data: URIs are cut short, they can be megabytes long.
fn short_uri(uri: &str) -> String {
    if uri.starts_with("data:") {
        let head: String = uri.chars().take(40).collect();
        format!("{head}…")
    } else {
        uri.to_string()
    }
}

/// Reads a buffer or image URI: a `data:` URI (base64 or percent-encoded), or a relative
/// path resolved against the scene file's folder (percent-decoded, as glTF URIs are).
fn read_uri(ctx: Ctx, item: &str, uri: &str) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, payload)) = rest.split_once(',') else {
            return Err(ctx.fail(
                ErrorKind::Buffer,
                item,
                "the data: URI has no ',' before its payload",
                "write it as data:<type>;base64,<data>",
            ));
        };
        return if header.ends_with(";base64") {
            decode_base64(payload).map_err(|at| {
                ctx.fail(
                    ErrorKind::Buffer,
                    item,
                    format!("the data: URI is not valid base64 (at character {at})"),
                    "re-encode the data as standard base64",
                )
            })
        } else {
            Ok(percent_decode(payload))
        };
    }
    if uri.contains("://") {
        return Err(ctx.fail(
            ErrorKind::Unsupported,
            item,
            format!("the uri \"{uri}\" is not a local file"),
            "download the file and refer to it by a relative path",
        ));
    }
    let decoded = percent_decode(uri);
    let relative = String::from_utf8_lossy(&decoded).into_owned();
    let file = ctx.path.parent().unwrap_or(Path::new("")).join(&relative);
    std::fs::read(&file).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            ctx.fail(ErrorKind::NotFound, item, format!("{} not found", file.display()), "put the file next to the .gltf, or fix the uri")
        } else {
            ctx.fail(ErrorKind::Io, item, format!("cannot read {}: {e}", file.display()), "check the file's permissions")
        }
    })
}

fn percent_decode(s: &str) -> Vec<u8> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            if let (Some(h), Some(l)) = (hex(bytes[i + 1]), hex(bytes[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(bytes[i]);
        i += 1;
    }
    out
}

/// Standard base64 (RFC 4648 §4), padding optional. Written here to avoid a dependency
/// for twenty lines; the error is the offset of the first bad character.
fn decode_base64(text: &str) -> Result<Vec<u8>, usize> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let body = text.trim_end_matches('=');
    if text.len() - body.len() > 2 {
        return Err(body.len());
    }
    let mut out = Vec::with_capacity(body.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0u32);
    for (at, c) in body.bytes().enumerate() {
        acc = (acc << 6) | value(c).ok_or(at)?;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    if bits >= 6 {
        // One leftover character cannot encode a byte.
        return Err(body.len());
    }
    Ok(out)
}

/// Decodes a PNG base-colour image to linear RGBA (sRGB transfer undone on rgb; alpha is
/// linear already). Other formats are refused by their signature, whatever the mimeType says.
fn decode_png(ctx: Ctx, item: &str, bytes: &[u8], name: String) -> Result<Texture, SceneError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_values() {
        assert_eq!(decode_base64("aGVsbG8=").unwrap(), b"hello");
        assert_eq!(decode_base64("aGVsbG8").unwrap(), b"hello");
        assert_eq!(decode_base64("AAECAwQ=").unwrap(), [0, 1, 2, 3, 4]);
        assert!(decode_base64("aGV*bG8=").is_err());
        assert!(decode_base64("a").is_err());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("my%20scene.bin"), b"my scene.bin");
        assert_eq!(percent_decode("100%"), b"100%");
        assert_eq!(percent_decode("a%2"), b"a%2");
    }

    #[test]
    fn camera_override_parses_and_rejects() {
        let c = CameraOverride::parse("eye=0,1,5; target=0,1,0; yfov=40").unwrap();
        assert_eq!(c.eye(), Vec3::new(0.0, 1.0, 5.0));
        assert_eq!(c.up(), Vec3::Y);
        assert_eq!(c.yfov_degrees(), 40.0);
        let cam = c.camera((Vec3::splat(-1.0), Vec3::splat(1.0)));
        assert!((cam.position() - Vec3::new(0.0, 1.0, 5.0)).length() < 1e-6);
        let forward = cam.world_from_camera.transform_vector3(Vec3::NEG_Z);
        assert!((forward - Vec3::NEG_Z).length() < 1e-6);
        assert!(cam.znear > 0.0 && cam.zfar > 6.0);
        for bad in [
            "eye=0,1;target=0,0,0",
            "target=0,0,0",
            "eye=0,0,0;target=0,0,0",
            "eye=0,0,0;target=0,1,0",
            "eye=1,2,3;target=0,0,0;yfov=200",
            "eye=1,2,3;target=0,0,0;fov=20",
            "eye=1,2,3;eye=1,2,3;target=0,0,0",
        ] {
            let e = CameraOverride::parse(bad).unwrap_err().to_string();
            assert!(e.contains("write it as eye="), "{e}");
            assert!(!e.contains('\n'));
        }
    }

    #[test]
    fn glb_splitter_refuses_damaged_headers_without_panicking() {
        let ctx = Ctx { path: Path::new("x.glb") };
        for bytes in
            [&b"glTF"[..], b"glTF\x02\0\0\0\x04\0\0\0", b"glTF\x02\0\0\0\xff\xff\xff\xff", b"glTF\x02\0\0\0\x20\0\0\0\xff\xff\0\0JSON"]
        {
            assert!(split_glb(ctx, bytes).is_err());
        }
    }
}
