//! The one contract every method's bake keeps (docs/ARCHITECTURE.md, "Adding a method"): a
//! method's bake settings, complete and checked, are a [`Baker`]; it prepares what its work
//! needs (atlas, BVH, tessellation), estimates its peak memory and has `WorkOptions` admit it
//! before the long work, runs its work items in passes through `WorkOptions` (threads, time
//! limit, progress, a seed per item), reduces (clustering, CPCA, solves) and returns its
//! sections with their statistics. The command line only maps its flags to a `Baker`.

use crate::artifact::Section;
use crate::scene::Scene;
use crate::work::{peak_memory_bytes, reset_peak_memory, WorkOptions};
use serde_json::{json, Value};
use std::time::Instant;

/// A method's whole bake, its settings decided.
pub trait Baker: Sync {
    /// Bakes `scene` through `work`, timing each stage in `stages`; an error says what failed
    /// and the fix (the caller names the scene).
    fn bake(&self, scene: &Scene, work: &WorkOptions, stages: &mut Stages) -> Result<Baked, String>;
}

/// What a method's bake made: its sections, what it was made with, and what it found.
#[derive(Default)]
pub struct Baked {
    pub sections: Vec<Section>,
    /// Every parameter the bake used (given and defaulted), for the manifest.
    pub parameters: Value,
    /// Method-specific statistics for stats.json.
    pub stats: Value,
    /// Lines for the terminal and the main job's report.
    pub summary: String,
}

impl Baked {
    /// Records a setting derived from the scene because the scene does not declare it: under
    /// `derived` in the manifest's parameters and in stats.json, and in one warning line naming
    /// what was chosen, `how`, and the scene key or flag that overrides it, `key`.
    pub fn derived(&mut self, name: &str, value: Value, how: &str, key: &str) {
        self.parameters["derived"][name] = value.clone();
        self.stats["derived"][name] = value;
        self.summary.push_str(&format!("warning: derived {name}: {how}; {key} sets it instead\n"));
    }
}

/// One bake stage's cost, as stats.json records it.
#[derive(Debug)]
pub struct TimedStage {
    pub name: &'static str,
    pub seconds: f64,
    pub peak_memory_bytes: Option<u64>,
}

/// The timed stages of one bake.
#[derive(Debug, Default)]
pub struct Stages(pub Vec<TimedStage>);

impl Stages {
    /// Runs `work` as the stage `name`: its wall time and the peak memory it reached.
    pub fn timed<R>(&mut self, name: &'static str, work: impl FnOnce() -> R) -> R {
        reset_peak_memory();
        let start = Instant::now();
        let result = work();
        self.0.push(TimedStage { name, seconds: start.elapsed().as_secs_f64(), peak_memory_bytes: peak_memory_bytes() });
        result
    }

    /// The highest of the stages' peaks: the bake's peak memory.
    pub fn peak_memory_bytes(&self) -> Option<u64> {
        self.0.iter().filter_map(|s| s.peak_memory_bytes).max()
    }

    pub fn json(&self) -> Value {
        json!(self
            .0
            .iter()
            .map(|s| json!({ "name": s.name, "seconds": s.seconds, "peak_memory_bytes": s.peak_memory_bytes }))
            .collect::<Vec<_>>())
    }

    /// One line per stage: seconds and peak memory.
    pub fn summary(&self) -> String {
        self.0
            .iter()
            .map(|s| {
                let memory = s.peak_memory_bytes.map_or("?".into(), |b| format!("{:.1} MiB", mib(b)));
                format!("  {:<13} {:>8.3} s, peak memory {memory}\n", s.name, s.seconds)
            })
            .collect()
    }
}

/// A bake's peak memory, estimated before its long work: a part that does not grow with the
/// work (the process, the scene, its BVH and atlas) and one that grows linearly with it, as
/// `count` units of `bytes_per_unit` (the method's constant, docs/BENCHMARKS.md), where the
/// units are proportional to the flag `lever` at `value`.
#[derive(Clone, Debug, PartialEq)]
pub struct Estimate {
    pub fixed: u64,
    pub count: u64,
    pub bytes_per_unit: u64,
    /// What a unit is, e.g. "texels x entry points".
    pub unit: String,
    pub lever: &'static str,
    pub value: u64,
    /// The units grow as the lever's value to this power.
    pub power: f64,
    /// Bytes per the lever's value squared, beside the units: a Gram matrix of the lever's
    /// items (light path maps' entry points); 0 for most.
    pub squared: u64,
}

impl Estimate {
    pub fn bytes(&self) -> u64 {
        let squared = self.squared.saturating_mul(self.value.saturating_mul(self.value));
        self.fixed.saturating_add(self.count.saturating_mul(self.bytes_per_unit)).saturating_add(squared)
    }

    /// The estimate at the lever's value `v`: the units scaled by (v / value)^power.
    fn at(&self, v: u64) -> f64 {
        let units = self.count as f64 * (v as f64 / self.value.max(1) as f64).powf(self.power);
        self.fixed as f64 + units * self.bytes_per_unit as f64 + self.squared as f64 * (v as f64).powi(2)
    }

    /// The largest value of the lever up to its own whose estimate is within `limit` (0: none
    /// is), by bisection: the estimate grows with the lever.
    pub fn fitting(&self, limit: u64) -> u64 {
        let within = |v: u64| self.at(v) <= limit as f64;
        let (mut lo, mut hi) = (0, self.value.max(1));
        if within(hi) {
            return hi;
        }
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            match within(mid) {
                true => lo = mid,
                false => hi = mid,
            }
        }
        lo
    }

    /// "N MiB (F MiB fixed + count unit x B bytes)", and "+ value^2 x S bytes" where the lever
    /// adds a square.
    pub fn describe(&self) -> String {
        let squared = match self.squared {
            0 => String::new(),
            s => format!(" + {}^2 {} x {s} bytes", self.value, self.lever.trim_start_matches("--")),
        };
        format!(
            "{:.0} MiB ({:.0} MiB fixed + {} {} x {} bytes{squared})",
            mib(self.bytes()),
            mib(self.fixed),
            self.count,
            self.unit,
            self.bytes_per_unit
        )
    }
}

/// Bytes the process holds before a bake's own work: the program, and the scene with its BVH
/// (measured: docs/BENCHMARKS.md, "Peak memory").
pub fn scene_bytes(scene: &Scene) -> u64 {
    let triangles: usize = scene.meshes.iter().map(|m| m.indices.len() / 3).sum();
    PROCESS_BYTES + triangles as u64 * BYTES_PER_TRIANGLE
}

/// The program and its libraries, resident before any scene.
pub const PROCESS_BYTES: u64 = 16 << 20;
/// A triangle of the scene and of its BVH, with what the BVH's build holds at its peak.
pub const BYTES_PER_TRIANGLE: u64 = 512;

pub(crate) fn mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lever's value a refusal names fits the limit, and one more does not, whether the
    /// units grow with it or with its fourth power, and with a square of it beside them (light
    /// path maps' Gram matrix, which once made "even --entry-points 1 would not fit").
    #[test]
    fn the_fitting_value_fits_and_one_more_does_not() {
        for (power, value, squared) in [(1.0, 4096u64, 0), (4.0, 8, 0), (1.0, 1 << 20, 16)] {
            let estimate = Estimate {
                fixed: 100 << 20,
                count: 1 << 30,
                bytes_per_unit: 12,
                unit: "units".into(),
                lever: "--lever",
                value,
                power,
                squared,
            };
            let limit = estimate.bytes() / 3;
            let fits = estimate.fitting(limit);
            let at = |v: u64| {
                let count = (estimate.count as f64 * (v as f64 / value as f64).powf(power)) as u64;
                Estimate { count, value: v, ..estimate.clone() }.bytes()
            };
            assert!(fits > 0 && fits < value, "power {power}: {fits}");
            assert!(at(fits) <= limit && at(fits + 1) > limit, "power {power}: {fits}");
            assert_eq!(Estimate { fixed: limit + 1, ..estimate.clone() }.fitting(limit), 0);
        }
    }
}
