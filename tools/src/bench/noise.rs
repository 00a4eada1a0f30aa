//! The references' own noise (two seeds), the samples that bring it to a sweep's target, and
//! the resolution it gives the bench's rankings (docs/BENCH.md, the sweep keys).

use super::reference_cache::{Reference, ReferenceCache};
use super::sweep::Sweep;
use anyhow::Result;
use relume_bake::bvh::SceneBvh;
use relume_bake::image::Image;
use relume_bake::metrics;
use relume_bake::reference::ReferenceSettings;
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;

/// A reference's own noise as an NRMSE against the truth, of the image and of its indirect
/// layer: two references of other seeds differ by sqrt(2) times it (their noise independent).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub(crate) struct ReferenceNoise {
    pub scene_nrmse: f64,
    pub indirect_nrmse: f64,
    /// The samples per pixel it was measured at: the scene's references'.
    pub spp: u32,
}

/// The noise of `a`, from `b` traced with another seed: NRMSE(a, b) / sqrt(2), measured
/// against `a` (the scale NRMSE of a method is measured at).
fn reference_noise(a: &Reference, b: &Reference, spp: u32) -> Result<ReferenceNoise> {
    let noise = |of: &Image, again: &Image| -> Result<f64> {
        let e = metrics::compare(again, of)?;
        Ok(e.nrmse / std::f64::consts::SQRT_2)
    };
    Ok(ReferenceNoise { scene_nrmse: noise(&a.combined, &b.combined)?, indirect_nrmse: noise(&a.indirect, &b.indirect)?, spp })
}

/// The noise of `scene`'s references (its first light configuration traced with two seeds), at
/// the sweep's reference_spp, and where that is over the sweep's reference_noise_target, at
/// the samples that should meet it (measured again there).
pub(super) fn measured_noise(
    name: &str,
    scene: &Scene,
    cache: &mut ReferenceCache,
    settings: &ReferenceSettings,
    sweep: &Sweep,
) -> Result<ReferenceNoise> {
    let bvh = SceneBvh::new(scene);
    let mut at = |spp: u32| -> Result<ReferenceNoise> {
        println!("{name}: reference 1 at {spp} spp with two seeds (its noise)");
        let settings = ReferenceSettings { samples_per_pixel: spp, ..settings.clone() };
        let seeded = ReferenceSettings { work: WorkOptions { seed: settings.work.seed + 1, ..settings.work }, ..settings.clone() };
        reference_noise(&cache.get(scene, &bvh, &settings)?, &cache.get(scene, &bvh, &seeded)?, spp)
    };
    let noise = at(settings.samples_per_pixel)?;
    let Some(target) = sweep.reference_noise_target else { return Ok(noise) };
    let spp = spp_for_noise(noise.spp, noise.scene_nrmse, target, sweep.reference_max_spp.unwrap_or(noise.spp));
    if spp == noise.spp {
        return Ok(noise);
    }
    println!("{name}: noise {:.4} over the target {target}: the references at {spp} spp", noise.scene_nrmse);
    at(spp)
}

/// The samples per pixel, from `spp` by doublings up to `max`, at which `noise` measured at
/// `spp` falls to `target`: noise falls as 1/sqrt(samples).
fn spp_for_noise(spp: u32, noise: f64, target: f64, max: u32) -> u32 {
    // A black reference's noise is infinite (NRMSE against nothing): no samples meet a target.
    if !noise.is_finite() {
        return spp;
    }
    let mut samples = spp;
    while samples < max && noise * (spp as f64 / samples as f64).sqrt() > target {
        samples = samples.saturating_mul(2).min(max);
    }
    samples
}

/// How many times the references' noise two errors must differ by to be ranked: the issue's
/// bar, a reference's noise under a third of the smallest difference ranked.
pub(crate) const RESOLVED_NOISES: f64 = 3.0;

/// Per scene, the smallest difference of error the bench ranks: RESOLVED_NOISES times its
/// references' own noise (none where it was not measured). Errors no further apart are ties
/// to the fronts, the budget and the report.
#[derive(Default)]
pub(crate) struct Resolution(pub Vec<(String, f64)>);

impl Resolution {
    pub(super) fn of_noise(noise: &[(String, ReferenceNoise)]) -> Resolution {
        Resolution(
            noise
                .iter()
                .filter(|(_, n)| n.scene_nrmse.is_finite())
                .map(|(scene, n)| (scene.clone(), RESOLVED_NOISES * n.scene_nrmse))
                .collect(),
        )
    }

    pub fn of(&self, scene: &str) -> f64 {
        self.0.iter().find(|(s, _)| s == scene).map_or(0.0, |(_, r)| *r)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn samples_double_until_the_noise_should_meet_the_target_or_the_cap() {
        // Measured on the default sweep at 256 spp: mrt-maze 0.205, cornell 0.048, classroom 0.024.
        assert_eq!(spp_for_noise(256, 0.205, 0.03, 2048), 2048, "capped");
        assert_eq!(spp_for_noise(256, 0.048, 0.03, 2048), 1024, "0.034 at 512, 0.024 at 1024");
        assert_eq!(spp_for_noise(256, 0.024, 0.03, 2048), 256, "already under");
        assert_eq!(spp_for_noise(256, 0.048, 0.03, 256), 256, "no room");
        assert_eq!(spp_for_noise(100, 0.2, 0.001, 300), 300, "the cap need not be a doubling");
        assert_eq!(spp_for_noise(256, f64::INFINITY, 0.03, 2048), 256, "a black reference's noise asks for nothing");
    }

    #[test]
    fn the_resolution_is_three_times_the_noise_and_none_where_unmeasured() {
        let noise = |n: f64| ReferenceNoise { scene_nrmse: n, indirect_nrmse: n, spp: 8 };
        let resolution = Resolution::of_noise(&[("a".into(), noise(0.01)), ("b".into(), noise(f64::NAN))]);
        assert!((resolution.of("a") - 0.03).abs() < 1e-12);
        assert_eq!((resolution.of("b"), resolution.of("c")), (0.0, 0.0));
    }
}
