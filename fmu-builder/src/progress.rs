//! What the builder is doing while it works, on stderr: on a terminal one status line (a spinner
//! with the phase and its progress, gone when the build ends), otherwise plain lines (the start
//! of every phase, and progress within long ones at most once a second). A [`Progress`] listens
//! to the `phases` crate's spans and events as a layer of the subscriber the command line sets
//! for one build (`-q` leaves it out; library users and tests see nothing).

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tracing::span::{Attributes, Id};
use tracing::{Event, Subscriber};
use tracing_subscriber::Layer;
use tracing_subscriber::layer::Context;
use tracing_subscriber::registry::LookupSpan;

enum Sink {
    Off,
    Bar(ProgressBar),
    Lines { last: Option<Instant> },
}

/// What the build is doing, shown while it runs; clones share the one status line.
#[derive(Clone)]
pub struct Progress {
    sink: Arc<Mutex<Sink>>,
    start: Instant,
}

impl Progress {
    /// A status line on a terminal, plain lines otherwise.
    pub fn on_stderr() -> Self {
        let sink = if std::io::stderr().is_terminal() {
            let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            bar.set_style(
                ProgressStyle::with_template("{spinner} [{elapsed:>4}] {msg}")
                    .unwrap_or(ProgressStyle::default_spinner()),
            );
            bar.enable_steady_tick(Duration::from_millis(120));
            Sink::Bar(bar)
        } else {
            Sink::Lines { last: None }
        };
        Progress { sink: Arc::new(Mutex::new(sink)), start: Instant::now() }
    }

    /// Clear the status line (before the summary is printed); nothing is shown after.
    pub fn finish(&self) {
        let mut s = self.lock();
        if let Sink::Bar(bar) = &*s {
            bar.finish_and_clear();
        }
        *s = Sink::Off;
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Sink> {
        self.sink.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// A phase begins.
    fn phase(&self, name: &str) {
        let elapsed = self.elapsed();
        match &mut *self.lock() {
            Sink::Off => {}
            Sink::Bar(bar) => bar.set_message(name.to_string()),
            Sink::Lines { last } => {
                let _ = writeln!(std::io::stderr(), "fmu-builder [{elapsed:6.1} s] {name}");
                *last = Some(Instant::now());
            }
        }
    }

    /// A warning the build goes on with, on a line of its own at once.
    fn warning(&self, what: &str) {
        match &mut *self.lock() {
            Sink::Off => {}
            Sink::Bar(bar) => bar.println(format!("warning: {what}")),
            Sink::Lines { .. } => {
                let _ = writeln!(std::io::stderr(), "warning: {what}");
            }
        }
    }

    /// Progress within a phase: `what` (e.g. "12 of 46 modes converged"). Plain lines come at
    /// most once a second.
    fn step(&self, what: &str) {
        let elapsed = self.elapsed();
        match &mut *self.lock() {
            Sink::Off => {}
            Sink::Bar(bar) => {
                let message = bar.message();
                let phase = message.split(": ").next().unwrap_or_default().to_string();
                bar.set_message(format!("{phase}: {what}"));
            }
            Sink::Lines { last } => {
                if last.is_none_or(|t| t.elapsed() >= Duration::from_secs(1)) {
                    let _ = writeln!(std::io::stderr(), "fmu-builder [{elapsed:6.1} s]   {what}");
                    *last = Some(Instant::now());
                }
            }
        }
    }
}

impl<S: Subscriber + for<'a> LookupSpan<'a>> Layer<S> for Progress {
    fn on_new_span(&self, attrs: &Attributes<'_>, _id: &Id, _ctx: Context<'_, S>) {
        if attrs.metadata().name() == phases::PHASE {
            let mut name = crate::profile::SpanText::default();
            attrs.record(&mut name);
            self.phase(&name.0);
        }
    }

    fn on_event(&self, event: &Event<'_>, _ctx: Context<'_, S>) {
        let target = event.metadata().target();
        if target == phases::STEP_TARGET || target == phases::WARNING_TARGET {
            let mut what = crate::profile::SpanText::default();
            event.record(&mut what);
            if target == phases::STEP_TARGET {
                self.step(&what.0);
            } else {
                self.warning(&what.0);
            }
        }
    }
}
