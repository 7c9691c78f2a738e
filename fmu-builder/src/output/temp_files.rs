//! The hidden files a build holds while it runs, and what happens to them when it is stopped.
//!
//! Every output is written to `.NAME.PID.N.tmp` in its own folder and renamed into place when
//! complete; every output is reserved by `.NAME.lock` beside it. Both are in a registry here that
//! a signal handler reads: on SIGINT, SIGTERM or SIGHUP it unlinks them (unlink is
//! async-signal-safe, memory allocation and locks are not, so the registry is fixed slots of
//! bytes behind atomics) and the process then ends with the signal, as it would have without
//! the handler. SIGXFSZ (a write past `ulimit -f`) is caught so that the write fails with EFBIG
//! instead of killing the builder: the error then names the file and removes the temporary file.
//!
//! SIGKILL cannot be caught: the temporary file of a killed build is removed by the next build
//! into the same folder (`sweep_stale`), which holds that output's lock, so no live build can own
//! the file: the sweep takes only files whose PID is not a live process, to be safe anyway.

use std::cell::UnsafeCell;
use std::ffi::OsStr;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU32, Ordering};

/// Files held at once: the FMU, four file exports and two folders' files, each with its lock.
const SLOTS: usize = 32;
/// PATH_MAX on Linux, with the terminating NUL.
const PATH_BYTES: usize = 4096;
/// A slot's state is `generation << 2 | FREE/BUSY/READY`: the handler reads a path only when
/// the state is READY and the same before and after the copy (a sequence lock).
const FREE: u32 = 0;
const BUSY: u32 = 1;
const READY: u32 = 2;

struct Slot {
    state: AtomicU32,
    path: UnsafeCell<[u8; PATH_BYTES]>,
}

// SAFETY: `path` is written only by the thread that moved the slot from FREE to BUSY, and the
// handler uses a copy only when the state says no write began or ended during the copy.
unsafe impl Sync for Slot {}

/// Fixed slots of paths, readable from a signal handler.
pub struct Registry([Slot; SLOTS]);

/// The build's temporary files and locks.
static REGISTRY: Registry = Registry::new();

/// A path in a registry, removed from it (not from the disk) when dropped.
#[derive(Debug)]
pub struct Registered(Option<(&'static Registry, usize)>);

impl std::fmt::Debug for Registry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Registry")
    }
}

/// Puts `path` in the build's registry; a path too long for a slot, or a full registry, is
/// simply not removed on a signal (the next build's sweep finds it).
pub fn register(path: &Path) -> Registered {
    REGISTRY.register(path)
}

impl Registry {
    const fn new() -> Self {
        Registry([const { Slot { state: AtomicU32::new(FREE), path: UnsafeCell::new([0; PATH_BYTES]) } }; SLOTS])
    }

    fn register(&'static self, path: &Path) -> Registered {
        let bytes = path.as_os_str().as_bytes();
        if bytes.len() >= PATH_BYTES || bytes.contains(&0) {
            return Registered(None);
        }
        for (i, slot) in self.0.iter().enumerate() {
            let s = slot.state.load(Ordering::Acquire);
            let busy = (s & !3) + 4 + BUSY;
            if s & 3 != FREE || slot.state.compare_exchange(s, busy, Ordering::AcqRel, Ordering::Relaxed).is_err() {
                continue;
            }
            // SAFETY: this thread owns the slot (BUSY) until it publishes it READY below
            let buffer = unsafe { &mut *slot.path.get() };
            buffer[..bytes.len()].copy_from_slice(bytes);
            buffer[bytes.len()] = 0;
            slot.state.store(busy - BUSY + READY, Ordering::Release);
            return Registered(Some((self, i)));
        }
        Registered(None)
    }

    /// Unlinks every registered path. Async-signal-safe: atomics, a copy on the stack, unlink(2).
    fn remove_all(&self) {
        for slot in &self.0 {
            let before = slot.state.load(Ordering::Acquire);
            if before & 3 != READY {
                continue;
            }
            let mut copy = [0u8; PATH_BYTES];
            // SAFETY: a plain copy; it is used only if no write to the slot began meanwhile
            unsafe { std::ptr::copy_nonoverlapping(slot.path.get() as *const u8, copy.as_mut_ptr(), PATH_BYTES) };
            if slot.state.load(Ordering::Acquire) == before {
                // SAFETY: a NUL-terminated path on the stack
                unsafe { libc::unlink(copy.as_ptr() as *const libc::c_char) };
            }
        }
    }
}

impl Drop for Registered {
    fn drop(&mut self) {
        if let Some((registry, i)) = self.0.take() {
            let state = &registry.0[i].state;
            let s = state.load(Ordering::Acquire);
            state.store((s & !3) + 4 + FREE, Ordering::Release);
        }
    }
}

/// Installs the handlers (once): SIGINT, SIGTERM and SIGHUP remove the registered files and end
/// the process with the signal; SIGXFSZ makes the write that passed the size limit fail instead.
pub fn install_handlers() {
    static INSTALLED: std::sync::OnceLock<()> = std::sync::OnceLock::new();
    INSTALLED.get_or_init(|| {
        // a signal the builder was started ignoring (nohup, `&` in a script) stays ignored
        for signal in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP].into_iter().filter(|&s| !ignored(s)) {
            // SAFETY: the action only uses atomics, copies, unlink, write and the default action
            let _ = unsafe { signal_hook::low_level::register(signal, move || on_interruption(signal)) };
        }
        // SAFETY: an action that does nothing
        let _ = unsafe { signal_hook::low_level::register(libc::SIGXFSZ, || {}) };
    });
}

/// Whether `signal`'s disposition is SIG_IGN.
fn ignored(signal: i32) -> bool {
    // SAFETY: reads the disposition into a zeroed sigaction, changing nothing
    unsafe {
        let mut current: libc::sigaction = std::mem::zeroed();
        libc::sigaction(signal, std::ptr::null(), &mut current) == 0 && current.sa_sigaction == libc::SIG_IGN
    }
}

fn on_interruption(signal: i32) {
    REGISTRY.remove_all();
    // a distributed build's own handler ends its ranks first, then the process with this signal
    if petsc_backend::process_group::ends_the_process_on_interruption() {
        return;
    }
    let text = b"\nerror: interrupted; the unfinished outputs' temporary files were removed\n";
    // SAFETY: write(2) to standard error
    unsafe { libc::write(2, text.as_ptr() as *const libc::c_void, text.len()) };
    let _ = signal_hook::low_level::emulate_default_handler(signal);
}

/// The part of an output's name its hidden files carry: the name itself, or for a name too long
/// to take `.` before and `.PID.N.tmp` after within NAME_MAX (255 bytes), its first 180 bytes
/// and a hash of the whole, so that two long names keep two stems.
pub fn stem(name: &OsStr) -> String {
    let text = name.to_string_lossy();
    if text.len() <= 200 {
        return text.into_owned();
    }
    let mut end = 180;
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    // FNV-1a: stable across builds and Rust versions, which a lock name must be
    let hash =
        name.as_bytes().iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x100_0000_01b3));
    format!("{}~{hash:016x}", &text[..end])
}

/// The temporary file `.STEM.PID.N.tmp` for an output named `name` in `dir`.
pub fn temp_path(dir: &Path, name: &OsStr, attempt: u32) -> PathBuf {
    dir.join(format!(".{}.{}.{attempt}.tmp", stem(name), std::process::id()))
}

/// Whether `pid` is a live process on this machine (EPERM: alive, another user's).
pub fn process_alive(pid: i32) -> bool {
    // SAFETY: signal 0 only checks that the process exists
    pid > 0
        && (unsafe { libc::kill(pid, 0) } == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM))
}

/// Removes from `dir` the temporary files `.STEM.PID.N.tmp` of the output named `name` left by
/// builds that are gone (killed, the machine reset): regular files of this user whose PID is
/// not a live process. Returns how many were removed.
pub fn sweep_stale(dir: &Path, name: &OsStr) -> usize {
    use std::os::unix::fs::MetadataExt;
    let prefix = format!(".{}.", stem(name));
    let Ok(entries) = std::fs::read_dir(dir) else { return 0 };
    // SAFETY: geteuid cannot fail
    let me = unsafe { libc::geteuid() };
    let mut removed = 0;
    for entry in entries.flatten() {
        let file_name = entry.file_name();
        let Some(rest) = file_name.to_str().and_then(|n| n.strip_prefix(&prefix)?.strip_suffix(".tmp")) else {
            continue;
        };
        let Some((pid, attempt)) = rest.split_once('.') else { continue };
        let (Ok(pid), Ok(_)) = (pid.parse::<i32>(), attempt.parse::<u32>()) else { continue };
        let ours = pid == std::process::id() as i32;
        let Ok(m) = std::fs::symlink_metadata(entry.path()) else { continue };
        if !ours && !process_alive(pid) && m.is_file() && m.uid() == me && std::fs::remove_file(entry.path()).is_ok() {
            removed += 1;
        }
    }
    removed
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registered_files_are_unlinked_and_freed_slots_reused() {
        let dir = std::env::temp_dir().join(format!("temp-files-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // a registry of its own: the build's is shared with the other tests' writes
        static LOCAL: Registry = Registry::new();
        let kept = dir.join("kept");
        std::fs::write(&kept, "x").unwrap();
        drop(LOCAL.register(&kept));
        let held = dir.join(".B.fmu.1.0.tmp");
        std::fs::write(&held, "x").unwrap();
        let registered: Vec<Registered> = (0..SLOTS).map(|_| LOCAL.register(&held)).collect();
        assert!(registered.iter().all(|r| r.0.is_some()) && LOCAL.register(&held).0.is_none());
        LOCAL.remove_all();
        assert!(!held.exists() && kept.exists());
        drop(registered);
        assert!(LOCAL.register(&kept).0.is_some());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn stale_temporary_files_of_gone_builds_are_swept_and_nothing_else() {
        let dir = std::env::temp_dir().join(format!("temp-sweep-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        // a PID above pid_max (4194304 at most) is no process
        let gone = dir.join(".B.fmu.4999999.0.tmp");
        let alive = dir.join(format!(".B.fmu.{}.0.tmp", std::process::id()));
        let other = dir.join(".C.fmu.4999999.0.tmp");
        let unlike = dir.join(".B.fmu.x.0.tmp");
        for f in [&gone, &alive, &other, &unlike] {
            std::fs::write(f, "x").unwrap();
        }
        assert_eq!(sweep_stale(&dir, OsStr::new("B.fmu")), 1);
        assert!(!gone.exists() && alive.exists() && other.exists() && unlike.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn long_names_keep_their_hidden_files_within_name_max() {
        let long = "é".repeat(150);
        let s = stem(OsStr::new(&long));
        assert!(s.len() <= 200 && s != stem(OsStr::new(&format!("{long}x"))), "{s}");
        let tmp = temp_path(Path::new("."), OsStr::new(&long), 99);
        assert!(tmp.file_name().unwrap().len() <= 255);
        assert_eq!(stem(OsStr::new("B.fmu")), "B.fmu");
    }
}
