//! docs/BENCHMARKS.md promises a command for every figure: each section with a table names
//! the figure of `tools/figures.sh` that remakes it, the script defines every figure it lists,
//! and every sweep file the document names exists.

use std::path::{Path, PathBuf};
use std::process::Command;

const FIGURE: &str = "bash tools/figures.sh ";

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn listed_figures() -> Vec<String> {
    let list = Command::new("bash").arg(root().join("tools/figures.sh")).arg("--list").output().expect("bash runs");
    assert!(list.status.success(), "tools/figures.sh --list: {}", String::from_utf8_lossy(&list.stderr));
    String::from_utf8(list.stdout).expect("UTF-8").lines().map(String::from).collect()
}

/// The names that follow `prefix` in `text`, each up to the first character outside `keep`.
fn names_after<'t>(text: &'t str, prefix: &str, keep: impl Fn(char) -> bool + Copy) -> Vec<&'t str> {
    text.match_indices(prefix)
        .map(|(i, _)| &text[i + prefix.len()..])
        .map(|rest| rest.split(|c: char| !keep(c)).next().unwrap_or(""))
        .collect()
}

/// A table's rule under its header: `|---|:--:|`, spaces allowed.
fn is_table_rule(line: &str) -> bool {
    let line = line.trim();
    line.starts_with('|') && line.contains('-') && line.chars().all(|c| matches!(c, '|' | '-' | ':' | ' '))
}

#[test]
fn every_table_of_the_benchmarks_names_a_figure_the_script_remakes() {
    let ids = listed_figures();
    let script = std::fs::read_to_string(root().join("tools/figures.sh")).expect("tools/figures.sh");
    for id in &ids {
        let function = format!("figure_{}() {{", id.replace('-', "_"));
        assert!(script.contains(&function), "tools/figures.sh lists {id} but defines no {function}");
    }
    let doc = std::fs::read_to_string(root().join("docs/BENCHMARKS.md")).expect("docs/BENCHMARKS.md");
    let mut named = Vec::new();
    for section in doc.split("\n## ").skip(1) {
        let title = section.lines().next().unwrap_or_default();
        let figures = names_after(section, FIGURE, |c| c.is_ascii_alphanumeric() || c == '-');
        if section.lines().any(is_table_rule) {
            assert!(!figures.is_empty(), "docs/BENCHMARKS.md, \"{title}\": a table, and no `{FIGURE}ID` that remakes it");
        }
        for figure in figures {
            assert!(ids.iter().any(|id| id == figure), "docs/BENCHMARKS.md, \"{title}\": no figure \"{figure}\" in tools/figures.sh");
            named.push(figure);
        }
    }
    for id in &ids {
        assert!(named.contains(&id.as_str()), "tools/figures.sh's figure {id} is named by no section of docs/BENCHMARKS.md");
    }
}

#[test]
fn every_sweep_file_the_benchmarks_and_the_script_name_exists() {
    let doc = std::fs::read_to_string(root().join("docs/BENCHMARKS.md")).expect("docs/BENCHMARKS.md");
    let script = std::fs::read_to_string(root().join("tools/figures.sh")).expect("tools/figures.sh");
    let sweep_name = |c: char| c.is_ascii_alphanumeric() || c == '-' || c == '.';
    let mut sweeps: Vec<String> = names_after(&doc, "tools/sweeps/", sweep_name)
        .iter()
        .map(|s| s.trim_end_matches('.').to_string())
        .filter(|s| !s.is_empty())
        .collect();
    assert!(sweeps.len() > 20, "the document names its sweeps: {sweeps:?}");
    let looped = script.lines().filter_map(|line| line.trim().strip_prefix("for sweep in ")?.split(';').next());
    sweeps.extend(looped.flat_map(|names| names.split_whitespace().map(|name| format!("{name}.toml"))));
    sweeps.extend(names_after(&script, "tools/sweeps/", sweep_name).iter().filter(|s| !s.is_empty()).map(|s| s.to_string()));
    for sweep in sweeps {
        assert!(root().join("tools/sweeps").join(&sweep).is_file(), "tools/sweeps/{sweep} is named and does not exist");
    }
}
