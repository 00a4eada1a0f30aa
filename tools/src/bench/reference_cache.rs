//! Reference images, cached on disk by a hash of everything that shapes them, so that a rerun
//! of a sweep never traces the same image twice.

use anyhow::Result;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::{self, Image};
use relume_bake::outputs::Outputs;
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
        std::fs::create_dir_all(folder)
            .map_err(|e| anyhow::anyhow!("{}: cannot create the reference cache ({e}); give another --cache", folder.display()))?;
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
        // A cache entry that does not read is the cache's to replace.
        relume_bake::inputs::release(&path);
        let images = render_reference(scene, bvh, settings);
        if images.nonfinite_samples > 0 {
            anyhow::bail!(
                "the reference path tracer met {} NaN or infinite samples; the scene holds degenerate data",
                images.nonfinite_samples
            );
        }
        let mut outputs = Outputs::new();
        let layers = [("direct", &images.direct), ("indirect", &images.indirect), ("combined", &images.combined)];
        image::write_exr_layers(&mut outputs, &path, &layers)?;
        outputs.commit()?;
        self.traced += 1;
        Ok(Reference { indirect: images.indirect, combined: images.combined })
    }
}

/// A hash of the scene as loaded (geometry, materials, textures, lights, camera), the
/// reference settings that change its pixels, and relume's version.
fn key(scene: &Scene, settings: &ReferenceSettings) -> String {
    let described = format!(
        "{}|{:?}|{:?}|{} {} {} {} {} {} {}|{}",
        relume_bake::artifact::scene_checksum(scene),
        scene.lights,
        scene.camera,
        settings.samples_per_pixel,
        settings.width,
        settings.height,
        settings.work.seed,
        settings.max_bounces,
        settings.pixel_centres,
        settings.shadows,
        env!("CARGO_PKG_VERSION"),
    );
    // The environment joins the key only where there is one, so older entries stay valid.
    let environment =
        scene.environment.as_ref().map(|e| format!("|{}", relume_bake::artifact::environment_checksum(e))).unwrap_or_default();
    relume_bake::artifact::checksum((described + &environment).as_bytes()).replace(':', "-")
}
