//! Signs of life from every rank, wherever it runs. The launcher and the local process group
//! show what happens on the builder's machine; a rank on another node that is stopped (SIGSTOP,
//! a debugger) or whose node hangs leaves the others waiting in a collective call, and the
//! launcher notices nothing. So each rank's driver forks, before MPI starts, a small watcher
//! that rewrites `heartbeat-<host>-<pid>` in the job folder (a file system every rank sees)
//! every second: its rank, host, PID, whether the rank is running or stopped (its state in
//! /proc), and a counter; when the rank is gone it writes a last beat, "ended". The builder reads
//! them while it waits: a rank reported stopped or ended is named at once, a file whose counter
//! has not moved for `silence` (by the builder's own clock: the nodes' clocks need not agree)
//! names a rank or node that stalled.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How long a rank's heartbeat may stand still before the rank is taken for stalled: long
/// beside its one-second beat and a network file system's attribute caching (NFS caches up to
/// 60 s by default, though opening the file revalidates it).
pub const SILENCE: Duration = Duration::from_secs(90);

/// One rank's last heartbeat as the builder saw it.
struct Seen {
    line: String,
    changed: Instant,
}

pub struct Heartbeats {
    folder: PathBuf,
    silence: Duration,
    seen: Mutex<HashMap<PathBuf, Seen>>,
}

/// What a heartbeat file says: rank, host, PID, state, counter.
struct Beat<'a> {
    rank: &'a str,
    host: &'a str,
    pid: &'a str,
    state: &'a str,
}

fn parse(line: &str) -> Option<Beat<'_>> {
    let mut words = line.split_whitespace();
    let (rank, host, pid, state) = (words.next()?, words.next()?, words.next()?, words.next()?);
    words.next()?;
    Some(Beat { rank, host, pid, state })
}

/// Why the job cannot go on, as a rank's heartbeat tells it.
#[derive(Debug, PartialEq)]
pub struct Trouble {
    pub why: String,
    /// The rank is gone (not stopped or stalled): the launcher, if it notices, says how it ended.
    pub ended: bool,
}

impl Heartbeats {
    pub fn new(folder: &Path, silence: Duration) -> Self {
        Self { folder: folder.to_path_buf(), silence, seen: Mutex::new(HashMap::new()) }
    }

    /// Why the job cannot go on, if a rank's heartbeat says so: stopped, ended, or silent for
    /// longer than `silence`.
    pub fn check(&self) -> Option<Trouble> {
        let now = Instant::now();
        let entries = std::fs::read_dir(&self.folder).ok()?;
        let mut seen = self.seen.lock().ok()?;
        for entry in entries.flatten() {
            let path = entry.path();
            if !entry.file_name().to_string_lossy().starts_with("heartbeat-") || path.extension().is_some() {
                continue;
            }
            let Ok(text) = std::fs::read_to_string(&path) else { continue };
            let line = text.trim().to_string();
            let Some(beat) = parse(&line) else { continue };
            let who = format!("rank {} (process {} on {})", beat.rank, beat.pid, beat.host);
            match beat.state {
                "stopped" => {
                    let why = format!("{who} is stopped (SIGSTOP, a debugger), as its heartbeat reports");
                    return Some(Trouble { why, ended: false });
                }
                "ended" => {
                    let why =
                        format!("{who} ended while the job ran (it failed or was killed), as its heartbeat reports");
                    return Some(Trouble { why, ended: true });
                }
                _ => {}
            }
            match seen.get_mut(&path) {
                Some(s) if s.line == line => {
                    if now.duration_since(s.changed) > self.silence {
                        let why = format!(
                            "{who} has given no sign of life for {:.0} s: its node or its heartbeat stalled",
                            now.duration_since(s.changed).as_secs_f64()
                        );
                        return Some(Trouble { why, ended: false });
                    }
                }
                Some(s) => {
                    s.line = line;
                    s.changed = now;
                }
                None => {
                    seen.insert(path, Seen { line, changed: now });
                }
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn folder(name: &str) -> PathBuf {
        let f = std::env::temp_dir().join(format!("heartbeat-test-{name}-{}", std::process::id()));
        std::fs::remove_dir_all(&f).ok();
        std::fs::create_dir_all(&f).unwrap();
        f
    }

    #[test]
    fn a_stopped_rank_is_named_at_once() {
        let f = folder("stopped");
        let beats = Heartbeats::new(&f, Duration::from_secs(60));
        std::fs::write(f.join("heartbeat-node2-4711"), "1 node2 4711 running 3\n").unwrap();
        assert_eq!(beats.check(), None);
        std::fs::write(f.join("heartbeat-node2-4711"), "1 node2 4711 stopped 4\n").unwrap();
        let trouble = beats.check().expect("the stopped rank");
        assert!(trouble.why.starts_with("rank 1 (process 4711 on node2) is stopped"), "{trouble:?}");
        assert!(!trouble.ended);
        std::fs::remove_dir_all(&f).ok();
    }

    #[test]
    fn a_heartbeat_that_stands_still_is_a_stall_and_one_that_moves_is_not() {
        let f = folder("silent");
        let beats = Heartbeats::new(&f, Duration::from_millis(200));
        let file = f.join("heartbeat-node3-99");
        // the watcher's temporary file is not read
        std::fs::write(f.join("heartbeat-node3-99.tmp"), "garbage").unwrap();
        for count in 0..4 {
            std::fs::write(&file, format!("0 node3 99 running {count}\n")).unwrap();
            assert_eq!(beats.check(), None);
            std::thread::sleep(Duration::from_millis(100));
        }
        std::thread::sleep(Duration::from_millis(250));
        let trouble = beats.check().expect("the silent rank");
        assert!(
            trouble.why.starts_with("rank 0 (process 99 on node3) has given no sign of life for 0 s"),
            "{trouble:?}"
        );
        std::fs::remove_dir_all(&f).ok();
    }

    #[test]
    fn a_rank_whose_last_beat_says_ended_is_named_as_gone() {
        let f = folder("ended");
        let beats = Heartbeats::new(&f, Duration::from_secs(60));
        std::fs::write(f.join("heartbeat-node4-17"), "3 node4 17 running 8\n").unwrap();
        assert_eq!(beats.check(), None);
        std::fs::write(f.join("heartbeat-node4-17"), "3 node4 17 ended 9\n").unwrap();
        let trouble = beats.check().expect("the ended rank");
        assert!(trouble.why.starts_with("rank 3 (process 17 on node4) ended while the job ran"), "{trouble:?}");
        assert!(trouble.ended);
        std::fs::remove_dir_all(&f).ok();
    }
}
