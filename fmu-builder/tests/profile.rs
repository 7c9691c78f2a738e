//! The build profile's recorder on its own (a test binary of its own: the resident set it samples
//! is the process's, so nothing else may allocate much meanwhile; the other test here only reads
//! the sources).

use fmu_builder::profile::{Profile, process_peak_mib, table};
use phases::{note, phase};
use tracing_subscriber::layer::SubscriberExt;

/// Run `work` with `profile` listening, as the command line runs a build.
fn recorded<T>(profile: &Profile, work: impl FnOnce() -> T) -> T {
    tracing::subscriber::with_default(tracing_subscriber::registry().with(profile.layer()), work)
}

/// Peak resident set as getrusage reports it (what `/usr/bin/time` shows) [MiB].
fn rusage_max_rss_mib() -> f64 {
    // SAFETY: getrusage writes into the zeroed struct it is given
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let rc = unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    assert_eq!(rc, 0, "getrusage failed");
    usage.ru_maxrss as f64 / 1024.0
}

#[test]
fn nested_phases_keep_their_order_depth_time_and_own_peaks() {
    let profile = Profile::new(true);
    const MIB: usize = 1 << 20;
    let outer = recorded(&profile, || {
        phase("outer", || {
            note(|| "first".into());
            let inner = phase("inner", || {
                // 200 MiB touched and freed inside the phase: only the sampler sees them
                let v = vec![1u8; 200 * MIB];
                std::thread::sleep(std::time::Duration::from_millis(20));
                v.iter().map(|&b| b as usize).sum::<usize>()
            });
            note(|| "second".into());
            phase("small", || std::hint::black_box(vec![1u8; MIB]).len()) + inner
        })
    });
    assert_eq!(outer, 201 * MIB);
    let phases = profile.take();
    let names: Vec<(&str, usize)> = phases.iter().map(|p| (p.name.as_str(), p.depth)).collect();
    assert_eq!(names, [("outer", 0), ("inner", 1), ("small", 1)]);
    assert_eq!(phases[0].detail, "first; second");
    assert!(phases[1].seconds >= 0.02 && phases[0].seconds >= phases[1].seconds);
    if let (Some(outer), Some(inner), Some(small)) = (phases[0].peak_mib, phases[1].peak_mib, phases[2].peak_mib) {
        assert!(inner >= 200.0, "inner peak {inner} MiB");
        assert!(outer >= inner, "the enclosing phase covers its child: {outer} < {inner}");
        // the small phase starts after the 200 MiB went back to the system: its own peak stays
        // far below the inner one's
        assert!(small < inner - 100.0, "small phase peak {small} MiB vs inner {inner}");
    }
    // the process's own high-water mark is never reset: the kernel's (VmHWM) and getrusage's
    // (what /usr/bin/time reports) keep the inner phase's 200 MiB
    // (less the slack of the kernel's resident-set counters: they are kept per thread and folded
    // in batches, so a VmRSS sample and the high-water mark can differ by tens of pages; measured
    // 0.14 MiB on the CI machine, allowed 2 MiB, far below the 200 MiB a reset would lose)
    const COUNTER_SLACK_MIB: f64 = 2.0;
    if let (Some(process), Some(inner)) = (process_peak_mib(), phases[1].peak_mib) {
        assert!(process >= inner - COUNTER_SLACK_MIB, "process peak {process} MiB below the inner phase's {inner}");
        let rusage = rusage_max_rss_mib();
        assert!(rusage >= inner - COUNTER_SLACK_MIB, "getrusage's peak {rusage} MiB below the inner phase's {inner}");
    }
    assert!(profile.take().is_empty());
    assert!(table(&phases).lines().count() == 4 && table(&phases).contains("  inner"));
}

/// Two builds at once, each under its own subscriber (as two jobs in one process run): each
/// profile holds its own phases and notes, none of the other's, and a phase run with nobody
/// listening goes nowhere.
#[test]
fn concurrent_builds_keep_their_own_phases() {
    let run = |tag: &'static str| {
        std::thread::spawn(move || {
            let profile = Profile::new(false);
            recorded(&profile, || {
                for i in 0..50 {
                    phase(format!("{tag} {i}"), || note(|| format!("{tag} note")));
                }
            });
            profile.take()
        })
    };
    let (a, b) = (run("a"), run("b"));
    let done = [("a", a.join().expect("thread a")), ("b", b.join().expect("thread b"))];
    // after the threads: tracing caches a call site's interest when it is first reached, and one
    // first reached while no subscriber exists anywhere would stay silent until the next
    // subscriber is made (the command line makes its subscriber before any phase runs)
    phase("unobserved", || note(|| "unobserved".into()));
    for (tag, phases) in done {
        assert_eq!(phases.len(), 50, "{tag}: {phases:?}");
        for (i, p) in phases.iter().enumerate() {
            assert_eq!(
                (p.name.as_str(), p.depth, p.detail.as_str()),
                (format!("{tag} {i}").as_str(), 0, format!("{tag} note").as_str())
            );
        }
    }
}

/// Writing to /proc/self/clear_refs resets the high-water mark that `/usr/bin/time -v`,
/// getrusage and the summary's peak read: no source of the builder may do it.
#[test]
fn no_source_resets_the_high_water_mark() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut stack = vec![src];
    let mut offenders = Vec::new();
    let mut files = 0;
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let path = entry.unwrap_or_else(|e| panic!("{}: {e}", dir.display())).path();
            if path.is_dir() {
                stack.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files += 1;
                let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                // the path as code would name it, in a string literal (the docs may mention it)
                if text.contains("clear_refs\"") {
                    offenders.push(path.display().to_string());
                }
            }
        }
    }
    assert!(files > 10, "only {files} sources found under src/");
    assert!(offenders.is_empty(), "/proc/self/clear_refs written in {offenders:?}");
}
