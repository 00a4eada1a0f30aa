//! 004 Fig. 5: how much of the transfer's variation each principal component accounts for,
//! for the indirect light the cloud stores and for the direct light it leaves to shadow maps.
//! The paper plots the back wall of its Cornell box; relume averages over the clusters of a
//! compressed cloud (each cluster is one PCA), weighted by their vertices.

use super::baker::unit_directional_light;
use super::{Columns, LightCloud};
use crate::bvh::SceneBvh;
use crate::cpca;
use crate::reference::punctual_irradiance;
use crate::scene::Scene;
use glam::Vec3;
use rayon::prelude::*;

/// Per component k (from the first), its share of the variance: the mean over `compressed`'s
/// clusters (by their vertices; those without variance left out) of eigenvalue k / the sum of
/// the cluster's eigenvalues.
#[derive(Clone, Debug, PartialEq)]
pub struct ExplainedVariance {
    /// The transfer as gathered (before compression): `reduced`'s rows.
    pub indirect: Vec<f64>,
    /// A 1 cd light's direct irradiance at each vertex, from the same lights: cos / r^2 (a
    /// direction's 1 lux: cos), zero where the light is hidden or behind the surface.
    pub direct: Vec<f64>,
}

/// The first `components` shares of both, over the clusters of `compressed`, which was made
/// from `reduced` (uncompressed, the same zones and lights).
pub fn explained_variance(
    scene: &Scene,
    bvh: &SceneBvh,
    reduced: &LightCloud,
    compressed: &LightCloud,
    components: usize,
) -> ExplainedVariance {
    let (positions, normals) = (super::vertex_positions(scene), super::vertex_normals(scene));
    let mut sums = VarianceSums::new(components);
    sums.add(bvh, (&positions, &normals), reduced, compressed);
    sums.finish()
}

/// Explained variance summed over clouds (a bake's zones, one after another).
pub struct VarianceSums {
    indirect: Shares,
    direct: Shares,
}

impl VarianceSums {
    pub fn new(components: usize) -> VarianceSums {
        VarianceSums { indirect: Shares::new(components), direct: Shares::new(components) }
    }

    /// Adds the clusters of `compressed`, made from `reduced`, whose vertices stand at
    /// `positions` facing `normals`.
    pub fn add(&mut self, bvh: &SceneBvh, (positions, normals): (&[Vec3], &[Vec3]), reduced: &LightCloud, compressed: &LightCloud) {
        let (columns, layout) = (Columns::new(reduced), compressed.layout());
        let members = cpca::groups(&compressed.assignment, compressed.cluster_count());
        for (vertices, at) in members.iter().zip(&layout).filter(|(m, _)| !m.is_empty()) {
            let cloud_columns = at.first_column as usize..(at.first_column + at.columns) as usize;
            let lights = cloud_columns.start / reduced.emission..cloud_columns.end / reduced.emission;
            let mut indirect = Vec::with_capacity(vertices.len() * cloud_columns.len() * reduced.per_column());
            for &v in vertices {
                for j in cloud_columns.clone() {
                    (0..reduced.coefficients).for_each(|k| indirect.extend(columns.coefficient(v as usize, j, k).to_array()));
                }
            }
            // White light: one value a light (its rgb are equal and share the same components).
            let direct: Vec<f32> = vertices
                .par_iter()
                .flat_map_iter(|&v| {
                    let (p, n) = (positions[v as usize], normals[v as usize]);
                    lights.clone().map(move |j| match reduced.is_direction(j) {
                        true => {
                            punctual_irradiance(bvh, &unit_directional_light(reduced.lights[j]), p, n, n, true).map_or(0.0, |(e, _)| e.x)
                        }
                        false => direct_irradiance(bvh, p, n, reduced.lights[j]),
                    })
                })
                .collect();
            self.indirect.add(&indirect, vertices.len());
            self.direct.add(&direct, vertices.len());
        }
    }

    pub fn finish(self) -> ExplainedVariance {
        ExplainedVariance { indirect: self.indirect.mean(), direct: self.direct.mean() }
    }
}

/// Per component, the shares of the clusters' variance summed by vertices.
struct Shares {
    sums: Vec<f64>,
    vertices: usize,
}

impl Shares {
    fn new(components: usize) -> Shares {
        Shares { sums: vec![0.0; components], vertices: 0 }
    }

    /// Adds a cluster of `members` rows; one without variance (a single vertex, or all dark)
    /// has no shares and counts for nothing.
    fn add(&mut self, rows: &[f32], members: usize) {
        let eigenvalues = cpca::cluster_eigenvalues(rows, rows.len() / members, &(0..members as u32).collect::<Vec<_>>());
        let total: f64 = eigenvalues.iter().sum();
        if total > 0.0 {
            self.sums.iter_mut().zip(&eigenvalues).for_each(|(s, e)| *s += members as f64 * e / total);
            self.vertices += members;
        }
    }

    fn mean(self) -> Vec<f64> {
        let vertices = self.vertices.max(1) as f64;
        self.sums.iter().map(|s| s / vertices).collect()
    }
}

/// The irradiance a 1 cd light at `light` gives a surface at `p` facing `n` (lux).
fn direct_irradiance(bvh: &SceneBvh, p: Vec3, n: Vec3, light: Vec3) -> f32 {
    let to_light = light - p;
    let (distance, cos) = (to_light.length(), n.dot(to_light.normalize_or_zero()));
    if cos <= 0.0 || distance == 0.0 {
        return 0.0;
    }
    let origin = bvh.offset_origin(p, n, to_light);
    if bvh.visible(origin, light) {
        cos / (distance * distance)
    } else {
        0.0
    }
}
