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
//! inverse-transpose, winding flipped under mirroring transforms); triangle primitives (lists,
//! and strips and fans read as lists) with POSITION, NORMAL (computed when absent),
//! TEXCOORD_0, TEXCOORD_1 and indices;
//! baseColorFactor, baseColorTexture (PNG), emissiveFactor × KHR_materials_emissive_strength;
//! KHR_lights_punctual lights; the first perspective camera. Everything else in the file
//! (metallic-roughness, normal maps, skins, morph targets, animations) is ignored: relume's
//! methods are Lambertian and static.

mod camera;
mod files;
mod lights;
mod materials;
mod primitives;

pub use camera::{CameraOverride, CameraOverrideError};

use crate::environment::{Environment, EnvironmentError, EnvironmentSettings};
use crate::scene::{Camera, Light, Material, Scene};
use crate::settings::SceneSettings;
use camera::{framing_camera, perspective_camera, Perspective};
use files::{load_buffers, split_glb};
use glam::{Mat4, Vec3, Vec4};
use std::borrow::Cow;
use std::fmt;
use std::path::{Path, PathBuf};

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
    /// A primitive is not triangles (points or lines), or its index count makes no triangle list,
    /// strip or fan.
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

/// Loads a scene with the camera the file gives (or a default one framing the scene).
pub fn load(path: &Path) -> Result<Loaded, SceneError> {
    load_with_camera(path, None)
}

/// Loads a scene; `camera`, when given, replaces the file's camera.
pub fn load_with_camera(path: &Path, camera: Option<&CameraOverride>) -> Result<Loaded, SceneError> {
    load_with_options(path, &LoadOptions { camera, ..Default::default() })
}

/// How a scene is loaded.
#[derive(Clone, Copy, Debug, Default)]
pub struct LoadOptions<'c> {
    /// Replaces the file's camera.
    pub camera: Option<&'c CameraOverride>,
    /// Lets the scene's buffers, images and environment lie outside its folder (an
    /// absolute path or one through `..`): off, a scene a user downloaded reads only its own
    /// folder.
    pub outside_files: bool,
    /// The most pixels a texture may have (its PNG header is checked before decoding);
    /// None: [`DEFAULT_MAX_TEXTURE_PIXELS`].
    pub max_texture_pixels: Option<u64>,
    /// Where the lights come from.
    pub lights: LightChoice<'c>,
}

/// Where a scene's lights come from.
#[derive(Clone, Copy, Debug, Default)]
pub enum LightChoice<'c> {
    /// The file's own; a scene with no light of any kind is refused.
    #[default]
    Scene,
    /// The file's own, or, for a scene with no light of any kind (most downloaded models),
    /// [`crate::lights_file::default_rig`], with a warning saying so.
    SceneOrDefaultRig,
    /// These (a lights file's), in place of the file's punctual lights.
    Given(&'c [Light]),
}

/// 8192 x 8192: decoded to linear RGBA f32, 1 GiB.
pub const DEFAULT_MAX_TEXTURE_PIXELS: u64 = 8192 * 8192;

/// Loads a scene as `options` say.
pub fn load_with_options(path: &Path, options: &LoadOptions) -> Result<Loaded, SceneError> {
    let ctx = Ctx {
        path,
        outside_files: options.outside_files,
        max_texture_pixels: options.max_texture_pixels.unwrap_or(DEFAULT_MAX_TEXTURE_PIXELS),
    };
    crate::inputs::admit(path).map_err(|e| ctx.fail(ErrorKind::Io, "", e, "give the scene's .gltf or .glb file"))?;
    let bytes = std::fs::read(path).map_err(|e| {
        let err = ctx;
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
    Loader::new(ctx, &bytes)?.load(options.camera, options.lights)
}

// ---------------------------------------------------------------------------------------------

/// Builds errors and warnings that name the file.
#[derive(Clone, Copy)]
struct Ctx<'a> {
    path: &'a Path,
    /// LoadOptions::outside_files.
    outside_files: bool,
    /// LoadOptions::max_texture_pixels, its default applied.
    max_texture_pixels: u64,
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
    Material { name: "default".into(), base_color: Vec4::ONE, base_color_texture: None, emission: Vec3::ZERO, phong: None }
}

fn quoted_name(kind: &str, name: Option<&str>, index: usize) -> String {
    match name {
        Some(n) if !n.is_empty() => format!("{kind} \"{n}\""),
        _ => format!("{kind} {index}"),
    }
}

impl<'a> Loader<'a> {
    fn new(ctx: Ctx<'a>, bytes: &'a [u8]) -> Result<Self, SceneError> {
        let path = ctx.path;
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
                environment: None,
                camera: placeholder_camera,
                settings: SceneSettings::defaults_for((Vec3::ZERO, Vec3::ONE)),
            },
            warnings: Vec::new(),
            material_map,
            default_material: None,
            image_map,
        })
    }

    fn load(mut self, camera_override: Option<&CameraOverride>, lights: LightChoice) -> Result<Loaded, SceneError> {
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
                .and_then(|extras| SceneSettings::from_extras(&extras, defaults, &crate::methods::SCENE_BLOCKS))
                .map_err(|problem| {
                    ctx.fail(ErrorKind::Invalid, scene_item.clone(), problem, "fix the scene's extras.relume block (docs/FORMATS.md)")
                })?,
            None => defaults,
        };
        if let Some(settings) = &self.scene.settings.environment {
            let environment = load_environment(ctx, &scene_item, settings)?;
            if environment.clamped_texels > 0 {
                let message =
                    format!("{} texels of {} slightly below 0 read as 0", environment.clamped_texels, environment.source.display());
                self.warnings.push(ctx.warning(&format!("{scene_item} extras.relume.environment"), &message));
            }
            self.scene.environment = Some(environment);
        }
        self.scene.camera = match (camera_override, camera_node) {
            (Some(o), _) => o.camera(bounds),
            (None, Some((p, world, item))) => perspective_camera(ctx, &item, &p, world, bounds)?,
            (None, None) => {
                self.warnings.push(ctx.warning(&scene_item, "no perspective camera; using a default one that frames the scene"));
                framing_camera(bounds)
            }
        };
        if let LightChoice::Given(given) = lights {
            self.scene.lights = given.to_vec();
        }
        let emissive = self.scene.materials.iter().any(|m| m.emission.max_element() > 0.0);
        let environment = self.scene.environment.as_ref().is_some_and(Environment::is_lit);
        if self.scene.lights.is_empty() && !emissive && !environment && self.scene.settings.ambient.max_element() <= 0.0 {
            if !matches!(lights, LightChoice::SceneOrDefaultRig) {
                return Err(ctx.fail(
                    ErrorKind::NoLight,
                    scene_item,
                    "has no light",
                    "add a KHR_lights_punctual light, an emissive material, an environment (extras.relume.environment) or an ambient light (extras.relume.ambient), or give a lights file (--lights)",
                ));
            }
            self.scene.lights = crate::lights_file::default_rig(bounds, &self.scene.camera);
            let rig = "has no light; lit by relume's default rig, a headlight at the camera (give --lights FILE to choose the lights)";
            self.warnings.push(ctx.warning(&scene_item, rig));
        }
        Ok(Loaded { scene: self.scene, warnings: self.warnings })
    }
}

/// The scene's environment, or the refusal naming its file and the fix.
fn load_environment(ctx: Ctx, scene_item: &str, settings: &EnvironmentSettings) -> Result<Environment, SceneError> {
    let item = format!("{scene_item} extras.relume.environment");
    files::refuse_outside(ctx, &item, &settings.image.to_string_lossy())?;
    Environment::load(settings, ctx.path).map_err(|e| match &e {
        EnvironmentError::NotFound(_) => {
            ctx.fail(ErrorKind::NotFound, item, e.to_string(), "fix environment.image (a lat-long EXR, relative to the glTF file)")
        }
        EnvironmentError::Unreadable(_) => ctx.fail(ErrorKind::Image, item, e.to_string(), "write the environment as an RGB EXR file"),
        EnvironmentError::Invalid { .. } => {
            ctx.fail(ErrorKind::Invalid, item, e.to_string(), "give a lat-long RGB EXR of finite radiance >= 0 (width twice the height)")
        }
    })
}
