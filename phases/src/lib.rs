//! The build's phases as `tracing` spans, the counts of a phase and the progress within it as
//! events. Every stage (the linear algebra, the back-ends, the input, the builder) reports
//! through these three functions and keeps no state of its own: whoever runs a build decides
//! what listens (the builder's profile and progress layers; nothing, for a library user), and two
//! builds on two threads each see only their own phases.
//!
//! The names below are the convention the listeners match on; they are defined here once.

/// Name of the span of one phase; its field [`NAME`] says which phase.
pub const PHASE: &str = "phase";
/// The field holding a phase's name.
pub const NAME: &str = "name";
/// Target of the events adding a count to the innermost phase.
pub const NOTE_TARGET: &str = "phases::note";
/// Target of the events telling progress within a phase.
pub const STEP_TARGET: &str = "phases::step";
/// Target of the events warning of something the build goes on with (a probable unit slip).
pub const WARNING_TARGET: &str = "phases::warning";
/// The field of every kind of event.
pub const MESSAGE: &str = "message";

/// Run `f` as the phase `name`: a span that listeners time and measure.
pub fn phase<T>(name: impl AsRef<str>, f: impl FnOnce() -> T) -> T {
    let span = tracing::info_span!("phase", name = name.as_ref());
    span.in_scope(f)
}

/// Add a count to the innermost running phase (e.g. "41 Lanczos vectors, 2 restarts"); `detail`
/// is only called when something listens.
pub fn note(detail: impl FnOnce() -> String) {
    if tracing::enabled!(target: "phases::note", tracing::Level::INFO) {
        tracing::info!(target: "phases::note", message = detail().as_str());
    }
}

/// Progress within a phase (e.g. "12 of 46 modes converged"); `what` is only called when
/// something listens.
pub fn step(what: impl FnOnce() -> String) {
    if tracing::enabled!(target: "phases::step", tracing::Level::INFO) {
        tracing::info!(target: "phases::step", message = what().as_str());
    }
}

/// A warning the build goes on with, said at once (not only in the summary at the end); `what`
/// is only called when something listens.
pub fn warning(what: impl FnOnce() -> String) {
    if tracing::enabled!(target: "phases::warning", tracing::Level::WARN) {
        tracing::warn!(target: "phases::warning", message = what().as_str());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The macros cannot take the constants; this keeps the literals and the constants one.
    #[test]
    fn the_literals_are_the_constants() {
        let source = include_str!("lib.rs");
        assert!(source.contains(&format!("info_span!(\"{PHASE}\", {NAME} = ")));
        assert!(source.contains(&format!("enabled!(target: \"{NOTE_TARGET}\"")));
        assert!(source.contains(&format!("info!(target: \"{STEP_TARGET}\", {MESSAGE} = ")));
        assert!(source.contains(&format!("warn!(target: \"{WARNING_TARGET}\", {MESSAGE} = ")));
    }

    #[test]
    fn without_a_listener_nothing_is_evaluated() {
        note(|| panic!("evaluated without a listener"));
        step(|| panic!("evaluated without a listener"));
        warning(|| panic!("evaluated without a listener"));
        assert_eq!(phase("p", || 3), 3);
    }
}
