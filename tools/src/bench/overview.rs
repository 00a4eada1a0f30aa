//! `relume bench --overview`: the front page of a sweep (the main job's out/report.md).

use super::budget::{scene_choices_text, Budget, Recommendation, SceneChoice};
use super::methods_table::{methods_text, MethodCell};
use super::report::{machine, Summary};
use super::Outcome;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

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

    pub(super) fn text(
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overview_links_are_relative_to_its_folder() {
        assert_eq!(relative(Path::new("out/bench/report.md"), Path::new("out")), Path::new("bench/report.md"));
        assert_eq!(relative(Path::new("out/cornell/report.md"), Path::new("docs/../out/x")), Path::new("../cornell/report.md"));
        assert_eq!(relative(Path::new("a.png"), Path::new(".")), Path::new("a.png"));
        let page = Overview { path: PathBuf::from("overview.md"), links: Vec::new() };
        assert_eq!(page.link(Path::new("out/report.md")), "out/report.md");
    }
}
