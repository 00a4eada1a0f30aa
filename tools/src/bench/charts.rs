//! The bench's charts, each written as SVG and PNG from one drawing: points (or lines) per
//! method configuration, and optionally the Pareto front as a staircase.

use anyhow::{bail, Result};
use plotters::coord::Shift;
use plotters::prelude::*;
use relume_bake::image::write_png_rgb8;
use relume_bake::outputs::Outputs;
use std::path::Path;
use std::sync::OnceLock;

/// Where Debian's fonts-dejavu-core puts the font the charts' text is set in.
const FONT_FILE: &str = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";
const FONT: &str = "sans-serif";
const SIZE: (u32, u32) = (900, 560);

pub(crate) struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Its colour and marker, by index (None: its place among the chart's series), so that
    /// one method looks the same in every chart.
    pub style: Option<usize>,
    /// A short label written beside each point (none when empty).
    pub point_labels: Vec<String>,
}

impl Series {
    pub fn new(label: String, points: Vec<(f64, f64)>) -> Series {
        Series { label, points, style: None, point_labels: Vec::new() }
    }
}

/// The markers a series is told apart by beside its colour, in style order.
const MARKERS: usize = 7;

/// Series `style`'s marker as a polygon about (0, 0), in pixels: a disc, a triangle, a
/// square, a plus, a diamond, a triangle upside down and a cross (one per method).
fn marker(style: usize) -> Vec<(i32, i32)> {
    match style % MARKERS {
        0 => (0..12)
            .map(|i| {
                let a = i as f64 * std::f64::consts::TAU / 12.0;
                ((5.5 * a.cos()).round() as i32, (5.5 * a.sin()).round() as i32)
            })
            .collect(),
        1 => vec![(0, -7), (7, 5), (-7, 5)],
        2 => vec![(-5, -5), (5, -5), (5, 5), (-5, 5)],
        3 => vec![(-2, -7), (2, -7), (2, -2), (7, -2), (7, 2), (2, 2), (2, 7), (-2, 7), (-2, 2), (-7, 2), (-7, -2), (-2, -2)],
        4 => vec![(0, -7), (7, 0), (0, 7), (-7, 0)],
        5 => vec![(0, 7), (7, -5), (-7, -5)],
        _ => vec![(-6, -4), (-4, -6), (0, -2), (4, -6), (6, -4), (2, 0), (6, 4), (4, 6), (0, 2), (-4, 6), (-6, 4), (-2, 0)],
    }
}

pub(crate) struct Chart<'a> {
    pub title: String,
    pub x_label: &'a str,
    pub y_label: &'a str,
    pub series: Vec<Series>,
    /// Join each series' points with a line (a path along the light configurations).
    pub lines: bool,
    /// The Pareto front's points, by rising x.
    pub front: Vec<(f64, f64)>,
    /// Both axes logarithmic (costs against sizes over orders of magnitude: a power law is a
    /// line whose slope is its exponent).
    pub log_log: bool,
}

/// Reads the font once; plotters keeps it for the life of the process.
fn register_font() -> Result<()> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    let result = REGISTERED.get_or_init(|| {
        let bytes = std::fs::read(FONT_FILE).map_err(|e| {
            format!("{FONT_FILE}: cannot read the charts' font ({e}); install Debian's fonts-dejavu-core (tools/setup.sh does)")
        })?;
        plotters::style::register_font(FONT, FontStyle::Normal, Box::leak(bytes.into_boxed_slice()))
            .map_err(|_| format!("{FONT_FILE}: not a usable TrueType font"))
    });
    result.clone().map_err(anyhow::Error::msg)
}

/// Stages `stem`.svg and `stem`.png.
pub(crate) fn write(outputs: &mut Outputs, stem: &Path, chart: &Chart) -> Result<()> {
    register_font()?;
    let mut svg = String::new();
    draw(SVGBackend::with_string(&mut svg, SIZE).into_drawing_area(), chart)?;
    let svg_path = stem.with_extension("svg");
    outputs.bytes(&svg_path, svg.as_bytes())?;
    let mut rgb = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    draw(BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area(), chart)?;
    write_png_rgb8(outputs, &stem.with_extension("png"), SIZE.0, SIZE.1, &rgb)?;
    Ok(())
}

/// The axis range of `values` with a margin, never empty.
fn range(values: impl Iterator<Item = f64>) -> std::ops::Range<f64> {
    let (lo, hi) = values.filter(|v| v.is_finite()).fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)));
    if !lo.is_finite() {
        return 0.0..1.0;
    }
    let span = hi - lo;
    let margin = if span > hi.abs() * 1e-3 { span * 0.08 } else { hi.abs().max(1e-6) * 0.05 };
    // Costs and errors are >= 0: their axes start at 0, so that ratios read true, unless every
    // value lies in the upper half, where 0 would squeeze the points into a sliver (a real
    // GPU's frame times differ by a few percent between methods).
    let start = if lo >= 0.0 && lo < hi * 0.5 { 0.0 } else { lo - margin };
    start..hi + margin
}

/// A log-log chart as a linear one of the values' base-10 logarithms (ticks are labelled with
/// the values); any other chart as it is.
fn on_log_axes<'a>(chart: &Chart<'a>) -> Chart<'a> {
    let log = |points: &[(f64, f64)]| -> Vec<(f64, f64)> {
        points.iter().map(|&(x, y)| if chart.log_log { (x.log10(), y.log10()) } else { (x, y) }).collect()
    };
    Chart {
        title: chart.title.clone(),
        series: chart
            .series
            .iter()
            .map(|s| Series { label: s.label.clone(), points: log(&s.points), style: s.style, point_labels: s.point_labels.clone() })
            .collect(),
        front: log(&chart.front),
        ..*chart
    }
}

/// 10^`exponent`, in three significant figures with k, M or G.
fn power_of_ten(exponent: f64) -> String {
    let value = 10f64.powf(exponent);
    let (scaled, suffix) =
        [(1e9, "G"), (1e6, "M"), (1e3, "k")].into_iter().find(|(s, _)| value >= *s).map_or((value, ""), |(s, n)| (value / s, n));
    let digits = if scaled >= 100.0 {
        0
    } else if scaled >= 10.0 {
        1
    } else {
        2
    };
    format!("{scaled:.digits$}{suffix}")
}

fn draw<DB: DrawingBackend>(root: DrawingArea<DB, Shift>, chart: &Chart) -> Result<()>
where
    DB::ErrorType: 'static,
{
    let fail = |e: DrawingAreaErrorKind<DB::ErrorType>| anyhow::anyhow!("drawing the chart \"{}\": {e}", chart.title);
    if chart.series.iter().all(|s| s.points.is_empty()) {
        bail!("chart \"{}\": no points to draw", chart.title);
    }
    root.fill(&WHITE).map_err(fail)?;
    let chart = &on_log_axes(chart);
    let all = || chart.series.iter().flat_map(|s| s.points.iter().copied());
    // Line charts keep their legend at the top, above room made for it; scatter charts put it
    // in the lower left, cheap and right, where a point would beat every other.
    let legend_at = if chart.lines { SeriesLabelPosition::UpperLeft } else { SeriesLabelPosition::LowerLeft };
    let mut y_range = range(all().map(|p| p.1));
    if chart.lines {
        y_range.end += (y_range.end - y_range.start) * 0.075 * chart.series.len() as f64;
    }
    let mut plot = ChartBuilder::on(&root)
        .caption(&chart.title, (FONT, 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(range(all().map(|p| p.0)), y_range)
        .map_err(fail)?;
    let tick = |v: &f64| if chart.log_log { power_of_ten(*v) } else { format!("{v}") };
    plot.configure_mesh()
        .x_desc(chart.x_label)
        .y_desc(chart.y_label)
        .x_label_formatter(&tick)
        .y_label_formatter(&tick)
        .label_style((FONT, 14))
        .draw()
        .map_err(fail)?;
    for (i, series) in chart.series.iter().enumerate() {
        let style = series.style.unwrap_or(i);
        let colour = Palette99::pick(style).to_rgba();
        if chart.lines {
            plot.draw_series(LineSeries::new(series.points.iter().copied(), colour.stroke_width(2))).map_err(fail)?;
        }
        plot.draw_series(series.points.iter().map(|&p| EmptyElement::at(p) + Polygon::new(marker(style), colour.filled())))
            .map_err(fail)?
            .label(&series.label)
            .legend(move |(x, y)| {
                Polygon::new(marker(style).into_iter().map(|(dx, dy)| (x + 8 + dx, y + dy)).collect::<Vec<_>>(), colour.filled())
            });
        let text = TextStyle::from((FONT, 12).into_font()).color(&colour);
        plot.draw_series(
            series
                .points
                .iter()
                .zip(&series.point_labels)
                .map(|(&p, label)| EmptyElement::at(p) + Text::new(label.clone(), (7, -16), text.clone())),
        )
        .map_err(fail)?;
    }
    if chart.front.len() > 1 {
        let staircase: Vec<(f64, f64)> =
            chart.front.windows(2).flat_map(|w| [w[0], (w[1].0, w[0].1)]).chain(chart.front.last().copied()).collect();
        plot.draw_series(LineSeries::new(staircase, BLACK.stroke_width(2)))
            .map_err(fail)?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK.stroke_width(2)));
    }
    plot.configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .position(legend_at)
        .draw()
        .map_err(fail)?;
    root.present().map_err(fail)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_start_at_zero_unless_the_values_would_be_a_sliver() {
        let spread = range([0.1, 0.4, 1.0].into_iter());
        assert_eq!(spread.start, 0.0);
        assert!(spread.end > 1.0 && spread.end < 1.1, "{spread:?}");
        let close = range([1.80, 1.85, 1.91].into_iter());
        assert!(close.start > 1.78 && close.start < 1.80 && close.end > 1.91 && close.end < 1.93, "{close:?}");
        let same = range([2.0, 2.0].into_iter());
        assert!(same.start < 2.0 && same.end > 2.0, "{same:?}");
        assert_eq!(range([f64::NAN].into_iter()), 0.0..1.0);
    }
}
