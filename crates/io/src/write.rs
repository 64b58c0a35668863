//! Outputs that respect the file system. A regular file (or a new one) is written atomically: a
//! temporary file beside the target, flushed to disk, then renamed over it, so that a run killed midway
//! leaves either the old file or the complete new one. Anything else is written in place — a device
//! (`/dev/null`), a pipe — and never replaced; a directory is refused; `-` is standard output.
//!
//! Temporary files are named `.<name>.thermokin-tmp-<pid>`: while one is being written it is registered,
//! so that a front end's signal handler can remove it ([`remove_temporaries`]); one left by a process
//! that no longer runs (killed by SIGKILL) is removed by the next write of the same target.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use crate::IoError;

/// The temporary files being written by this process.
static TEMPORARIES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// The marker of this project's temporary files, between the target's name and the writer's pid.
const MARKER: &str = ".thermokin-tmp-";

/// Writes `bytes` to `path` ([`write_atomic_with`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), IoError> {
    write_atomic_with(path, |w| w.write_all(bytes))
}

/// Writes to `path` through a writer callback: atomically for a regular or new file, in place for a
/// device or pipe, on standard output for `-`; a directory is refused.
pub fn write_atomic_with(
    path: &Path,
    fill: impl FnOnce(&mut std::io::BufWriter<Box<dyn Write>>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    if path == Path::new("-") {
        let mut w = std::io::BufWriter::new(Box::new(std::io::stdout()) as Box<dyn Write>);
        return fill(&mut w).and_then(|()| w.flush()).map_err(|e| IoError::file(path, e));
    }
    // A symbolic link is followed: the file it names is the output.
    let target = match std::fs::symlink_metadata(path) {
        Ok(m) if m.file_type().is_symlink() => std::fs::canonicalize(path).map_err(|e| IoError::file(path, e))?,
        _ => path.to_path_buf(),
    };
    match std::fs::metadata(&target) {
        Ok(m) if m.is_dir() => Err(IoError::file(path, "is a directory, not a file")),
        Ok(m) if !m.is_file() => {
            // A device, a FIFO, a socket: written where it is, never replaced by a rename.
            let file = std::fs::OpenOptions::new().write(true).open(&target).map_err(|e| IoError::file(path, e))?;
            let mut w = std::io::BufWriter::new(Box::new(file) as Box<dyn Write>);
            fill(&mut w).and_then(|()| w.flush()).map_err(|e| IoError::file(path, e))
        }
        _ => replace_atomically(path, &target, fill),
    }
}

/// Writes a temporary file beside `target` and renames it over `target`.
fn replace_atomically(
    path: &Path,
    target: &Path,
    fill: impl FnOnce(&mut std::io::BufWriter<Box<dyn Write>>) -> std::io::Result<()>,
) -> Result<(), IoError> {
    remove_stale(target);
    let tmp = temporary_path(target, std::process::id());
    register(&tmp);
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(Box::new(file.try_clone()?) as Box<dyn Write>);
        fill(&mut w)?;
        w.flush()?;
        drop(w);
        file.sync_all()?;
        std::fs::rename(&tmp, target)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    deregister(&tmp);
    result.map_err(|e| IoError::file(path, e))
}

/// `dir/.name.thermokin-tmp-<pid>`: hidden, in the same directory (so the rename stays on one file system).
fn temporary_path(path: &Path, pid: u32) -> PathBuf {
    let name = path.file_name().map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}{MARKER}{pid}"))
}

fn register(tmp: &Path) {
    if let Ok(mut list) = TEMPORARIES.lock() {
        list.push(tmp.to_path_buf());
    }
}

fn deregister(tmp: &Path) {
    if let Ok(mut list) = TEMPORARIES.lock() {
        list.retain(|p| p != tmp);
    }
}

/// Removes every temporary file this process is writing: for a signal handler, before the process
/// exits.
pub fn remove_temporaries() {
    if let Ok(list) = TEMPORARIES.lock() {
        for p in list.iter() {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// Removes the temporary files of `target` left by processes that no longer run (a writer killed by
/// SIGKILL cannot remove its own); on systems without `/proc` nothing is removed.
fn remove_stale(target: &Path) {
    let (Some(dir), Some(name)) = (target.parent(), target.file_name()) else { return };
    let dir = if dir.as_os_str().is_empty() { Path::new(".") } else { dir };
    if !Path::new("/proc/self").exists() {
        return;
    }
    let prefix = format!(".{}{MARKER}", name.to_string_lossy());
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries.flatten() {
        let file = entry.file_name().to_string_lossy().into_owned();
        let Some(pid) = file.strip_prefix(&prefix).and_then(|p| p.parse::<u32>().ok()) else { continue };
        if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // Tests unwrap to fail.
mod tests {
    use super::*;

    #[test]
    fn a_leftover_of_a_dead_writer_is_removed_and_a_live_ones_kept() {
        let dir = std::env::temp_dir().join(format!("thermokin-write-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let target = dir.join("out.csv");
        // A pid no process has (beyond the kernel's maximum) and this process's own.
        let dead = temporary_path(&target, 4_194_304 + 7);
        let live = temporary_path(&target, 1);
        std::fs::write(&dead, "half").unwrap();
        std::fs::write(&live, "busy").unwrap();
        write_atomic(&target, b"whole").unwrap();
        assert_eq!(std::fs::read_to_string(&target).unwrap(), "whole");
        assert!(!dead.exists(), "the dead writer's leftover stays");
        assert!(live.exists(), "a running process's temporary was removed");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
