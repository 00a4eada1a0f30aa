//! The bench's table across methods (report.md, methods.csv): per scene and method its best
//! configuration and that one's costs, the references' noise beside the errors, and the frame
//! times the run does not tell apart.

use super::noise::RESOLVED_NOISES;
use super::report::Summary;
use super::{Outcome, Resolution};
use std::fmt::Write as _;

/// A number with `decimals`, or "-" where it means nothing (NaN).
pub(super) fn cell(value: f64, decimals: usize) -> String {
    if value.is_finite() {
        format!("{value:.decimals$}")
    } else {
        "-".into()
    }
}

/// One method on one scene: its configurations, the most accurate first.
pub(super) struct MethodCell<'a, 's> {
    configurations: Vec<(&'a Summary<'s>, bool)>,
}

impl MethodCell<'_, '_> {
    pub(super) fn best(&self) -> &Summary<'_> {
        self.configurations[0].0
    }
    fn best_indirect(&self) -> f64 {
        self.configurations.iter().map(|c| c.0.mean_indirect_nrmse).filter(|v| v.is_finite()).fold(f64::NAN, f64::min)
    }
    /// The labels of its configurations on the scene's front.
    fn on_front(&self) -> Vec<String> {
        let mut labels: Vec<usize> = self.configurations.iter().filter(|c| c.1).map(|c| c.0.number).collect();
        labels.sort();
        labels.iter().map(|n| n.to_string()).collect()
    }
}

/// Per scene and method (in the order they ran), its configurations scored at every light
/// configuration, with whether each is on the scene's front.
pub(super) fn method_cells<'a, 's>(summaries: &'a [Summary<'s>], fronts: &[bool]) -> Vec<MethodCell<'a, 's>> {
    let mut cells: Vec<MethodCell> = Vec::new();
    for (s, &on) in summaries.iter().zip(fronts).filter(|(s, _)| s.ok()) {
        let same = |c: &&mut MethodCell| c.best().first().scene == s.first().scene && c.best().first().method == s.first().method;
        match cells.iter_mut().find(|c| same(c)) {
            Some(c) => c.configurations.push((s, on)),
            None => cells.push(MethodCell { configurations: vec![(s, on)] }),
        }
    }
    for c in &mut cells {
        c.configurations.sort_by(|a, b| a.0.mean_nrmse.total_cmp(&b.0.mean_nrmse));
    }
    cells
}

/// methods.csv and the report's table across methods: per scene and method, the best image and
/// indirect NRMSE, and the costs of its most accurate configuration.
pub(super) fn methods_rows(cells: &[MethodCell]) -> Vec<[String; 13]> {
    cells
        .iter()
        .map(|c| {
            let best = c.best();
            let row = best.first();
            [
                row.scene.clone(),
                row.method.clone(),
                c.configurations.len().to_string(),
                cell(best.mean_nrmse, 4),
                cell(c.best_indirect(), 4),
                best.number.to_string(),
                cell(row.bake.seconds, 2),
                cell(best.peak_mib(), 1),
                cell(best.artifact_mib(), 2),
                cell(best.gpu_ms, 2),
                match best.gpu_p10_ms.is_finite() && best.gpu_p90_ms.is_finite() {
                    true => format!("{:.2}-{:.2}", best.gpu_p10_ms, best.gpu_p90_ms),
                    false => "-".into(),
                },
                cell(best.gpu_without_shadow_maps_ms, 3),
                c.on_front().join(" "),
            ]
        })
        .collect()
}

pub(super) const METHODS_HEADER: [&str; 13] = [
    "scene",
    "method",
    "configurations",
    "best NRMSE",
    "best indirect NRMSE",
    "its label",
    "bake s",
    "bake peak MiB",
    "artifact MiB",
    "GPU ms",
    "GPU ms p10-p90",
    "GPU ms without shadow maps",
    "labels on the front",
];

pub(super) fn methods_text(r: &mut String, cells: &[MethodCell], outcome: &Outcome) {
    let _ = writeln!(r, "## Across methods\n");
    let _ = writeln!(r, "Per scene and method: the lowest mean NRMSE of its configurations and the costs of that configuration (its label), the lowest mean indirect NRMSE of any, and which of its configurations are on the scene's Pareto front of (GPU frame time, mean NRMSE; errors within three times the references' noise tied, below). Empty cells mean nothing for the method or scene (-). Also in methods.csv.\n");
    let _ = writeln!(r, "| {} |\n|{}", METHODS_HEADER.join(" | "), "---|".repeat(METHODS_HEADER.len()));
    for row in methods_rows(cells) {
        let _ = writeln!(r, "| {} |", row.join(" | "));
    }
    noise_text(r, cells, outcome);
    timing_text(r, cells);
    if !outcome.not_applicable.is_empty() {
        let _ = writeln!(r, "\nNot run where they do not apply:\n");
        for line in &outcome.not_applicable {
            let _ = writeln!(r, "- {line}");
        }
    }
    let _ = writeln!(r);
}

/// Per scene that measured it, the references' own noise, whether it met the sweep's target,
/// and the methods whose best NRMSE is within the scene's resolution of the best: not told
/// apart by this reference.
fn noise_text(r: &mut String, cells: &[MethodCell], outcome: &Outcome) {
    if outcome.noise.is_empty() {
        return;
    }
    let _ = writeln!(r, "\nThe references' own noise (the first light configuration traced with two seeds: their NRMSE / sqrt 2), beside the errors ranked. Errors no further apart than {RESOLVED_NOISES} times it are ties: the fronts and the budget do not rank them (the cheaper counts as on the front, and as the more accurate).\n");
    let resolution = Resolution::of_noise(&outcome.noise);
    for (scene, n) in &outcome.noise {
        let mut bests: Vec<(f64, &str)> = cells
            .iter()
            .filter(|c| c.best().first().scene == *scene)
            .map(|c| (c.best().mean_nrmse, c.best().first().method.as_str()))
            .collect();
        bests.sort_by(|a, b| a.0.total_cmp(&b.0));
        let tied = |b: &&(f64, &str)| bests.first().is_some_and(|first| b.0 <= first.0 + resolution.of(scene));
        let close: Vec<&str> = bests.iter().skip(1).filter(tied).map(|b| b.1).collect();
        let verdict = match (bests.first(), close.is_empty()) {
            _ if bests.len() < 2 || !n.scene_nrmse.is_finite() => String::new(),
            (Some(first), false) => format!("; within {RESOLVED_NOISES}x the noise of the best ({}): {}", first.1, close.join(", ")),
            (Some(first), true) => format!("; the best ({}) is apart from the rest by more than {RESOLVED_NOISES}x the noise", first.1),
            (None, _) => String::new(),
        };
        let over = match outcome.sweep.reference_noise_target {
            Some(target) if n.scene_nrmse > target => {
                let capped = if Some(n.spp) == outcome.sweep.reference_max_spp { ", at reference_max_spp" } else { "" };
                format!(" (over the target {target}{capped})")
            }
            _ => String::new(),
        };
        let _ = writeln!(
            r,
            "- {scene} ({} spp): image NRMSE {:.4}{over}, indirect {}{verdict}",
            n.spp,
            n.scene_nrmse,
            cell(n.indirect_nrmse, 4)
        );
    }
}

/// Per scene, the pairs of methods (their most accurate configurations) whose frame times
/// 10th-90th percentile spreads overlap: this run does not tell their frame times apart.
fn timing_text(r: &mut String, cells: &[MethodCell]) {
    let mut scenes: Vec<&str> = cells.iter().map(|c| c.best().first().scene.as_str()).collect();
    scenes.dedup();
    let _ = writeln!(r, "\nFrame times this run does not tell apart (the 10th-90th percentile spreads of the methods' most accurate configurations overlap):\n");
    for scene in scenes {
        let of: Vec<&Summary> = cells.iter().map(|c| c.best()).filter(|s| s.first().scene == scene).collect();
        if of.iter().any(|s| !(s.gpu_p10_ms.is_finite() && s.gpu_p90_ms.is_finite())) {
            let _ = writeln!(r, "- {scene}: unknown (the device gave no timestamps)");
            continue;
        }
        let mut pairs = Vec::new();
        for (i, a) in of.iter().enumerate() {
            for b in &of[i + 1..] {
                if a.gpu_p10_ms <= b.gpu_p90_ms && b.gpu_p10_ms <= a.gpu_p90_ms {
                    pairs.push(format!("{} ~ {}", a.first().method, b.first().method));
                }
            }
        }
        let _ = writeln!(r, "- {scene}: {}", if pairs.is_empty() { "none".to_string() } else { pairs.join(", ") });
    }
}
