//! How every output is put in place: written completely to a temporary file `.NAME.PID.N.tmp`
//! in its own folder, then renamed over its name. A build that fails, runs out of disk or file
//! size, or is interrupted leaves no partial file where an importer or a script would take it,
//! and an existing file is replaced only by a complete one.
//!
//! The destination is looked at again right before the rename, not only before the build: a
//! name that has become a symbolic link, or the input or another output under another name (a
//! hard link), while the build ran is refused, and the temporary file removed. rename(2) acts on
//! the name and never follows a link, so even a link made between that look and the rename is
//! replaced itself and the file it names is untouched. Without `--force`, the rename does not
//! replace a file that appeared meanwhile (RENAME_NOREPLACE).

use super::temp_files::{self, Registered};
use crate::error::{BuildError, Refusal, Result};
use std::cell::RefCell;
use std::fs::{File, OpenOptions};
use std::io::Write;
use std::os::unix::fs::MetadataExt;
use std::path::{Path, PathBuf};

/// What the rename checks against: the build's inputs and outputs and its `--force`.
#[derive(Debug, Clone, Default)]
pub struct Guarded {
    /// The files the build reads, with their (device, inode) when the build began.
    pub inputs: Vec<(PathBuf, Option<(u64, u64)>)>,
    /// Every file the build writes, with the option that names it.
    pub outputs: Vec<(&'static str, PathBuf)>,
    pub force: bool,
}

thread_local! {
    // the job's thread writes every output; a library caller without a job has none
    static GUARDED: RefCell<Option<Guarded>> = const { RefCell::new(None) };
}

/// While held, the writes of this thread are checked against `Guarded`.
#[derive(Debug)]
pub struct Guard(());

pub fn guard(guarded: Guarded) -> Guard {
    GUARDED.with(|g| *g.borrow_mut() = Some(guarded));
    Guard(())
}

impl Drop for Guard {
    fn drop(&mut self) {
        GUARDED.with(|g| *g.borrow_mut() = None);
    }
}

/// Writes `bytes` at `path` through a temporary file and a checked rename.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_with(path, |mut file| {
        file.write_all(bytes).and_then(|_| file.sync_all()).map_err(|e| Refusal::caused_by(io_words(&e), e))
    })
}

/// Writes `path` through a temporary file that `fill` writes (and syncs), then a checked rename.
/// A failure of `fill` is its message; the temporary file is removed on every failure.
pub fn write_with(path: &Path, fill: impl FnOnce(File) -> std::result::Result<(), Refusal>) -> Result<()> {
    let name = path.file_name().ok_or_else(|| BuildError::file(path, "is not a file path"))?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let (file, temp) = create_temp(dir, name).map_err(|e| {
        BuildError::file(path, format!("cannot create a temporary file in {}: {}", dir.display(), io_words(&e)))
            .caused_by(e)
    })?;
    fill(file).map_err(|m| {
        BuildError::file(path, format!("{m}; nothing was written there (the unfinished file was removed)")).caused_by(m)
    })?;
    GUARDED.with(|g| put_in_place(&temp.path, path, g.borrow().as_ref()))?;
    temp.disarm();
    Ok(())
}

/// An I/O error with what to do for the ones a user can act on.
pub fn io_words(e: &std::io::Error) -> String {
    match e.raw_os_error() {
        Some(libc::ENOSPC) => format!("{e}: the disk is full; free space, or name a folder on another disk"),
        Some(libc::EDQUOT) => format!("{e}: the disk quota is used up; free space, or name another folder"),
        Some(libc::EFBIG) => format!("{e}: the file size limit (ulimit -f) was reached; raise it"),
        _ => e.to_string(),
    }
}

/// A temporary file being written: unlinked when dropped unless put in place.
struct Temp {
    path: PathBuf,
    _registered: Registered,
    placed: bool,
}

impl Temp {
    fn disarm(mut self) {
        self.placed = true;
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        if !self.placed {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

fn create_temp(dir: &Path, name: &std::ffi::OsStr) -> std::io::Result<(File, Temp)> {
    let mut last = None;
    // create_new: never clobber a file someone else (a concurrent build) is writing
    for attempt in 0..100 {
        let path = temp_files::temp_path(dir, name, attempt);
        // registered first: a signal between the creation and the registration would leave it
        let registered = temp_files::register(&path);
        match OpenOptions::new().write(true).create_new(true).open(&path) {
            Ok(f) => return Ok((f, Temp { path, _registered: registered, placed: false })),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => last = Some(e),
            Err(e) => return Err(e),
        }
    }
    Err(last.unwrap_or_else(|| std::io::Error::other("no free temporary file name")))
}

/// Renames the complete `temp` to `dest` once `dest` is seen to be neither a link nor, by
/// (device, inode), an input or another output; `guarded` None: a library caller's write,
/// which replaces what is there.
pub fn put_in_place(temp: &Path, dest: &Path, guarded: Option<&Guarded>) -> Result<()> {
    let shown = guarded
        .and_then(|g| g.outputs.iter().find(|(_, p)| p == dest))
        .map_or_else(|| dest.display().to_string(), |(option, p)| format!("{option} {}", p.display()));
    let refuse = |reason: String| BuildError::destination(shown.clone(), reason);
    if let Some(reason) = changed_meanwhile(dest, guarded) {
        return Err(refuse(reason));
    }
    let replace = guarded.is_none_or(|g| g.force);
    match rename(temp, dest, replace) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(refuse(
            "appeared while the build ran; it was kept and this output not written. Pass --force to replace it, \
             or name another file"
                .into(),
        )),
        Err(e) => Err(BuildError::file(
            dest,
            format!("cannot move the finished file {} into place: {}", temp.display(), io_words(&e)),
        )
        .caused_by(e)),
    }
}

/// Why `dest` may not be replaced now, if it has become what no output may be.
fn changed_meanwhile(dest: &Path, guarded: Option<&Guarded>) -> Option<String> {
    let id = |m: std::fs::Metadata| (m.dev(), m.ino());
    let now = std::fs::symlink_metadata(dest).ok()?;
    if now.file_type().is_symlink() {
        let target = std::fs::read_link(dest).map(|t| t.display().to_string()).unwrap_or_default();
        return Some(format!(
            "became a symbolic link (to {target}) while the build ran; it was not written, and the link and what \
             it names are kept. Remove the link and build again, or name another file"
        ));
    }
    let dest_id = id(now);
    let g = guarded?;
    if let Some((input, _)) = g
        .inputs
        .iter()
        .find(|(path, at_start)| *at_start == Some(dest_id) || std::fs::metadata(path).ok().map(id) == Some(dest_id))
    {
        return Some(format!(
            "is now the input {} (a link to it appeared while the build ran); it was not written, and the input is \
             kept. Remove the link and build again, or name another file",
            input.display()
        ));
    }
    let (option, other) = g
        .outputs
        .iter()
        .find(|(_, other)| other != dest && std::fs::symlink_metadata(other).ok().map(id) == Some(dest_id))?;
    Some(format!(
        "is now the same file as {}, which {option} writes (a link appeared while the build ran); it was not \
         written. Give each output its own file",
        other.display()
    ))
}

/// rename(2); without `replace`, one that fails with AlreadyExists rather than replace a file.
fn rename(temp: &Path, dest: &Path, replace: bool) -> std::io::Result<()> {
    if replace {
        return std::fs::rename(temp, dest);
    }
    use std::os::unix::ffi::OsStrExt;
    let c = |p: &Path| std::ffi::CString::new(p.as_os_str().as_bytes()).map_err(std::io::Error::other);
    let (from, to) = (c(temp)?, c(dest)?);
    // SAFETY: two NUL-terminated paths, relative to the working directory
    let done =
        unsafe { libc::renameat2(libc::AT_FDCWD, from.as_ptr(), libc::AT_FDCWD, to.as_ptr(), libc::RENAME_NOREPLACE) };
    if done == 0 {
        return Ok(());
    }
    let e = std::io::Error::last_os_error();
    if !matches!(e.raw_os_error(), Some(libc::EINVAL | libc::ENOSYS)) {
        return Err(e);
    }
    // a file system without RENAME_NOREPLACE: link(2) does not replace either
    std::fs::hard_link(temp, dest)?;
    std::fs::remove_file(temp)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("place-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn guarded(input: &Path, outputs: &[(&'static str, &Path)], force: bool) -> Guarded {
        let m = std::fs::metadata(input).unwrap();
        Guarded {
            inputs: vec![(input.to_path_buf(), Some((m.dev(), m.ino())))],
            outputs: outputs.iter().map(|(o, p)| (*o, p.to_path_buf())).collect(),
            force,
        }
    }

    #[test]
    fn a_destination_that_became_a_link_to_the_input_is_refused_at_the_rename() {
        let dir = scratch("link");
        let input = dir.join("part.json");
        std::fs::write(&input, "{}").unwrap();
        let report = dir.join("r.json");
        let g = guarded(&input, &[("--report", &report)], true);
        let temp = dir.join(".r.json.1.0.tmp");
        std::fs::write(&temp, "report").unwrap();
        // made after every check before the build: as a process racing the build would
        std::os::unix::fs::symlink(&input, &report).unwrap();
        let e = put_in_place(&temp, &report, Some(&g)).unwrap_err().to_string();
        assert!(e.starts_with(&format!("--report {}: became a symbolic link", report.display())), "{e}");
        assert!(e.contains("Remove the link"), "{e}");
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "{}");
        // a hard link to the input, or to another output
        std::fs::remove_file(&report).unwrap();
        std::fs::hard_link(&input, &report).unwrap();
        let e = put_in_place(&temp, &report, Some(&g)).unwrap_err().to_string();
        assert!(e.contains(&format!("is now the input {}", input.display())), "{e}");
        std::fs::remove_file(&report).unwrap();
        let fmu = dir.join("B.fmu");
        std::fs::write(&fmu, "PK").unwrap();
        std::fs::hard_link(&fmu, &report).unwrap();
        let g = guarded(&input, &[("-o", &fmu), ("--report", &report)], true);
        let e = put_in_place(&temp, &report, Some(&g)).unwrap_err().to_string();
        assert!(e.contains(&format!("is now the same file as {}, which -o writes", fmu.display())), "{e}");
        assert_eq!(std::fs::read_to_string(&fmu).unwrap(), "PK");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn without_force_a_file_that_appeared_is_kept_and_with_it_replaced() {
        let dir = scratch("appeared");
        let input = dir.join("part.json");
        std::fs::write(&input, "{}").unwrap();
        let out = dir.join("B.fmu");
        let temp = dir.join(".B.fmu.1.0.tmp");
        std::fs::write(&temp, "new").unwrap();
        std::fs::write(&out, "theirs").unwrap();
        let e = put_in_place(&temp, &out, Some(&guarded(&input, &[("-o", &out)], false))).unwrap_err().to_string();
        assert!(e.contains("appeared while the build ran; it was kept") && e.contains("--force"), "{e}");
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "theirs");
        put_in_place(&temp, &out, Some(&guarded(&input, &[("-o", &out)], true))).unwrap();
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_failed_write_leaves_nothing_and_says_so() {
        let dir = scratch("failed");
        let out = dir.join("r.json");
        let e = write_with(&out, |_| Err("disk full".into())).unwrap_err().to_string();
        assert!(e.contains("r.json: disk full; nothing was written there"), "{e}");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
        write_bytes(&out, b"{}").unwrap();
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
