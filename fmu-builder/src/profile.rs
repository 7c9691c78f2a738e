//! Where a build spends its time and memory: a profile of its phases (import, assembly, coupling,
//! factorisations, eigen-solves, shapes, invariants, accuracy comparison, packaging), each with
//! wall time and peak resident memory, for `fmu-builder --timings` and the benchmarks. A user
//! sizing a machine for a large model, and whoever makes the builder faster, reads it.
//!
//! Phases nest (a factorisation inside the Craig-Bampton basis); the recorder is per thread, so
//! stages need not pass it along. Peak memory per phase: the resident set (VmRSS) read when a
//! phase starts and ends and, while per-phase memory is asked for (`per_phase_memory(true)`,
//! `--timings`), every millisecond by a sampler thread, the largest reading going to every phase
//! open then; so each phase's peak is its own, and an enclosing phase's peak covers its
//! children's. Linux's own high-water mark (VmHWM) is never reset (writing to
//! /proc/self/clear_refs would): it stays the process's peak for `process_peak_mib`,
//! `/usr/bin/time -v` and getrusage alike. A resident set that rises and falls back within one
//! sampling interval is missed by the phases, not by the process's peak: pages are touched at
//! some 10 GB/s, so what a millisecond hides is about 10 MB. Without per-phase memory, a phase
//! reports the process's peak so far (never less than its own).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Whether the sampler thread reads the resident set between phase boundaries.
static PER_PHASE_MEMORY: AtomicBool = AtomicBool::new(false);
/// Whether the sampler thread has been started (once per process).
static SAMPLER_STARTED: AtomicBool = AtomicBool::new(false);
/// The largest resident set read since the last phase boundary [KiB].
static WINDOW_PEAK_KIB: AtomicU64 = AtomicU64::new(0);
/// How often the sampler reads the resident set: reading /proc/self/statm costs some
/// microseconds, so a millisecond keeps the sampler under a percent of a core.
const SAMPLE_INTERVAL: Duration = Duration::from_millis(1);

/// Ask for each phase's own peak memory (a sampler thread reads the resident set meanwhile).
pub fn per_phase_memory(on: bool) {
    PER_PHASE_MEMORY.store(on, Ordering::Relaxed);
    if on && !SAMPLER_STARTED.swap(true, Ordering::Relaxed) {
        let started = std::thread::Builder::new().name("rss-sampler".into()).spawn(|| {
            // the thread lives as long as the process; it only sleeps while not asked for
            loop {
                if PER_PHASE_MEMORY.load(Ordering::Relaxed)
                    && let Some(rss) = resident_kib()
                {
                    WINDOW_PEAK_KIB.fetch_max(rss, Ordering::Relaxed);
                }
                std::thread::sleep(SAMPLE_INTERVAL);
            }
        });
        // without a thread, phase boundaries still bound each phase's peak from below
        if started.is_err() {
            SAMPLER_STARTED.store(false, Ordering::Relaxed);
        }
    }
}

/// Peak resident memory of the whole process so far [MiB] (Linux: VmHWM, never reset).
pub fn process_peak_mib() -> Option<f64> {
    high_water_kib().map(|k| k as f64 / 1024.0)
}

/// One finished phase.
#[derive(Debug, Clone, PartialEq)]
pub struct Phase {
    pub name: String,
    /// Nesting depth: 0 for the build's own phases, 1 for what runs inside one, ...
    pub depth: usize,
    pub seconds: f64,
    /// Peak resident memory while the phase ran [MiB]; None where the system does not tell.
    pub peak_mib: Option<f64>,
    /// Counts of the phase (sizes, iterations, solves), in words.
    pub detail: String,
}

struct Open {
    index: usize,
    start: Instant,
    /// Peak seen so far in this phase, up to the last phase boundary [KiB].
    peak_kib: Option<u64>,
}

#[derive(Default)]
struct Recorder {
    finished: Vec<Phase>,
    open: Vec<Open>,
}

thread_local! {
    static RECORDER: RefCell<Recorder> = RefCell::new(Recorder::default());
}

/// Peak resident set of this process [KiB] (Linux: VmHWM).
fn high_water_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Resident set of this process now [KiB] (Linux: the second field of /proc/self/statm, in
/// pages; statm rather than status because the sampler reads it a thousand times a second).
fn resident_kib() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    // SAFETY: sysconf only reads a system constant
    let page = unsafe { libc::sysconf(libc::_SC_PAGESIZE) };
    Some(pages * u64::try_from(page).ok().filter(|&p| p > 0)? / 1024)
}

/// The largest resident set since the last boundary, the present one included; the window then
/// starts again from the present one. Where per-phase memory is not asked for: the process's
/// peak so far.
fn close_window() -> Option<u64> {
    if !PER_PHASE_MEMORY.load(Ordering::Relaxed) {
        return high_water_kib();
    }
    let now = resident_kib()?;
    Some(WINDOW_PEAK_KIB.swap(now, Ordering::Relaxed).max(now))
}

fn max_opt(a: Option<u64>, b: Option<u64>) -> Option<u64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// Run `f` as the phase `name` and record its wall time and peak memory.
pub fn phase<T>(name: impl Into<String>, f: impl FnOnce() -> T) -> T {
    let name = name.into();
    crate::progress::phase(&name);
    RECORDER.with(|r| {
        let mut r = r.borrow_mut();
        // what the enclosing phases reached before this one starts is theirs
        let mark = close_window();
        for open in r.open.iter_mut() {
            open.peak_kib = max_opt(open.peak_kib, mark);
        }
        let index = r.finished.len();
        let depth = r.open.len();
        // placed now so that phases list in the order they started
        r.finished.push(Phase { name, depth, seconds: 0.0, peak_mib: None, detail: String::new() });
        r.open.push(Open { index, start: Instant::now(), peak_kib: None });
    });
    let result = f();
    RECORDER.with(|r| {
        let mut r = r.borrow_mut();
        let Some(open) = r.open.pop() else { return };
        let peak = max_opt(open.peak_kib, close_window());
        for parent in r.open.iter_mut() {
            parent.peak_kib = max_opt(parent.peak_kib, peak);
        }
        let phase = &mut r.finished[open.index];
        phase.seconds = open.start.elapsed().as_secs_f64();
        phase.peak_mib = peak.map(|k| k as f64 / 1024.0);
    });
    result
}

/// Add a count to the innermost running phase (e.g. "41 Lanczos vectors, 2 restarts").
pub fn note(detail: impl FnOnce() -> String) {
    RECORDER.with(|r| {
        let mut r = r.borrow_mut();
        let Some(index) = r.open.last().map(|o| o.index) else { return };
        let phase = &mut r.finished[index];
        if !phase.detail.is_empty() {
            phase.detail.push_str("; ");
        }
        phase.detail.push_str(&detail());
    });
}

/// The phases finished on this thread since the last call, in the order they started.
pub fn take() -> Vec<Phase> {
    RECORDER.with(|r| {
        let mut r = r.borrow_mut();
        if r.open.is_empty() { std::mem::take(&mut r.finished) } else { Vec::new() }
    })
}

/// The profile as a table for the terminal: nested phases indented under their parent.
pub fn table(phases: &[Phase]) -> String {
    let mut out = format!("{:<62} {:>8}  {:>10}  detail\n", "phase", "wall [s]", "peak [MiB]");
    for p in phases {
        let name = format!("{}{}", "  ".repeat(p.depth), p.name);
        let peak = p.peak_mib.map_or("-".to_string(), |m| format!("{m:.0}"));
        out.push_str(&format!("{name:<62} {:>8.3}  {peak:>10}  {}\n", p.seconds, p.detail));
    }
    out
}
