//! The fuzz targets' settings (fmu-runtime's reduced-model loader, fmu-builder's readers): cases,
//! per-case time limit and seed from the environment (docs/FUZZING.md), every case in a forked
//! child, and the child's memory ceiling.

use proptest::test_runner::{Config, RngSeed};

/// The environment variable `name` as a number, `default` when unset or not a number.
pub fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.trim().parse().ok()).unwrap_or(default)
}

/// `default_cases` unless FUZZ_CASES says otherwise; FUZZ_TIMEOUT_MS and FUZZ_SEED likewise.
pub fn config(default_cases: u64) -> Config {
    Config {
        cases: env_u64("FUZZ_CASES", default_cases) as u32,
        fork: true,
        timeout: env_u64("FUZZ_TIMEOUT_MS", 20_000) as u32,
        rng_seed: RngSeed::Fixed(env_u64("FUZZ_SEED", 1)),
        failure_persistence: None,
        max_shrink_iters: 4096,
        ..Config::default()
    }
}

/// The child's ceiling on its address space (FUZZ_MEMORY_MB): an allocation sized from the
/// input beyond it aborts the child (a counted crash) instead of taking the machine's memory.
pub fn limit_memory() {
    let bytes = env_u64("FUZZ_MEMORY_MB", 3072) << 20;
    let limit = libc::rlimit { rlim_cur: bytes as libc::rlim_t, rlim_max: bytes as libc::rlim_t };
    // SAFETY: plain system call on a valid struct; lowering the limit is always permitted.
    unsafe {
        libc::setrlimit(libc::RLIMIT_AS, &limit);
    }
}
