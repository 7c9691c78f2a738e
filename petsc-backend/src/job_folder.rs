//! The job folder and the driver's token, private to the user who builds: the token is what
//! makes a connection to the builder's port the driver's, so no other local user may read it,
//! guess it, or swap the driver it is given to.
//!
//! - The token and the folder's name are 32 and 8 bytes of the system's random source
//!   (/dev/urandom): not the clock and the PID, which another process can reconstruct.
//! - The folder is created (not reused: `create_dir` fails on an existing path) with mode 0700,
//!   every file in it with 0600, so the token in job.json, the driver the ranks run and the
//!   matrices are the builder's user's alone, whatever the umask.
//! - The name also carries the host and the PID of the builder that made it,
//!   `fmu-builder-petsc-<host>-<pid>-<random>`: a builder killed outright (SIGKILL, whose
//!   handler cannot run) leaves its folder, and the next build on that host removes it
//!   (`sweep_stale`) once no process of that PID lives.

use crate::error::{BackendError, Result};
use std::io::Read;
use std::os::unix::fs::{DirBuilderExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// `bytes` bytes of the system's random source, in hex.
pub fn random_hex(bytes: usize) -> Result<String> {
    let mut buffer = vec![0u8; bytes];
    std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut buffer)).map_err(|e| {
        BackendError::unavailable(format!("reading the random source /dev/urandom for the driver's token: {e}"))
            .caused_by(e)
    })?;
    Ok(buffer.iter().map(|b| format!("{b:02x}")).collect())
}

/// A new folder `fmu-builder-petsc-<host>-<pid>-<random>` in `base`, mode 0700; the error names
/// the path.
pub fn create(base: &Path) -> Result<PathBuf> {
    let folder = base.join(format!("{PREFIX}{}-{}-{}", host(), std::process::id(), random_hex(8)?));
    std::fs::DirBuilder::new().mode(0o700).create(&folder).map_err(|e| {
        BackendError::unavailable(format!(
            "cannot create the job folder {}: {e}; name a writable folder every rank sees \
             (reduction.backend.job_folder)",
            folder.display()
        ))
        .caused_by(e)
    })?;
    Ok(folder)
}

const PREFIX: &str = "fmu-builder-petsc-";

/// This machine's name as a job folder carries it: characters other than letters, digits, `.`
/// and `_` as `_` (a `-` would make the name ambiguous).
fn host() -> String {
    let name = std::fs::read_to_string("/proc/sys/kernel/hostname").unwrap_or_default();
    name.trim().chars().map(|c| if c.is_ascii_alphanumeric() || c == '.' || c == '_' { c } else { '_' }).collect()
}

/// The file that marks a folder kept on purpose (`FMU_BUILDER_KEEP_PETSC_JOB`): never swept.
const KEPT: &str = "kept";

/// Marks `folder` as one to keep for a look after its build.
pub fn mark_kept(folder: &Path) -> Result<()> {
    write_private(&folder.join(KEPT), "FMU_BUILDER_KEEP_PETSC_JOB was set: remove this folder by hand\n")
}

/// Removes from `base` the job folders of builders on this host that are gone: named
/// `fmu-builder-petsc-<this host>-<pid>-<16 hex>`, a folder (not a link) of this user, not kept
/// on purpose (`mark_kept`), and no process of that PID alive. Folders of other hosts (a shared job folder on a cluster), of
/// other users and of live builders stay. Returns the folders removed.
pub fn sweep_stale(base: &Path) -> Vec<PathBuf> {
    use std::os::unix::fs::MetadataExt;
    let Ok(entries) = std::fs::read_dir(base) else { return Vec::new() };
    let host = host();
    // SAFETY: geteuid cannot fail
    let me = unsafe { libc::geteuid() };
    let mut removed = Vec::new();
    for entry in entries.flatten() {
        let name = entry.file_name();
        let Some(pid) = name.to_str().and_then(|n| stale_pid(n, &host)) else { continue };
        let Ok(m) = std::fs::symlink_metadata(entry.path()) else { continue };
        if m.is_dir() && m.uid() == me && !alive(pid) && !entry.path().join(KEPT).exists() {
            std::fs::remove_dir_all(entry.path()).ok();
            removed.push(entry.path());
        }
    }
    removed
}

/// The PID in a job folder's name made on `host`.
fn stale_pid(name: &str, host: &str) -> Option<i32> {
    let (rest, random) = name.strip_prefix(PREFIX)?.rsplit_once('-')?;
    let (made_on, pid) = rest.rsplit_once('-')?;
    let random_ok = random.len() == 16 && random.bytes().all(|b| b.is_ascii_hexdigit());
    (random_ok && made_on == host).then(|| pid.parse().ok()).flatten()
}

/// Whether a process of `pid` lives on this machine (EPERM: another user's).
fn alive(pid: i32) -> bool {
    // SAFETY: signal 0 only checks that the process exists
    pid > 0
        && (unsafe { libc::kill(pid, 0) } == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM))
}

/// Removes the job folder. Ranks the launcher did not hold (other nodes) may still be ending,
/// their heartbeat watchers writing a last beat while the folder goes: again, for up to five
/// seconds, until it is gone (a watcher stops once the folder is).
pub fn remove(folder: &Path) {
    for _ in 0..50 {
        std::fs::remove_dir_all(folder).ok();
        if !folder.exists() {
            return;
        }
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
}

/// A new file readable and writable by this user only (0600), truncating one of the builder's
/// own; the error names the path.
pub fn private_file(path: &Path) -> Result<std::fs::File> {
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .mode(0o600)
        .open(path)
        .map_err(|e| BackendError::unavailable(format!("cannot write {}: {e}", path.display())).caused_by(e))
}

/// `private_file` with `text` in it.
pub fn write_private(path: &Path, text: &str) -> Result<()> {
    use std::io::Write;
    private_file(path)?
        .write_all(text.as_bytes())
        .map_err(|e| BackendError::unavailable(format!("cannot write {}: {e}", path.display())).caused_by(e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    #[test]
    fn tokens_are_random_hex_and_folders_and_files_private() {
        let a = random_hex(32).unwrap();
        let b = random_hex(32).unwrap();
        assert_eq!(a.len(), 64);
        assert!(a.chars().all(|c| c.is_ascii_hexdigit()) && a != b);
        let base = std::env::temp_dir();
        let folder = create(&base).unwrap();
        assert_eq!(std::fs::metadata(&folder).unwrap().permissions().mode() & 0o777, 0o700);
        write_private(&folder.join("job.json"), "{}").unwrap();
        assert_eq!(std::fs::metadata(folder.join("job.json")).unwrap().permissions().mode() & 0o777, 0o600);
        std::fs::remove_dir_all(&folder).unwrap();
        let e = create(Path::new("/proc/no-such-folder")).unwrap_err().to_string();
        assert!(e.contains("cannot create the job folder /proc/no-such-folder/fmu-builder-petsc-"), "{e}");
    }

    #[test]
    fn folders_of_gone_builders_on_this_host_are_swept_and_no_other() {
        let base = std::env::temp_dir().join(format!("job-sweep-{}", std::process::id()));
        std::fs::remove_dir_all(&base).ok();
        std::fs::create_dir_all(&base).unwrap();
        let live = create(&base).unwrap();
        // a PID above pid_max (4194304 at most) is no process
        let gone = base.join(format!("{PREFIX}{}-4999999-0123456789abcdef", host()));
        let elsewhere = base.join(format!("{PREFIX}another_host-4999999-0123456789abcdef"));
        let old_style = base.join(format!("{PREFIX}0123456789abcdef"));
        let kept = base.join(format!("{PREFIX}{}-4999999-00000000000000ff", host()));
        for f in [&gone, &elsewhere, &old_style, &kept] {
            std::fs::create_dir(f).unwrap();
        }
        mark_kept(&kept).unwrap();
        write_private(&gone.join("job.json"), "{\"token\": \"t\"}").unwrap();
        assert_eq!(sweep_stale(&base), vec![gone.clone()]);
        assert!(!gone.exists() && live.exists() && elsewhere.exists() && old_style.exists() && kept.exists());
        std::fs::remove_dir_all(&base).unwrap();
    }
}
