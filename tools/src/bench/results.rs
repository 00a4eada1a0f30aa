//! One row per point of a sweep, and its two written forms: results.csv (columns in
//! docs/BENCH.md) and results.json.

use super::{pareto, Resolution};
use anyhow::{Context as _, Result};
use serde::Serialize;
use std::path::Path;

/// What the bake of a point's method configuration cost (all 0 for a method without a bake).
#[derive(Clone, Debug, Default, Serialize)]
pub(crate) struct BakeCost {
    pub seconds: f64,
    /// (stage, seconds), in the order the bake ran them.
    pub stages: Vec<(String, f64)>,
    pub peak_memory_bytes: u64,
    /// Every file of the bake artifact.
    pub artifact_bytes: u64,
    /// The bake's stats.json, for charts of its statistics.
    #[serde(skip)]
    pub statistics: serde_json::Value,
}

impl BakeCost {
    /// The costs a bake recorded in its artifact folder (stats.json) and the folder's size.
    pub fn read(dir: &Path) -> Result<BakeCost> {
        let path = dir.join("stats.json");
        let text = std::fs::read_to_string(&path).with_context(|| format!("{}: cannot read", path.display()))?;
        let stats: serde_json::Value = serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
        let stages: Vec<(String, f64, u64)> = stats["stages"]
            .as_array()
            .map(|stages| {
                stages
                    .iter()
                    .map(|s| {
                        (
                            s["name"].as_str().unwrap_or("?").to_string(),
                            s["seconds"].as_f64().unwrap_or(0.0),
                            s["peak_memory_bytes"].as_u64().unwrap_or(0),
                        )
                    })
                    .collect()
            })
            .unwrap_or_default();
        let mut artifact_bytes = 0;
        for entry in std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))? {
            artifact_bytes += entry?.metadata()?.len();
        }
        Ok(BakeCost {
            seconds: stages.iter().map(|s| s.1).sum(),
            peak_memory_bytes: stages.iter().map(|s| s.2).max().unwrap_or(0),
            stages: stages.into_iter().map(|(name, seconds, _)| (name, seconds)).collect(),
            artifact_bytes,
            statistics: stats,
        })
    }
}

/// What a frame cost over the timed frames.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct FrameCost {
    /// Median GPU time per pass that ran, in frame order; empty without timestamps.
    pub passes_ms: Vec<(String, f64)>,
    /// Median, 10th and 90th percentile of the GPU frame time (sum of the passes).
    pub gpu_ms: f64,
    pub gpu_p10_ms: f64,
    pub gpu_p90_ms: f64,
    /// Median CPU wall time of one `render` call: record, submit, wait for the frame's fence.
    pub cpu_ms: f64,
}

impl FrameCost {
    /// The medians of the passes other than the shadow maps' (`vsm_*`, the same work for every
    /// method, which dominates a frame on lavapipe); NaN without timestamps.
    pub fn without_shadow_maps_ms(&self) -> f64 {
        let own = self.passes_ms.iter().filter(|(name, _)| !name.starts_with("vsm_"));
        if self.passes_ms.is_empty() {
            f64::NAN
        } else {
            own.map(|(_, ms)| ms).sum()
        }
    }

    /// The cost of a configuration that never rendered: NaN (empty in the CSV, null in JSON).
    pub fn unknown() -> FrameCost {
        FrameCost { passes_ms: Vec::new(), gpu_ms: f64::NAN, gpu_p10_ms: f64::NAN, gpu_p90_ms: f64::NAN, cpu_ms: f64::NAN }
    }
}

/// Errors against the reference path tracer (NRMSE as docs/METRICS.md defines it; FLIP mean).
#[derive(Clone, Copy, Debug, Serialize)]
pub(crate) struct Accuracy {
    pub rmse: f64,
    pub nrmse: f64,
    pub flip: f64,
    pub indirect_rmse: f64,
    pub indirect_nrmse: f64,
    pub indirect_flip: f64,
}

#[derive(Clone, Debug, Serialize)]
pub(crate) struct Row {
    pub scene: String,
    /// The light configuration's index (0 when the scene's lights are used as they are).
    pub light: usize,
    pub light_position: Option<[f32; 3]>,
    /// The moving occluder's translation (None without an occluder path).
    pub occluder_translation: Option<[f32; 3]>,
    /// Its turn about the vertical axis, degrees (None without an occluder path).
    pub occluder_turn_degrees: Option<f32>,
    /// A spot sweep's outer cone angle, degrees, and how far its aim turned from the spot's own
    /// direction, degrees (None without a spot sweep).
    pub spot_outer_degrees: Option<f32>,
    pub spot_turn_degrees: Option<f32>,
    pub method: String,
    pub params: String,
    #[serde(skip)]
    pub params_table: toml::Table,
    /// "ok", or why the point failed.
    pub status: String,
    pub bake: BakeCost,
    pub frame: FrameCost,
    /// None when the point failed.
    pub accuracy: Option<Accuracy>,
    /// Popping against the previous light configuration (None for the first, or a failed point).
    pub flicker: Option<f64>,
    pub non_finite_pixels: usize,
    /// On the Pareto front of (GPU frame time, NRMSE) among the points of its scene and light,
    /// errors within the scene's resolution tied (`mark_front`).
    pub on_front: bool,
    pub device: String,
    /// The stem of the point's pictures under images/.
    pub image_id: String,
}

/// The q-quantile (0..=1) of `values` by the nearest rank; NaN when there are none.
pub(crate) fn percentile(values: &[f64], q: f64) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// Sets `on_front` on every row: the Pareto front of (GPU frame time, NRMSE) among the
/// successful rows of the same scene and light configuration, errors within the scene's
/// resolution tied.
pub(crate) fn mark_front(rows: &mut [Row], resolution: &Resolution) {
    let groups: Vec<(String, usize)> = rows.iter().map(|r| (r.scene.clone(), r.light)).collect();
    for group in &groups {
        let members: Vec<usize> =
            (0..rows.len()).filter(|&i| (&rows[i].scene, rows[i].light) == (&group.0, group.1) && rows[i].accuracy.is_some()).collect();
        let points: Vec<(f64, f64)> =
            members.iter().map(|&i| (rows[i].frame.gpu_ms, rows[i].accuracy.map_or(f64::NAN, |a| a.nrmse))).collect();
        for (&i, on) in members.iter().zip(pareto::front(&points, resolution.of(&group.0))) {
            rows[i].on_front = on;
        }
    }
}

/// The CSV's columns, in order (docs/BENCH.md describes each).
/// The header: fixed columns, then `gpu_<pass>_ms` for every pass any row ran (`passes`,
/// in the order frames run them), then the errors.
pub(crate) fn csv_header(passes: &[String]) -> Vec<String> {
    let mut columns: Vec<String> = [
        "scene",
        "light",
        "light_x",
        "light_y",
        "light_z",
        "occluder_dx",
        "occluder_dy",
        "occluder_dz",
        "occluder_turn_degrees",
        "spot_outer_degrees",
        "spot_turn_degrees",
        "method",
        "params",
        "status",
        "bake_seconds",
        "bake_stages",
        "bake_peak_memory_bytes",
        "artifact_bytes",
        "gpu_frame_ms",
        "gpu_frame_p10_ms",
        "gpu_frame_p90_ms",
        "cpu_frame_ms",
    ]
    .map(String::from)
    .to_vec();
    columns.extend(passes.iter().map(|p| format!("gpu_{p}_ms")));
    columns.extend(
        ["rmse", "nrmse", "flip", "indirect_rmse", "indirect_nrmse", "indirect_flip", "flicker", "non_finite_pixels", "on_front", "device"]
            .map(String::from),
    );
    columns
}

fn csv_cells(row: &Row, passes: &[String]) -> Vec<String> {
    let optional = |v: Option<f64>| v.map(number).unwrap_or_default();
    let position = |i: usize| row.light_position.map(|p| p[i].to_string()).unwrap_or_default();
    let translation = |i: usize| row.occluder_translation.map(|t| t[i].to_string()).unwrap_or_default();
    let stages: Vec<String> = row.bake.stages.iter().map(|(name, s)| format!("{name}={s:.4}")).collect();
    let mut cells = vec![
        row.scene.clone(),
        row.light.to_string(),
        position(0),
        position(1),
        position(2),
        translation(0),
        translation(1),
        translation(2),
        row.occluder_turn_degrees.map(|t| t.to_string()).unwrap_or_default(),
        row.spot_outer_degrees.map(|t| t.to_string()).unwrap_or_default(),
        row.spot_turn_degrees.map(|t| t.to_string()).unwrap_or_default(),
        row.method.clone(),
        row.params.clone(),
        row.status.clone(),
        number(row.bake.seconds),
        stages.join(";"),
        row.bake.peak_memory_bytes.to_string(),
        row.bake.artifact_bytes.to_string(),
        number(row.frame.gpu_ms),
        number(row.frame.gpu_p10_ms),
        number(row.frame.gpu_p90_ms),
        number(row.frame.cpu_ms),
    ];
    cells.extend(passes.iter().map(|p| optional(row.frame.passes_ms.iter().find(|(name, _)| name == p).map(|(_, ms)| *ms))));
    let a = row.accuracy;
    cells.extend(
        [
            a.map(|a| a.rmse),
            a.map(|a| a.nrmse),
            a.map(|a| a.flip),
            a.map(|a| a.indirect_rmse),
            a.map(|a| a.indirect_nrmse),
            a.map(|a| a.indirect_flip),
            row.flicker,
        ]
        .map(optional),
    );
    cells.extend([row.non_finite_pixels.to_string(), row.on_front.to_string(), row.device.clone()]);
    cells
}

/// A CSV number cell; unknown figures (a failed configuration's costs) are empty, never "NaN".
pub(crate) fn number(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.6}")
    } else {
        String::new()
    }
}

/// One CSV line of `cells`, each quoted where it must be.
pub(crate) fn csv_line<S: AsRef<str>>(cells: &[S]) -> String {
    cells.iter().map(|c| quote(c.as_ref())).collect::<Vec<_>>().join(",") + "\n"
}

/// A CSV field, quoted when it holds a comma, a quote or a line break.
fn quote(cell: &str) -> String {
    if cell.contains([',', '"', '\n']) {
        format!("\"{}\"", cell.replace('"', "\"\""))
    } else {
        cell.to_string()
    }
}

/// Every pass any row ran, each once, in the order the rows' frames ran them (a pass only some
/// methods run comes after the passes before it in those rows).
fn pass_names(rows: &[Row]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for row in rows {
        let mut at = 0;
        for (name, _) in &row.frame.passes_ms {
            match names.iter().position(|n| n == name) {
                Some(i) => at = i + 1,
                None => {
                    names.insert(at, name.clone());
                    at += 1;
                }
            }
        }
    }
    names
}

pub(crate) fn csv(rows: &[Row]) -> String {
    let passes = pass_names(rows);
    std::iter::once(csv_line(&csv_header(&passes))).chain(rows.iter().map(|r| csv_line(&csv_cells(r, &passes)))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_nearest_rank() {
        let v = [5.0, 1.0, 3.0, 2.0, 4.0];
        assert_eq!((percentile(&v, 0.0), percentile(&v, 0.5), percentile(&v, 1.0)), (1.0, 3.0, 5.0));
        assert!(percentile(&[], 0.5).is_nan());
    }

    #[test]
    fn csv_fields_with_commas_are_quoted() {
        assert_eq!(quote("a,b"), "\"a,b\"");
        assert_eq!(quote("rays=64 seed=1"), "rays=64 seed=1");
        assert_eq!(quote("x\"y,"), "\"x\"\"y,\"");
    }
}
