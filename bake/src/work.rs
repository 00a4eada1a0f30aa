//! What every long bake stage shares: its worker threads, its progress bar and the peak
//! memory it reached.

use indicatif::{ProgressBar, ProgressStyle};
use std::ops::Range;
use std::time::{Duration, Instant};

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

    /// Runs `pass` on the worker threads over 0..total (rays, walks) in ranges of `step`,
    /// stopping at a whole pass once the time limit has passed (one pass at least); returns
    /// how many were taken. The ranges do not depend on the thread count.
    pub fn in_passes(&self, total: u32, step: u32, mut pass: impl FnMut(Range<u32>) + Send) -> u32 {
        let start = Instant::now();
        with_threads(self.threads, || {
            let mut taken = 0;
            while taken < total {
                if self.time_limit.is_some_and(|limit| taken > 0 && start.elapsed() >= limit) {
                    break;
                }
                let range = taken..(taken + step.max(1)).min(total);
                taken = range.end;
                pass(range);
            }
            taken
        })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_cover_the_total_in_steps_and_a_spent_time_limit_leaves_one() {
        let mut ranges = Vec::new();
        let options = WorkOptions { threads: Some(2), ..WorkOptions::default() };
        assert_eq!(options.in_passes(10, 4, |r| ranges.push(r)), 10);
        assert_eq!(ranges, [0..4, 4..8, 8..10]);
        let spent = WorkOptions { time_limit: Some(Duration::ZERO), ..options };
        let mut count = 0;
        assert_eq!(spent.in_passes(10, 4, |_| count += 1), 4);
        assert_eq!(count, 1);
    }
}
