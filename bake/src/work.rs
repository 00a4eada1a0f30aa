//! What every long bake stage shares: its worker threads, its progress bar and the peak
//! memory it reached.

use indicatif::{ProgressBar, ProgressStyle};
use std::time::Duration;

/// What every long CPU job (a bake, the path tracer) takes from the command line: its seed,
/// its worker threads, a time limit, and whether to draw a progress bar. The same inputs and
/// seed give the same bytes at any thread count.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WorkOptions {
    pub seed: u64,
    /// Worker threads; None uses rayon's global pool (all cores).
    pub threads: Option<usize>,
    /// Stop early, at a whole pass of the job, after this long (at least one pass is made).
    pub time_limit: Option<Duration>,
    /// Draw a progress bar on stderr (hidden when stderr is not a terminal).
    pub progress: bool,
}

impl WorkOptions {
    /// Refuses zero threads, and more than any machine relume runs on has cores to give.
    pub fn validate(&self) -> Result<(), String> {
        crate::settings::first_failed_check(&[(self.threads.is_none_or(|n| (1..=1024).contains(&n)), "threads must be 1..=1024")])
    }
}

/// Runs `f` on a pool of `threads` workers, or on rayon's global pool (all cores) for None.
pub fn with_threads<R: Send>(threads: Option<usize>, f: impl FnOnce() -> R + Send) -> R {
    match threads {
        Some(n) => rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("could not start the worker threads").install(f),
        None => f(),
    }
}

/// A progress bar of `len` steps labelled `label` on stderr, or a hidden one.
pub fn progress_bar(len: u64, label: &str, visible: bool) -> ProgressBar {
    if !visible {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    let template = format!("{label} {{bar:40}} {{percent:>3}}% {{elapsed_precise}} (eta {{eta}})");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style);
    }
    bar
}

/// The process's peak resident memory in bytes since it started or since the last
/// [`reset_peak_memory`] (Linux `VmHWM`); None where the kernel does not say.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Starts a new peak-memory measurement (writing 5 to `clear_refs` resets `VmHWM` to the
/// current resident size); false where that is not possible, and the peak then counts from
/// the start of the process.
pub fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}
