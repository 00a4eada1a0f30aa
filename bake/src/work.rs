//! What every long bake stage shares: its worker threads, its progress bar and the peak
//! memory it reached.

use crate::bvh::RayBackend;
use crate::contract::{mib, Estimate};
use crate::shards::{self, Items, Role};
use indicatif::{ProgressBar, ProgressStyle};
use std::io::Write;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
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
    /// Refuse, before its long work, a bake whose peak memory is estimated above this many
    /// bytes (`admit`); None: the machine's memory.
    pub memory_limit: Option<u64>,
    /// When the job began (`begun`): its time limit counts from here over all its stages;
    /// None: each stage's own start.
    pub started: Option<Instant>,
    /// Which library casts the job's rays.
    pub ray_backend: RayBackend,
    /// The bake's role in a sharded one (`shards`): a plan, a shard or the merge; None: a
    /// whole bake.
    pub role: Option<&'static Role>,
}

impl WorkOptions {
    /// Refuses zero threads, and more than any machine relume runs on has cores to give.
    pub fn validate(&self) -> Result<(), String> {
        crate::settings::first_failed_check(&[(self.threads.is_none_or(|n| (1..=1024).contains(&n)), "threads must be 1..=1024")])
    }

    /// The same options with the time limit counting from now, over every stage that follows.
    pub fn begun(self) -> WorkOptions {
        WorkOptions { started: Some(self.started.unwrap_or_else(Instant::now)), ..self }
    }

    /// Whether the time limit has passed, counted from `started` (else from `stage_start`).
    pub fn out_of_time(&self, stage_start: Instant) -> bool {
        self.time_limit.is_some_and(|limit| self.started.unwrap_or(stage_start).elapsed() >= limit)
    }

    /// Refuses a bake whose `estimate` is over the memory limit (without --memory-limit: the
    /// machine's memory, which the bake could not finish in), naming the lever's value that
    /// would fit; prints the estimate first when progress is shown.
    pub fn admit(&self, stage: &str, estimate: &Estimate) -> Result<(), String> {
        if self.progress {
            eprintln!("{stage}: peak memory estimate {}", estimate.describe());
        }
        let (limit, what, raise) = match self.memory_limit {
            Some(limit) => (limit, "--memory-limit", ", or raise --memory-limit"),
            None => match machine_memory_bytes() {
                Some(machine) => (machine, "this machine's memory", ", or bake on a larger machine (or in shards: `relume bake plan`)"),
                None => return Ok(()),
            },
        };
        if estimate.bytes() <= limit {
            return Ok(());
        }
        let fits = match estimate.fitting(limit) {
            0 => format!("even {} 1 would not fit", estimate.lever),
            n => format!("{} {n} or less would fit", estimate.lever),
        };
        Err(format!("{stage}: the peak memory is estimated at {}, over {what} {:.0} MiB: {fits}{raise}", estimate.describe(), mib(limit)))
    }

    /// Makes the rows of a bake's long work, `items`: `make(chunk, range)` makes the rows of a
    /// range of items within the chunk `chunk`, each row a function of its item and the seed
    /// alone; `take` takes each chunk's rows in order. In a sharded bake (`role`) the rows are
    /// sampled (a plan), made for a range only (a shard), or read from the shards' parts (the
    /// merge).
    pub fn gather<T: bytemuck::Pod>(
        &self,
        items: &Items,
        make: impl FnMut(usize, Range<u64>) -> Result<Vec<T>, String> + Send,
        take: impl FnMut(Vec<T>) -> Result<(), String>,
    ) -> Result<(), String> {
        shards::gather(self.role, items, make, take)
    }

    /// Runs `pass` on the worker threads over 0..total (rays, walks) in ranges of `step`,
    /// stopping at a whole pass once the time limit has passed (one pass at least); returns
    /// how many were taken. The ranges do not depend on the thread count.
    pub fn in_passes(&self, total: u32, step: u32, mut pass: impl FnMut(Range<u32>) + Send) -> u32 {
        let start = Instant::now();
        with_threads(self.threads, || {
            let mut taken = 0;
            while taken < total {
                if taken > 0 && self.out_of_time(start) {
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

/// How often a log (stderr not a terminal) gets a progress line.
pub const LOG_INTERVAL: Duration = Duration::from_secs(5);

/// The progress of one long stage of `len` steps: a bar on stderr when it is a terminal; when
/// it is not (a log, a batch job), a line every [`LOG_INTERVAL`] from a thread of its own, so
/// lines come even while a step takes long: the stage, steps done of all, the rate and the
/// time left; and a last line when it ends, if any line was written. Nothing when not
/// `visible`.
pub struct Progress {
    bar: ProgressBar,
    log: Option<LogLines>,
}

impl Progress {
    pub fn new(len: u64, label: &str, visible: bool) -> Progress {
        use std::io::IsTerminal;
        match (visible, std::io::stderr().is_terminal()) {
            (false, _) => Progress { bar: ProgressBar::hidden(), log: None },
            (true, true) => Progress { bar: terminal_bar(len, label), log: None },
            (true, false) => Progress::logged(len, label, LOG_INTERVAL, Box::new(std::io::stderr())),
        }
    }

    /// Lines every `interval` into `sink` (stderr, or a test's buffer).
    fn logged(len: u64, label: &str, interval: Duration, sink: Box<dyn Write + Send>) -> Progress {
        let shared = Arc::new(LogShared {
            label: label.to_string(),
            len,
            start: Instant::now(),
            done: AtomicU64::new(0),
            finished: Mutex::new(false),
            wake: Condvar::new(),
        });
        let ticker = Arc::clone(&shared);
        let thread = std::thread::spawn(move || ticker.write_lines(interval, sink));
        Progress { bar: ProgressBar::hidden(), log: Some(LogLines { shared, thread: Some(thread) }) }
    }

    pub fn inc(&self, steps: u64) {
        self.bar.inc(steps);
        if let Some(log) = &self.log {
            log.shared.done.fetch_add(steps, Ordering::Relaxed);
        }
    }

    /// Ends the stage: clears the bar, or writes the log's last line.
    pub fn finish(&mut self) {
        self.bar.finish_and_clear();
        if let Some(mut log) = self.log.take() {
            log.stop();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.finish();
    }
}

fn terminal_bar(len: u64, label: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    let template = format!("{label} {{bar:40}} {{percent:>3}}% {{elapsed_precise}} (eta {{eta}})");
    if let Ok(style) = ProgressStyle::with_template(&template) {
        bar.set_style(style);
    }
    bar
}

struct LogLines {
    shared: Arc<LogShared>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl LogLines {
    fn stop(&mut self) {
        *self.shared.finished.lock().unwrap_or_else(|e| e.into_inner()) = true;
        self.shared.wake.notify_all();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

struct LogShared {
    label: String,
    len: u64,
    start: Instant,
    done: AtomicU64,
    finished: Mutex<bool>,
    wake: Condvar,
}

impl LogShared {
    fn write_lines(&self, interval: Duration, mut sink: Box<dyn Write + Send>) {
        let mut wrote = false;
        let mut finished = self.finished.lock().unwrap_or_else(|e| e.into_inner());
        loop {
            let (guard, timeout) = self.wake.wait_timeout_while(finished, interval, |f| !*f).unwrap_or_else(|e| e.into_inner());
            finished = guard;
            if !timeout.timed_out() {
                break;
            }
            let _ = writeln!(sink, "{}", self.line());
            wrote = true;
        }
        if wrote {
            let _ = writeln!(
                sink,
                "{}: done {} of {} in {:.1} s",
                self.label,
                self.done.load(Ordering::Relaxed),
                self.len,
                self.start.elapsed().as_secs_f64()
            );
        }
    }

    /// "stage: done of all (percent), rate, time left".
    fn line(&self) -> String {
        let done = self.done.load(Ordering::Relaxed);
        let seconds = self.start.elapsed().as_secs_f64();
        let rate = done as f64 / seconds.max(1e-9);
        let left =
            if rate > 0.0 { format!("{:.0} s left", self.len.saturating_sub(done) as f64 / rate) } else { "time left unknown".into() };
        let percent = 100.0 * done as f64 / self.len.max(1) as f64;
        format!("{}: {done} of {} ({percent:.1} %), {}, {left}", self.label, self.len, per_second(rate))
    }
}

fn per_second(rate: f64) -> String {
    match rate {
        r if r >= 1e6 => format!("{:.2} M/s", r * 1e-6),
        r if r >= 1e3 => format!("{:.1} k/s", r * 1e-3),
        r => format!("{r:.2}/s"),
    }
}

/// The process's peak resident memory in bytes since it started or since the last
/// [`reset_peak_memory`] (Linux `VmHWM`); None where the kernel does not say.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The machine's memory in bytes (Linux `MemTotal`); None where the kernel does not say.
pub fn machine_memory_bytes() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemTotal:"))?;
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

    /// A log gets a line per interval while the stage runs, with the stage, the steps done of
    /// all, the rate and the time left, and a last line when it ends; a stage shorter than
    /// the interval writes nothing.
    #[test]
    fn a_log_gets_a_line_every_interval_and_a_last_one() {
        #[derive(Clone, Default)]
        struct Sink(Arc<Mutex<Vec<u8>>>);
        impl Write for Sink {
            fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
                self.0.lock().unwrap().write(bytes)
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        let sink = Sink::default();
        let mut progress = Progress::logged(100, "stage", Duration::from_millis(40), Box::new(sink.clone()));
        progress.inc(25);
        std::thread::sleep(Duration::from_millis(300));
        progress.finish();
        let text = String::from_utf8(sink.0.lock().unwrap().clone()).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert!(lines.len() >= 2, "{text}");
        assert!(lines[0].starts_with("stage: 25 of 100 (25.0 %), ") && lines[0].ends_with(" s left"), "{text}");
        assert!(lines.last().unwrap().starts_with("stage: done 25 of 100 in "), "{text}");

        let quiet = Sink::default();
        let mut short = Progress::logged(10, "short", Duration::from_secs(60), Box::new(quiet.clone()));
        short.inc(10);
        short.finish();
        assert!(quiet.0.lock().unwrap().is_empty());
    }
}
