//! Where a build spends its time and memory: a profile of its phases (import, assembly, coupling,
//! factorisations, eigen-solves, shapes, invariants, accuracy comparison, packaging), each with
//! wall time, peak resident memory and CPU time (so the serial phases show), for
//! `fmu-builder --timings` and the benchmarks. A user
//! sizing a machine for a large model, and whoever makes the builder faster, reads it.
//!
//! The stages emit their phases as `tracing` spans (the `phases` crate); a [`Profile`] is a
//! recorder whose [`layer`](Profile::layer) listens to them in the subscriber the caller sets
//! for one build, so two builds, each with its own subscriber, never share or lose phases.
//! (tracing caches whether anyone listens to a call site when it is first reached: a phase first
//! reached while no subscriber exists anywhere in the process stays unheard until the next
//! subscriber is made. A build sets its subscriber before its first phase, so it hears all.)
//! Phases nest (a factorisation inside the Craig-Bampton basis) as their spans do. Peak memory per phase: the resident set (VmRSS) read when a
//! phase starts and ends and, while per-phase memory is asked for (`Profile::new(true)`,
//! `--timings`), every millisecond by the profile's sampler thread, the largest reading going to every phase
//! open then; so each phase's peak is its own, and an enclosing phase's peak covers its
//! children's. Linux's own high-water mark (VmHWM) is never reset (writing to
//! /proc/self/clear_refs would): it stays the process's peak for `process_peak_mib`,
//! `/usr/bin/time -v` and getrusage alike. A resident set that rises and falls back within one
//! sampling interval is missed by the phases, not by the process's peak: pages are touched at
//! some 10 GB/s, so what a millisecond hides is about 10 MB. Without per-phase memory, a phase
//! reports the process's peak so far (never less than its own).

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tracing::span::{Attributes, Id};
use tracing::{Event, Subscriber};
use tracing_subscriber::Layer;
use tracing_subscriber::layer::Context;
use tracing_subscriber::registry::LookupSpan;

/// How often the sampler reads the resident set: reading /proc/self/statm costs some
/// microseconds, so a millisecond keeps the sampler under a percent of a core.
const SAMPLE_INTERVAL: Duration = Duration::from_millis(1);

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
    /// CPU time of the whole process while the phase ran, every thread's, user and system [s];
    /// None where the system does not tell. Over `seconds`: the cores the phase kept busy (1.0
    /// for a serial phase, 2.0 for one that uses both cores of a 2-core machine throughout).
    pub cpu_seconds: Option<f64>,
    /// Counts of the phase (sizes, iterations, solves), in words.
    pub detail: String,
}

struct Open {
    span: Id,
    index: usize,
    start: Instant,
    start_cpu: Option<f64>,
    /// Peak seen so far in this phase, up to the last phase boundary [KiB].
    peak_kib: Option<u64>,
}

/// The resident-set window the sampler widens between phase boundaries.
struct Window {
    /// Whether the sampler reads the resident set (per-phase memory asked for).
    sampling: bool,
    /// The largest resident set read since the last phase boundary [KiB].
    peak_kib: AtomicU64,
    /// Tells the sampler thread to end (the profile was dropped).
    ended: AtomicBool,
}

#[derive(Default)]
struct Recorder {
    finished: Vec<Phase>,
    open: Vec<Open>,
}

/// The phases of the builds run under its [`layer`](Profile::layer), in the order they started.
pub struct Profile {
    recorder: Arc<Mutex<Recorder>>,
    window: Arc<Window>,
}

/// Listens to the phase spans for a [`Profile`].
pub struct ProfileLayer {
    recorder: Arc<Mutex<Recorder>>,
    window: Arc<Window>,
}

impl Profile {
    /// A recorder; `per_phase_memory` starts a sampler thread that reads the resident set every
    /// millisecond until the profile is dropped (without one, a phase reports the process's
    /// peak so far).
    pub fn new(per_phase_memory: bool) -> Self {
        let window =
            Arc::new(Window { sampling: per_phase_memory, peak_kib: AtomicU64::new(0), ended: AtomicBool::new(false) });
        if per_phase_memory {
            let sampled = Arc::downgrade(&window);
            // without a thread, phase boundaries still bound each phase's peak from below
            let _ = std::thread::Builder::new().name("rss-sampler".into()).spawn(move || {
                while let Some(window) = sampled.upgrade().filter(|w| !w.ended.load(Ordering::Relaxed)) {
                    if let Some(rss) = resident_kib() {
                        window.peak_kib.fetch_max(rss, Ordering::Relaxed);
                    }
                    drop(window);
                    std::thread::sleep(SAMPLE_INTERVAL);
                }
            });
        }
        Profile { recorder: Arc::default(), window }
    }

    /// The layer that records into this profile, for the subscriber of a build.
    pub fn layer(&self) -> ProfileLayer {
        ProfileLayer { recorder: Arc::clone(&self.recorder), window: Arc::clone(&self.window) }
    }

    /// The phases finished since the last call, in the order they started (none while a phase
    /// is still open).
    pub fn take(&self) -> Vec<Phase> {
        let mut r = self.recorder.lock().unwrap_or_else(|e| e.into_inner());
        if r.open.is_empty() { std::mem::take(&mut r.finished) } else { Vec::new() }
    }
}

impl Drop for Profile {
    fn drop(&mut self) {
        self.window.ended.store(true, Ordering::Relaxed);
    }
}

/// CPU time this process has used so far, all its threads, user and system [s] (getrusage).
pub fn process_cpu_seconds() -> Option<f64> {
    // SAFETY: getrusage writes into the zeroed struct it is given
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } != 0 {
        return None;
    }
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    Some(seconds(usage.ru_utime) + seconds(usage.ru_stime))
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

impl Window {
    /// The largest resident set since the last boundary, the present one included; the window
    /// then starts again from the present one. Where per-phase memory is not asked for: the
    /// process's peak so far.
    fn close(&self) -> Option<u64> {
        if !self.sampling {
            return high_water_kib();
        }
        let now = resident_kib()?;
        Some(self.peak_kib.swap(now, Ordering::Relaxed).max(now))
    }
}

fn max_opt(a: Option<u64>, b: Option<u64>) -> Option<u64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(a.max(b)),
        (a, b) => a.or(b),
    }
}

/// The name of a phase span, read from its fields.
#[derive(Default)]
pub(crate) struct SpanText(pub(crate) String);

impl tracing::field::Visit for SpanText {
    fn record_str(&mut self, field: &tracing::field::Field, value: &str) {
        if field.name() == phases::NAME || field.name() == phases::MESSAGE {
            self.0 = value.to_string();
        }
    }
    fn record_debug(&mut self, field: &tracing::field::Field, value: &dyn std::fmt::Debug) {
        if field.name() == phases::NAME || field.name() == phases::MESSAGE {
            self.0 = format!("{value:?}");
        }
    }
}

impl ProfileLayer {
    fn lock(&self) -> std::sync::MutexGuard<'_, Recorder> {
        self.recorder.lock().unwrap_or_else(|e| e.into_inner())
    }
}

impl<S: Subscriber + for<'a> LookupSpan<'a>> Layer<S> for ProfileLayer {
    fn on_new_span(&self, attrs: &Attributes<'_>, id: &Id, _ctx: Context<'_, S>) {
        if attrs.metadata().name() != phases::PHASE {
            return;
        }
        let mut name = SpanText::default();
        attrs.record(&mut name);
        let mut r = self.lock();
        // what the enclosing phases reached before this one starts is theirs
        let mark = self.window.close();
        for open in r.open.iter_mut() {
            open.peak_kib = max_opt(open.peak_kib, mark);
        }
        let (index, depth) = (r.finished.len(), r.open.len());
        // placed now so that phases list in the order they started
        r.finished.push(Phase {
            name: name.0,
            depth,
            seconds: 0.0,
            peak_mib: None,
            cpu_seconds: None,
            detail: String::new(),
        });
        r.open.push(Open {
            span: id.clone(),
            index,
            start: Instant::now(),
            start_cpu: process_cpu_seconds(),
            peak_kib: None,
        });
    }

    fn on_close(&self, id: Id, _ctx: Context<'_, S>) {
        let mut r = self.lock();
        let Some(at) = r.open.iter().rposition(|o| o.span == id) else { return };
        let open = r.open.remove(at);
        let peak = max_opt(open.peak_kib, self.window.close());
        for parent in r.open.iter_mut() {
            parent.peak_kib = max_opt(parent.peak_kib, peak);
        }
        let phase = &mut r.finished[open.index];
        phase.seconds = open.start.elapsed().as_secs_f64();
        phase.peak_mib = peak.map(|k| k as f64 / 1024.0);
        phase.cpu_seconds = process_cpu_seconds().zip(open.start_cpu).map(|(end, start)| (end - start).max(0.0));
    }

    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        if event.metadata().target() != phases::NOTE_TARGET {
            return;
        }
        let mut note = SpanText::default();
        event.record(&mut note);
        let mut r = self.lock();
        let Some(index) = r.open.last().map(|o| o.index) else { return };
        let phase = &mut r.finished[index];
        if !phase.detail.is_empty() {
            phase.detail.push_str("; ");
        }
        phase.detail.push_str(&note.0);
    }
}

/// The profile as a table for the terminal: nested phases indented under their parent. The
/// cpu/wall column is the cores a phase kept busy: a phase near 1.0 on a machine of several
/// cores is serial.
pub fn table(phases: &[Phase]) -> String {
    let mut out = format!(
        "{:<62} {:>8}  {:>10}  {:>8}  {:>8}  detail\n",
        "phase", "wall [s]", "peak [MiB]", "cpu [s]", "cpu/wall"
    );
    for p in phases {
        let name = format!("{}{}", "  ".repeat(p.depth), p.name);
        let peak = p.peak_mib.map_or("-".to_string(), |m| format!("{m:.0}"));
        let cpu = p.cpu_seconds.map_or("-".to_string(), |c| format!("{c:.3}"));
        // a phase too short for the clock's resolution (getrusage counts in ticks) has no ratio
        let ratio =
            p.cpu_seconds.filter(|_| p.seconds >= 0.01).map_or("-".to_string(), |c| format!("{:.2}", c / p.seconds));
        out.push_str(&format!("{name:<62} {:>8.3}  {peak:>10}  {cpu:>8}  {ratio:>8}  {}\n", p.seconds, p.detail));
    }
    out
}
