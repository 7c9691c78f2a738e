//! Every file the builder reads (the input, meshes and their includes, matrices, node tables,
//! platform binaries) is read through here: a regular file, at most a size that fits its kind
//! and the machine's memory, read with that bound. A FIFO would otherwise block the build
//! forever and /dev/zero would be read until memory runs out; both are refused at once.

use std::io::Read;
use std::path::Path;

const MIB: u64 = 1 << 20;
const GIB: u64 = 1 << 30;

/// What a file is to the builder: sets its size limit and the word messages use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileKind {
    /// The JSON input: a few kB usually; inline node or load tables may make it megabytes.
    Input,
    /// A mesh (`.inp`, `.msh`, an included deck): 2e6 DoF of tet10 is about 100 MB of text.
    Mesh,
    /// Matrix Market K and M, DoF maps, node tables: K of a 2e6-DoF part is some 6 GB of text.
    Matrix,
    /// A compiled fmu-runtime for another platform: a few MB.
    PlatformBinary,
}

impl FileKind {
    pub fn limit(self) -> u64 {
        match self {
            FileKind::Input => 256 * MIB,
            FileKind::Mesh => 16 * GIB,
            FileKind::Matrix => 64 * GIB,
            FileKind::PlatformBinary => 256 * MIB,
        }
    }

    fn what(self) -> &'static str {
        match self {
            FileKind::Input => "an input file",
            FileKind::Mesh => "a mesh file",
            FileKind::Matrix => "a matrix file",
            FileKind::PlatformBinary => "a runtime binary",
        }
    }
}

pub use crate::error::Refusal;

/// What a non-regular file is, in words.
pub fn file_type_words(t: std::fs::FileType) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Ok when `path` names (through links) a regular file of at most `kind`'s limit and of no more
/// than `memory_bytes` (reading it holds it whole in memory). Decided by the file's metadata
/// alone: nothing is opened, so a FIFO cannot block.
pub fn check(path: &Path, kind: FileKind, memory_bytes: f64) -> Result<u64, Refusal> {
    let meta = std::fs::metadata(path).map_err(|e| Refusal::caused_by(format!("cannot be read: {e}"), e))?;
    check_metadata(&meta, kind, memory_bytes)
}

fn check_metadata(meta: &std::fs::Metadata, kind: FileKind, memory_bytes: f64) -> Result<u64, Refusal> {
    if !meta.is_file() {
        return Err(Refusal::from(format!(
            "is {}, not a regular file; give {} the builder can read to its end",
            file_type_words(meta.file_type()),
            kind.what()
        )));
    }
    let size = meta.len();
    if size > kind.limit() {
        return Err(Refusal::from(format!(
            "is {}, more than the {} {} may have",
            bytes_words(size),
            bytes_words(kind.limit()),
            kind.what()
        )));
    }
    if size as f64 > memory_bytes {
        return Err(Refusal::from(format!(
            "is {}, more than the {} of memory this process may use to hold it",
            bytes_words(size),
            bytes_words(memory_bytes as u64)
        )));
    }
    Ok(size)
}

/// The whole file, checked as `check` does on the opened file itself, then read with the bound:
/// a file that grows while it is read (or a device that lied about its size) stops at the limit
/// with a refusal. The file is opened non-blocking, so a FIFO is refused, not waited on.
pub fn read(path: &Path, kind: FileKind, memory_bytes: f64) -> Result<Vec<u8>, Refusal> {
    use std::os::unix::fs::OpenOptionsExt;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(|e| Refusal::caused_by(format!("cannot be read: {e}"), e))?;
    let meta = file.metadata().map_err(|e| Refusal::caused_by(format!("cannot be read: {e}"), e))?;
    let size = check_metadata(&meta, kind, memory_bytes)?;
    let bound = kind.limit().min(memory_bytes as u64);
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(size as usize).map_err(|_| {
        Refusal::from(format!("is {}, and this process cannot allocate that much to read it", bytes_words(size)))
    })?;
    file.take(bound + 1).read_to_end(&mut bytes).map_err(|e| Refusal::caused_by(format!("cannot be read: {e}"), e))?;
    if bytes.len() as u64 > bound {
        return Err(Refusal::from(format!("grew past {} while it was read", bytes_words(bound))));
    }
    Ok(bytes)
}

/// `read` as text (invalid UTF-8 replaced: it only matters in comments).
pub fn read_text(path: &Path, kind: FileKind, memory_bytes: f64) -> Result<String, Refusal> {
    let bytes = read(path, kind, memory_bytes)?;
    Ok(match String::from_utf8(bytes) {
        Ok(s) => s,
        Err(e) => String::from_utf8_lossy(e.as_bytes()).into_owned(),
    })
}

fn bytes_words(b: u64) -> String {
    if b >= GIB {
        format!("{:.1} GiB", b as f64 / GIB as f64)
    } else if b >= MIB {
        format!("{:.1} MiB", b as f64 / MIB as f64)
    } else {
        format!("{b} bytes")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::{Duration, Instant};

    const PLENTY: f64 = 1e12;

    #[test]
    fn a_fifo_is_refused_at_once_without_blocking() {
        let dir = std::env::temp_dir().join(format!("file-read-fifo-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let fifo = dir.join("pipe");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: mkfifo on a NUL-terminated path
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let start = Instant::now();
        let e = read(&fifo, FileKind::PlatformBinary, PLENTY).unwrap_err();
        assert!(start.elapsed() < Duration::from_secs(1));
        assert!(e.reason.contains("is a FIFO (named pipe), not a regular file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn dev_zero_and_folders_are_refused_with_their_kind() {
        let start = Instant::now();
        let e = read(Path::new("/dev/zero"), FileKind::Mesh, PLENTY).unwrap_err();
        assert!(start.elapsed() < Duration::from_secs(1));
        assert!(e.reason.contains("is a character device, not a regular file; give a mesh file"), "{e}");
        let e = read(Path::new("/"), FileKind::Input, PLENTY).unwrap_err();
        assert!(e.reason.starts_with("is a folder"), "{e}");
    }

    #[test]
    fn a_file_over_its_limit_or_the_memory_is_refused_before_reading() {
        let dir = std::env::temp_dir().join(format!("file-read-size-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("big.bin");
        // sparse: 300 MiB of size, no blocks
        let f = std::fs::File::create(&path).unwrap();
        f.set_len(300 * MIB).unwrap();
        let e = read(&path, FileKind::PlatformBinary, PLENTY).unwrap_err();
        assert_eq!(e.reason, "is 300.0 MiB, more than the 256.0 MiB a runtime binary may have");
        let e = read(&path, FileKind::Mesh, 100.0 * MIB as f64).unwrap_err();
        assert!(e.reason.contains("more than the 100.0 MiB of memory this process may use"), "{e}");
        std::fs::write(&path, b"ok").unwrap();
        assert_eq!(read(&path, FileKind::Input, PLENTY).unwrap(), b"ok");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
