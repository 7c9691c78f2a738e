//! The job folder and the driver's token, private to the user who builds: the token is what
//! makes a connection to the builder's port the driver's, so no other local user may read it,
//! guess it, or swap the driver it is given to.
//!
//! - The token and the folder's name are 32 and 8 bytes of the system's random source
//!   (/dev/urandom): not the clock and the PID, which another process can reconstruct.
//! - The folder is created (not reused: `create_dir` fails on an existing path) with mode 0700,
//!   every file in it with 0600, so the token in job.json, the driver the ranks run and the
//!   matrices are the builder's user's alone, whatever the umask.

use crate::error::{BackendError, Result};
use std::io::Read;
use std::os::unix::fs::{DirBuilderExt, OpenOptionsExt};
use std::path::{Path, PathBuf};

/// `bytes` bytes of the system's random source, in hex.
pub fn random_hex(bytes: usize) -> Result<String> {
    let mut buffer = vec![0u8; bytes];
    std::fs::File::open("/dev/urandom").and_then(|mut f| f.read_exact(&mut buffer)).map_err(|e| {
        BackendError::Unavailable(format!("reading the random source /dev/urandom for the driver's token: {e}"))
    })?;
    Ok(buffer.iter().map(|b| format!("{b:02x}")).collect())
}

/// A new folder `fmu-builder-petsc-<random>` in `base`, mode 0700; the error names the path.
pub fn create(base: &Path) -> Result<PathBuf> {
    let folder = base.join(format!("fmu-builder-petsc-{}", random_hex(8)?));
    std::fs::DirBuilder::new().mode(0o700).create(&folder).map_err(|e| {
        BackendError::Unavailable(format!(
            "cannot create the job folder {}: {e}; name a writable folder every rank sees \
             (reduction.backend.job_folder)",
            folder.display()
        ))
    })?;
    Ok(folder)
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
        .map_err(|e| BackendError::Unavailable(format!("cannot write {}: {e}", path.display())))
}

/// `private_file` with `text` in it.
pub fn write_private(path: &Path, text: &str) -> Result<()> {
    use std::io::Write;
    private_file(path)?
        .write_all(text.as_bytes())
        .map_err(|e| BackendError::Unavailable(format!("cannot write {}: {e}", path.display())))
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
}
