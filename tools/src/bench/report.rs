//! The bench's outputs: results.csv, results.json, the charts, recommended.toml (with
//! `--budget`) and report.md, all in the report folder.

use super::budget::{budget_text, choose, recommend, recommended_toml, Budget, Recommendation, SceneChoice};
use super::charts::{self, Chart, Series};
use super::methods_table::{cell, method_cells, methods_rows, methods_text, MethodCell, METHODS_HEADER};
use super::overview::Overview;
use super::results::{self, percentile, Row};
use super::{pareto, Outcome, Resolution};
use anyhow::Result;
use relume_bake::outputs::Outputs;
use std::fmt::Write as _;
use std::path::Path;

/// One method configuration on one scene, over its light configurations.
pub(super) struct Summary<'r> {
    pub(super) rows: Vec<&'r Row>,
    /// Its place among its method's configurations on its scene, from 1: its label in charts.
    pub(super) number: usize,
    pub(super) mean_nrmse: f64,
    pub(super) mean_flip: f64,
    pub(super) mean_indirect_nrmse: f64,
    pub(super) max_flicker: Option<f64>,
    pub(super) gpu_ms: f64,
    /// The medians over its points of the frames' 10th and 90th percentiles.
    pub(super) gpu_p10_ms: f64,
    pub(super) gpu_p90_ms: f64,
    /// The median over its points of the frame less the shadow maps' passes.
    pub(super) gpu_without_shadow_maps_ms: f64,
    pub(super) cpu_ms: f64,
    pub(super) failed: usize,
}

impl Summary<'_> {
    pub(super) fn first(&self) -> &Row {
        self.rows[0]
    }
    /// Its points, one per light configuration.
    pub(super) fn rows(&self) -> &[&Row] {
        &self.rows
    }
    pub(super) fn artifact_mib(&self) -> f64 {
        self.first().bake.artifact_bytes as f64 / (1 << 20) as f64
    }
    pub(super) fn peak_mib(&self) -> f64 {
        self.first().bake.peak_memory_bytes as f64 / (1 << 20) as f64
    }
    /// Usable in charts and budgets: every light configuration scored.
    pub(super) fn ok(&self) -> bool {
        self.failed == 0
    }
}

pub(super) fn summaries(rows: &[Row]) -> Vec<Summary<'_>> {
    let mut keys: Vec<(&str, &str, &str)> = Vec::new();
    for r in rows {
        if !keys.contains(&(&r.scene, &r.method, &r.params)) {
            keys.push((&r.scene, &r.method, &r.params));
        }
    }
    let mut numbers: Vec<(&str, &str)> = Vec::new();
    keys.into_iter()
        .map(|key| {
            numbers.push((key.0, key.1));
            let number = numbers.iter().filter(|n| **n == (key.0, key.1)).count();
            let rows: Vec<&Row> = rows.iter().filter(|r| (r.scene.as_str(), r.method.as_str(), r.params.as_str()) == key).collect();
            let scored: Vec<_> = rows.iter().filter_map(|r| r.accuracy).collect();
            let mean = |f: &dyn Fn(&results::Accuracy) -> f64| {
                if scored.is_empty() {
                    f64::NAN
                } else {
                    scored.iter().map(f).sum::<f64>() / scored.len() as f64
                }
            };
            let flickers: Vec<f64> = rows.iter().filter_map(|r| r.flicker).collect();
            let median = |f: &dyn Fn(&Row) -> f64| percentile(&rows.iter().map(|r| f(r)).collect::<Vec<_>>(), 0.5);
            Summary {
                number,
                mean_nrmse: mean(&|a| a.nrmse),
                mean_flip: mean(&|a| a.flip),
                mean_indirect_nrmse: mean(&|a| a.indirect_nrmse),
                max_flicker: flickers.iter().copied().reduce(f64::max),
                gpu_ms: median(&|r| r.frame.gpu_ms),
                gpu_p10_ms: median(&|r| r.frame.gpu_p10_ms),
                gpu_p90_ms: median(&|r| r.frame.gpu_p90_ms),
                gpu_without_shadow_maps_ms: median(&|r| r.frame.without_shadow_maps_ms()),
                cpu_ms: median(&|r| r.frame.cpu_ms),
                failed: rows.len() - scored.len(),
                rows,
            }
        })
        .collect()
}

/// Per summary: on the Pareto front of (GPU frame time, mean NRMSE) among its scene's
/// configurations scored at every light configuration, errors within the scene's resolution
/// not told apart.
pub(super) fn fronts(summaries: &[Summary], resolution: &Resolution) -> Vec<bool> {
    summaries
        .chunk_by(|a, b| a.first().scene == b.first().scene)
        .flat_map(|of_scene| {
            let points: Vec<(f64, f64)> = of_scene.iter().map(|s| (s.gpu_ms, if s.ok() { s.mean_nrmse } else { f64::NAN })).collect();
            pareto::front(&points, resolution.of(&of_scene[0].first().scene))
        })
        .collect()
}

/// summary.csv: the report's summary table, one row per method configuration (docs/BENCH.md).
fn summary_csv(summaries: &[Summary], fronts: &[bool]) -> String {
    use results::number;
    let header = [
        "scene",
        "method",
        "params",
        "points",
        "failed",
        "mean_nrmse",
        "mean_flip",
        "mean_indirect_nrmse",
        "max_flicker",
        "gpu_frame_ms",
        "cpu_frame_ms",
        "bake_seconds",
        "bake_peak_memory_bytes",
        "artifact_bytes",
        "on_front",
    ];
    let lines = summaries.iter().zip(fronts).map(|(s, on)| {
        let row = s.first();
        let cells = [
            row.scene.clone(),
            row.method.clone(),
            row.params.clone(),
            s.rows.len().to_string(),
            s.failed.to_string(),
            number(s.mean_nrmse),
            number(s.mean_flip),
            number(s.mean_indirect_nrmse),
            s.max_flicker.map(number).unwrap_or_default(),
            number(s.gpu_ms),
            number(s.cpu_ms),
            number(row.bake.seconds),
            row.bake.peak_memory_bytes.to_string(),
            row.bake.artifact_bytes.to_string(),
            on.to_string(),
        ];
        results::csv_line(&cells)
    });
    std::iter::once(results::csv_line(&header)).chain(lines).collect()
}

/// The files `write_all` writes under the output folder, whatever the sweep.
pub(crate) const FILES: [&str; 6] = ["results.csv", "results.json", "summary.csv", "methods.csv", "recommended.toml", "report.md"];

/// Writes the results, summary, charts and report, all or none.
pub(crate) fn write_all(out: &Path, outcome: &Outcome, budget: Option<Budget>, overview: Option<&Overview>) -> Result<()> {
    let mut outputs = Outputs::new();
    let mut save = |name: &str, text: &str| outputs.bytes(&out.join(name), text.as_bytes());
    save("results.csv", &results::csv(&outcome.rows))?;
    let json = serde_json::json!({
        "sweep": outcome.sweep.name,
        "device": outcome.device,
        "relume_version": env!("CARGO_PKG_VERSION"),
        "machine": machine(),
        "warmup_seconds": outcome.sweep.warmup_seconds,
        "seconds": outcome.seconds,
        "references": { "traced": outcome.references_traced, "from_cache": outcome.references_found },
        "skipped": outcome.skipped,
        "not_applicable": outcome.not_applicable,
        "reference_noise": outcome.noise.iter().map(|(scene, n)| serde_json::json!({ "scene": scene, "nrmse": n.scene_nrmse, "indirect_nrmse": n.indirect_nrmse, "spp": n.spp })).collect::<Vec<_>>(),
        "rows": outcome.rows,
    });
    save("results.json", &serde_json::to_string_pretty(&json)?)?;
    let summaries = summaries(&outcome.rows);
    let resolution = Resolution::of_noise(&outcome.noise);
    let fronts = fronts(&summaries, &resolution);
    let cells = method_cells(&summaries, &fronts);
    save("summary.csv", &summary_csv(&summaries, &fronts))?;
    // The CSV leaves empty what the report marks "-".
    let blank = |row: [String; 13]| row.map(|c| if c == "-" { String::new() } else { c });
    let methods_csv: String = std::iter::once(results::csv_line(&METHODS_HEADER))
        .chain(methods_rows(&cells).into_iter().map(|r| results::csv_line(&blank(r))))
        .collect();
    save("methods.csv", &methods_csv)?;
    let recommendations = budget.map(|b| recommend(&summaries, &b, &resolution));
    let choices = recommendations.as_deref().zip(budget).map(|(r, b)| choose(r, &b, &resolution));
    if let (Some(recommendations), Some(choices), Some(budget)) = (&recommendations, &choices, &budget) {
        save("recommended.toml", &recommended_toml(recommendations, choices, budget))?;
    }
    let mut scenes: Vec<&str> = summaries.iter().map(|s| s.first().scene.as_str()).collect();
    scenes.dedup();
    let mut charts_md = String::new();
    for scene in &scenes {
        let of_scene: Vec<&Summary> = summaries.iter().filter(|s| s.first().scene == *scene && s.ok()).collect();
        let mut written = write_scene_charts(&mut outputs, out, scene, &of_scene, resolution.of(scene))?;
        written.extend(super::figures::write(&mut outputs, out, &outcome.sweep.charts, scene, &of_scene)?);
        for (stem, md) in written {
            let _ = writeln!(charts_md, "![{md}]({stem}.png) ([SVG]({stem}.svg))\n");
        }
    }
    let budgeted = recommendations.as_deref().zip(choices.as_deref()).zip(budget).map(|((r, c), b)| (r, c, b));
    let report = report_text(outcome, &summaries, &fronts, &cells, &charts_md, budgeted);
    outputs.bytes(&out.join("report.md"), report.as_bytes())?;
    if let Some(overview) = overview {
        let text = overview.text(out, outcome, &summaries, &cells, &scenes, budgeted);
        outputs.bytes(&overview.path, text.as_bytes())?;
    }
    outputs.commit()?;
    if recommendations.is_none() {
        // An earlier run's choices must not pass for this run's.
        remove_stale(&out.join("recommended.toml"))?;
    }
    Ok(())
}

fn remove_stale(path: &Path) -> Result<()> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(anyhow::anyhow!("{}: cannot remove the earlier run's file ({e})", path.display()))
        }
        _ => Ok(()),
    }
}

/// One chart's points per method: (x, mean NRMSE) of each of its configurations, labelled by
/// their numbers, each method in the style of its place in the registry.
fn by_method(of_scene: &[&Summary], x: impl Fn(&Summary) -> f64, resolution: f64) -> (Vec<Series>, Vec<(f64, f64)>) {
    let mut series: Vec<Series> = Vec::new();
    for s in of_scene {
        let method = &s.first().method;
        let at = match series.iter().position(|series| series.label == *method) {
            Some(at) => at,
            None => {
                let mut new = Series::new(method.clone(), Vec::new());
                new.style = method_style(method);
                series.push(new);
                series.len() - 1
            }
        };
        series[at].points.push((x(s), s.mean_nrmse));
        series[at].point_labels.push(s.number.to_string());
    }
    let points: Vec<(f64, f64)> = of_scene.iter().map(|s| (x(s), s.mean_nrmse)).collect();
    let front = pareto::front_in_cost_order(&points, resolution).into_iter().map(|i| points[i]).collect();
    (series, front)
}

/// A method's colour and marker in every chart: its place in the registry.
fn method_style(method: &str) -> Option<usize> {
    crate::methods::METHODS.iter().position(|m| m.name() == method)
}

/// A cost axis: (file-name part, axis label, the cost of a configuration).
type ChartCost<'f> = (&'static str, &'static str, &'f dyn Fn(&Summary) -> f64);

/// The scene's charts; returns (file stem, caption) of each.
fn write_scene_charts(
    outputs: &mut Outputs,
    out: &Path,
    scene: &str,
    of_scene: &[&Summary],
    resolution: f64,
) -> Result<Vec<(String, String)>> {
    if of_scene.is_empty() {
        return Ok(Vec::new());
    }
    let mut written = Vec::new();
    let costs: [ChartCost; 3] = [
        ("frame_time", "GPU frame time, ms (median)", &|s| s.gpu_ms),
        ("bake_time", "bake time, s", &|s| s.first().bake.seconds),
        ("memory", "bake artifact, MiB", &|s| s.artifact_mib()),
    ];
    for (name, x_label, x) in costs {
        let (series, front) = by_method(of_scene, x, resolution);
        let stem = format!("{scene}_error_vs_{name}");
        let title = format!("{scene}: error against {}", x_label.split(',').next().unwrap_or(name));
        charts::write(
            outputs,
            &out.join(&stem),
            &Chart {
                title: title.clone(),
                x_label,
                y_label: "NRMSE vs reference (mean over lights)",
                series,
                lines: false,
                front,
                log_log: false,
            },
        )?;
        written.push((stem, title));
    }
    if of_scene[0].rows.len() > 1 {
        let series = of_scene
            .iter()
            .map(|s| {
                let mut line = Series::new(
                    format!("{} {} [{}]", s.first().method, s.number, s.first().params),
                    s.rows.iter().filter_map(|r| r.accuracy.map(|a| (r.light as f64, a.nrmse))).collect(),
                );
                // Its method's colour and marker, as in the other charts.
                line.style = method_style(&s.first().method);
                line
            })
            .collect();
        let stem = format!("{scene}_error_along_path");
        let title = format!("{scene}: error along the path");
        charts::write(
            outputs,
            &out.join(&stem),
            &Chart {
                title: title.clone(),
                x_label: "position along the light or occluder path",
                y_label: "NRMSE vs reference",
                series,
                lines: true,
                front: Vec::new(),
                log_log: false,
            },
        )?;
        written.push((stem, title));
    }
    Ok(written)
}

pub(super) fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| text.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split(':').nth(1)).map(|s| s.trim().to_string()))
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} core(s)")
}

/// The references' samples per pixel: the sweep's, or per scene where a noise target raised them.
fn reference_samples(outcome: &Outcome) -> String {
    let raised: Vec<String> =
        outcome.noise.iter().filter(|(_, n)| n.spp != outcome.sweep.reference_spp).map(|(scene, n)| format!("{scene} {}", n.spp)).collect();
    match raised.is_empty() {
        true => format!("{} spp", outcome.sweep.reference_spp),
        false => format!(
            "{} spp ({} for the noise target {})",
            outcome.sweep.reference_spp,
            raised.join(", "),
            outcome.sweep.reference_noise_target.expect("samples are raised only towards a target")
        ),
    }
}

fn report_text(
    outcome: &Outcome,
    summaries: &[Summary],
    fronts: &[bool],
    cells: &[MethodCell],
    charts_md: &str,
    budgeted: Option<(&[Recommendation], &[SceneChoice], Budget)>,
) -> String {
    let sweep = &outcome.sweep;
    let mut r = String::new();
    let _ = writeln!(r, "# relume bench: {}\n", sweep.name);
    let _ = writeln!(r, "Device: {}. Machine: {}. relume {}.", outcome.device, machine(), env!("CARGO_PKG_VERSION"));
    let _ = writeln!(
        r,
        "Images {}x{}; reference {} at pixel centres ({} traced, {} from the cache); {} timed frames per point, in rounds over the scene's configurations, after {} s of warm-up frames (3 at least); {:.1} s in all.\n",
        sweep.width, sweep.height, reference_samples(outcome), outcome.references_traced, outcome.references_found, sweep.frames, sweep.warmup_seconds, outcome.seconds
    );
    if !outcome.skipped.is_empty() {
        let _ = writeln!(r, "**Skipped by --time-limit:** {}.\n", outcome.skipped.join("; "));
    }
    let failed: Vec<&Row> = outcome.rows.iter().filter(|r| r.accuracy.is_none()).collect();
    if !failed.is_empty() {
        let _ = writeln!(r, "## Failed points\n");
        for row in failed {
            let _ = writeln!(r, "- {} {} [{}] light {}: {}", row.scene, row.method, row.params, row.light, row.status);
        }
        let _ = writeln!(r);
    }
    methods_text(&mut r, cells, outcome);
    let _ = writeln!(r, "## Summary per method configuration\n");
    let _ = writeln!(r, "Means over the light configurations; NRMSE and FLIP against the reference's `combined`, indirect NRMSE of the image minus the direct-only frame against `indirect` (none under an environment, where the direct-only frame lacks the environment's direct light: -); flicker as docs/BENCH.md defines it (largest over the path); GPU and CPU times are medians. Front: on the Pareto front of (GPU frame time, mean NRMSE) within its scene, errors nearer than three times the references' noise tied (where measured). The label is the configuration's number in the charts.\n");
    let _ = writeln!(r, "| scene | method (label) | params | NRMSE | FLIP | indirect NRMSE | max flicker | GPU ms | CPU ms | bake s | bake peak MiB | artifact MiB | front |");
    let _ = writeln!(r, "|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for (s, &on) in summaries.iter().zip(fronts) {
        let row = s.first();
        // Means over the points that were scored: say so when some were not.
        let failed = if s.failed > 0 { format!(" ({} of {} failed)", s.failed, s.rows.len()) } else { String::new() };
        let _ = writeln!(
            r,
            "| {} | {} {} | {} | {}{failed} | {} | {} | {} | {} | {} | {:.2} | {:.1} | {:.2} | {} |",
            row.scene,
            row.method,
            s.number,
            row.params,
            cell(s.mean_nrmse, 4),
            cell(s.mean_flip, 4),
            cell(s.mean_indirect_nrmse, 4),
            s.max_flicker.map_or("-".into(), |f| format!("{f:.4}")),
            cell(s.gpu_ms, 2),
            cell(s.cpu_ms, 2),
            row.bake.seconds,
            s.peak_mib(),
            s.artifact_mib(),
            if on { "yes" } else { "" }
        );
    }
    let _ = writeln!(r, "\n## Charts\n\n{charts_md}");
    if let Some((recommendations, choices, budget)) = budgeted {
        budget_text(&mut r, recommendations, choices, &budget);
    }
    let _ = writeln!(r, "## Every point: method image, reference, false-colour error\n");
    let _ = writeln!(r, "| point | method | reference | error | NRMSE |\n|---|---|---|---|---|");
    for row in &outcome.rows {
        let reference = format!("images/{}_light{}_reference.png", row.scene, row.light);
        let _ = writeln!(
            r,
            "| {} {} [{}] light {} | ![](images/{id}.png) | ![]({reference}) | ![](images/{id}_error.png) | {} |",
            row.scene,
            row.method,
            row.params,
            row.light,
            row.accuracy.map_or(row.status.clone(), |a| format!("{:.4}", a.nrmse)),
            id = row.image_id
        );
    }
    r
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::bench::budget::tests::error;
    use crate::bench::results::{Accuracy, BakeCost, FrameCost};

    /// A point of method "m" with parameter set `params` at light `light`; `nrmse` None: failed.
    pub(crate) fn point(params: &str, light: usize, nrmse: Option<f64>) -> Row {
        let accuracy = nrmse.map(|nrmse| Accuracy {
            rmse: nrmse,
            nrmse,
            flip: nrmse,
            indirect_rmse: nrmse,
            indirect_nrmse: nrmse,
            indirect_flip: nrmse,
        });
        Row {
            scene: "s".into(),
            light,
            light_position: None,
            occluder_translation: None,
            occluder_turn_degrees: None,
            spot_outer_degrees: None,
            spot_turn_degrees: None,
            method: "m".into(),
            params: params.into(),
            params_table: toml::Table::new(),
            status: if nrmse.is_some() { "ok".into() } else { "failed: 3 NaN or infinite pixel(s)".into() },
            bake: BakeCost::default(),
            frame: FrameCost { gpu_ms: 1.0, gpu_p10_ms: 1.0, gpu_p90_ms: 1.0, cpu_ms: 1.0, passes_ms: Vec::new() },
            accuracy,
            flicker: None,
            non_finite_pixels: if nrmse.is_some() { 0 } else { 3 },
            on_front: false,
            device: "d".into(),
            image_id: format!("{params}{light}"),
        }
    }

    #[test]
    fn a_failed_point_is_reported_and_kept_out_of_fronts_and_budgets() {
        // "a" is the better configuration where it was scored, but one of its points failed.
        let rows = [point("a", 0, Some(0.1)), point("a", 1, None), point("b", 0, Some(0.3)), point("b", 1, Some(0.3))];
        let summaries = summaries(&rows);
        assert_eq!((summaries[0].failed, summaries[0].ok(), summaries[0].mean_nrmse), (1, false, 0.1));
        assert_eq!(fronts(&summaries, &Resolution::default()), [false, true]);
        let recommendations = recommend(&summaries, &error(0.5), &Resolution::default());
        assert_eq!(recommendations[0].ladder.len(), 1, "a configuration with a failed point is never recommended");
        assert_eq!(recommendations[0].ladder[0].first().params, "b");

        let csv = results::csv(&rows);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let failed: Vec<&str> =
            csv.lines().find(|l| l.contains("failed: 3 NaN")).expect("the failed point has its row").split(',').collect();
        let cell = |name: &str| failed[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!((cell("nrmse"), cell("flip"), cell("non_finite_pixels")), ("", "", "3"), "error cells empty, the NaN count kept");
        assert!(summary_csv(&summaries, &fronts(&summaries, &Resolution::default())).contains("\ns,m,a,2,1,0.100000,"));
    }
}
