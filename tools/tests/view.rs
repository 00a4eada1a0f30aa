//! `relume view` under Xvfb on lavapipe, with validation and synchronization validation on:
//! a scripted session (a method switch, a moved light, a resize, a small reference, an idle
//! spell) ends with a screenshot of the swapchain image that equals `relume render` of the
//! same state, no validation message (teardown included), an idle window that draws and
//! allocates nothing; and the refusals: no display, a bad script, a bake for another scene.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-view-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn scene(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.gltf"))
}

/// Runs relume with no display but `display`, killed (and the test failed) past 10 minutes.
fn relume(args: &[&str], dir: &Path, display: Option<&str>) -> Output {
    let mut command = Command::new(env!("CARGO_BIN_EXE_relume"));
    command.args(args).current_dir(dir).stdout(Stdio::piped()).stderr(Stdio::piped());
    for variable in ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET"] {
        command.env_remove(variable);
    }
    if let Some(display) = display {
        command.env("DISPLAY", display);
    }
    let mut child = command.spawn().expect("run relume");
    let deadline = Instant::now() + Duration::from_secs(600);
    while child.try_wait().expect("wait for relume").is_none() {
        if Instant::now() > deadline {
            let _ = child.kill();
            let output = child.wait_with_output().expect("relume's output");
            panic!("relume {args:?} ran past 10 minutes: {}", String::from_utf8_lossy(&output.stderr));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("relume's output")
}

/// An X server of its own, on a display it chose free itself (-displayfd: it writes the
/// number once it listens), 24-bit (Mesa's WSI refuses Xvfb's old 8-bit default); killed on
/// drop.
struct Xvfb {
    child: Child,
    display: String,
}

impl Xvfb {
    fn start() -> Xvfb {
        let mut child = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "1024x768x24", "-nolisten", "tcp"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("Xvfb (tools/setup.sh installs the xvfb package)");
        let mut line = String::new();
        let stdout = child.stdout.take().expect("Xvfb's stdout");
        BufReader::new(stdout).read_line(&mut line).expect("Xvfb's display number");
        let number: u32 = line.trim().parse().unwrap_or_else(|_| panic!("Xvfb did not start: {line:?}"));
        Xvfb { child, display: format!(":{number}") }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// RGB8 pixels of a PNG relume wrote.
fn pixels(path: &Path) -> (u32, u32, Vec<u8>) {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).expect("png")));
    let mut reader = decoder.read_info().expect("png header");
    let mut buffer = vec![0; reader.output_buffer_size().expect("size")];
    let info = reader.next_frame(&mut buffer).expect("png data");
    buffer.truncate(info.buffer_size());
    (info.width, info.height, buffer)
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn a_scripted_session_ends_with_the_headless_image_no_validation_message_and_an_idle_window_that_does_nothing() {
    let dir = temp_dir("session");
    let cornell = scene("cornell");
    let cornell = cornell.to_str().unwrap();
    let bake = relume(&["bake", cornell, "--method", "obscurance", "--patches", "500", "--rays", "4", "--out", "bake"], &dir, None);
    assert!(bake.status.success(), "{}", stderr(&bake));
    let script = "overlay off\nframes 2\nmethod obscurance\nlight 0 position 0.1 1.2 0.3\nlight 0 intensity 3 2.5 2\nframes 2\n\
                  size 160 120\nreference 2\nidle 400\nsave-lights lights.json\nscreenshot view.png\noverlay on\nframes 2\nscreenshot overlay.png\n";
    std::fs::write(dir.join("script.txt"), script).unwrap();
    let xvfb = Xvfb::start();
    let view = relume(
        &[
            "view",
            cornell,
            "--bake",
            "bake",
            "--width",
            "200",
            "--height",
            "150",
            "--validation",
            "--script",
            "script.txt",
            "--device",
            "llvmpipe",
        ],
        &dir,
        Some(&xvfb.display),
    );
    let log = stderr(&view);
    assert!(view.status.success(), "{log}");
    assert!(String::from_utf8_lossy(&view.stdout).contains("0 validation messages"), "{log}");
    assert!(log.contains("relume view: idle: 0 frame(s), 0 heap allocation(s) on the window's thread"), "{log}");
    let traced = log.lines().find(|l| l.contains("reference of the view")).unwrap_or_else(|| panic!("no reference finished: {log}"));
    assert!(traced.contains("2 spp"), "{traced}");

    let render = relume(
        &[
            "render",
            cornell,
            "--bake",
            "bake",
            "--lights",
            "lights.json",
            "--width",
            "160",
            "--height",
            "120",
            "--out",
            "render.exr",
            "--device",
            "llvmpipe",
        ],
        &dir,
        None,
    );
    assert!(render.status.success(), "{}", stderr(&render));
    let (width, height, shown) = pixels(&dir.join("view.png"));
    let (_, _, rendered) = pixels(&dir.join("render.png"));
    assert_eq!((width, height), (160, 120), "the screenshot has the resized window's size");
    let differ = shown.iter().zip(&rendered).filter(|(a, b)| a.abs_diff(**b) > 1).count();
    assert_eq!(differ, 0, "the swapchain image is relume render's image of the same state (to 1 in 255)");
    let (_, _, with_overlay) = pixels(&dir.join("overlay.png"));
    let covered = with_overlay.iter().zip(&shown).filter(|(a, b)| a != b).count();
    assert!(covered > shown.len() / 20, "the overlay draws on the swapchain image ({covered} values differ)");
}

#[test]
fn without_a_display_the_viewer_says_so_in_one_line_and_exits_1() {
    let dir = temp_dir("no-display");
    let view = relume(&["view", scene("cornell").to_str().unwrap()], &dir, None);
    let log = stderr(&view);
    assert_eq!(view.status.code(), Some(1), "{log}");
    let lines: Vec<&str> = log.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{log}");
    assert!(lines[0].contains("no display") && lines[0].contains("DISPLAY"), "{log}");
}

#[test]
fn a_bad_script_and_a_bake_for_another_scene_are_refused_before_any_window() {
    let dir = temp_dir("refusals");
    std::fs::write(dir.join("bad.txt"), "frames 1\nlight 0 position 1 2\n").unwrap();
    let view = relume(&["view", scene("cornell").to_str().unwrap(), "--script", "bad.txt"], &dir, None);
    let log = stderr(&view);
    assert_eq!(view.status.code(), Some(1), "{log}");
    assert!(log.contains("bad.txt") && log.contains("line 2") && log.contains("3 finite number"), "{log}");

    let cornell = scene("cornell");
    let bake = relume(
        &["bake", cornell.to_str().unwrap(), "--method", "obscurance", "--patches", "500", "--rays", "4", "--out", "bake"],
        &dir,
        None,
    );
    assert!(bake.status.success(), "{}", stderr(&bake));
    let view = relume(&["view", scene("occluder-plane").to_str().unwrap(), "--bake", "bake"], &dir, None);
    let log = stderr(&view);
    assert_eq!(view.status.code(), Some(1), "{log}");
    assert!(log.contains("--bake bake") && !log.contains("no display"), "refused for the bake, before the window: {log}");
}
