//! Reference images, cached on disk by a hash of everything that shapes them, so that a rerun
//! of a sweep never traces the same image twice.

use anyhow::Result;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::{self, Image};
use relume_bake::reference::{render_reference, ReferenceSettings};
use relume_bake::scene::Scene;
use std::path::{Path, PathBuf};

/// The reference's layers at one light configuration that the bench compares with (the
/// cached file holds `direct` too).
pub(crate) struct Reference {
    pub indirect: Image,
    pub combined: Image,
}

/// The cache folder, and how many references it traced and how many it found.
pub(crate) struct ReferenceCache {
    folder: PathBuf,
    pub traced: usize,
    pub found: usize,
}

impl ReferenceCache {
    pub fn new(folder: &Path) -> Result<ReferenceCache> {
        std::fs::create_dir_all(folder).map_err(|e| anyhow::anyhow!("{}: cannot create the reference cache ({e}); give another --cache", folder.display()))?;
        Ok(ReferenceCache { folder: folder.to_path_buf(), traced: 0, found: 0 })
    }

    /// The reference of `scene` (its lights as they are now) with `settings`: from the cache
    /// when an entry has the same key, else traced and stored.
    pub fn get(&mut self, scene: &Scene, bvh: &SceneBvh, settings: &ReferenceSettings) -> Result<Reference> {
        let path = self.folder.join(format!("{}.exr", key(scene, settings)));
        if let Ok(layers) = image::read_exr_layers(&path) {
            let layer = |name: &str| layers.iter().find(|(n, _)| n == name).map(|(_, image)| image.clone());
            if let (Some(indirect), Some(combined)) = (layer("indirect"), layer("combined")) {
                self.found += 1;
                return Ok(Reference { indirect, combined });
            }
        }
        let images = render_reference(scene, bvh, settings);
        if images.nonfinite_samples > 0 {
            anyhow::bail!("the reference path tracer met {} NaN or infinite samples; the scene holds degenerate data", images.nonfinite_samples);
        }
        image::write_exr_layers(&path, &[("direct", &images.direct), ("indirect", &images.indirect), ("combined", &images.combined)])?;
        self.traced += 1;
        Ok(Reference { indirect: images.indirect, combined: images.combined })
    }
}

/// A hash of the scene as loaded (geometry, materials, textures, lights, camera), the
/// reference settings that change its pixels, and relume's version.
fn key(scene: &Scene, settings: &ReferenceSettings) -> String {
    let described = format!(
        "{}|{:?}|{:?}|{} {} {} {} {} {} {}|{}",
        relume_bake::artifact::checksum(&traced_bytes(scene)),
        scene.lights,
        scene.camera,
        settings.samples_per_pixel,
        settings.width,
        settings.height,
        settings.seed,
        settings.max_bounces,
        settings.pixel_centres,
        settings.shadows,
        env!("CARGO_PKG_VERSION"),
    );
    relume_bake::artifact::checksum(described.as_bytes()).replace(':', "-")
}

/// The bytes of everything the path tracer reads of the scene's surfaces: meshes (positions,
/// normals, uv0, triangles, material), materials and textures.
fn traced_bytes(scene: &Scene) -> Vec<u8> {
    fn floats<'a>(bytes: &mut Vec<u8>, values: impl IntoIterator<Item = &'a f32>) {
        bytes.extend(values.into_iter().flat_map(|f| f.to_le_bytes()));
    }
    let mut bytes = Vec::new();
    for mesh in &scene.meshes {
        floats(&mut bytes, mesh.positions.iter().chain(&mesh.normals).flat_map(|v| v.as_ref()));
        floats(&mut bytes, mesh.uv0.iter().flatten().flat_map(|v| v.as_ref()));
        bytes.extend(mesh.indices.iter().flat_map(|i| i.to_le_bytes()));
        bytes.extend((mesh.material as u64).to_le_bytes());
    }
    for material in &scene.materials {
        floats(&mut bytes, material.base_color.as_ref().iter().chain(material.emission.as_ref()));
        bytes.extend(material.base_color_texture.map_or(u64::MAX, |t| t as u64).to_le_bytes());
    }
    for texture in &scene.textures {
        bytes.extend([texture.width, texture.height].iter().flat_map(|v| v.to_le_bytes()));
        floats(&mut bytes, texture.texels.iter().flat_map(|t| t.as_ref()));
    }
    bytes
}
