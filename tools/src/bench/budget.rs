//! The bench's budget (`--budget`, `--budget-ms`, `--budget-mib`): per scene and method the
//! best configuration within it, per scene the best method, recommended.toml and the report's
//! section on them.

use super::report::Summary;
use super::Resolution;
use std::fmt::Write as _;

/// The `--budget` choice for one scene and method.
pub(crate) struct Recommendation<'s> {
    scene: &'s str,
    method: &'s str,
    /// The method's configurations in cost order.
    pub(super) ladder: Vec<&'s Summary<'s>>,
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
    /// the error; else the cheaper of those whose error is within `resolution` (what the
    /// reference's noise lets the bench tell apart) of the `lowest` within the budget, then
    /// the rest by error.
    fn order(&self, lowest: f64, resolution: f64, a: &Summary, b: &Summary) -> std::cmp::Ordering {
        let tied = |s: &Summary| s.mean_nrmse <= lowest + resolution;
        match (self.nrmse, tied(a), tied(b)) {
            (Some(_), _, _) | (None, true, true) => cost_order(a, b),
            (None, true, false) => std::cmp::Ordering::Less,
            (None, false, true) => std::cmp::Ordering::Greater,
            (None, false, false) => a.mean_nrmse.total_cmp(&b.mean_nrmse).then(cost_order(a, b)),
        }
    }

    /// What it asks, in words.
    pub(super) fn text(&self) -> String {
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

/// The lowest error of `candidates`.
fn lowest<'s>(candidates: impl Iterator<Item = &'s Summary<'s>>) -> f64 {
    candidates.map(|s| s.mean_nrmse).fold(f64::INFINITY, f64::min)
}

/// Per scene and method: the configurations in cost order, and the best within the budget.
pub(super) fn recommend<'s>(summaries: &'s [Summary<'s>], budget: &Budget, resolution: &Resolution) -> Vec<Recommendation<'s>> {
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
        let within: Vec<usize> = (0..r.ladder.len()).filter(|&i| budget.within(r.ladder[i])).collect();
        let (lowest, resolution) = (lowest(within.iter().map(|&i| r.ladder[i])), resolution.of(r.scene));
        r.chosen = within.into_iter().min_by(|&a, &b| budget.order(lowest, resolution, r.ladder[a], r.ladder[b]));
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
pub(super) fn choose<'s>(recommendations: &[Recommendation<'s>], budget: &Budget, resolution: &Resolution) -> Vec<SceneChoice<'s>> {
    let mut scenes: Vec<&str> = recommendations.iter().map(|r| r.scene).collect();
    scenes.dedup();
    scenes
        .into_iter()
        .map(|scene| {
            let mut within: Vec<usize> =
                (0..recommendations.len()).filter(|&i| recommendations[i].scene == scene && recommendations[i].chosen.is_some()).collect();
            let choice = |i: usize| recommendations[i].choice().unwrap();
            // The scene's lowest within the budget, not that of the methods' choices: those
            // already gave up a tie's worth of error each, and ties must not chain.
            let of_scene = recommendations.iter().filter(|r| r.scene == scene).flat_map(|r| r.ladder.iter().copied());
            let (lowest, resolution) = (lowest(of_scene.filter(|s| budget.within(s))), resolution.of(scene));
            within.sort_by(|&a, &b| budget.order(lowest, resolution, choice(a), choice(b)));
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

pub(super) fn recommended_toml(recommendations: &[Recommendation], choices: &[SceneChoice], budget: &Budget) -> String {
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

/// A configuration as the budget's text names it.
pub(super) fn describe(s: &Summary) -> String {
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
pub(super) fn budget_text(r: &mut String, recommendations: &[Recommendation], choices: &[SceneChoice], budget: &Budget) {
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
pub(super) fn scene_choices_text(r: &mut String, recommendations: &[Recommendation], choices: &[SceneChoice]) {
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
pub(super) mod tests {
    use super::*;
    use crate::bench::report::summaries;
    use crate::bench::report::tests::point;
    use crate::bench::results::{BakeCost, FrameCost, Row};

    pub(crate) fn error(nrmse: f64) -> Budget {
        Budget { nrmse: Some(nrmse), ..Budget::default() }
    }

    /// A point of `method` with parameter set `params`, its error and its artifact's bytes.
    fn of(method: &str, params: &str, nrmse: f64, bytes: u64) -> Row {
        Row { method: method.into(), bake: BakeCost { artifact_bytes: bytes, ..BakeCost::default() }, ..point(params, 0, Some(nrmse)) }
    }

    /// Across methods, the budget picks the cheaper of two methods when both meet it, and the
    /// more accurate when only one does; recommended.toml names it; with none within it, the
    /// report names the most accurate.
    #[test]
    fn the_budget_picks_the_cheaper_method_within_it_and_else_the_one_that_meets_it() {
        let rows = [of("small", "a", 0.15, 1_000), of("small", "b", 0.12, 4_000), of("large", "c", 0.05, 50_000)];
        let summaries = summaries(&rows);
        let recommendations = recommend(&summaries, &error(0.2), &Resolution::default());
        let choices = choose(&recommendations, &error(0.2), &Resolution::default());
        assert_eq!(choices.len(), 1);
        let chosen = &recommendations[choices[0].chosen.unwrap()];
        assert_eq!((chosen.method, chosen.choice().unwrap().first().params.as_str()), ("small", "a"), "both meet 0.2: the cheaper");
        assert_eq!(recommendations[choices[0].runner_up.unwrap()].method, "large");
        let written: toml::Table = toml::from_str(&recommended_toml(&recommendations, &choices, &error(0.2))).unwrap();
        assert_eq!(written["s"]["method"].as_str(), Some("small"));
        assert_eq!(written["s"]["large"]["mean_nrmse"].as_float(), Some(0.05));

        let recommendations = recommend(&summaries, &error(0.1), &Resolution::default());
        let choices = choose(&recommendations, &error(0.1), &Resolution::default());
        assert_eq!(recommendations[choices[0].chosen.unwrap()].method, "large", "only the dearer meets 0.1");
        assert!(choices[0].runner_up.is_none());

        let recommendations = recommend(&summaries, &error(0.01), &Resolution::default());
        let choices = choose(&recommendations, &error(0.01), &Resolution::default());
        assert!(choices[0].chosen.is_none());
        let mut text = String::new();
        budget_text(&mut text, &recommendations, &choices, &error(0.01));
        assert!(text.contains("- s: no method within the budget (the most accurate: large [c] NRMSE 0.0500"), "{text}");
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
        let recommendations = recommend(&summaries, &budget, &Resolution::default());
        let choices = choose(&recommendations, &budget, &Resolution::default());
        let chosen = recommendations[choices[0].chosen.unwrap()].choice().unwrap();
        assert_eq!(chosen.first().params, "e", "c is too slow, d too large: e is the most accurate within both");
        assert_eq!(recommendations[choices[0].runner_up.unwrap()].choice().unwrap().first().params, "b");
        assert_eq!(budget.text(), "the most accurate within GPU frame <= 2 ms, artifact <= 16 MiB");
        let tight = Budget { frame_ms: Some(0.1), ..Budget::default() };
        assert!(choose(&recommend(&summaries, &tight, &Resolution::default()), &tight, &Resolution::default())[0].chosen.is_none());

        // Where the reference cannot tell 0.05, 0.10 and 0.15 apart (three times its noise is
        // 0.12), the most accurate is the cheapest of them: e (4 MiB against c's 12 MiB).
        let loose = Budget { frame_ms: Some(5.0), ..Budget::default() };
        let blurred = Resolution(vec![("s".into(), 0.12)]);
        let recommendations = recommend(&summaries, &loose, &blurred);
        let choices = choose(&recommendations, &loose, &blurred);
        assert_eq!(recommendations[choices[0].chosen.unwrap()].choice().unwrap().first().params, "e");
        let recommendations = recommend(&summaries, &loose, &Resolution::default());
        let choices = choose(&recommendations, &loose, &Resolution::default());
        assert_eq!(recommendations[choices[0].chosen.unwrap()].choice().unwrap().first().params, "c", "told apart: the most accurate");
    }

    /// Ties do not chain: a method whose choice gave up a tie's worth of error does not make a
    /// method tied with that choice, but not with the scene's lowest, a tie.
    #[test]
    fn ties_are_within_the_resolution_of_the_scenes_lowest() {
        let rows = [of("a", "exact", 0.05, 8_000), of("a", "small", 0.10, 1_000), of("b", "tiny", 0.15, 500)];
        let summaries = summaries(&rows);
        let (budget, resolution) = (Budget { frame_ms: Some(5.0), ..Budget::default() }, Resolution(vec![("s".into(), 0.06)]));
        let recommendations = recommend(&summaries, &budget, &resolution);
        let choices = choose(&recommendations, &budget, &resolution);
        let chosen = &recommendations[choices[0].chosen.unwrap()];
        assert_eq!((chosen.method, chosen.choice().unwrap().first().params.as_str()), ("a", "small"), "0.15 is 0.10 from 0.05");
    }
}
