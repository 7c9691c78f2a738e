//! What the builder is doing while it works, on stderr: on a terminal one status line (a spinner
//! with the phase and its progress, gone when the build ends), otherwise plain lines (the start
//! of every phase, and progress within long ones at most once a second). Off unless the binary
//! turns it on (`-q` leaves it off; library users and tests see nothing).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::{Duration, Instant};

enum Sink {
    Off,
    Bar(ProgressBar),
    Lines { last: Option<Instant> },
}

static SINK: Mutex<Sink> = Mutex::new(Sink::Off);
static START: Mutex<Option<Instant>> = Mutex::new(None);

/// Turn progress reporting on (a status line on a terminal, plain lines otherwise) or off.
pub fn enable(on: bool) {
    let sink = if !on {
        Sink::Off
    } else if std::io::stderr().is_terminal() {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
        bar.set_style(
            ProgressStyle::with_template("{spinner} [{elapsed:>4}] {msg}").unwrap_or(ProgressStyle::default_spinner()),
        );
        bar.enable_steady_tick(Duration::from_millis(120));
        Sink::Bar(bar)
    } else {
        Sink::Lines { last: None }
    };
    if let Ok(mut s) = SINK.lock() {
        *s = sink;
    }
    if let Ok(mut t) = START.lock() {
        *t = Some(Instant::now());
    }
}

/// Clear the status line (before the summary is printed).
pub fn finish() {
    if let Ok(mut s) = SINK.lock() {
        if let Sink::Bar(bar) = &*s {
            bar.finish_and_clear();
        }
        *s = Sink::Off;
    }
}

fn elapsed() -> f64 {
    START.lock().ok().and_then(|t| *t).map_or(0.0, |t| t.elapsed().as_secs_f64())
}

/// A phase begins (called by `profile::phase`).
pub fn phase(name: &str) {
    let Ok(mut s) = SINK.lock() else { return };
    match &mut *s {
        Sink::Off => {}
        Sink::Bar(bar) => bar.set_message(name.to_string()),
        Sink::Lines { last } => {
            let _ = writeln!(std::io::stderr(), "fmu-builder [{:6.1} s] {name}", elapsed());
            *last = Some(Instant::now());
        }
    }
}

/// Progress within a phase: `what` (e.g. "12 of 46 modes converged"). Plain lines come at most
/// once a second.
pub fn step(what: impl FnOnce() -> String) {
    let Ok(mut s) = SINK.lock() else { return };
    match &mut *s {
        Sink::Off => {}
        Sink::Bar(bar) => {
            let message = bar.message();
            let phase = message.split(": ").next().unwrap_or_default().to_string();
            bar.set_message(format!("{phase}: {}", what()));
        }
        Sink::Lines { last } => {
            if last.is_none_or(|t| t.elapsed() >= Duration::from_secs(1)) {
                let _ = writeln!(std::io::stderr(), "fmu-builder [{:6.1} s]   {}", elapsed(), what());
                *last = Some(Instant::now());
            }
        }
    }
}
