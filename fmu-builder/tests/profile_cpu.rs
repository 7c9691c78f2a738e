//! The build profile's CPU time per phase (a test binary of its own: the CPU time is the
//! process's, so no other test may run meanwhile).

use fmu_builder::profile::{Profile, table};
use phases::phase;
use std::time::{Duration, Instant};
use tracing_subscriber::layer::SubscriberExt;

/// Keep one core busy for `d`.
fn spin(d: Duration) -> u64 {
    let start = Instant::now();
    let mut x = 0u64;
    while start.elapsed() < d {
        x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
    }
    x
}

/// A phase that keeps two threads busy shows about two cores, one that keeps one busy about one,
/// and one that sleeps about none: the cpu/wall column tells a serial phase from a parallel one.
#[test]
fn cpu_time_per_phase_tells_serial_from_parallel() {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    // without the resident-set sampler, whose thread would add its own CPU time
    let profile = Profile::new(false);
    let busy = Duration::from_millis(300);
    tracing::subscriber::with_default(tracing_subscriber::registry().with(profile.layer()), || {
        phase("two threads", || {
            std::thread::scope(|s| {
                let other = s.spawn(|| spin(busy));
                spin(busy);
                other.join().unwrap();
            })
        });
        phase("one thread", || spin(busy));
        phase("asleep", || std::thread::sleep(busy));
    });
    let phases = profile.take();
    assert_eq!(phases.len(), 3);
    let ratio: Vec<f64> = phases.iter().map(|p| p.cpu_seconds.expect("getrusage on Linux") / p.seconds).collect();
    println!("{}", table(&phases));
    // ranges: a thread descheduled now and then loses a few percent; a tick-based CPU clock
    // (4 ms) errs by a few percent of 300 ms
    if cores >= 2 {
        assert!((1.6..=2.2).contains(&ratio[0]), "two busy threads: cpu/wall {}", ratio[0]);
    }
    assert!((0.8..=1.2).contains(&ratio[1]), "one busy thread: cpu/wall {}", ratio[1]);
    assert!(ratio[2] <= 0.1, "asleep: cpu/wall {}", ratio[2]);
    let text = table(&phases);
    assert!(text.lines().next().unwrap().contains("cpu/wall"), "{text}");
    assert_eq!(text.lines().count(), 4);
}
