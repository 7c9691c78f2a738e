//! Where an eigen-solve's time went.

/// Where an eigen-solve's time went, for the build profile's note.
#[derive(Default, Clone, Copy)]
pub(super) struct Clock {
    pub(super) solves: std::time::Duration,
    pub(super) orthogonalisation: std::time::Duration,
    pub(super) ritz: std::time::Duration,
    pub(super) checks: std::time::Duration,
}

impl Clock {
    /// Run `f`, adding its wall time to the entry `at` picks.
    pub(super) fn time<R>(&mut self, at: fn(&mut Self) -> &mut std::time::Duration, f: impl FnOnce() -> R) -> R {
        let began = std::time::Instant::now();
        let r = f();
        *at(self) += began.elapsed();
        r
    }

    pub(super) fn add(&mut self, other: &Clock) {
        self.solves += other.solves;
        self.orthogonalisation += other.orthogonalisation;
        self.ritz += other.ritz;
        self.checks += other.checks;
    }

    pub(super) fn describe(&self) -> String {
        format!(
            "block solves {:.1} s, orthogonalisation {:.1} s, Ritz pairs {:.1} s, checks {:.1} s",
            self.solves.as_secs_f64(),
            self.orthogonalisation.as_secs_f64(),
            self.ritz.as_secs_f64(),
            self.checks.as_secs_f64()
        )
    }
}
