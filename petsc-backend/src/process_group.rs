//! The launcher and everything it starts, as one process group the builder owns: killed as a
//! group on every error, timeout, interruption (SIGINT, SIGTERM, SIGHUP: a handler) and at the
//! end, so no rank outlives the build; and watched while the builder waits for an answer, so a
//! stopped rank (SIGSTOP, a debugger) is named instead of waited for.
//!
//! The launcher is started as the leader of a new group (`process_group(0)`), so a Ctrl-C in
//! the terminal reaches the builder only, which then ends the job and removes the job folder.
//! OpenMPI's mpirun puts each local rank in a process group of its own, so the job is the
//! launcher's group and every descendant of the launcher, found through /proc before anything
//! is signalled (a rank whose launcher is gone is re-parented and could not be found after).

use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

/// Seconds a group gets between SIGTERM and SIGKILL: MPI's own shutdown (mpirun forwards the
/// signal to the ranks and reports) takes a fraction of that.
const GRACE: Duration = Duration::from_secs(3);

/// Groups and job folders to clean up if the builder is interrupted.
struct Job {
    group: i32,
    folder: PathBuf,
    keep_folder: bool,
}

static JOBS: Mutex<Vec<Job>> = Mutex::new(Vec::new());
static HANDLER: OnceLock<()> = OnceLock::new();
static INTERRUPTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
/// Set once the handler's thread waits for signals: from then on it ends the process.
static HANDLING: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether an interruption (SIGINT, SIGTERM, SIGHUP) is this crate's to end the process with,
/// after the ranks: other handlers (the builder's, which removes its temporary files) must then
/// not end it first. Async-signal-safe: one atomic load.
pub fn ends_the_process_on_interruption() -> bool {
    HANDLING.load(std::sync::atomic::Ordering::SeqCst)
}

/// Called where the job's end shows as an error (a closed connection, an ended launcher): after
/// an interruption that end is the handler's doing, and the handler ends the builder with the
/// signal's status; the error must not race it to the exit with its own message.
pub fn park_if_interrupted() {
    while INTERRUPTED.load(std::sync::atomic::Ordering::SeqCst) {
        std::thread::sleep(Duration::from_secs(1));
    }
}

/// Ends the job led by `group` (the launcher's pid and group id): its group and all its
/// descendants get SIGTERM, then SIGKILL after the grace time for what is left.
pub fn kill_group(group: i32) {
    if group <= 1 {
        return;
    }
    let members = descendants(group);
    let signal_all = |signal: i32| {
        // SAFETY: signals to the group we started and to processes found as its descendants;
        // errors (already gone) are ignored
        unsafe {
            libc::killpg(group, signal);
            for &pid in &members {
                libc::kill(pid, signal);
            }
        }
    };
    signal_all(libc::SIGTERM);
    let alive = || group_alive(group) || members.iter().any(|&p| process_alive(p));
    let deadline = Instant::now() + GRACE;
    while Instant::now() < deadline && alive() {
        // the leader is the builder's child: reaped here, else as a zombie it keeps the group
        // "alive" (callers' later wait() then finds it gone, which they ignore)
        // SAFETY: waitpid on our own child's pid, without blocking
        unsafe {
            libc::waitpid(group, std::ptr::null_mut(), libc::WNOHANG);
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    signal_all(libc::SIGKILL);
}

/// Whether `pid` exists and is not a zombie.
fn process_alive(pid: i32) -> bool {
    stat_of(pid).is_some_and(|(state, _, _)| state != "Z")
}

/// State, parent and process group of `pid` from /proc/<pid>/stat.
fn stat_of(pid: i32) -> Option<(String, i32, i32)> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // pid (comm) state ppid pgrp ...: comm may hold spaces, so split after its ')'
    let after = &stat[stat.rfind(')')? + 1..];
    let fields: Vec<&str> = after.split_whitespace().collect();
    Some((fields.first()?.to_string(), fields.get(1)?.parse().ok()?, fields.get(2)?.parse().ok()?))
}

/// Every process below `root` in the parent tree.
fn descendants(root: i32) -> Vec<i32> {
    let Ok(entries) = std::fs::read_dir("/proc") else { return Vec::new() };
    let parents: Vec<(i32, i32)> = entries
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<i32>().ok())
        .filter_map(|pid| Some((pid, stat_of(pid)?.1)))
        .collect();
    let mut found = vec![root];
    let mut i = 0;
    while i < found.len() {
        let parent = found[i];
        found.extend(parents.iter().filter(|&&(_, pp)| pp == parent).map(|&(pid, _)| pid));
        i += 1;
    }
    found.remove(0);
    found
}

/// Whether any process of the group still runs. Zombies do not count: an orphaned rank's
/// zombie waits for PID 1 to reap it, which in a container may never happen.
pub fn group_alive(group: i32) -> bool {
    let Ok(entries) = std::fs::read_dir("/proc") else { return false };
    entries
        .flatten()
        .filter_map(|e| e.file_name().to_str()?.parse::<i32>().ok())
        .filter_map(stat_of)
        .any(|(state, _, pgrp)| pgrp == group && state != "Z")
}

/// Registers a running job for the interruption handler (installed on first use).
pub fn register(group: i32, folder: &Path, keep_folder: bool) {
    HANDLER.get_or_init(install_handler);
    if let Ok(mut jobs) = JOBS.lock() {
        jobs.push(Job { group, folder: folder.to_path_buf(), keep_folder });
    }
}

/// Removes a job that ended normally.
pub fn unregister(group: i32) {
    if let Ok(mut jobs) = JOBS.lock() {
        jobs.retain(|j| j.group != group);
    }
}

/// A thread that waits for SIGINT, SIGTERM or SIGHUP, ends every registered job's group,
/// removes its folder, then ends the builder as the signal would have.
fn install_handler() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    HANDLING.store(true, std::sync::atomic::Ordering::SeqCst);
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            INTERRUPTED.store(true, std::sync::atomic::Ordering::SeqCst);
            let jobs = JOBS.lock().map(|mut j| std::mem::take(&mut *j)).unwrap_or_default();
            for job in &jobs {
                kill_group(job.group);
                if !job.keep_folder {
                    super::job_folder::remove(&job.folder);
                }
            }
            eprintln!("\nerror: interrupted (signal {signal}); the PETSc back-end's ranks were ended");
            let _ = signal_hook::low_level::emulate_default_handler(signal);
            std::process::exit(128 + signal);
        }
    });
}

/// The first process of the job led by `group` that is stopped (state T: SIGSTOP, a debugger), with its MPI
/// rank where its environment says it: (pid, rank, command line).
pub fn stopped_member(group: i32) -> Option<(i32, Option<String>, String)> {
    for pid in std::iter::once(group).chain(descendants(group)) {
        let Some((state, _, _)) = stat_of(pid) else { continue };
        if !(state == "T" || state == "t") {
            continue;
        }
        let cmdline = std::fs::read(format!("/proc/{pid}/cmdline")).unwrap_or_default();
        let cmdline = String::from_utf8_lossy(&cmdline).replace('\0', " ").trim().to_string();
        return Some((pid, rank_of(pid), cmdline));
    }
    None
}

/// The MPI rank of `pid`, where its environment says it.
fn rank_of(pid: i32) -> Option<String> {
    let environ = std::fs::read(format!("/proc/{pid}/environ")).ok()?;
    environ.split(|&b| b == 0).find_map(|v| {
        let v = String::from_utf8_lossy(v);
        ["OMPI_COMM_WORLD_RANK=", "PMI_RANK=", "PMIX_RANK=", "SLURM_PROCID="]
            .iter()
            .find_map(|k| v.strip_prefix(k).map(str::to_string))
    })
}

/// The job's ranks on this machine seen so far, to tell when one has ended while the launcher
/// runs on: a launcher that outlives a failed rank (srun without --kill-on-bad-exit, mpirun
/// with --enable-recovery) leaves the other ranks waiting for it, and the whole job with them.
/// This sees a rank that its heartbeat watcher cannot report: one killed with its watcher
/// (a signal to its process group) or before the watcher started.
#[derive(Default)]
pub struct LocalRanks {
    seen: Mutex<Vec<(i32, String)>>,
}

impl LocalRanks {
    /// A rank seen before that has ended since (gone, or a zombie its launcher left): its pid
    /// and rank.
    pub fn ended(&self, group: i32) -> Option<(i32, String)> {
        let mut seen = self.seen.lock().ok()?;
        // parents before children: a rank's fork (its heartbeat watcher before it execs) has the
        // rank's environment, and is told apart by its parent
        for pid in descendants(group) {
            let known = |p: i32| seen.iter().any(|&(s, _)| s == p);
            if known(pid) || stat_of(pid).is_some_and(|(_, parent, _)| known(parent)) {
                continue;
            }
            if let Some(rank) = rank_of(pid) {
                seen.push((pid, rank));
            }
        }
        seen.iter().find(|&&(pid, _)| !process_alive(pid)).cloned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::process::CommandExt;

    #[test]
    fn a_stopped_member_is_found_and_the_whole_group_is_ended() {
        // a shell leading its own group, with a child that sleeps: the launcher and a rank
        let mut leader =
            std::process::Command::new("sh").args(["-c", "sleep 30 & wait"]).process_group(0).spawn().unwrap();
        let group = leader.id() as i32;
        std::thread::sleep(Duration::from_millis(200));
        assert!(group_alive(group));
        assert!(stopped_member(group).is_none());
        // SAFETY: stopping our own child
        unsafe {
            libc::kill(group, libc::SIGSTOP);
        }
        std::thread::sleep(Duration::from_millis(100));
        let (pid, _, cmdline) = stopped_member(group).expect("the stopped leader");
        assert_eq!(pid, group);
        assert!(cmdline.starts_with("sh -c"), "{cmdline}");
        kill_group(group);
        let _ = leader.wait();
        std::thread::sleep(Duration::from_millis(100));
        assert!(!group_alive(group), "the sleeping child outlived its group's end");
    }
}
