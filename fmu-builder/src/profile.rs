//! Where a build spends its time and memory: a profile of its phases (import, assembly, coupling,
//! factorisations, eigen-solves, shapes, invariants, accuracy comparison, packaging), each with
//! wall time and peak resident memory, for `fmu-builder --timings` and the benchmarks. A user
//! sizing a machine for a large model, and whoever makes the builder faster, reads it.
//!
//! Phases nest (a factorisation inside the Craig-Bampton basis); the recorder is per thread, so
//! stages need not pass it along. Peak memory per phase: Linux keeps one high-water mark of the
//! resident set (VmHWM), which writing "5" to /proc/self/clear_refs resets. A phase resets it
//! when it starts, after folding the mark so far into every enclosing phase, and reads it when
//! it ends; so each phase's peak is its own, and an enclosing phase's peak covers its children.
//! The reset also lowers what outside tools (`/usr/bin/time`, getrusage's ru_maxrss) see, so it
//! happens only when per-phase memory is asked for (`per_phase_memory(true)`, `--timings`); every
//! mark is folded into the process's own peak first (`process_peak_mib`). Without the reset, or
//! where it is not possible, a phase reports the process's peak so far (never less than its own).

use std::cell::RefCell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

/// Whether phases reset the high-water mark (per-phase peaks) or not (the process's peak stays
/// visible to outside tools).
static PER_PHASE_MEMORY: AtomicBool = AtomicBool::new(false);
/// The largest high-water mark read before any reset [KiB].
static PROCESS_PEAK_KIB: AtomicU64 = AtomicU64::new(0);

/// Ask for each phase's own peak memory (resets the process's high-water mark between phases).
pub fn per_phase_memory(on: bool) {
    PER_PHASE_MEMORY.store(on, Ordering::Relaxed);
}

/// Peak resident memory of the whole process so far [MiB], resets included.
pub fn process_peak_mib() -> Option<f64> {
    let now = high_water_kib();
    let folded = PROCESS_PEAK_KIB.load(Ordering::Relaxed);
    now.map(|k| k.max(folded) as f64 / 1024.0)
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
    /// Peak seen so far in this phase, before a child's reset cleared the mark [KiB].
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

/// Peak resident set of this process since the last reset [KiB] (Linux: VmHWM).
fn high_water_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Reset the high-water mark to the present resident set, after folding it into the process's
/// peak; false where not possible.
pub fn reset_high_water() -> bool {
    if let Some(mark) = high_water_kib() {
        PROCESS_PEAK_KIB.fetch_max(mark, Ordering::Relaxed);
    }
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
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
        let mark = high_water_kib();
        for open in r.open.iter_mut() {
            open.peak_kib = max_opt(open.peak_kib, mark);
        }
        if PER_PHASE_MEMORY.load(Ordering::Relaxed) {
            reset_high_water();
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
        let peak = max_opt(open.peak_kib, high_water_kib());
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
