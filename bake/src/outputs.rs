//! A command's outputs, written all or none. Each output is first written as a hidden
//! temporary beside its final path (`.NAME.PID.tmp`); `commit` then moves every one in place
//! together, so until then nothing under a final name has changed, and a failure on the way
//! (an encoder error, a path that is a folder, a full disk) leaves every output as it was.
//!
//! Temporaries are registered process-wide: `remove_unfinished` (the interrupt handler's
//! work) removes them and holds back any commit from starting, and one that a killed run left
//! behind (its process id no longer running) is removed by the next run that writes the same
//! output.
//!
//! No output may be a file the run has read ([`crate::inputs`]): staging refuses it.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// Why an output could not be written: the path and what went wrong.
#[derive(Debug, thiserror::Error)]
#[error("{}: {message}", path.display())]
pub struct OutputError {
    pub path: PathBuf,
    pub message: String,
}

fn fail(path: &Path, message: impl std::fmt::Display) -> OutputError {
    OutputError { path: path.to_path_buf(), message: message.to_string() }
}

/// Temporaries of this process not yet moved in place or removed.
static UNFINISHED: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn unfinished() -> MutexGuard<'static, Vec<PathBuf>> {
    UNFINISHED.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// Removes every temporary this process has made and not committed, and keeps any commit
/// from starting after it: for an interrupt, just before the process exits.
pub fn remove_unfinished() {
    let held = unfinished();
    held.iter().for_each(|path| remove(path));
    std::mem::forget(held);
}

fn remove(path: &Path) {
    let _ = match std::fs::symlink_metadata(path) {
        Ok(m) if m.is_dir() => std::fs::remove_dir_all(path),
        _ => std::fs::remove_file(path),
    };
}

/// Outputs staged together; dropped without `commit`, their temporaries are removed.
#[derive(Default)]
pub struct Outputs {
    /// (temporary, final path), in staging order.
    staged: Vec<(PathBuf, PathBuf)>,
    /// Folders made to hold a staged folder, innermost first: removed, when left empty, with
    /// the temporaries of outputs that were never committed.
    made: Vec<PathBuf>,
}

impl Outputs {
    pub fn new() -> Outputs {
        Outputs::default()
    }

    /// Stages the file `path`, written by `write` into its temporary. Outputs are regular
    /// files: anything else under the name (a folder, a device such as /dev/null, a FIFO, a
    /// socket) is refused, not replaced.
    pub fn file(&mut self, path: &Path, write: impl FnOnce(&mut File) -> Result<(), String>) -> Result<(), OutputError> {
        if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
            return Err(fail(path, "exists and is not a regular file (a folder, a device, a FIFO or a socket); relume writes only regular files: choose a file path"));
        }
        crate::inputs::refuse_output_file(path).map_err(|why| fail(path, why))?;
        let temporary = self.stage(path)?;
        let mut file = {
            // Created under the lock, so an interrupt either removes it or finds it not yet made.
            let mut held = unfinished();
            let file = File::create_new(&temporary).map_err(|e| fail(path, format!("cannot write ({e})")))?;
            held.push(temporary.clone());
            file
        };
        self.staged.push((temporary, path.to_path_buf()));
        write(&mut file).map_err(|e| {
            // Not left staged: a caller that went on to commit would move a broken file in.
            self.abandon_last();
            fail(path, e)
        })
    }

    fn abandon_last(&mut self) {
        if let Some((temporary, _)) = self.staged.pop() {
            let mut held = unfinished();
            remove(&temporary);
            held.retain(|p| *p != temporary);
        }
    }

    /// Stages the file `path` holding `bytes`.
    pub fn bytes(&mut self, path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
        self.file(path, |file| std::io::Write::write_all(file, bytes).map_err(|e| e.to_string()))
    }

    /// Stages the folder `path` (which the caller has checked may be replaced): returns the
    /// empty temporary folder to fill.
    pub fn folder(&mut self, path: &Path) -> Result<PathBuf, OutputError> {
        crate::inputs::refuse_output_folder(path).map_err(|why| fail(path, format!("{why}; write it elsewhere")))?;
        let temporary = self.stage(path)?;
        if let Some(parent) = temporary.parent() {
            let missing = parent.ancestors().take_while(|a| !a.as_os_str().is_empty() && !a.exists()).map(Path::to_path_buf);
            let missing: Vec<PathBuf> = missing.collect();
            std::fs::create_dir_all(parent).map_err(|e| fail(parent, format!("cannot create the folder ({e})")))?;
            self.made.extend(missing);
        }
        {
            let mut held = unfinished();
            std::fs::create_dir(&temporary).map_err(|e| fail(&temporary, format!("cannot create the folder ({e})")))?;
            held.push(temporary.clone());
        }
        self.staged.push((temporary.clone(), path.to_path_buf()));
        Ok(temporary)
    }

    /// The temporary for `path`, after removing what killed runs left for it.
    fn stage(&self, path: &Path) -> Result<PathBuf, OutputError> {
        if self.staged.iter().any(|(_, staged)| staged == path) {
            return Err(fail(path, "is written twice by one command; give each output its own path"));
        }
        remove_stale(path);
        sibling(path, std::process::id(), "tmp").ok_or_else(|| fail(path, "not a file path"))
    }

    /// Moves every staged output in place. A folder replaces the one under its name (moved
    /// aside first, then removed), a file replaces the file by a rename. Should a move fail
    /// (a permission, a mount point), the error names the outputs already moved in.
    pub fn commit(mut self) -> Result<(), OutputError> {
        let mut held = unfinished();
        let staged = std::mem::take(&mut self.staged);
        self.made.clear();
        let failed = staged.iter().enumerate().find_map(|(k, (temporary, path))| move_in_place(temporary, path).err().map(|e| (k, e)));
        held.retain(|p| !staged.iter().any(|(temporary, _)| temporary == p));
        let Some((k, mut error)) = failed else { return Ok(()) };
        staged[k..].iter().for_each(|(temporary, _)| remove(temporary));
        if k > 0 {
            let moved: Vec<String> = staged[..k].iter().map(|(_, path)| path.display().to_string()).collect();
            error.message.push_str(&format!("; already replaced: {} (the others are as they were)", moved.join(", ")));
        }
        Err(error)
    }
}

impl Drop for Outputs {
    fn drop(&mut self) {
        if self.staged.is_empty() {
            return;
        }
        let mut held = unfinished();
        for (temporary, _) in &self.staged {
            remove(temporary);
            held.retain(|p| p != temporary);
        }
        for folder in &self.made {
            let _ = std::fs::remove_dir(folder);
        }
    }
}

/// Writes `bytes` as the file `path` inside a folder staged by [`Outputs::folder`]. The file
/// is created under the lock, so an interrupt removing the folder never races a new entry.
pub fn write_staged(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut file = {
        let _held = unfinished();
        File::create(path)?
    };
    std::io::Write::write_all(&mut file, bytes)
}

fn move_in_place(temporary: &Path, path: &Path) -> Result<(), OutputError> {
    let is_dir = |p: &Path| std::fs::symlink_metadata(p).is_ok_and(|m| m.is_dir());
    // A file replaces only a file: a folder that appeared under its name since is not removed.
    if !is_dir(temporary) || !is_dir(path) {
        return std::fs::rename(temporary, path).map_err(|e| fail(path, format!("cannot move the output in place ({e})")));
    }
    let aside = sibling(path, std::process::id(), "old").ok_or_else(|| fail(path, "not a folder path"))?;
    remove(&aside);
    std::fs::rename(path, &aside).map_err(|e| {
        fail(path, format!("cannot move the old folder aside ({e}); a mount point cannot be replaced: write into a folder inside it"))
    })?;
    if let Err(e) = std::fs::rename(temporary, path) {
        let put_back = match std::fs::rename(&aside, path) {
            Ok(()) => String::new(),
            Err(_) => format!("; the old folder is at {}", aside.display()),
        };
        return Err(fail(path, format!("cannot move the new folder in place ({e}){put_back}")));
    }
    remove(&aside);
    Ok(())
}

/// `.NAME.PID.KIND` beside `path`.
fn sibling(path: &Path, pid: u32, kind: &str) -> Option<PathBuf> {
    let mut name = std::ffi::OsString::from(".");
    name.push(path.file_name()?);
    name.push(format!(".{pid}.{kind}"));
    Some(path.with_file_name(name))
}

/// Removes the temporaries and set-aside folders for `path` whose process is gone (or is this
/// one, which registers all its own: an unregistered one is a killed run's whose process id
/// this one reuses, as PID 1 in a container does); a folder set aside by a run killed before
/// its new one moved in goes back in place.
fn remove_stale(path: &Path) {
    let (Some(name), Some(parent)) = (path.file_name(), path.parent()) else { return };
    let parent = if parent.as_os_str().is_empty() { Path::new(".") } else { parent };
    let Ok(entries) = std::fs::read_dir(parent) else { return };
    for entry in entries.flatten() {
        let Some((pid, kind)) = temporary_of(&entry.file_name(), name) else { continue };
        let ours = pid == std::process::id() && sibling(path, pid, kind).is_some_and(|p| !unfinished().contains(&p));
        let put_back = || kind == "old" && std::fs::symlink_metadata(path).is_err() && std::fs::rename(entry.path(), path).is_ok();
        if (ours || pid != std::process::id() && !process_running(pid)) && !put_back() {
            remove(&entry.path());
        }
    }
}

/// The process id and kind ("tmp" or "old") of `entry` when it is named `.NAME.PID.KIND`.
fn temporary_of(entry: &std::ffi::OsStr, name: &std::ffi::OsStr) -> Option<(u32, &'static str)> {
    use std::os::unix::ffi::OsStrExt;
    let rest = entry.as_bytes().strip_prefix(b".")?.strip_prefix(name.as_bytes())?.strip_prefix(b".")?;
    let (pid, kind) = std::str::from_utf8(rest).ok()?.split_once('.')?;
    let kind = ["tmp", "old"].into_iter().find(|k| *k == kind)?;
    Some((pid.parse().ok()?, kind))
}

/// Whether process `pid` runs (Linux: /proc); without /proc every process counts as running,
/// so nothing is removed that might be another run's.
fn process_running(pid: u32) -> bool {
    !Path::new("/proc/self").exists() || Path::new(&format!("/proc/{pid}")).exists()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn folder(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("relume-outputs-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into()).collect();
        names.sort();
        names
    }

    fn text(text: &'static str) -> impl FnOnce(&mut File) -> Result<(), String> {
        move |file| file.write_all(text.as_bytes()).map_err(|e| e.to_string())
    }

    #[test]
    fn nothing_moves_until_commit_and_a_failure_keeps_every_old_output() {
        let dir = folder("all-or-none");
        std::fs::write(dir.join("a.txt"), "old a").unwrap();
        let mut outputs = Outputs::new();
        outputs.file(&dir.join("a.txt"), text("new a")).unwrap();
        std::fs::create_dir(dir.join("b.txt")).unwrap();
        let error = outputs.file(&dir.join("b.txt"), text("new b")).unwrap_err().to_string();
        assert!(error.contains("b.txt") && error.contains("not a regular file"), "{error}");
        assert_eq!(std::fs::read_to_string(dir.join("a.txt")).unwrap(), "old a");
        drop(outputs);
        assert_eq!(entries(&dir), ["a.txt", "b.txt"], "the temporary of a.txt is removed");

        let mut outputs = Outputs::new();
        outputs.file(&dir.join("a.txt"), text("new a")).unwrap();
        outputs.file(&dir.join("c.txt"), text("new c")).unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("a.txt")).unwrap(), "old a");
        outputs.commit().unwrap();
        assert_eq!(std::fs::read_to_string(dir.join("a.txt")).unwrap(), "new a");
        assert_eq!(entries(&dir), ["a.txt", "b.txt", "c.txt"]);
    }

    #[test]
    fn a_folder_replaces_the_old_one_whole() {
        let dir = folder("folder");
        let out = dir.join("bake");
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join("old.bin"), "old").unwrap();
        let mut outputs = Outputs::new();
        let staging = outputs.folder(&out).unwrap();
        std::fs::write(staging.join("new.bin"), "new").unwrap();
        assert_eq!(entries(&out), ["old.bin"]);
        outputs.commit().unwrap();
        assert_eq!(entries(&out), ["new.bin"]);
        assert_eq!(entries(&dir), ["bake"], "no temporary or set-aside folder is left");
        // A folder staged inside folders that did not exist, never committed: none is left.
        let mut outputs = Outputs::new();
        outputs.folder(&dir.join("run/bake/obscurance")).unwrap();
        drop(outputs);
        assert_eq!(entries(&dir), ["bake"], "the folders made to hold it are left");
    }

    #[test]
    fn what_a_killed_run_left_is_removed_and_a_running_ones_kept() {
        let dir = folder("stale");
        let dead = (2_000_000..).find(|pid| !process_running(*pid)).unwrap();
        let running = 1;
        for (name, pid, kind) in [("out.exr", dead, "tmp"), ("bake", dead, "tmp"), ("bake", dead, "old"), ("out.exr", running, "tmp")] {
            let path = sibling(&dir.join(name), pid, kind).unwrap();
            match name {
                "bake" => std::fs::create_dir(&path).unwrap(),
                _ => std::fs::write(&path, "left").unwrap(),
            }
        }
        std::fs::write(dir.join(".other.exr.1.tmp"), "not ours to judge").unwrap();
        let mut outputs = Outputs::new();
        outputs.file(&dir.join("out.exr"), text("new")).unwrap();
        outputs.commit().unwrap();
        remove_stale(&dir.join("bake"));
        assert!(dir.join("bake").is_dir(), "a folder set aside by a killed run goes back where it was");
        assert_eq!(entries(&dir), [".other.exr.1.tmp", ".out.exr.1.tmp", "bake", "out.exr"]);
    }

    #[test]
    fn a_failed_write_is_not_staged_and_a_failed_commit_names_what_it_replaced() {
        let dir = folder("failures");
        let mut outputs = Outputs::new();
        assert!(outputs.file(&dir.join("x.png"), |_| Err("disk full".into())).unwrap_err().to_string().contains("disk full"));
        outputs.commit().unwrap();
        assert_eq!(entries(&dir), Vec::<String>::new(), "the broken file was moved in or left behind");

        let mut outputs = Outputs::new();
        outputs.file(&dir.join("a.txt"), text("a")).unwrap();
        outputs.file(&dir.join("b.txt"), text("b")).unwrap();
        std::fs::create_dir(dir.join("b.txt")).unwrap();
        std::fs::write(dir.join("b.txt/inside"), "in the way").unwrap();
        let error = outputs.commit().unwrap_err().to_string();
        assert!(error.contains("b.txt") && error.contains("already replaced") && error.contains("a.txt"), "{error}");
        assert_eq!(entries(&dir), ["a.txt", "b.txt"], "a temporary is left");
    }

    #[test]
    fn a_temporary_of_a_killed_run_under_this_process_id_is_removed() {
        let dir = folder("reused-pid");
        let left = sibling(&dir.join("out.exr"), std::process::id(), "tmp").unwrap();
        std::fs::write(&left, "a killed run's").unwrap();
        let mut outputs = Outputs::new();
        outputs.file(&dir.join("out.exr"), text("new")).unwrap();
        outputs.commit().unwrap();
        assert_eq!(entries(&dir), ["out.exr"]);
        assert_eq!(std::fs::read_to_string(dir.join("out.exr")).unwrap(), "new");
    }

    #[test]
    fn one_path_twice_is_refused() {
        let dir = folder("twice");
        let mut outputs = Outputs::new();
        outputs.file(&dir.join("x.png"), text("1")).unwrap();
        let error = outputs.file(&dir.join("x.png"), text("2")).unwrap_err().to_string();
        assert!(error.contains("written twice"), "{error}");
    }
}
