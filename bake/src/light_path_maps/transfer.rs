//! The large-scale transfer of Umenhoffer et al., "Partial, Multi-scale Precomputed Radiance
//! Transfer" (000), as the renderer reads it: entry points, and per cluster of entry points
//! the mean light path map M^c and D eigen-textures B^c_d, with each entry point's weights
//! w^e_d (§3.2.3). Plain data shared by the baker (`baker.rs`, `cpca`), the bake
//! artifact and the renderer; the CPU evaluation here is the formula the GPU passes compute.
//!
//! Units: a texture holds, per atlas texel, the irradiance (rgb) that unit irradiance at an
//! entry point sends there by paths with at least one bounce, already divided by the entry
//! point density (§3.2.1), so that I[u, v] = sum_e I_e T_e[u, v] (§3.4) with I_e in lux.

use crate::scene::{Light, LightKind};
use glam::Vec3;

/// A first hit of light from the region lights may move in (§3.2.1).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EntryPoint {
    pub position: Vec3,
    /// Unit normal on the side the light arrives from.
    pub normal: Vec3,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClusteredTransfer {
    /// Every entry point, cluster after cluster.
    pub entry_points: Vec<EntryPoint>,
    /// Cluster c owns entry points `cluster_starts[c]..cluster_starts[c + 1]`; C + 1 values,
    /// the first 0, the last the entry-point count.
    pub cluster_starts: Vec<u32>,
    /// D: eigen-textures per cluster.
    pub basis_count: u32,
    /// w^e_d, D values per entry point, in entry-point order.
    pub weights: Vec<f32>,
    /// Atlas texels per texture (width x height x pages, empty texels included).
    pub texel_count: usize,
    /// Per cluster, M^c then B^c_1 .. B^c_D, each `texel_count` rgb values.
    pub textures: Vec<Vec3>,
    /// Delta-l of §3.4's area-light approximation, square metres (0: exact for punctual lights).
    pub light_area: f32,
}

impl ClusteredTransfer {
    pub fn cluster_count(&self) -> usize {
        self.cluster_starts.len().saturating_sub(1)
    }

    /// Textures per cluster: the mean and the D eigen-textures.
    pub fn terms_per_cluster(&self) -> usize {
        1 + self.basis_count as usize
    }

    /// Texture k of cluster c: k = 0 the mean M^c, k = d the eigen-texture B^c_d.
    pub fn texture(&self, cluster: usize, k: usize) -> &[Vec3] {
        let start = (cluster * self.terms_per_cluster() + k) * self.texel_count;
        &self.textures[start..start + self.texel_count]
    }

    /// Refuses data that does not hang together, saying what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let entries = self.entry_points.len();
        let starts_ok = self.cluster_starts.first() == Some(&0)
            && self.cluster_starts.last() == Some(&(entries as u32))
            && self.cluster_starts.windows(2).all(|w| w[0] <= w[1]);
        if !starts_ok {
            return Err(format!(
                "cluster starts {:?}.. do not split the {entries} entry points in order",
                &self.cluster_starts[..self.cluster_starts.len().min(4)]
            ));
        }
        if self.weights.len() != entries * self.basis_count as usize {
            return Err(format!("{} weights for {entries} entry points of {} each", self.weights.len(), self.basis_count));
        }
        let textures = self.cluster_count() * self.terms_per_cluster() * self.texel_count;
        if self.textures.len() != textures {
            return Err(format!(
                "{} texture values; {} clusters of {} textures of {} texels need {textures}",
                self.textures.len(),
                self.cluster_count(),
                self.terms_per_cluster(),
                self.texel_count
            ));
        }
        let finite = self.entry_points.iter().all(|e| e.position.is_finite() && e.normal.is_finite())
            && self.weights.iter().all(|w| crate::artifact::stored(*w))
            && self.textures.iter().all(|t| t.to_array().into_iter().all(crate::artifact::stored));
        if !finite {
            return Err("an entry point, weight or texture value is not finite (or past 1e9)".into());
        }
        if !(self.light_area.is_finite() && self.light_area >= 0.0) {
            return Err(format!("light area {} must be finite and >= 0 square metres", self.light_area));
        }
        Ok(())
    }

    /// Step 3 of §3.4: per cluster, s_c = sum I_e and t_cd = sum I_e w^e_d, laid out as the
    /// textures are (cluster after cluster, s_c first).
    pub fn cluster_sums(&self, irradiance: &[Vec3]) -> Vec<Vec3> {
        let d = self.basis_count as usize;
        let mut sums = vec![Vec3::ZERO; self.cluster_count() * (1 + d)];
        for (c, range) in self.cluster_starts.windows(2).enumerate() {
            for (e, &i_e) in irradiance.iter().enumerate().take(range[1] as usize).skip(range[0] as usize) {
                sums[c * (1 + d)] += i_e;
                for k in 0..d {
                    sums[c * (1 + d) + 1 + k] += i_e * self.weights[e * d + k];
                }
            }
        }
        sums
    }

    /// Step 4 of §3.4: I[u, v] = sum_c s_c M^c[u, v] + sum_{c,d} t_cd B^c_d[u, v], per texel.
    pub fn reconstruct(&self, sums: &[Vec3]) -> Vec<Vec3> {
        let mut irradiance = vec![Vec3::ZERO; self.texel_count];
        for (k, sum) in sums.iter().enumerate() {
            let texture = &self.textures[k * self.texel_count..(k + 1) * self.texel_count];
            for (out, t) in irradiance.iter_mut().zip(texture) {
                *out += *sum * *t;
            }
        }
        irradiance
    }

    /// Bytes of the compressed transfer as the renderer holds it (f32 rgb textures, D f32
    /// weights and a position and normal per entry point).
    pub fn size_bytes(&self) -> usize {
        self.textures.len() * 12 + self.weights.len() * 4 + self.entry_points.len() * 24
    }
}

/// Irradiance at an entry point from one light, visibility left out (§3.4): the light's
/// irradiance on a surface facing it (`Light::incident`: glTF falloff, range window, spot
/// cone) with the squared distance widened by `light_area` / pi, times the cosine at the
/// entry point. A directional light ignores the area.
pub fn entry_irradiance_unshadowed(light: &Light, entry: &EntryPoint, light_area: f32) -> Vec3 {
    let incident = light.incident(entry.position);
    let cos_e = entry.normal.dot(incident.to_light).max(0.0);
    if light.kind == LightKind::Directional {
        return incident.irradiance * cos_e;
    }
    let d2 = incident.distance * incident.distance;
    // 000 §3.4: L_e cos / (|l - e|^2 + delta-l / pi).
    incident.irradiance * (d2 / (d2 + light_area / std::f32::consts::PI)) * cos_e
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_clusters() -> ClusteredTransfer {
        let e = EntryPoint { position: Vec3::ZERO, normal: Vec3::Y };
        ClusteredTransfer {
            entry_points: vec![e; 3],
            cluster_starts: vec![0, 2, 3],
            basis_count: 1,
            weights: vec![0.5, -1.0, 2.0],
            texel_count: 2,
            textures: [1.0, 2.0, 10.0, 20.0, 3.0, 4.0, 30.0, 40.0].map(Vec3::splat).to_vec(),
            light_area: 0.0,
        }
    }

    #[test]
    fn sums_and_reconstruction_follow_the_formula() {
        let t = two_clusters();
        t.validate().unwrap();
        let irradiance = [1.0, 2.0, 4.0].map(Vec3::splat);
        let sums = t.cluster_sums(&irradiance);
        // s_0 = 3, t_00 = 0.5 - 2 = -1.5; s_1 = 4, t_10 = 8.
        assert_eq!(sums, [3.0, -1.5, 4.0, 8.0].map(Vec3::splat).to_vec());
        let i = t.reconstruct(&sums);
        // texel 0: 3*1 - 1.5*10 + 4*3 + 8*30 = 240; texel 1: 3*2 - 1.5*20 + 4*4 + 8*40 = 312.
        assert_eq!(i, vec![Vec3::splat(240.0), Vec3::splat(312.0)]);
    }

    #[test]
    fn validation_names_what_does_not_fit() {
        let mut t = two_clusters();
        t.weights.pop();
        assert!(t.validate().unwrap_err().contains("weights"));
        let mut t = two_clusters();
        t.cluster_starts = vec![0, 3, 2];
        assert!(t.validate().unwrap_err().contains("cluster starts"));
        let mut t = two_clusters();
        t.textures[3] = Vec3::NAN;
        assert!(t.validate().unwrap_err().contains("finite"));
    }
}
