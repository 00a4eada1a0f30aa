//! `relume scaling`: bakes' time and peak memory against their scenes' triangles, drawn
//! log-log with each series' fitted power law (docs/BENCHMARKS.md, "Scale sweep").

use super::charts::{self, Chart, Series};
use anyhow::{bail, Context as _, Result};
use clap::Args;
use relume_bake::outputs::Outputs;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ScalingArgs {
    /// Bake artifact folders (`relume bake --out`), each named SERIES-SIZE: the name less its
    /// last '-' part names the series it is drawn in (bake-1 ... bake-10).
    #[arg(required = true, num_args = 2..)]
    bakes: Vec<PathBuf>,
    /// The folder for scaling.md (the table and exponents) and the charts (SVG and PNG).
    #[arg(long, default_value = "out/scaling")]
    out: PathBuf,
}

/// A chart's file stem, its y axis's label and the cost it draws.
type Axis = (&'static str, &'static str, fn(&Point) -> f64);

/// One bake's size and costs, from its stats.json.
#[derive(Clone, Debug, PartialEq)]
struct Point {
    triangles: f64,
    seconds: f64,
    peak_bytes: f64,
}

/// The bakes of one series, by rising size.
#[derive(Debug, PartialEq)]
struct Line {
    name: String,
    points: Vec<Point>,
}

pub fn scaling_command(args: &ScalingArgs) -> Result<()> {
    let lines = read_lines(&args.bakes)?;
    let summary = table(&lines);
    std::fs::create_dir_all(&args.out).with_context(|| format!("{}: cannot create the folder", args.out.display()))?;
    let mut outputs = Outputs::new();
    outputs.bytes(&args.out.join("scaling.md"), summary.as_bytes())?;
    let axes: [Axis; 2] =
        [("time", "bake time, seconds (the stages' sum)", |p| p.seconds), ("memory", "peak memory, bytes", |p| p.peak_bytes)];
    for (stem, y_label, y) in axes {
        let series = lines
            .iter()
            .enumerate()
            .map(|(i, line)| {
                let points: Vec<(f64, f64)> = line.points.iter().map(|p| (p.triangles, y(p))).collect();
                let label = match exponent(&points) {
                    Some(e) => format!("{} (exponent {e:.2})", line.name),
                    None => line.name.clone(),
                };
                Series { style: Some(i), ..Series::new(label, points) }
            })
            .collect();
        let chart = Chart {
            title: format!("Bake {stem} against the scene's size"),
            x_label: "scene triangles",
            y_label,
            series,
            lines: true,
            front: Vec::new(),
            log_log: true,
        };
        charts::write(&mut outputs, &args.out.join(format!("scaling-{stem}")), &chart)?;
    }
    outputs.commit()?;
    print!("{summary}");
    println!("wrote {}", args.out.display());
    Ok(())
}

/// The bakes grouped into series by their folders' names, each by rising size.
fn read_lines(bakes: &[PathBuf]) -> Result<Vec<Line>> {
    let mut lines: Vec<Line> = Vec::new();
    for dir in bakes {
        let name = dir.file_name().and_then(|n| n.to_str()).unwrap_or_default();
        let Some((series, _)) = name.rsplit_once('-') else {
            bail!("{}: a bake folder's name must be SERIES-SIZE (bake-10), so that it joins a series", dir.display());
        };
        let point = read_point(dir)?;
        match lines.iter_mut().find(|l| l.name == series) {
            Some(line) => line.points.push(point),
            None => lines.push(Line { name: series.to_string(), points: vec![point] }),
        }
    }
    lines.iter_mut().for_each(|l| l.points.sort_by(|a, b| a.triangles.total_cmp(&b.triangles)));
    Ok(lines)
}

fn read_point(dir: &Path) -> Result<Point> {
    let path = dir.join("stats.json");
    let text = std::fs::read_to_string(&path).with_context(|| format!("{}: cannot read a bake's statistics", path.display()))?;
    let stats: Value = serde_json::from_str(&text).with_context(|| format!("{}: not JSON", path.display()))?;
    let number = |key: &str| {
        stats[key]
            .as_f64()
            .filter(|v| *v > 0.0)
            .with_context(|| format!("{}: no positive \"{key}\" (a bake of an older relume: bake it again with this one)", path.display()))
    };
    let stages = stats["stages"].as_array().with_context(|| format!("{}: no \"stages\"", path.display()))?;
    let seconds = stages.iter().map(|s| s["seconds"].as_f64().unwrap_or(0.0)).sum();
    Ok(Point { triangles: number("triangles")?, seconds, peak_bytes: number("peak_memory_bytes")? })
}

/// The least-squares slope of log y against log x: the power a cost grows with; None for
/// fewer than two sizes.
fn exponent(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points.iter().filter(|p| p.0 > 0.0 && p.1 > 0.0).map(|p| (p.0.ln(), p.1.ln())).collect();
    let n = logs.len() as f64;
    let (mx, my) = (logs.iter().map(|p| p.0).sum::<f64>() / n, logs.iter().map(|p| p.1).sum::<f64>() / n);
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    (logs.len() >= 2 && sxx > 0.0).then(|| logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>() / sxx)
}

/// The series as Markdown: each bake's size and costs, and the fitted exponents.
fn table(lines: &[Line]) -> String {
    let mut md = String::from("| series | triangles | seconds | peak MiB |\n|---|---|---|---|\n");
    for line in lines {
        for p in &line.points {
            let _ = writeln!(md, "| {} | {:.0} | {:.1} | {:.0} |", line.name, p.triangles, p.seconds, p.peak_bytes / (1u64 << 20) as f64);
        }
    }
    md.push_str("\n| series | exponent of time | exponent of peak memory |\n|---|---|---|\n");
    for line in lines {
        let fit = |y: fn(&Point) -> f64| {
            exponent(&line.points.iter().map(|p| (p.triangles, y(p))).collect::<Vec<_>>()).map_or("-".into(), |e| format!("{e:.2}"))
        };
        let _ = writeln!(md, "| {} | {} | {} |", line.name, fit(|p| p.seconds), fit(|p| p.peak_bytes));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_power_law_fits_its_exponent() {
        let points: Vec<(f64, f64)> = [1e3, 1e4, 1e5, 1e6].iter().map(|&x: &f64| (x, 3.0 * x.powf(1.5))).collect();
        assert!((exponent(&points).unwrap() - 1.5).abs() < 1e-9);
        assert_eq!(exponent(&points[..1]), None);
        assert_eq!(exponent(&[(10.0, 1.0), (10.0, 2.0)]), None);
    }

    #[test]
    fn bakes_join_series_by_name_and_old_bakes_are_refused() {
        let dir = std::env::temp_dir().join(format!("relume-scaling-{}", std::process::id()));
        let bake = |name: &str, stats: &str| {
            let folder = dir.join(name);
            std::fs::create_dir_all(&folder).unwrap();
            std::fs::write(folder.join("stats.json"), stats).unwrap();
            folder
        };
        let stats =
            |t: u32| format!(r#"{{"triangles": {t}, "peak_memory_bytes": 2048, "stages": [{{"seconds": 1.5}}, {{"seconds": 0.5}}]}}"#);
        let bakes = [bake("a-b-10", &stats(100)), bake("c-1", &stats(7)), bake("a-b-1", &stats(10))];
        let lines = read_lines(&bakes).unwrap();
        assert_eq!(lines.iter().map(|l| (l.name.as_str(), l.points.len())).collect::<Vec<_>>(), [("a-b", 2), ("c", 1)]);
        assert_eq!(lines[0].points[0], Point { triangles: 10.0, seconds: 2.0, peak_bytes: 2048.0 });
        let old = bake("old-1", r#"{"peak_memory_bytes": 2048, "stages": []}"#);
        let error = read_lines(&[old]).unwrap_err().to_string();
        assert!(error.contains("old-1/stats.json") && error.contains("\"triangles\"") && error.contains("bake it again"), "{error}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
