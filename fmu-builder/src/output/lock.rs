//! One build per output at a time: a build takes an exclusive flock(2) on `.NAME.lock` beside
//! each output before any work and holds it to the end. A second build to the same output is
//! refused at once, naming the build that holds it (its PID and host, written into the lock
//! file); with `--force` it waits for that build to end, then replaces what it wrote.
//!
//! The lock file is removed at the end, while still locked: a build that was waiting then holds
//! the lock of a file no longer in the folder, sees that (its inode is not the name's) and takes
//! the lock again on a new file. flock is released by the kernel when a build dies, even by
//! SIGKILL, so a lock is never stale; the file it leaves is taken over by the next build.

use super::temp_files::{self, Registered};
use crate::error::BuildError;
use std::fs::File;
use std::io::{Read, Seek, Write};
use std::os::fd::AsRawFd;
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// A held lock; released and its file removed when dropped.
#[derive(Debug)]
pub struct OutputLock {
    path: PathBuf,
    _file: File,
    _registered: Registered,
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// The lock file of the output `path` (a file, or a folder an export writes into).
pub fn lock_path(path: &Path) -> Option<PathBuf> {
    let name = path.file_name()?;
    let folder = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
    Some(folder.join(format!(".{}.lock", temp_files::stem(name))))
}

/// Takes the lock of the output `path`, `shown` (its option and path) naming it in messages.
/// Busy: refused, or with `wait` (`--force`) waited for, saying so on standard error unless
/// `quiet`.
pub fn lock(path: &Path, shown: &str, wait: bool, quiet: bool) -> Result<Option<OutputLock>, BuildError> {
    let Some(lock_path) = lock_path(path) else { return Ok(None) };
    let refuse = |reason: String| BuildError::destination(shown, reason);
    let cannot =
        |e: std::io::Error| refuse(format!("cannot lock it through {}: {e}", lock_path.display())).caused_by(e);
    loop {
        let mut file = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .mode(0o600)
            .custom_flags(libc::O_NOFOLLOW | libc::O_CLOEXEC)
            .open(&lock_path)
            .map_err(cannot)?;
        if !try_flock(&file, false).map_err(cannot)? {
            let holder = holder(&mut file);
            if !wait {
                return Err(refuse(format!(
                    "another build ({holder}) is writing this output now; wait for it to end, or pass --force \
                     to wait for it and then replace what it wrote"
                )));
            }
            if !quiet {
                eprintln!("waiting for another build ({holder}) that writes {shown} to end (--force)");
            }
            try_flock(&file, true).map_err(cannot)?;
        }
        // the holder before us may have removed the file as it ended: then lock the new one
        let same = match (file.metadata(), std::fs::symlink_metadata(&lock_path)) {
            (Ok(held), Ok(named)) => held.dev() == named.dev() && held.ino() == named.ino(),
            _ => false,
        };
        if same {
            // registered only once held: a signal while waiting must not unlink the holder's file
            let registered = temp_files::register(&lock_path);
            let _ = file.set_len(0);
            let _ = write!(file, "pid {} on {}", std::process::id(), host_name());
            return Ok(Some(OutputLock { path: lock_path, _file: file, _registered: registered }));
        }
    }
}

/// flock(LOCK_EX), blocking when `wait`: Ok(false) when another holds it and not `wait`.
fn try_flock(file: &File, wait: bool) -> std::io::Result<bool> {
    let operation = if wait { libc::LOCK_EX } else { libc::LOCK_EX | libc::LOCK_NB };
    loop {
        // SAFETY: flock on a file this function borrows open
        if unsafe { libc::flock(file.as_raw_fd(), operation) } == 0 {
            return Ok(true);
        }
        let e = std::io::Error::last_os_error();
        match e.raw_os_error() {
            Some(libc::EINTR) => continue,
            Some(libc::EWOULDBLOCK) => return Ok(false),
            _ => return Err(e),
        }
    }
}

/// What the holder wrote into the lock file ("pid 1234 on host"), or that it has not yet.
fn holder(file: &mut File) -> String {
    let mut text = String::new();
    let _ = file.rewind().and_then(|_| file.take(200).read_to_string(&mut text));
    if text.trim().is_empty() { "one that has just started".to_string() } else { text.trim().to_string() }
}

/// This machine's name, for the lock's holder.
fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname").map(|h| h.trim().to_string()).unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_second_lock_is_refused_naming_the_holder_and_the_file_goes_with_the_lock() {
        let dir = std::env::temp_dir().join(format!("output-lock-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let out = dir.join("B.fmu");
        let held = lock(&out, "-o B.fmu", false, true).unwrap().unwrap();
        // flock is per open file: a second open in this process is refused as another build's
        let e = lock(&out, "-o B.fmu", false, true).unwrap_err().to_string();
        assert!(
            e.starts_with("-o B.fmu: another build (pid ") && e.contains(&format!("pid {} on", std::process::id())),
            "{e}"
        );
        assert!(dir.join(".B.fmu.lock").exists());
        drop(held);
        assert!(!dir.join(".B.fmu.lock").exists());
        drop(lock(&out, "-o B.fmu", false, true).unwrap());
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
