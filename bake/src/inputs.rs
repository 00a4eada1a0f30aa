//! The files a command has read, so that none of its outputs replaces one. Every reader of a
//! file a command is given or a scene names (the scene, its buffers and images, environments,
//! lights files, a bake's manifest and sections, sweeps, scripts) admits it here first; every
//! output ([`crate::outputs::Outputs`], and a command's own check before its work starts) is
//! refused when it is one of them. Files are the same when they are the same file on disk
//! (device and inode), so a symlink, a `..` or a hard link to an input is refused too.
//!
//! Inputs are recorded while a command runs ([`track`], which `relume`'s main holds): a
//! program that uses this crate as a library and reads a bake it later bakes again is not
//! refused unless it asks to be.

use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};

/// A file read: as it was named, where it resolves, and which file it is on disk.
struct Input {
    named: PathBuf,
    resolved: PathBuf,
    identity: (u64, u64),
}

/// The files read, while a command tracks them.
#[derive(Default)]
struct Inputs(Vec<Input>);

impl Inputs {
    fn admit(&mut self, path: &Path, meta: &std::fs::Metadata) {
        let identity = (meta.dev(), meta.ino());
        if !self.0.iter().any(|i| i.identity == identity) {
            let resolved = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
            self.0.push(Input { named: path.to_path_buf(), resolved, identity });
        }
    }

    fn release(&mut self, path: &Path) {
        let identity = std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()));
        let resolved = std::fs::canonicalize(path).ok();
        self.0.retain(|i| Some(i.identity) != identity && !resolved.as_ref().is_some_and(|r| i.resolved.starts_with(r)));
    }

    /// The input that `path` is, by device and inode.
    fn file(&self, path: &Path) -> Option<&Input> {
        let meta = std::fs::metadata(path).ok()?;
        self.0.iter().find(|i| i.identity == (meta.dev(), meta.ino()))
    }

    /// An input inside the folder `path`.
    fn under(&self, path: &Path) -> Option<&Input> {
        let folder = std::fs::canonicalize(path).ok()?;
        self.0.iter().find(|i| i.resolved.starts_with(&folder))
    }
}

static TRACKED: Mutex<Option<Inputs>> = Mutex::new(None);

fn tracked() -> MutexGuard<'static, Option<Inputs>> {
    TRACKED.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
}

/// While held, the files read are recorded and refused as outputs.
pub struct Tracking(());

/// Starts recording inputs, for as long as the returned value is held.
pub fn track() -> Tracking {
    tracked().get_or_insert_with(Inputs::default);
    Tracking(())
}

impl Drop for Tracking {
    fn drop(&mut self) {
        *tracked() = None;
    }
}

/// Admits `path` as an input before it is read. Inputs are regular files: a FIFO would block
/// the read for ever, a device such as /dev/zero read without end. Err names what the path is
/// not, for the caller's message; a path that does not exist is the reader's to report.
pub fn admit(path: &Path) -> Result<(), String> {
    let Ok(meta) = std::fs::metadata(path) else { return Ok(()) };
    if !meta.is_file() {
        return Err("is not a regular file (a folder, a device, a FIFO or a socket); give a file".into());
    }
    if let Some(inputs) = tracked().as_mut() {
        inputs.admit(path, &meta);
    }
    Ok(())
}

/// The text of the input file `path` (a sweep, a recommended.toml), admitted first; Err says
/// why it cannot be read, for the caller's message.
pub fn read_text(path: &Path) -> Result<String, String> {
    admit(path)?;
    std::fs::read_to_string(path).map_err(|e| format!("cannot read it ({e})"))
}

/// Forgets the input `path`, or every input under the folder `path`: a cache entry read and
/// found stale is the command's to replace.
pub fn release(path: &Path) {
    if let Some(inputs) = tracked().as_mut() {
        inputs.release(path);
    }
}

/// Refuses the output file `path` when it is a file the command has read; Err is the whole
/// problem and fix, naming the input.
pub fn refuse_output_file(path: &Path) -> Result<(), String> {
    tracked().as_ref().and_then(|inputs| inputs.file(path)).map_or(Ok(()), |input| Err(replaces(input)))
}

/// Refuses the output folder `path` (replaced whole) when it holds a file the command has
/// read; Err names the input, the caller adds the fix.
pub fn refuse_output_folder(path: &Path) -> Result<(), String> {
    tracked().as_ref().and_then(|inputs| inputs.under(path)).map_or(Ok(()), |input| Err(holds(input)))
}

fn replaces(input: &Input) -> String {
    format!("is the input {} (the same file on disk), which this output would replace; write it elsewhere", input.named.display())
}

fn holds(input: &Input) -> String {
    format!("holds the input {}, and the folder would be replaced whole", input.named.display())
}

/// Refuses, before a command's work starts, any of its output files that is one of the
/// inputs it has read: one message naming the output, the input and the fix.
pub fn refuse_outputs<'a>(outputs: impl IntoIterator<Item = &'a Path>) -> Result<(), String> {
    outputs.into_iter().try_for_each(|output| refuse_output_file(output).map_err(|why| format!("{}: {why}", output.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a registry of its own: the process-wide one is off in tests, where tests that read
    /// and write the same files run side by side.
    #[test]
    fn an_input_is_found_by_any_name_and_inside_a_folder() {
        let dir = std::env::temp_dir().join(format!("relume-inputs-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let scene = dir.join("scene.gltf");
        std::fs::write(&scene, "{}").unwrap();
        std::fs::hard_link(&scene, dir.join("hard.gltf")).unwrap();
        std::os::unix::fs::symlink(&scene, dir.join("soft.gltf")).unwrap();
        std::fs::write(dir.join("other.png"), "").unwrap();
        let mut inputs = Inputs::default();
        inputs.admit(&scene, &std::fs::metadata(&scene).unwrap());
        for name in ["scene.gltf", "hard.gltf", "soft.gltf", "sub/../scene.gltf"] {
            let found = inputs.file(&dir.join(name)).map(replaces).unwrap_or_default();
            assert!(found.contains("scene.gltf (the same file") && found.contains("elsewhere"), "{name}: {found}");
        }
        assert!(inputs.file(&dir.join("other.png")).is_none() && inputs.file(&dir.join("new.png")).is_none());
        assert!(inputs.under(&dir).map(holds).unwrap_or_default().contains("scene.gltf"));
        assert!(inputs.under(&dir.join("sub")).is_none());
        inputs.release(&scene);
        assert!(inputs.file(&scene).is_none());
        inputs.admit(&scene, &std::fs::metadata(&scene).unwrap());
        inputs.release(&dir);
        assert!(inputs.under(&dir).is_none());
        assert!(admit(&dir).unwrap_err().contains("not a regular file"));
    }
}
