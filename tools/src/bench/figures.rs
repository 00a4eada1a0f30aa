//! A sweep's own charts of one method (`[[charts]]`, docs/BENCH.md): its error against one of
//! its parameters (a paper's "error against vectors" figure), against what a scene's light
//! configurations vary (a spot sweep's cone or turn), or a statistic its bakes recorded (a
//! paper's spectrum).

use super::charts::{self, Chart, Series};
use super::report::Summary;
use super::results::Row;
use super::sweep::SweepChart;
use anyhow::Result;
use relume_bake::outputs::Outputs;
use std::path::Path;

/// The scene's charts of `charts` that have points; returns (file stem, caption) of each.
pub(crate) fn write(
    outputs: &mut Outputs,
    out: &Path,
    charts: &[SweepChart],
    scene: &str,
    of_scene: &[&Summary],
) -> Result<Vec<(String, String)>> {
    let mut written = Vec::new();
    for chart in charts {
        let of_method: Vec<&Summary> = of_scene.iter().copied().filter(|s| s.first().method == chart.method).collect();
        let (stem, drawn) = match (&chart.x, &chart.statistic) {
            (Some(x), _) if CONFIGURATION_VARIABLES.contains(&x.as_str()) => {
                (format!("{scene}_{}_indirect_error_vs_{x}", chart.method), against_configuration(&of_method, x))
            }
            (Some(x), _) => (format!("{scene}_{}_indirect_error_vs_{x}", chart.method), against_parameter(&of_method, x)),
            (_, Some(statistic)) => (format!("{scene}_{}_{statistic}", chart.method), statistic_lines(&of_method, statistic)),
            (None, None) => continue,
        };
        let Some(mut drawn) = drawn else {
            eprintln!("{scene}: chart {stem} skipped: no configuration of {} has points for it", chart.method);
            continue;
        };
        drawn.title = format!("{scene}: {}", drawn.title);
        charts::write(outputs, &out.join(&stem), &drawn)?;
        written.push((stem, drawn.title));
    }
    Ok(written)
}

/// A parameter's value as a number (counts and numbers; true is 1).
fn number(value: &toml::Value) -> Option<f64> {
    match value {
        toml::Value::Integer(i) => Some(*i as f64),
        toml::Value::Float(f) => Some(*f),
        toml::Value::Boolean(b) => Some(*b as u8 as f64),
        _ => None,
    }
}

/// Mean indirect NRMSE against parameter `x`, a line per set of the other parameters.
fn against_parameter<'a>(of_method: &[&Summary], x: &'a str) -> Option<Chart<'a>> {
    let mut series: Vec<Series> = Vec::new();
    for s in of_method {
        let table = &s.first().params_table;
        // Under an environment no indirect part is told apart: nothing to draw.
        let Some(at) = table.get(x).and_then(number).filter(|_| s.mean_indirect_nrmse.is_finite()) else { continue };
        let others: Vec<String> = table.iter().filter(|(k, _)| *k != x).map(|(k, v)| format!("{k} = {v}")).collect();
        let label = if others.is_empty() { "defaults".to_string() } else { others.join(", ") };
        match series.iter_mut().find(|line| line.label == label) {
            Some(line) => line.points.push((at, s.mean_indirect_nrmse)),
            None => series.push(Series::new(label, vec![(at, s.mean_indirect_nrmse)])),
        }
    }
    series.iter_mut().for_each(|line| line.points.sort_by(|a, b| a.0.total_cmp(&b.0)));
    (!series.is_empty()).then(|| Chart {
        title: format!("{} indirect error against {x}", of_method[0].first().method),
        x_label: x,
        y_label: "indirect NRMSE vs reference (mean over lights)",
        series,
        lines: true,
        front: Vec::new(),
        log_log: false,
    })
}

/// What a scene's light configurations vary, by the name a chart's `x` gives it.
pub(crate) const CONFIGURATION_VARIABLES: [&str; 2] = ["spot_outer_degrees", "spot_turn_degrees"];

/// Each light configuration's indirect NRMSE against the value it varies (`x`, one of
/// [`CONFIGURATION_VARIABLES`]), a line per configuration of the method.
fn against_configuration<'a>(of_method: &[&Summary], x: &'a str) -> Option<Chart<'a>> {
    let value = |row: &Row| match x {
        "spot_outer_degrees" => row.spot_outer_degrees,
        _ => row.spot_turn_degrees,
    };
    let mut series = Vec::new();
    for s in of_method {
        let mut points: Vec<(f64, f64)> = s
            .rows()
            .iter()
            .filter_map(|r| Some((value(r)? as f64, r.accuracy.as_ref()?.indirect_nrmse)))
            .filter(|p| p.1.is_finite())
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        let label = if s.first().params.is_empty() { "defaults".to_string() } else { s.first().params.clone() };
        // A line needs the configurations to vary what it is drawn against.
        if points.windows(2).any(|w| w[0].0 != w[1].0) {
            series.push(Series::new(label, points));
        }
    }
    (!series.is_empty()).then(|| Chart {
        title: format!("{} indirect error against {x}", of_method[0].first().method),
        x_label: x,
        y_label: "indirect NRMSE vs reference",
        series,
        lines: true,
        front: Vec::new(),
        log_log: false,
    })
}

/// Each number array of the bakes' statistic `name` against its index, a line per array and
/// configuration.
fn statistic_lines<'a>(of_method: &[&Summary], name: &'a str) -> Option<Chart<'a>> {
    let mut series = Vec::new();
    for s in of_method {
        let Some(arrays) = s.first().bake.statistics[name].as_object() else { continue };
        for (key, values) in arrays {
            let points: Vec<(f64, f64)> =
                values.as_array().into_iter().flatten().enumerate().filter_map(|(i, v)| Some(((i + 1) as f64, v.as_f64()?))).collect();
            if points.is_empty() {
                continue;
            }
            let params = &s.first().params;
            series.push(Series::new(if params.is_empty() { key.clone() } else { format!("{key} [{params}]") }, points));
        }
    }
    (!series.is_empty()).then(|| Chart {
        title: format!("{} {name}", of_method[0].first().method),
        x_label: "index (from 1)",
        y_label: name,
        series,
        lines: true,
        front: Vec::new(),
        log_log: false,
    })
}
