//! A script of viewer steps (`relume view --script FILE`): what a user does, replayed one
//! step per frame, for tests and for reproducing a session. One step a line; `#` comments.
//!
//! | step | does |
//! |---|---|
//! | `method NAME` | switches to the method named |
//! | `light I position X Y Z` / `light I intensity R G B` | moves or re-powers light I |
//! | `light I cone INNER OUTER` | a spot light's cone angles, degrees |
//! | `size W H` | asks the window for this inner size and waits for it |
//! | `overlay on` / `overlay off` | shows or hides the overlay |
//! | `orbit YAW PITCH` | turns the camera about its pivot, degrees |
//! | `reference SPP` | traces the reference of the current view to SPP samples and waits |
//! | `frames N` | draws N frames |
//! | `idle MS` | asks for no frame for MS milliseconds, then reports the frames drawn and the heap allocations the window's thread made meanwhile |
//! | `screenshot PATH` | writes the swapchain image as PNG |
//! | `save-lights PATH` | writes the lights file |
//! | `quit` | closes the window |

use anyhow::{bail, Context as _, Result};
use glam::Vec3;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    Method(String),
    LightPosition(usize, Vec3),
    LightIntensity(usize, Vec3),
    LightCone(usize, f32, f32),
    Size(u32, u32),
    Overlay(bool),
    Orbit(f32, f32),
    Reference(u32),
    Frames(u32),
    Idle(u32),
    Screenshot(PathBuf),
    SaveLights(PathBuf),
    Quit,
}

/// Reads a script file; every bad line is refused with its number and what it should be.
pub fn read(path: &Path) -> Result<Vec<Step>> {
    // A FIFO would block the read until killed, a device be read without end.
    relume_bake::inputs::admit(path).map_err(|why| anyhow::anyhow!("{}: {why}", path.display()))?;
    let text = std::fs::read_to_string(path).with_context(|| format!("{}: cannot read the script", path.display()))?;
    parse(&text).with_context(|| format!("{}: not a viewer script (see `relume view --help`)", path.display()))
}

impl Step {
    /// The file the step writes, if it writes one.
    pub fn output(&self) -> Option<&Path> {
        match self {
            Step::Screenshot(path) | Step::SaveLights(path) => Some(path),
            _ => None,
        }
    }
}

pub fn parse(text: &str) -> Result<Vec<Step>> {
    let mut steps = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split('#').next().unwrap_or("").trim();
        if !line.is_empty() {
            steps.push(step(line).with_context(|| format!("line {}: \"{line}\"", n + 1))?);
        }
    }
    Ok(steps)
}

fn step(line: &str) -> Result<Step> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let numbers = |from: usize, count: usize| -> Result<Vec<f32>> {
        let values: Vec<f32> = words.get(from..).unwrap_or(&[]).iter().map(|w| w.parse::<f32>()).collect::<Result<_, _>>()?;
        if values.len() != count || values.iter().any(|v| !v.is_finite()) {
            bail!("expected {count} finite number(s) after \"{}\"", words[..from].join(" "));
        }
        Ok(values)
    };
    let count = |text: Option<&&str>| -> Result<u32> {
        text.and_then(|t| t.parse::<u32>().ok()).filter(|&v| v > 0).context("expected a whole number > 0")
    };
    let vec3 = |v: Vec<f32>| Vec3::new(v[0], v[1], v[2]);
    Ok(match words[..] {
        ["method", name] => Step::Method(name.to_string()),
        ["light", index, "position", ..] => Step::LightPosition(index.parse()?, vec3(numbers(3, 3)?)),
        ["light", index, "intensity", ..] => Step::LightIntensity(index.parse()?, vec3(numbers(3, 3)?)),
        ["light", index, "cone", ..] => {
            let v = numbers(3, 2)?;
            Step::LightCone(index.parse()?, v[0], v[1])
        }
        ["size", ..] => Step::Size(count(words.get(1))?, count(words.get(2))?),
        ["overlay", "on"] => Step::Overlay(true),
        ["overlay", "off"] => Step::Overlay(false),
        ["orbit", ..] => {
            let v = numbers(1, 2)?;
            Step::Orbit(v[0], v[1])
        }
        ["reference", _] => Step::Reference(count(words.get(1))?),
        ["frames", _] => Step::Frames(count(words.get(1))?),
        ["idle", _] => Step::Idle(count(words.get(1))?),
        ["screenshot", path] => Step::Screenshot(path.into()),
        ["save-lights", path] => Step::SaveLights(path.into()),
        ["quit"] => Step::Quit,
        _ => bail!("unknown step; steps are method, light, size, overlay, orbit, reference, frames, idle, screenshot, save-lights, quit"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_script_reads_every_step_and_refuses_a_bad_line_by_number() {
        let text = "method direct # first\nlight 0 position 1 2 3\nlight 1 cone 10 20\nsize 320 200\noverlay off\nframes 2\nscreenshot a.png\nquit\n";
        let steps = parse(text).expect("valid");
        assert_eq!(steps.len(), 8);
        assert_eq!(steps[1], Step::LightPosition(0, Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!(steps[3], Step::Size(320, 200));
        for bad in ["light 0 position 1 2", "size 0 10", "frames x", "light 0 intensity 1 NaN 1", "dance"] {
            let error = format!("{:#}", parse(&format!("quit\n{bad}")).unwrap_err());
            assert!(error.starts_with("line 2"), "{bad}: {error}");
        }
    }
}
