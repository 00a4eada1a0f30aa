//! Every bake honours `--threads`, `--time-limit` and `--memory-limit` alike, through the bake
//! contract: the same bytes at 1 and 2 threads; a spent time limit either cuts a stage's
//! Monte Carlo passes short (the artifact says how many were taken) or, for a stage that
//! needs all its work, refuses naming the limit; a memory limit below the estimate refuses
//! before the long work, naming the estimate and the lever's value that fits, and writes
//! nothing.

use super::matrix::{least_effort, shipped};
use super::{suits, Method, METHODS};
use crate::bake::bake_scene;
use relume_bake::scene::Scene;
use relume_bake::work::WorkOptions;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// The first shipped scene the method runs on.
fn scene_for(method: &dyn Method) -> Scene {
    relume_tools::scenegen::SCENE_NAMES
        .iter()
        .map(|name| shipped(name))
        .find(|scene| suits(method, scene))
        .unwrap_or_else(|| panic!("no shipped scene suits {}", method.name()))
}

fn bake(method: &dyn Method, scene: &Scene, extra: &[(&str, &str)], work: WorkOptions, out: &Path) -> Result<String, String> {
    let dictionaries = out.with_extension("dictionaries");
    let mut pairs: Vec<(String, String)> = least_effort(method.name(), &dictionaries).into_iter().map(|(k, v)| (k.into(), v)).collect();
    pairs.retain(|(k, _)| !extra.iter().any(|(e, _)| e == k));
    pairs.extend(extra.iter().map(|(k, v)| (k.to_string(), v.to_string())));
    let values = super::parse_values(method, &pairs, None).map_err(|e| format!("{e:#}"))?;
    bake_scene(scene, method, &values, work, out).map_err(|e| format!("{e:#}"))
}

/// Every section file of an artifact, by name: not stats.json (its times and thread count) nor
/// the manifest (its given parameters name each bake's dictionary cache; its checksums are
/// the files').
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| !["stats.json", "manifest.json"].contains(&p.file_name().unwrap().to_str().unwrap()))
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    files.sort();
    files
}

fn stats(dir: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(dir.join("stats.json")).unwrap()).unwrap()
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-limits-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn baking() -> impl Iterator<Item = &'static dyn Method> {
    METHODS.iter().copied().filter(|m| m.bakes())
}

#[test]
fn every_bake_gives_the_same_bytes_at_one_and_two_threads() {
    let dir = temp("threads");
    for method in baking() {
        let scene = scene_for(method);
        let baked: Vec<_> = [1, 2]
            .map(|threads| {
                let out = dir.join(format!("{}-{threads}", method.name()));
                let work = WorkOptions { threads: Some(threads), ..WorkOptions::default() };
                bake(method, &scene, &[], work, &out).unwrap_or_else(|e| panic!("{}: {e}", method.name()));
                files(&out)
            })
            .into();
        assert!(baked[0] == baked[1], "{}: the artifacts at 1 and 2 threads differ", method.name());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// What a spent time limit does to each method's bake: the stat that shows the passes cut
/// short (asked for, taken), or the refusal of a stage that needs all its work.
enum Cut {
    Passes { extra: &'static [(&'static str, &'static str)], stat: &'static [&'static str], asked: u64 },
    Refused,
}

fn cut(method: &str) -> Cut {
    match method {
        // 64 rays: two passes of 32.
        "obscurance" => Cut::Passes { extra: &[("rays", "64")], stat: &["rays_per_texel"], asked: 64 },
        // Two walks: two passes of one; the obscurance before them keeps its one ray.
        "light-path-maps" => Cut::Passes { extra: &[("walks", "2")], stat: &["light_path_maps", "walks"], asked: 2 },
        // 16 paths a vertex: two passes of 8.
        "light-cloud" => Cut::Passes { extra: &[("samples", "16")], stat: &["samples"], asked: 16 },
        _ => Cut::Refused,
    }
}

#[test]
fn a_spent_time_limit_cuts_passes_short_or_refuses_a_stage_that_needs_all_its_work() {
    let dir = temp("time");
    let spent = WorkOptions { time_limit: Some(Duration::from_nanos(1)), ..WorkOptions::default() };
    for method in baking() {
        let scene = scene_for(method);
        let out = dir.join(method.name());
        match cut(method.name()) {
            Cut::Passes { extra, stat, asked } => {
                bake(method, &scene, extra, spent, &out).unwrap_or_else(|e| panic!("{}: {e}", method.name()));
                let taken = stat.iter().fold(&stats(&out), |v, key| &v[key]).as_u64();
                assert!(taken.is_some_and(|t| (1..asked).contains(&t)), "{}: {stat:?} = {taken:?} of {asked}", method.name());
            }
            Cut::Refused => {
                let error = bake(method, &scene, &[], spent, &out).expect_err(method.name());
                assert!(error.contains("--time-limit ran out"), "{}: {error}", method.name());
                assert!(!out.exists(), "{}: a refused bake wrote {}", method.name(), out.display());
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_memory_limit_below_the_estimate_refuses_before_the_work_and_names_what_fits() {
    let dir = temp("memory");
    for method in baking() {
        let scene = scene_for(method);
        let out = dir.join(method.name());
        let tight = WorkOptions { memory_limit: Some(1 << 20), ..WorkOptions::default() };
        let error = bake(method, &scene, &[], tight, &out).expect_err(method.name());
        assert!(
            error.contains("peak memory is estimated at")
                && error.contains("over --memory-limit 1 MiB")
                && error.contains(" 1 would not fit"),
            "{}: {error}",
            method.name()
        );
        assert!(!out.exists(), "{}: a refused bake wrote {}", method.name(), out.display());
        let roomy = WorkOptions { memory_limit: Some(64 << 30), ..WorkOptions::default() };
        bake(method, &scene, &[], roomy, &out).unwrap_or_else(|e| panic!("{}: {e}", method.name()));
    }
    std::fs::remove_dir_all(&dir).ok();
}
