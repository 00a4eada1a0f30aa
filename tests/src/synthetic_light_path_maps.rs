//! Synthetic light path maps for the renderer's tests, made without the baker: an atlas of a
//! scene, the scene with uv1 applied, an obscurance of one constant W (alpha the
//! coverage), and a clustered transfer whose entry points sit at covered texel centres and
//! whose textures and weights come from a seeded hash. The values mean nothing physically;
//! they are there so GPU and CPU evaluations of the same formulas can be compared.

use glam::{Vec3, Vec4};
use relume_bake::atlas::{Atlas, AtlasSettings};
use relume_bake::light_path_maps::{ClusteredTransfer, EntryPoint};
use relume_bake::sampling::{hash_u32, u32_to_unit};
use relume_bake::scene::Scene;

/// `scene`'s atlas at `texel_density` texels per metre, and the scene re-indexed with uv1.
pub fn atlas_scene(scene: &Scene, texel_density: f32) -> (Atlas, Scene) {
    let atlas = Atlas::build(scene, &AtlasSettings { texel_density, ..AtlasSettings::default() }).expect("atlas");
    let mut applied = scene.clone();
    atlas.apply_to(&mut applied);
    (atlas, applied)
}

/// The obscurance `w` on every covered texel, alpha the coverage (empty texels 0).
pub fn constant_obscurance(atlas: &Atlas, w: Vec3) -> Vec<Vec4> {
    atlas.texels.iter().map(|t| if t.coverage > 0.0 { w.extend(t.coverage) } else { Vec4::ZERO }).collect()
}

/// A transfer on `atlas`: `cluster_starts.last()` entry points spread evenly over the covered
/// texels (centre and normal), `basis_count` eigen-textures per cluster. Means are in
/// [0, 0.004), eigen-textures in [-0.001, 0.001), weights in [-1, 1): the reconstruction stays
/// positive wherever some entry point of a cluster is lit. Light area 0.01 m^2.
pub fn synthetic_transfer(atlas: &Atlas, cluster_starts: Vec<u32>, basis_count: u32, seed: u64) -> ClusteredTransfer {
    let covered: Vec<usize> = (0..atlas.texels.len()).filter(|&t| atlas.texels[t].coverage > 0.0).collect();
    let entries = *cluster_starts.last().expect("cluster starts") as usize;
    let entry_points = (0..entries)
        .map(|e| {
            let texel = &atlas.texels[covered[e * covered.len() / entries]];
            EntryPoint { position: texel.centre, normal: texel.normal }
        })
        .collect();
    let unit = |stream: u32, index: u32, dim: u32| u32_to_unit(hash_u32(seed, stream, index, dim));
    let weights = (0..entries as u32 * basis_count).map(|i| 2.0 * unit(0, i, 0) - 1.0).collect();
    let texel_count = atlas.texels.len();
    let clusters = cluster_starts.len() - 1;
    let terms = 1 + basis_count as usize;
    let mut textures = Vec::with_capacity(clusters * terms * texel_count);
    for k in 0..clusters * terms {
        let (scale, offset) = if k % terms == 0 { (0.004, 0.0) } else { (0.002, -0.001) };
        textures.extend((0..texel_count as u32).map(|t| {
            let value = |channel| scale * unit(1 + k as u32, t, channel) + offset;
            Vec3::new(value(0), value(1), value(2))
        }));
    }
    let transfer = ClusteredTransfer { entry_points, cluster_starts, basis_count, weights, texel_count, textures, light_area: 0.01 };
    transfer.validate().expect("a valid synthetic transfer");
    transfer
}
