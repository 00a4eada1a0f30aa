//! The frame, the lighting pass, the technique contract, the artifact reader and the tools'
//! dispatch know no method: every method lives in its own folders and one line per registry
//! (docs/ARCHITECTURE.md). This fails when a method's name appears in any of those files
//! (their test modules aside), so that adding a method never means editing them.

use relume_tests::repo_root;

/// The names of the methods with a technique or a bake, present and to come, in every
/// spelling the code uses (CLI, modules, shaders, files).
const METHOD_NAMES: [&str; 8] = ["obscurance", "light-path-maps", "light_path_maps", "lpm", "fiv", "light-cloud", "light_cloud", "mrt"];

/// Files that must stay method-agnostic, relative to the repository root.
const AGNOSTIC: [&str; 20] = [
    "renderer/src/frame.rs",
    "renderer/src/technique.rs",
    "renderer/src/headless.rs",
    "renderer/src/passes/lighting.rs",
    "renderer/src/passes/compute.rs",
    "shaders/lighting.frag",
    "shaders/lighting.vert",
    "shaders/lighting_interface.glsl",
    "shaders/frame.glsl",
    "bake/src/artifact.rs",
    "bake/src/settings.rs",
    "tools/src/main.rs",
    "tools/src/bake.rs",
    "tools/src/render.rs",
    "tools/src/report.rs",
    "tools/src/gpu.rs",
    "tools/src/args.rs",
    "tools/src/bench/mod.rs",
    "tools/src/bench/config.rs",
    "tools/src/bench/results.rs",
];

#[test]
fn the_frame_the_lighting_pass_the_artifact_reader_and_the_dispatch_name_no_method() {
    let mut found = Vec::new();
    for file in AGNOSTIC {
        let text = std::fs::read_to_string(repo_root().join(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        // The file's test module may exercise a real method.
        let code = text.split("#[cfg(test)]").next().unwrap_or_default().to_lowercase();
        for (n, line) in code.lines().enumerate() {
            for name in METHOD_NAMES {
                let whole_word = line.match_indices(name).any(|(at, _)| {
                    let before = line[..at].chars().next_back();
                    let after = line[at + name.len()..].chars().next();
                    !before.is_some_and(|c| c.is_alphanumeric()) && !after.is_some_and(|c| c.is_alphanumeric())
                });
                if whole_word {
                    found.push(format!("{file}:{}: {name}: {}", n + 1, line.trim()));
                }
            }
        }
    }
    assert!(found.is_empty(), "method names in method-agnostic files:\n{}", found.join("\n"));
}

#[test]
fn the_check_sees_a_method_name() {
    // The scan itself: a line that names a method is caught, a longer word is not.
    let hits = |line: &str| {
        METHOD_NAMES.iter().any(|name| {
            line.match_indices(name).any(|(at, _)| {
                !line[..at].chars().next_back().is_some_and(|c| c.is_alphanumeric())
                    && !line[at + name.len()..].chars().next().is_some_and(|c| c.is_alphanumeric())
            })
        })
    };
    assert!(hits("let maps = light_path_maps::read(dir);"));
    assert!(hits("methods::find(\"obscurance\")"));
    assert!(!hits("let obscurances_total = 1; // lpms"));
}
