//! The frame, the lighting pass, the technique contract, the artifact reader and the tools'
//! dispatch know no method: every method lives in its own folders and one line per registry
//! (docs/ARCHITECTURE.md). This fails when a method's name appears in any of those files
//! (their test modules aside), so that adding a method never means editing them.

use relume_tests::repo_root;

/// The names of the methods with a technique or a bake, present and to come, in every
/// spelling the code uses (CLI, modules, shaders, files).
const METHOD_NAMES: [&str; 8] = ["obscurance", "light-path-maps", "light_path_maps", "lpm", "fiv", "light-cloud", "light_cloud", "mrt"];

/// Files that must stay method-agnostic, relative to the repository root; besides these,
/// every file of `tools/src` outside the registry (`methods/`) and the scene generator
/// (`scenegen/`, which writes each method's block of the scene settings), and of `viewer/src`.
const AGNOSTIC: [&str; 14] = [
    "renderer/src/frame.rs",
    "renderer/src/effect.rs",
    "renderer/src/passes/graphics.rs",
    "shaders/include/relume.glsl",
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
];

/// The method named by a whole word of `line`, if any.
fn names_a_method(line: &str) -> Option<&'static str> {
    METHOD_NAMES.into_iter().find(|name| {
        line.match_indices(name).any(|(at, _)| {
            !line[..at].chars().next_back().is_some_and(|c| c.is_alphanumeric())
                && !line[at + name.len()..].chars().next().is_some_and(|c| c.is_alphanumeric())
        })
    })
}

/// The tools' files outside the registry and the scene generator, and the viewer's (every
/// method reaches the window through the registry).
fn tools_dispatch() -> Vec<String> {
    let mut files = Vec::new();
    let mut folders = vec![repo_root().join("tools/src"), repo_root().join("viewer/src")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap_or_else(|e| panic!("{}: {e}", folder.display())) {
            let path = entry.expect("a folder entry").path();
            let relative = path.strip_prefix(repo_root()).expect("under the root").to_string_lossy().into_owned();
            match path.is_dir() {
                true if !relative.ends_with("tools/src/methods") && !relative.ends_with("tools/src/scenegen") => folders.push(path),
                false if relative.ends_with(".rs") => files.push(relative),
                _ => {}
            }
        }
    }
    files.sort();
    files
}

#[test]
fn the_frame_the_lighting_pass_the_artifact_reader_and_the_dispatch_name_no_method() {
    let tools = tools_dispatch();
    assert!(tools.iter().any(|f| f.ends_with("tools/src/bench/mod.rs")) && tools.len() > 15, "{tools:?}");
    let mut found = Vec::new();
    for file in AGNOSTIC.iter().map(|f| f.to_string()).chain(tools) {
        let text = std::fs::read_to_string(repo_root().join(&file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        // The file's test module may exercise a real method.
        let code = text.split("#[cfg(test)]").next().unwrap_or_default().to_lowercase();
        for (n, line) in code.lines().enumerate() {
            if let Some(name) = names_a_method(line) {
                found.push(format!("{file}:{}: {name}: {}", n + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "method names in method-agnostic files:\n{}", found.join("\n"));
}

#[test]
fn the_check_sees_a_method_name() {
    // The scan itself: a line that names a method is caught, a longer word is not.
    assert_eq!(names_a_method("let maps = light_path_maps::read(dir);"), Some("light_path_maps"));
    assert_eq!(names_a_method("methods::find(\"obscurance\")"), Some("obscurance"));
    assert_eq!(names_a_method("let obscurances_total = 1; // lpms"), None);
}
