//! An interrupted command changes nothing it had not finished: `bake` and `reference`,
//! stopped by SIGINT or SIGTERM at points spread over their whole run (loading, working,
//! writing), leave the previous outputs byte for byte and no temporary; killed outright
//! (SIGKILL, which nothing can catch) they leave the previous outputs too, and the next run
//! removes the temporaries the killed one left.

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus};
use std::time::{Duration, Instant};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("workspace root").to_path_buf()
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("relume-interrupt-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

fn relume(args: &[String]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_relume"));
    command.args(args).stdout(std::process::Stdio::null()).stderr(std::process::Stdio::piped());
    command
}

fn run(args: &[String]) {
    let output = relume(args).output().expect("run relume");
    assert!(output.status.success(), "relume {args:?}: {}", String::from_utf8_lossy(&output.stderr));
}

/// Starts relume and waits until it catches SIGINT and SIGTERM (its handler is installed
/// first thing; a signal before that would end it outright, as it ends any program).
fn start(args: &[String]) -> Child {
    let child = relume(args).spawn().expect("start relume");
    let status = format!("/proc/{}/status", child.id());
    let wanted = (1u64 << (libc::SIGINT - 1)) | (1u64 << (libc::SIGTERM - 1));
    loop {
        let text = std::fs::read_to_string(&status).unwrap_or_default();
        let caught = text.lines().find_map(|l| l.strip_prefix("SigCgt:")).and_then(|h| u64::from_str_radix(h.trim(), 16).ok());
        match caught {
            Some(mask) if mask & wanted != wanted => std::thread::sleep(Duration::from_micros(100)),
            _ => return child,
        }
    }
}

fn signal(child: &Child, signal: i32) {
    // SAFETY: kill(2) on our own child's pid; a child that already ended is a zombie until
    // waited for, so the pid cannot have been reused.
    unsafe { libc::kill(child.id() as i32, signal) };
}

/// Runs relume, sends `signal` `delay` after its start (unless it has ended), and waits.
fn run_and_signal(args: &[String], delay: Duration, sent: i32) -> ExitStatus {
    let started = Instant::now();
    let mut child = start(args);
    std::thread::sleep(delay.saturating_sub(started.elapsed()));
    signal(&child, sent);
    child.wait().expect("wait for relume")
}

/// Starts relume and waits until a temporary appears in `dir` (it is writing its outputs) or
/// it ends.
fn start_and_wait_for_writing(args: &[String], dir: &Path) -> Child {
    let mut child = start(args);
    while hidden_entries(dir).is_empty() && child.try_wait().expect("poll relume").is_none() {
        std::thread::sleep(Duration::from_micros(100));
    }
    child
}

/// Every file under `dir` (recursively, hidden ones included) by its path in `dir`, with its
/// bytes; stats.json (timings, which differ run to run) is left out.
fn snapshot(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut files = Vec::new();
    let mut folders = vec![dir.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for path in std::fs::read_dir(&folder).expect("list").map(|e| e.expect("entry").path()) {
            match path.is_dir() {
                true => folders.push(path),
                false if path.ends_with("stats.json") => {}
                false => files.push((path.strip_prefix(dir).expect("inside").to_path_buf(), std::fs::read(&path).expect("read"))),
            }
        }
    }
    files.sort();
    files
}

fn hidden_entries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("list")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .filter(|name| name.starts_with('.'))
        .collect()
}

/// A command, run in three ways: `old` and `new` write the same outputs in `dir`
/// differently, `timed` is `new` writing into `timed_dir`, run once to time it and to know
/// what `new` writes.
struct Case<'a> {
    dir: &'a Path,
    timed_dir: &'a Path,
    old: Vec<String>,
    new: Vec<String>,
    timed: Vec<String>,
}

impl Case<'_> {
    /// Runs `timed`: how long `new` takes, and what it writes.
    fn time_new(&self) -> (Duration, Vec<(PathBuf, Vec<u8>)>) {
        let start = Instant::now();
        run(&self.timed);
        (start.elapsed(), snapshot(self.timed_dir))
    }

    /// After an interrupt: no temporary, and the outputs all old or (the interrupt came while
    /// they were moved in place, which finishes first) all new; `old` runs again after new.
    fn check_after_interrupt(&self, status: ExitStatus, before: &mut Vec<(PathBuf, Vec<u8>)>, new: &[(PathBuf, Vec<u8>)], when: &str) {
        assert_eq!(hidden_entries(self.dir), Vec::<String>::new(), "a temporary is left after a signal {when}");
        let after = snapshot(self.dir);
        match status.code() {
            Some(130) if after == *before => {}
            Some(130) | Some(0) if after == new => {
                run(&self.old);
                *before = snapshot(self.dir);
            }
            Some(130) | Some(0) => panic!("after a signal {when}, the outputs are neither all old nor all new"),
            other => panic!("a signal {when} ended relume with {other:?} ({status})"),
        }
    }
}

/// `new` interrupted with SIGINT and SIGTERM at fractions of its run time, then the moment
/// it starts writing; each time the outputs stay whole (all old or all new) and no
/// temporary is left.
fn interrupting_changes_nothing(case: &Case) {
    run(&case.old);
    let mut before = snapshot(case.dir);
    let (whole, new) = case.time_new();
    let mut interrupted = 0;
    for (k, fraction) in [0.02, 0.15, 0.3, 0.45, 0.6, 0.75, 0.85, 0.92, 0.97].into_iter().enumerate() {
        let signal = if k % 2 == 0 { libc::SIGINT } else { libc::SIGTERM };
        let status = run_and_signal(&case.new, whole.mul_f64(fraction), signal);
        interrupted += (status.code() == Some(130)) as usize;
        case.check_after_interrupt(status, &mut before, &new, &format!("at {fraction} of the run"));
    }
    assert!(interrupted >= 5, "only {interrupted} of 9 runs were interrupted before they ended; the test proves too little");
    interrupting_while_writing_changes_nothing(case, &mut before, &new);
}

/// Signals the moment a temporary appears in `dir` (the command is writing its outputs),
/// until one run was interrupted there with the old outputs still in place.
fn interrupting_while_writing_changes_nothing(case: &Case, before: &mut Vec<(PathBuf, Vec<u8>)>, new: &[(PathBuf, Vec<u8>)]) {
    for _ in 0..20 {
        let mut child = start_and_wait_for_writing(&case.new, case.dir);
        signal(&child, libc::SIGINT);
        let status = child.wait().expect("wait for relume");
        let kept = snapshot(case.dir) == *before;
        case.check_after_interrupt(status, before, new, "while writing");
        if status.code() == Some(130) && kept {
            return;
        }
    }
    panic!("20 runs finished writing before the interrupt reached them; the test proves nothing");
}

/// SIGKILL halfway, then the moment a temporary appears, leaves the outputs all old or all
/// new; the next run removes the temporary the killed one left.
fn killing_leaves_the_old_outputs_and_the_next_run_cleans_up(case: &Case) {
    run(&case.old);
    let before = snapshot(case.dir);
    let (whole, new) = case.time_new();
    let visible = || -> Vec<_> { snapshot(case.dir).into_iter().filter(|(p, _)| !p.to_string_lossy().starts_with('.')).collect() };
    run_and_signal(&case.new, whole.mul_f64(0.5), libc::SIGKILL);
    assert!(visible() == before || visible() == new, "killed halfway, the outputs are neither all old nor all new");
    for _ in 0..20 {
        let mut child = start_and_wait_for_writing(&case.new, case.dir);
        signal(&child, libc::SIGKILL);
        child.wait().expect("wait for relume");
        assert!(visible() == before || visible() == new, "killed while writing, the outputs are neither all old nor all new");
        if !hidden_entries(case.dir).is_empty() {
            run(&case.old);
            assert_eq!(hidden_entries(case.dir), Vec::<String>::new(), "the next run left the killed run's temporary");
            return;
        }
    }
    panic!("20 runs finished writing before SIGKILL reached them; the test proves nothing");
}

/// `relume COMMAND ... ARGS --out OUT cornell.gltf`, where `vary` is the value of the flag
/// that tells the old run from the new.
fn cornell(command: &str, fixed: &[&str], flag: &str, vary: &str, out: &Path) -> Vec<String> {
    let mut args: Vec<String> = [command].iter().chain(fixed).chain(&[flag, vary, "--out"]).map(|s| s.to_string()).collect();
    args.extend([out.display().to_string(), repo_root().join("scenes/cornell.gltf").display().to_string()]);
    args
}

/// Runs every interruption on `command` writing `output`, old and new told apart by `flag`;
/// one command at a time, so that the run timed is as fast as the runs signalled.
fn interrupt_and_kill(command: &str, fixed: &[&str], output: &str, flag: &str, (old, new): (&str, &str)) {
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _alone = ONE_AT_A_TIME.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    let (dir, timed_dir) = (temp_dir(command), temp_dir(&format!("{command}-timed")));
    let (out, timed_out) = (dir.join(output), timed_dir.join(output));
    let case = Case {
        dir: &dir,
        timed_dir: &timed_dir,
        old: cornell(command, fixed, flag, old, &out),
        new: cornell(command, fixed, flag, new, &out),
        timed: cornell(command, fixed, flag, new, &timed_out),
    };
    interrupting_changes_nothing(&case);
    killing_leaves_the_old_outputs_and_the_next_run_cleans_up(&case);
}

#[test]
fn an_interrupted_bake_keeps_the_previous_artifact() {
    interrupt_and_kill("bake", &["--method", "obscurance", "--patches", "40000"], "bake", "--rays", ("4", "256"));
}

#[test]
fn an_interrupted_reference_keeps_the_previous_images() {
    interrupt_and_kill("reference", &["--width", "512", "--height", "512"], "reference.exr", "--spp", ("1", "8"));
}
