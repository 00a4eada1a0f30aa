//! The bench's outputs: results.csv, results.json, the charts, recommended.toml (with
//! `--budget`) and report.md, all in the report folder.

use super::charts::{self, Chart, Series};
use super::results::{self, percentile, Row};
use super::{pareto, Outcome};
use anyhow::Result;
use relume_bake::outputs::Outputs;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One method configuration on one scene, over its light configurations.
pub(super) struct Summary<'r> {
    rows: Vec<&'r Row>,
    /// Its place among its method's configurations on its scene, from 1: its label in charts.
    number: usize,
    mean_nrmse: f64,
    mean_flip: f64,
    pub(super) mean_indirect_nrmse: f64,
    max_flicker: Option<f64>,
    gpu_ms: f64,
    /// The medians over its points of the frames' 10th and 90th percentiles.
    gpu_p10_ms: f64,
    gpu_p90_ms: f64,
    /// The median over its points of the frame less the shadow maps' passes.
    gpu_without_shadow_maps_ms: f64,
    cpu_ms: f64,
    failed: usize,
}

impl Summary<'_> {
    pub(super) fn first(&self) -> &Row {
        self.rows[0]
    }
    /// Its points, one per light configuration.
    pub(super) fn rows(&self) -> &[&Row] {
        &self.rows
    }
    fn artifact_mib(&self) -> f64 {
        self.first().bake.artifact_bytes as f64 / (1 << 20) as f64
    }
    fn peak_mib(&self) -> f64 {
        self.first().bake.peak_memory_bytes as f64 / (1 << 20) as f64
    }
    /// Usable in charts and budgets: every light configuration scored.
    fn ok(&self) -> bool {
        self.failed == 0
    }
}

fn summaries(rows: &[Row]) -> Vec<Summary<'_>> {
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
/// configurations scored at every light configuration.
fn fronts(summaries: &[Summary]) -> Vec<bool> {
    summaries
        .chunk_by(|a, b| a.first().scene == b.first().scene)
        .flat_map(|of_scene| {
            pareto::front(&of_scene.iter().map(|s| (s.gpu_ms, if s.ok() { s.mean_nrmse } else { f64::NAN })).collect::<Vec<_>>())
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
        "reference_noise": outcome.noise.iter().map(|(scene, n)| serde_json::json!({ "scene": scene, "nrmse": n.scene_nrmse, "indirect_nrmse": n.indirect_nrmse })).collect::<Vec<_>>(),
        "rows": outcome.rows,
    });
    save("results.json", &serde_json::to_string_pretty(&json)?)?;
    let summaries = summaries(&outcome.rows);
    let fronts = fronts(&summaries);
    let cells = method_cells(&summaries, &fronts);
    save("summary.csv", &summary_csv(&summaries, &fronts))?;
    // The CSV leaves empty what the report marks "-".
    let blank = |row: [String; 13]| row.map(|c| if c == "-" { String::new() } else { c });
    let methods_csv: String = std::iter::once(results::csv_line(&METHODS_HEADER))
        .chain(methods_rows(&cells).into_iter().map(|r| results::csv_line(&blank(r))))
        .collect();
    save("methods.csv", &methods_csv)?;
    let recommendations = budget.map(|b| recommend(&summaries, &b));
    let choices = recommendations.as_deref().zip(budget).map(|(r, b)| choose(r, &b));
    if let (Some(recommendations), Some(choices), Some(budget)) = (&recommendations, &choices, &budget) {
        save("recommended.toml", &recommended_toml(recommendations, choices, budget))?;
    }
    let mut scenes: Vec<&str> = summaries.iter().map(|s| s.first().scene.as_str()).collect();
    scenes.dedup();
    let mut charts_md = String::new();
    for scene in &scenes {
        let of_scene: Vec<&Summary> = summaries.iter().filter(|s| s.first().scene == *scene && s.ok()).collect();
        let mut written = write_scene_charts(&mut outputs, out, scene, &of_scene)?;
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

/// `relume bench --overview`: one page that leads with the budget's answer and the charts
/// across methods, then the table across methods, and links the reports given (the main job's
/// out/report.md).
pub(crate) struct Overview {
    pub path: PathBuf,
    pub links: Vec<PathBuf>,
}

impl Overview {
    /// `target` as a link from the overview's folder.
    fn link(&self, target: &Path) -> String {
        let folder = self.path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        relative(target, folder).display().to_string()
    }

    fn text(
        &self,
        out: &Path,
        outcome: &Outcome,
        summaries: &[Summary],
        cells: &[MethodCell],
        scenes: &[&str],
        budgeted: Option<(&[Recommendation], &[SceneChoice], Budget)>,
    ) -> String {
        let mut r = String::new();
        let _ = writeln!(r, "# relume: every method against the reference\n");
        let _ = writeln!(
            r,
            "The sweep `{}` on {}: every method that applies on each scene, at a small ladder of configurations, against the reference path tracer. Device: {}. Machine: {}. The whole sweep: [{}]({}).\n",
            outcome.sweep.name,
            scenes.join(", "),
            outcome.device,
            machine(),
            self.link(&out.join("report.md")),
            self.link(&out.join("report.md"))
        );
        if let Some((recommendations, choices, budget)) = budgeted {
            let _ = writeln!(r, "## The budget's answer: {}\n", budget.text());
            scene_choices_text(&mut r, recommendations, choices);
            let _ = writeln!(r, "\n`relume bake SCENE --recommended {0}` bakes a scene's choice; `relume run SCENE --recommended {0}` bakes and renders it against the reference.\n", out.join("recommended.toml").display());
        }
        let _ = writeln!(r, "## Error against frame time, every method\n");
        for scene in scenes {
            let stem = out.join(format!("{scene}_error_vs_frame_time"));
            // write_scene_charts drew it where the scene has a configuration scored throughout.
            if summaries.iter().any(|s| s.first().scene == *scene && s.ok()) {
                let _ = writeln!(r, "![{scene}]({}.png)\n", self.link(&stem));
            }
        }
        methods_text(&mut r, cells, outcome);
        if !self.links.is_empty() {
            let _ = writeln!(r, "## Each scene's own report\n");
            for link in &self.links {
                let _ = writeln!(r, "- [{0}]({0})", self.link(link));
            }
        }
        r
    }
}

/// `target` as a path relative to the folder `from` (both as given, from the working folder):
/// the common folders dropped, a `..` for each folder of `from` left.
fn relative(target: &Path, from: &Path) -> PathBuf {
    // The folders from the root, `..` resolved by name (the report's folders are no links).
    let parts = |p: &Path| -> Vec<std::ffi::OsString> {
        let whole = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        let mut parts = Vec::new();
        for c in whole.components() {
            match c {
                std::path::Component::Normal(name) => parts.push(name.to_os_string()),
                std::path::Component::ParentDir => {
                    parts.pop();
                }
                _ => {}
            }
        }
        parts
    };
    let (target, from) = (parts(target), parts(from));
    let common = target.iter().zip(&from).take_while(|(a, b)| a == b).count();
    let mut path: PathBuf = from[common..].iter().map(|_| "..").collect();
    path.extend(&target[common..]);
    path
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
fn by_method(of_scene: &[&Summary], x: impl Fn(&Summary) -> f64) -> (Vec<Series>, Vec<(f64, f64)>) {
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
    let front = pareto::front_in_cost_order(&points).into_iter().map(|i| points[i]).collect();
    (series, front)
}

/// A method's colour and marker in every chart: its place in the registry.
fn method_style(method: &str) -> Option<usize> {
    crate::methods::METHODS.iter().position(|m| m.name() == method)
}

/// A cost axis: (file-name part, axis label, the cost of a configuration).
type ChartCost<'f> = (&'static str, &'static str, &'f dyn Fn(&Summary) -> f64);

/// The scene's charts; returns (file stem, caption) of each.
fn write_scene_charts(outputs: &mut Outputs, out: &Path, scene: &str, of_scene: &[&Summary]) -> Result<Vec<(String, String)>> {
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
        let (series, front) = by_method(of_scene, x);
        let stem = format!("{scene}_error_vs_{name}");
        let title = format!("{scene}: error against {}", x_label.split(',').next().unwrap_or(name));
        charts::write(
            outputs,
            &out.join(&stem),
            &Chart { title: title.clone(), x_label, y_label: "NRMSE vs reference (mean over lights)", series, lines: false, front },
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
            },
        )?;
        written.push((stem, title));
    }
    Ok(written)
}

/// The `--budget` choice for one scene and method.
pub(crate) struct Recommendation<'s> {
    scene: &'s str,
    method: &'s str,
    /// The method's configurations in cost order.
    ladder: Vec<&'s Summary<'s>>,
    chosen: Option<usize>,
}

/// The budget's cost order: artifact size (to 3 significant digits, so that bytes of
/// compression noise do not rank configurations), then bake time, then GPU frame time.
fn cost_order(a: &Summary, b: &Summary) -> std::cmp::Ordering {
    let size = |s: &Summary| format!("{:.2e}", s.first().bake.artifact_bytes as f64).parse::<f64>().unwrap_or(f64::NAN);
    size(a).total_cmp(&size(b)).then(a.first().bake.seconds.total_cmp(&b.first().bake.seconds)).then(a.gpu_ms.total_cmp(&b.gpu_ms))
}

/// `relume bench --budget`: a bound on the error, under which the cheapest configuration is
/// chosen, and bounds on the frame time and the artifact's size, beyond which none is; with
/// no bound on the error, the most accurate within the others is chosen.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Budget {
    pub nrmse: Option<f64>,
    pub frame_ms: Option<f64>,
    pub artifact_mib: Option<f64>,
}

impl Budget {
    /// None when no bound is given.
    pub fn given(self) -> Option<Budget> {
        (self.nrmse.is_some() || self.frame_ms.is_some() || self.artifact_mib.is_some()).then_some(self)
    }

    fn within(&self, s: &Summary) -> bool {
        let under = |bound: Option<f64>, value: f64| bound.is_none_or(|b| value <= b);
        under(self.nrmse, s.mean_nrmse) && under(self.frame_ms, s.gpu_ms) && under(self.artifact_mib, s.artifact_mib())
    }

    /// Of two configurations within the budget, the better first: the cheaper under a bound on
    /// the error, else the more accurate.
    fn order(&self, a: &Summary, b: &Summary) -> std::cmp::Ordering {
        match self.nrmse {
            Some(_) => cost_order(a, b),
            None => a.mean_nrmse.total_cmp(&b.mean_nrmse).then(cost_order(a, b)),
        }
    }

    /// What it asks, in words.
    fn text(&self) -> String {
        let bounds: Vec<String> = [
            self.nrmse.map(|b| format!("NRMSE <= {b}")),
            self.frame_ms.map(|b| format!("GPU frame <= {b} ms")),
            self.artifact_mib.map(|b| format!("artifact <= {b} MiB")),
        ]
        .into_iter()
        .flatten()
        .collect();
        let goal = if self.nrmse.is_some() { "the cheapest" } else { "the most accurate" };
        format!("{goal} within {}", bounds.join(", "))
    }
}

/// Per scene and method: the configurations in cost order, and the best within the budget.
fn recommend<'s>(summaries: &'s [Summary<'s>], budget: &Budget) -> Vec<Recommendation<'s>> {
    let mut recommendations: Vec<Recommendation> = Vec::new();
    for s in summaries.iter().filter(|s| s.ok()) {
        let row = s.first();
        match recommendations.iter_mut().find(|r| r.scene == row.scene && r.method == row.method) {
            Some(r) => r.ladder.push(s),
            None => recommendations.push(Recommendation { scene: &row.scene, method: &row.method, ladder: vec![s], chosen: None }),
        }
    }
    for r in &mut recommendations {
        r.ladder.sort_by(|a, b| cost_order(a, b));
        r.chosen = (0..r.ladder.len()).filter(|&i| budget.within(r.ladder[i])).min_by(|&a, &b| budget.order(r.ladder[a], r.ladder[b]));
    }
    recommendations
}

/// The budget's choice for one scene across its methods: of each method's choice, the best
/// (`Budget::order`); the next best method within the budget beside it. Without any within
/// the budget, neither.
pub(crate) struct SceneChoice<'s> {
    scene: &'s str,
    /// Indices into the recommendations: the chosen method's, then the next cheapest's.
    chosen: Option<usize>,
    runner_up: Option<usize>,
}

/// Per scene, in the order the scenes ran: the method the budget picks (the best of the
/// methods' choices) and the next best within the budget.
fn choose<'s>(recommendations: &[Recommendation<'s>], budget: &Budget) -> Vec<SceneChoice<'s>> {
    let mut scenes: Vec<&str> = recommendations.iter().map(|r| r.scene).collect();
    scenes.dedup();
    scenes
        .into_iter()
        .map(|scene| {
            let mut within: Vec<usize> =
                (0..recommendations.len()).filter(|&i| recommendations[i].scene == scene && recommendations[i].chosen.is_some()).collect();
            within.sort_by(|&a, &b| budget.order(recommendations[a].choice().unwrap(), recommendations[b].choice().unwrap()));
            SceneChoice { scene, chosen: within.first().copied(), runner_up: within.get(1).copied() }
        })
        .collect()
}

impl<'s> Recommendation<'s> {
    /// The configuration chosen within the budget.
    fn choice(&self) -> Option<&'s Summary<'s>> {
        self.chosen.map(|i| self.ladder[i])
    }
}

fn recommended_toml(recommendations: &[Recommendation], choices: &[SceneChoice], budget: &Budget) -> String {
    let mut root = toml::Table::new();
    for c in choices {
        if let Some(i) = c.chosen {
            let mut scene = toml::Table::new();
            scene.insert("method".into(), toml::Value::String(recommendations[i].method.to_string()));
            root.insert(c.scene.to_string(), toml::Value::Table(scene));
        }
    }
    for r in recommendations {
        let Some(chosen) = r.chosen else { continue };
        let s = r.ladder[chosen];
        let scene = root.entry(r.scene.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
        let mut entry = toml::Table::new();
        entry.insert("params".into(), toml::Value::Table(s.first().params_table.clone()));
        entry.insert("mean_nrmse".into(), toml::Value::Float(s.mean_nrmse));
        entry.insert("artifact_mib".into(), toml::Value::Float(s.artifact_mib()));
        entry.insert("bake_seconds".into(), toml::Value::Float(s.first().bake.seconds));
        entry.insert("gpu_frame_ms".into(), toml::Value::Float(s.gpu_ms));
        if let toml::Value::Table(scene) = scene {
            scene.insert(r.method.to_string(), toml::Value::Table(entry));
        }
    }
    format!(
        "# relume bench, the budget: {}.\n# Per scene the method whose choice is best of all (`method`), and per method its best parameter set.\n{}",
        budget.text(),
        toml::to_string(&root).unwrap_or_default()
    )
}

fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|text| text.lines().find(|l| l.starts_with("model name")).and_then(|l| l.split(':').nth(1)).map(|s| s.trim().to_string()))
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    format!("{cpu}, {cores} core(s)")
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
        "Images {}x{}; reference {} spp at pixel centres ({} traced, {} from the cache); {} timed frames per point after {} s of warm-up frames (3 at least); {:.1} s in all.\n",
        sweep.width, sweep.height, sweep.reference_spp, outcome.references_traced, outcome.references_found, sweep.frames, sweep.warmup_seconds, outcome.seconds
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
    let _ = writeln!(r, "Means over the light configurations; NRMSE and FLIP against the reference's `combined`, indirect NRMSE of the image minus the direct-only frame against `indirect` (none under an environment, where the direct-only frame lacks the environment's direct light: -); flicker as docs/BENCH.md defines it (largest over the path); GPU and CPU times are medians. Front: on the Pareto front of (GPU frame time, mean NRMSE) within its scene. The label is the configuration's number in the charts.\n");
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

/// A number with `decimals`, or "-" where it means nothing (NaN).
fn cell(value: f64, decimals: usize) -> String {
    if value.is_finite() {
        format!("{value:.decimals$}")
    } else {
        "-".into()
    }
}

/// One method on one scene: its configurations, the most accurate first.
struct MethodCell<'a, 's> {
    configurations: Vec<(&'a Summary<'s>, bool)>,
}

impl MethodCell<'_, '_> {
    fn best(&self) -> &Summary<'_> {
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
fn method_cells<'a, 's>(summaries: &'a [Summary<'s>], fronts: &[bool]) -> Vec<MethodCell<'a, 's>> {
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
fn methods_rows(cells: &[MethodCell]) -> Vec<[String; 13]> {
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

const METHODS_HEADER: [&str; 13] = [
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

fn methods_text(r: &mut String, cells: &[MethodCell], outcome: &Outcome) {
    let _ = writeln!(r, "## Across methods\n");
    let _ = writeln!(r, "Per scene and method: the lowest mean NRMSE of its configurations and the costs of that configuration (its label), the lowest mean indirect NRMSE of any, and which of its configurations are on the scene's Pareto front of (GPU frame time, mean NRMSE). Empty cells mean nothing for the method or scene (-). Also in methods.csv.\n");
    let _ = writeln!(r, "| {} |\n|{}", METHODS_HEADER.join(" | "), "---|".repeat(METHODS_HEADER.len()));
    for row in methods_rows(cells) {
        let _ = writeln!(r, "| {} |", row.join(" | "));
    }
    noise_text(r, cells, &outcome.noise);
    timing_text(r, cells);
    if !outcome.not_applicable.is_empty() {
        let _ = writeln!(r, "\nNot run where they do not apply:\n");
        for line in &outcome.not_applicable {
            let _ = writeln!(r, "- {line}");
        }
    }
    let _ = writeln!(r);
}

/// Per scene that measured it, the references' own noise, and the methods whose best NRMSE is
/// nearer the scene's best than three times that noise: not told apart by this reference.
fn noise_text(r: &mut String, cells: &[MethodCell], noise: &[(String, super::ReferenceNoise)]) {
    if noise.is_empty() {
        return;
    }
    let _ = writeln!(r, "\nThe references' own noise (the first light configuration traced again with the next seed: their NRMSE / sqrt 2), beside the errors ranked:\n");
    for (scene, n) in noise {
        let mut bests: Vec<(f64, &str)> = cells
            .iter()
            .filter(|c| c.best().first().scene == *scene)
            .map(|c| (c.best().mean_nrmse, c.best().first().method.as_str()))
            .collect();
        bests.sort_by(|a, b| a.0.total_cmp(&b.0));
        let close: Vec<&str> =
            bests.iter().skip(1).filter(|b| bests.first().is_some_and(|first| b.0 - first.0 < 3.0 * n.scene_nrmse)).map(|b| b.1).collect();
        let verdict = match (bests.first(), close.is_empty()) {
            _ if bests.len() < 2 || !n.scene_nrmse.is_finite() => String::new(),
            (Some(first), false) => format!("; within 3x the noise of the best ({}): {}", first.1, close.join(", ")),
            (Some(first), true) => format!("; the best ({}) is apart from the rest by more than 3x the noise", first.1),
            (None, _) => String::new(),
        };
        let _ = writeln!(r, "- {scene}: image NRMSE {:.4}, indirect {}{verdict}", n.scene_nrmse, cell(n.indirect_nrmse, 4));
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

/// A configuration as the budget's text names it.
fn describe(s: &Summary) -> String {
    format!(
        "{} [{}] NRMSE {:.4}, {:.2} MiB, bake {:.2} s, {:.2} ms",
        s.first().method,
        s.first().params,
        s.mean_nrmse,
        s.artifact_mib(),
        s.first().bake.seconds,
        s.gpu_ms
    )
}

/// The report's budget section: per scene the method chosen across methods, the next best
/// and what one step more of the chosen method buys; then per scene and method.
fn budget_text(r: &mut String, recommendations: &[Recommendation], choices: &[SceneChoice], budget: &Budget) {
    let _ = writeln!(r, "## The budget: {}\n", budget.text());
    let _ = writeln!(r, "Per scene, across methods: the best of each method's choice (below), the next best method within the budget, and what one step dearer of the chosen method would cost and give. Written to recommended.toml as the scene's `method`.\n");
    scene_choices_text(r, recommendations, choices);
    let _ = writeln!(r, "\nPer scene and method, the configurations in order of cost (artifact size to 3 digits, then bake time, then GPU frame time); the best within the budget is chosen and written to recommended.toml.\n");
    for rec in recommendations {
        match rec.chosen {
            Some(i) => {
                let smaller = if i > 0 { describe(rec.ladder[i - 1]) } else { "none".into() };
                let larger = rec.ladder.get(i + 1).map_or("none".into(), |s| describe(s));
                let _ = writeln!(
                    r,
                    "- {} {}: **{}**; one step smaller: {smaller}; one step larger: {larger}",
                    rec.scene,
                    rec.method,
                    describe(rec.ladder[i])
                );
            }
            None => {
                let best = rec.ladder.iter().min_by(|a, b| a.mean_nrmse.total_cmp(&b.mean_nrmse)).map_or(String::new(), |s| describe(s));
                let _ = writeln!(r, "- {} {}: no configuration within the budget (the best: {best})", rec.scene, rec.method);
            }
        }
    }
    let _ = writeln!(r);
}

/// The budget's answer per scene: the method chosen, the next best, one step dearer.
fn scene_choices_text(r: &mut String, recommendations: &[Recommendation], choices: &[SceneChoice]) {
    for c in choices {
        let Some(i) = c.chosen else {
            let best = recommendations
                .iter()
                .filter(|rec| rec.scene == c.scene)
                .flat_map(|rec| rec.ladder.iter())
                .min_by(|a, b| a.mean_nrmse.total_cmp(&b.mean_nrmse));
            let _ = writeln!(
                r,
                "- {}: no method within the budget (the most accurate: {})",
                c.scene,
                best.map_or("none".into(), |s| describe(s))
            );
            continue;
        };
        let rec = &recommendations[i];
        let next = c.runner_up.and_then(|j| recommendations[j].choice()).map_or("no other method within the budget".into(), describe);
        let more = rec.chosen.and_then(|k| rec.ladder.get(k + 1)).map_or("none".into(), |s| describe(s));
        let _ =
            writeln!(r, "- {}: **{}**; the next best method: {next}; one step dearer: {more}", c.scene, describe(rec.choice().unwrap()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::results::{Accuracy, BakeCost, FrameCost};

    fn error(nrmse: f64) -> Budget {
        Budget { nrmse: Some(nrmse), ..Budget::default() }
    }

    /// A point of method "m" with parameter set `params` at light `light`; `nrmse` None: failed.
    fn point(params: &str, light: usize, nrmse: Option<f64>) -> Row {
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
        assert_eq!(fronts(&summaries), [false, true]);
        let recommendations = recommend(&summaries, &error(0.5));
        assert_eq!(recommendations[0].ladder.len(), 1, "a configuration with a failed point is never recommended");
        assert_eq!(recommendations[0].ladder[0].first().params, "b");

        let csv = results::csv(&rows);
        let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
        let failed: Vec<&str> =
            csv.lines().find(|l| l.contains("failed: 3 NaN")).expect("the failed point has its row").split(',').collect();
        let cell = |name: &str| failed[header.iter().position(|h| *h == name).unwrap()];
        assert_eq!((cell("nrmse"), cell("flip"), cell("non_finite_pixels")), ("", "", "3"), "error cells empty, the NaN count kept");
        assert!(summary_csv(&summaries, &fronts(&summaries)).contains("\ns,m,a,2,1,0.100000,"));
    }

    /// Across methods, the budget picks the cheaper of two methods when both meet it, and the
    /// more accurate when only one does; recommended.toml names it; with none within it, the
    /// report names the most accurate.
    #[test]
    fn the_budget_picks_the_cheaper_method_within_it_and_else_the_one_that_meets_it() {
        let of = |method: &str, params: &str, nrmse: f64, bytes: u64| Row {
            method: method.into(),
            bake: BakeCost { artifact_bytes: bytes, ..BakeCost::default() },
            ..point(params, 0, Some(nrmse))
        };
        let rows = [of("small", "a", 0.15, 1_000), of("small", "b", 0.12, 4_000), of("large", "c", 0.05, 50_000)];
        let summaries = summaries(&rows);
        let recommendations = recommend(&summaries, &error(0.2));
        let choices = choose(&recommendations, &error(0.2));
        assert_eq!(choices.len(), 1);
        let chosen = &recommendations[choices[0].chosen.unwrap()];
        assert_eq!((chosen.method, chosen.choice().unwrap().first().params.as_str()), ("small", "a"), "both meet 0.2: the cheaper");
        assert_eq!(recommendations[choices[0].runner_up.unwrap()].method, "large");
        let written: toml::Table = toml::from_str(&recommended_toml(&recommendations, &choices, &error(0.2))).unwrap();
        assert_eq!(written["s"]["method"].as_str(), Some("small"));
        assert_eq!(written["s"]["large"]["mean_nrmse"].as_float(), Some(0.05));

        let recommendations = recommend(&summaries, &error(0.1));
        let choices = choose(&recommendations, &error(0.1));
        assert_eq!(recommendations[choices[0].chosen.unwrap()].method, "large", "only the dearer meets 0.1");
        assert!(choices[0].runner_up.is_none());

        let recommendations = recommend(&summaries, &error(0.01));
        let choices = choose(&recommendations, &error(0.01));
        assert!(choices[0].chosen.is_none());
        let mut text = String::new();
        budget_text(&mut text, &recommendations, &choices, &error(0.01));
        assert!(text.contains("- s: no method within the budget (the most accurate: large [c] NRMSE 0.0500"), "{text}");
    }

    #[test]
    fn overview_links_are_relative_to_its_folder() {
        assert_eq!(relative(Path::new("out/bench/report.md"), Path::new("out")), Path::new("bench/report.md"));
        assert_eq!(relative(Path::new("out/cornell/report.md"), Path::new("docs/../out/x")), Path::new("../cornell/report.md"));
        assert_eq!(relative(Path::new("a.png"), Path::new(".")), Path::new("a.png"));
        let page = Overview { path: PathBuf::from("overview.md"), links: Vec::new() };
        assert_eq!(page.link(Path::new("out/report.md")), "out/report.md");
    }

    /// With bounds on the frame time and the artifact and none on the error, the budget picks
    /// the most accurate configuration within them, across methods.
    #[test]
    fn a_budget_on_frame_time_and_memory_picks_the_most_accurate_within_it() {
        let of = |method: &str, params: &str, nrmse: f64, mib: u64, ms: f64| Row {
            method: method.into(),
            bake: BakeCost { artifact_bytes: mib << 20, ..BakeCost::default() },
            frame: FrameCost { gpu_ms: ms, gpu_p10_ms: ms, gpu_p90_ms: ms, cpu_ms: ms, passes_ms: Vec::new() },
            ..point(params, 0, Some(nrmse))
        };
        let rows = [
            of("fast", "a", 0.30, 1, 0.5),
            of("fast", "b", 0.20, 8, 1.5),
            of("exact", "c", 0.05, 12, 3.0),
            of("exact", "d", 0.10, 32, 1.0),
            of("exact", "e", 0.15, 4, 1.8),
        ];
        let summaries = summaries(&rows);
        let budget = Budget { frame_ms: Some(2.0), artifact_mib: Some(16.0), ..Budget::default() };
        let recommendations = recommend(&summaries, &budget);
        let choices = choose(&recommendations, &budget);
        let chosen = recommendations[choices[0].chosen.unwrap()].choice().unwrap();
        assert_eq!(chosen.first().params, "e", "c is too slow, d too large: e is the most accurate within both");
        assert_eq!(recommendations[choices[0].runner_up.unwrap()].choice().unwrap().first().params, "b");
        assert_eq!(budget.text(), "the most accurate within GPU frame <= 2 ms, artifact <= 16 MiB");
        let tight = Budget { frame_ms: Some(0.1), ..Budget::default() };
        assert!(choose(&recommend(&summaries, &tight), &tight)[0].chosen.is_none());
    }
}
