//! The build profile's recorder on its own (one test per process: the resident-set high-water
//! mark it resets is the process's, so no other test may allocate meanwhile).

use fmu_builder::profile::{note, per_phase_memory, phase, process_peak_mib, reset_high_water, table, take};

#[test]
fn nested_phases_keep_their_order_depth_time_and_own_peaks() {
    take();
    per_phase_memory(true);
    const MIB: usize = 1 << 20;
    let outer = phase("outer", || {
        note(|| "first".into());
        let inner = phase("inner", || {
            // 200 MiB touched: the inner phase's peak must show it
            let v = vec![1u8; 200 * MIB];
            std::thread::sleep(std::time::Duration::from_millis(20));
            v.iter().map(|&b| b as usize).sum::<usize>()
        });
        note(|| "second".into());
        phase("small", || std::hint::black_box(vec![1u8; MIB]).len()) + inner
    });
    assert_eq!(outer, 201 * MIB);
    let phases = take();
    let names: Vec<(&str, usize)> = phases.iter().map(|p| (p.name.as_str(), p.depth)).collect();
    assert_eq!(names, [("outer", 0), ("inner", 1), ("small", 1)]);
    assert_eq!(phases[0].detail, "first; second");
    assert!(phases[1].seconds >= 0.02 && phases[0].seconds >= phases[1].seconds);
    if let (Some(outer), Some(inner), Some(small)) = (phases[0].peak_mib, phases[1].peak_mib, phases[2].peak_mib) {
        assert!(inner >= 200.0, "inner peak {inner} MiB");
        assert!(outer >= inner, "the enclosing phase covers its child: {outer} < {inner}");
        // measured: the small phase's own peak stays far below the inner one's when the
        // high-water mark can be reset; where it cannot, every phase reports the peak so far
        if reset_high_water() {
            assert!(small < inner - 100.0, "small phase peak {small} MiB vs inner {inner}");
        }
    }
    // the resets do not hide the process's own peak: the inner phase's 200 MiB stay in it
    if let (Some(process), Some(inner)) = (process_peak_mib(), phases[1].peak_mib) {
        assert!(process >= inner, "process peak {process} MiB below the inner phase's {inner}");
    }
    assert!(take().is_empty());
    assert!(table(&phases).lines().count() == 4 && table(&phases).contains("  inner"));
}
