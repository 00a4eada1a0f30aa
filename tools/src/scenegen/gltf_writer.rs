//! The glTF writer: deterministic JSON and a little-endian `.bin`.

use super::settings::Settings;
use glam::{DMat3, DQuat, DVec3};
use serde_json::{json, Value};

/// An f32 as a JSON number in its shortest round-trip form (`0.5528`, not the f64 widening
/// `0.5527999997138977`), so the text is readable and reads back to the exact f32 in the .bin.
pub(super) fn num(x: f64) -> Value {
    let x = x as f32;
    let x = if x == 0.0 { 0.0 } else { x }; // no "-0.0"
    let shortest: f64 = format!("{x}").parse().unwrap_or(0.0);
    json!(shortest)
}

pub(super) fn vec_json(v: DVec3) -> Value {
    json!([num(v.x), num(v.y), num(v.z)])
}

pub(super) fn quat_json(q: DQuat) -> Value {
    json!([num(q.x), num(q.y), num(q.z), num(q.w)])
}

pub(super) struct Builder {
    settings: Settings,
    /// `extras.relume.environment`: the lat-long image (relative to the glTF file) and its
    /// intensity, if the scene is lit by one.
    environment: Option<(String, f64)>,
    /// `extras.relume.fiv.occluders`: the nodes that occlude.
    occluders: Vec<String>,
    light_cloud: Option<Value>,
    /// `extras.relume.mrt`: the block proxy.
    mrt: Option<Value>,
    bin: Vec<u8>,
    buffer_views: Vec<Value>,
    accessors: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    nodes: Vec<Value>,
    lights: Vec<Value>,
    cameras: Vec<Value>,
}

pub(super) const ARRAY_BUFFER: u32 = 34962;
pub(super) const ELEMENT_ARRAY_BUFFER: u32 = 34963;
pub(super) const FLOAT: u32 = 5126;
pub(super) const UNSIGNED_INT: u32 = 5125;

impl Builder {
    /// An empty scene; its settings are required up front so that no scene can lack them.
    pub(super) fn new(settings: Settings) -> Self {
        Builder {
            settings,
            environment: None,
            occluders: Vec::new(),
            light_cloud: None,
            mrt: None,
            bin: Vec::new(),
            buffer_views: Vec::new(),
            accessors: Vec::new(),
            meshes: Vec::new(),
            materials: Vec::new(),
            nodes: Vec::new(),
            lights: Vec::new(),
            cameras: Vec::new(),
        }
    }

    /// A diffuse material: metallic 0 and roughness 1, so that viewers other than relume
    /// (whose surfaces are all Lambertian) show it the same way.
    pub(super) fn material(&mut self, name: &str, rgb: [f64; 3]) -> usize {
        self.materials.push(json!({
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [num(rgb[0]), num(rgb[1]), num(rgb[2]), num(1.0)],
                "metallicFactor": num(0.0),
                "roughnessFactor": num(1.0),
            },
        }));
        self.materials.len() - 1
    }

    /// A diffuse material with relume's glossy lobe (`extras.relume.phong`: the normalised
    /// modified Phong lobe of rho_s `specular` and exponent e the path tracer opts into).
    pub(super) fn phong_material(&mut self, name: &str, rgb: [f64; 3], specular: f64, exponent: f64) -> usize {
        let m = self.material(name, rgb);
        self.materials[m]["extras"] = json!({ "relume": { "phong": { "specular": num(specular), "exponent": num(exponent) } } });
        m
    }

    /// Appends bytes as a bufferView (4-byte aligned, as every accessor here needs).
    pub(super) fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        self.buffer_views.push(json!({
            "buffer": 0,
            "byteOffset": self.bin.len(),
            "byteLength": bytes.len(),
            "target": target,
        }));
        self.bin.extend_from_slice(bytes);
        self.buffer_views.len() - 1
    }

    pub(super) fn vec3_accessor(&mut self, values: &[[f32; 3]], with_bounds: bool) -> usize {
        let bytes: Vec<u8> = values.iter().flatten().flat_map(|c| c.to_le_bytes()).collect();
        let view = self.view(&bytes, ARRAY_BUFFER);
        let mut accessor = json!({ "bufferView": view, "componentType": FLOAT, "count": values.len(), "type": "VEC3" });
        if with_bounds {
            // POSITION accessors must carry min and max (glTF 2.0 §5.1.1).
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            for v in values {
                for c in 0..3 {
                    lo[c] = lo[c].min(v[c]);
                    hi[c] = hi[c].max(v[c]);
                }
            }
            accessor["min"] = json!(lo.map(|x| num(x as f64)));
            accessor["max"] = json!(hi.map(|x| num(x as f64)));
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// A smooth mesh: triangles that share a corner (the same numbers) share its vertex, and
    /// no normals are written, so the loader computes them area-weighted (docs/FORMATS.md);
    /// for the large stand-ins, a quarter of the flat-shaded file.
    pub(super) fn smooth_mesh(&mut self, name: &str, triangles: &[[DVec3; 3]], material: usize) -> usize {
        let mut index_of = std::collections::HashMap::new();
        let mut positions: Vec<[f32; 3]> = Vec::new();
        let mut indices: Vec<u8> = Vec::with_capacity(triangles.len() * 12);
        for p in triangles.iter().flatten() {
            let position = p.as_vec3().to_array();
            let index = *index_of.entry(position.map(f32::to_bits)).or_insert_with(|| {
                positions.push(position);
                positions.len() as u32 - 1
            });
            indices.extend(index.to_le_bytes());
        }
        let position = self.vec3_accessor(&positions, true);
        let index_view = self.view(&indices, ELEMENT_ARRAY_BUFFER);
        self.accessors
            .push(json!({ "bufferView": index_view, "componentType": UNSIGNED_INT, "count": triangles.len() * 3, "type": "SCALAR" }));
        let index_accessor = self.accessors.len() - 1;
        self.meshes.push(json!({
            "name": name,
            "primitives": [{ "attributes": { "POSITION": position }, "indices": index_accessor, "material": material, "mode": 4 }],
        }));
        self.meshes.len() - 1
    }

    /// A flat-shaded mesh: three vertices per triangle carrying the face normal.
    pub(super) fn mesh(&mut self, name: &str, triangles: &[[DVec3; 3]], material: usize) -> usize {
        let mut positions = Vec::with_capacity(triangles.len() * 3);
        let mut normals = Vec::with_capacity(triangles.len() * 3);
        for [a, b, c] in triangles {
            let n = (*b - *a).cross(*c - *a).normalize();
            for p in [a, b, c] {
                positions.push(p.as_vec3().to_array());
                normals.push(n.as_vec3().to_array());
            }
        }
        let indices: Vec<u32> = (0..positions.len() as u32).collect();
        self.mesh_with_normals(name, &positions, &normals, &indices, material)
    }

    /// A mesh of vertices with their normals and a triangle list of indices into them.
    fn mesh_with_normals(&mut self, name: &str, positions: &[[f32; 3]], normals: &[[f32; 3]], indices: &[u32], material: usize) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let position = self.vec3_accessor(positions, true);
        let normal = self.vec3_accessor(normals, false);
        let index_view = self.view(&bytes, ELEMENT_ARRAY_BUFFER);
        self.accessors.push(json!({ "bufferView": index_view, "componentType": UNSIGNED_INT, "count": indices.len(), "type": "SCALAR" }));
        let index_accessor = self.accessors.len() - 1;
        self.meshes.push(json!({
            "name": name,
            "primitives": [{
                "attributes": { "NORMAL": normal, "POSITION": position },
                "indices": index_accessor,
                "material": material,
                "mode": 4,
            }],
        }));
        self.meshes.len() - 1
    }

    /// A mesh of quads, each split into an `n` x `n` grid whose vertices its cells share
    /// (welded within the quad, split at its edges, so a crease keeps two normals), each
    /// vertex carrying its quad's normal; each quad's front faces `outward(its centre)`.
    /// For the per-vertex methods, which need vertices across a surface.
    pub(super) fn grid_mesh(
        &mut self,
        name: &str,
        quads: &[[DVec3; 4]],
        n: u32,
        outward: impl Fn(DVec3) -> DVec3,
        material: usize,
    ) -> usize {
        let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
        for q in quads {
            let centre = (q[0] + q[1] + q[2] + q[3]) / 4.0;
            let normal = (q[2] - q[0]).cross(q[3] - q[1]).normalize();
            let flip = normal.dot(outward(centre)) < 0.0;
            let first = positions.len() as u32;
            for j in 0..=n {
                for i in 0..=n {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let p = (q[0] * (1.0 - s) + q[1] * s) * (1.0 - t) + (q[3] * (1.0 - s) + q[2] * s) * t;
                    positions.push(p.as_vec3().to_array());
                    normals.push((if flip { -normal } else { normal }).as_vec3().to_array());
                }
            }
            let at = |i: u32, j: u32| first + j * (n + 1) + i;
            for j in 0..n {
                for i in 0..n {
                    for [a, b, c] in [[at(i, j), at(i + 1, j), at(i + 1, j + 1)], [at(i, j), at(i + 1, j + 1), at(i, j + 1)]] {
                        indices.extend(if flip { [a, c, b] } else { [a, b, c] });
                    }
                }
            }
        }
        self.mesh_with_normals(name, &positions, &normals, &indices, material)
    }

    /// Declares the light cloud's grid (`extras.relume.light_cloud`): a box and its cells.
    pub(super) fn light_cloud_grid(&mut self, min: DVec3, max: DVec3, counts: [u32; 3]) {
        self.light_cloud = Some(json!({ "grid": { "box": [vec_json(min), vec_json(max)], "counts": counts } }));
    }

    /// Declares the blocks of modular radiance transfer (`extras.relume.mrt.grid`): cubes of
    /// size `cell` from `origin`, `rows` of '.' blocks and '#' solid cells.
    pub(super) fn mrt_grid(&mut self, origin: [f64; 3], cell: [f64; 3], rows: &[&str]) {
        self.mrt = Some(json!({ "grid": { "origin": origin.map(num), "cell": cell.map(num), "rows": rows } }));
    }

    /// Declares warped blocks of modular radiance transfer (`extras.relume.mrt.blocks`): each
    /// by its 8 corners, corner i at the unit cube's (i & 1, i >> 1 & 1, i >> 2 & 1).
    pub(super) fn mrt_blocks(&mut self, blocks: &[[DVec3; 8]]) {
        let blocks: Vec<Value> = blocks.iter().map(|c| json!({ "corners": c.iter().map(|p| vec_json(*p)).collect::<Vec<_>>() })).collect();
        self.mrt = Some(json!({ "blocks": blocks }));
    }

    /// Declares the meshes (by node name) that modular radiance transfer's light volume lights
    /// instead of mapping them onto the blocks (`extras.relume.mrt.dynamic`), after the blocks.
    pub(super) fn mrt_dynamic(&mut self, names: &[&str]) {
        self.mrt.as_mut().expect("the blocks are declared first")["dynamic"] = json!(names);
    }

    /// Lights the scene by the lat-long EXR `image` (relative to the glTF file) times `intensity`.
    pub(super) fn environment(&mut self, image: &str, intensity: f64) {
        self.environment = Some((image.to_string(), intensity));
    }

    /// A mesh node that is one of FIV's occluders.
    pub(super) fn occluder_node(&mut self, name: &str, mesh: usize, translation: DVec3, scale: DVec3) {
        self.mesh_node(name, mesh, translation, scale);
        self.occluders.push(name.to_string());
    }

    pub(super) fn mesh_node(&mut self, name: &str, mesh: usize, translation: DVec3, scale: DVec3) {
        let mut node = json!({ "name": name, "mesh": mesh });
        if translation != DVec3::ZERO {
            node["translation"] = vec_json(translation);
        }
        if scale != DVec3::ONE {
            node["scale"] = vec_json(scale);
        }
        self.nodes.push(node);
    }

    /// A KHR_lights_punctual point light, white, `intensity` candela. It shines every way;
    /// its node's -Z is turned onto `sized_for`, the direction of the surface its intensity is
    /// chosen for (which the scene tests check).
    pub(super) fn point_light(&mut self, name: &str, position: DVec3, sized_for: DVec3, intensity: f64) {
        self.light(name, position, sized_for, json!({ "type": "point", "intensity": num(intensity) }));
    }

    /// A KHR_lights_punctual spot light, white, `intensity` candela, cone angles in degrees;
    /// the node's rotation turns its -Z onto `direction`.
    pub(super) fn spot_light(
        &mut self,
        name: &str,
        position: DVec3,
        direction: DVec3,
        intensity: f64,
        inner_degrees: f64,
        outer_degrees: f64,
    ) {
        let spot = json!({ "innerConeAngle": num(inner_degrees.to_radians()), "outerConeAngle": num(outer_degrees.to_radians()) });
        self.light(name, position, direction, json!({ "type": "spot", "intensity": num(intensity), "spot": spot }));
    }

    /// A KHR_lights_punctual directional light, white, `illuminance` lux, its light travelling
    /// along `direction`; glTF ignores its node's `position`, which the scene tests cast from.
    pub(super) fn directional_light(&mut self, name: &str, position: DVec3, direction: DVec3, illuminance: f64) {
        self.light(name, position, direction, json!({ "type": "directional", "intensity": num(illuminance) }));
    }

    /// A white light (`light`: its type and what the type needs) on a node at `position` whose
    /// rotation turns its -Z onto `direction`.
    fn light(&mut self, name: &str, position: DVec3, direction: DVec3, mut light: Value) {
        light["name"] = json!(name);
        light["color"] = json!([num(1.0), num(1.0), num(1.0)]);
        self.lights.push(light);
        let rotation = DQuat::from_rotation_arc(DVec3::NEG_Z, direction.normalize());
        self.nodes.push(json!({
            "name": name,
            "translation": vec_json(position),
            "rotation": quat_json(rotation),
            "extensions": { "KHR_lights_punctual": { "light": self.lights.len() - 1 } },
        }));
    }

    /// A perspective camera at `eye` looking at `target` with +Y up (glTF cameras look down
    /// their -Z); no rotation is written when it looks straight down -Z.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn camera(&mut self, name: &str, eye: DVec3, target: DVec3, yfov: f64, aspect: Option<f64>, znear: f64, zfar: f64) {
        let mut perspective = json!({ "yfov": num(yfov), "znear": num(znear), "zfar": num(zfar) });
        if let Some(a) = aspect {
            perspective["aspectRatio"] = num(a);
        }
        self.cameras.push(json!({ "name": name, "type": "perspective", "perspective": perspective }));
        let forward = (target - eye).normalize();
        let right = forward.cross(DVec3::Y).normalize();
        let up = right.cross(forward);
        let rotation = DQuat::from_mat3(&DMat3::from_cols(right, up, -forward)).normalize();
        let mut node = json!({ "name": name, "camera": self.cameras.len() - 1, "translation": vec_json(eye) });
        if rotation.angle_between(DQuat::IDENTITY) > 1e-9 {
            node["rotation"] = quat_json(rotation);
        }
        self.nodes.push(node);
    }

    pub(super) fn finish(self, name: &str) -> (String, Vec<u8>) {
        let root = json!({
            "asset": { "version": "2.0", "generator": "relume scenes" },
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": { "KHR_lights_punctual": { "lights": self.lights } },
            "scene": 0,
            "scenes": [{
                "name": name,
                "nodes": (0..self.nodes.len()).collect::<Vec<_>>(),
                "extras": { "relume": self.settings_json() },
            }],
            "nodes": self.nodes,
            "meshes": self.meshes,
            "materials": self.materials,
            "cameras": self.cameras,
            "accessors": self.accessors,
            "bufferViews": self.buffer_views,
            "buffers": [{ "byteLength": self.bin.len(), "uri": format!("{name}.bin") }],
        });
        // Serialising a Value built from plain maps cannot fail; keep an empty string if it did.
        let mut text = serde_json::to_string_pretty(&root).unwrap_or_default();
        text.push('\n');
        (text, self.bin)
    }
}

impl Builder {
    /// The settings, the environment, the occluders and the light cloud as `extras.relume`.
    fn settings_json(&self) -> Value {
        let mut block = settings_json(&self.settings);
        if let Some((image, intensity)) = &self.environment {
            block["environment"] = json!({ "image": image, "intensity": num(*intensity) });
        }
        if !self.occluders.is_empty() {
            block["fiv"] = json!({ "occluders": self.occluders });
        }
        if let Some(cloud) = &self.light_cloud {
            block["light_cloud"] = cloud.clone();
        }
        if let Some(mrt) = &self.mrt {
            block["mrt"] = mrt.clone();
        }
        block
    }
}

/// The settings as `extras.relume` (the block `relume_bake::settings` reads).
fn settings_json(s: &Settings) -> Value {
    let light_path_maps = match s.light_region {
        Some((min, max, test_points)) => json!({
            "region": { "box": [min.map(num), max.map(num)], "test_points": test_points },
            "light_area": num(s.light_area),
        }),
        None => json!({ "light_area": num(s.light_area) }),
    };
    json!({
        "ambient": s.ambient.map(num),
        "beta": num(s.beta),
        "texel_density": num(s.texel_density),
        "obscurance": { "tau": num(s.tau), "l_max": num(s.l_max) },
        "light_path_maps": light_path_maps,
    })
}
