//! Instances are independent: 1000 instances stepped interleaved on 8 threads give bit for bit
//! the results of the same instances run one at a time (no shared mutable state in the runtime,
//! no order dependence). Through the FMI entry points, as a host drives them.

use std::ffi::CString;
use std::ptr::null;
use test_support::scratch::{Scratch, file_uri};

use fmi2::api;
use fmi2::types::fmi2Status::fmi2OK;
use fmi2::types::*;
use fmi2::{Causality, VarType};
use fmu_runtime::fmu::BodyFmu;
use fmu_runtime::format::RESOURCE_FILE;
use fmu_runtime::interface::VariableTable;
use fmu_runtime::reduced::two_mode_body;

const INSTANCES: usize = 1000;
const THREADS: usize = 8;
const STEPS: usize = 60;
const H: f64 = 1e-3;

/// A component handed to another thread: each is used by one thread at a time, as FMI requires.
struct Component(fmi2Component);
unsafe impl Send for Component {}

struct Setup {
    uri: CString,
    guid: CString,
    table: VariableTable,
    outputs: Vec<u32>,
    force: u32,
    shake: u32,
    alpha: u32,
}

fn setup(dir: &std::path::Path) -> Setup {
    let mut body = two_mode_body();
    body.seal();
    std::fs::write(dir.join(RESOURCE_FILE), body.to_bytes()).unwrap();
    let table = VariableTable::new(&body);
    let outputs = table
        .variables
        .iter()
        .filter(|v| v.var_type == VarType::Real && matches!(v.causality, Causality::Output | Causality::Local))
        .map(|v| v.vr)
        .collect();
    let vr = |name: &str| table.value_reference(name).unwrap();
    Setup {
        uri: file_uri(dir),
        guid: CString::new(body.guid.clone()).unwrap(),
        force: vr("tip.f[2]"),
        shake: vr("base.a[3]"),
        alpha: vr("damping.alpha"),
        outputs,
        table,
    }
}

fn ok(s: fmi2Status, what: &str) {
    assert_eq!(s, fmi2OK, "{what}");
}

impl Setup {
    /// Instance `k`: its own damping, load and base motion, so a mix-up between instances shows.
    fn start(&self, k: usize) -> Component {
        let c = unsafe {
            api::fmi2Instantiate::<BodyFmu>(
                c"many".as_ptr(),
                fmi2CoSimulation,
                self.guid.as_ptr(),
                self.uri.as_ptr(),
                null(),
                0,
                0,
            )
        };
        assert!(!c.is_null());
        unsafe {
            ok(api::fmi2SetReal::<BodyFmu>(c, &self.alpha, 1, &(0.1 + k as f64 * 1e-3)), "set damping.alpha");
            ok(api::fmi2SetupExperiment::<BodyFmu>(c, 0, 0.0, 0.0, 0, 0.0), "fmi2SetupExperiment");
            ok(api::fmi2EnterInitializationMode::<BodyFmu>(c), "fmi2EnterInitializationMode");
            ok(api::fmi2ExitInitializationMode::<BodyFmu>(c), "fmi2ExitInitializationMode");
        }
        Component(c)
    }

    /// Step `i` of instance `k`: set its inputs, step, read every output (as bits).
    fn step(&self, c: &Component, k: usize, i: usize, record: &mut Vec<u64>) {
        let t = i as f64 * H;
        let force = 1.0 + (k as f64 * 0.37 + 40.0 * t).sin();
        let shake = 2.0 * (k % 7) as f64 * (90.0 * t).cos();
        let mut values = vec![0.0; self.outputs.len()];
        unsafe {
            ok(api::fmi2SetReal::<BodyFmu>(c.0, &self.force, 1, &force), "set tip.f[2]");
            ok(api::fmi2SetReal::<BodyFmu>(c.0, &self.shake, 1, &shake), "set base.a[3]");
            ok(api::fmi2DoStep::<BodyFmu>(c.0, t, H, fmi2True), "fmi2DoStep");
            ok(
                api::fmi2GetReal::<BodyFmu>(c.0, self.outputs.as_ptr(), self.outputs.len(), values.as_mut_ptr()),
                "fmi2GetReal",
            );
        }
        record.extend(values.iter().map(|v| v.to_bits()));
    }

    fn free(&self, c: Component) {
        unsafe { api::fmi2FreeInstance::<BodyFmu>(c.0) };
    }
}

#[test]
fn a_thousand_instances_on_eight_threads_match_the_same_instances_run_alone() {
    let dir = Scratch::new("fmu-runtime-concurrent");
    let s = setup(dir.path());
    assert!(s.outputs.len() > 10, "{} outputs of {}", s.outputs.len(), s.table.variables.len());

    // alone: one instance at a time, from instantiation to free
    let alone: Vec<Vec<u64>> = (0..INSTANCES)
        .map(|k| {
            let c = s.start(k);
            let mut record = Vec::new();
            for i in 0..STEPS {
                s.step(&c, k, i, &mut record);
            }
            s.free(c);
            record
        })
        .collect();

    // together: all 1000 alive at once, each thread stepping its share interleaved
    let instances: Vec<(usize, Component)> = (0..INSTANCES).map(|k| (k, s.start(k))).collect();
    let mut shares: Vec<Vec<(usize, Component)>> = (0..THREADS).map(|_| Vec::new()).collect();
    for (k, c) in instances {
        shares[k % THREADS].push((k, c));
    }
    let mut together: Vec<(usize, Vec<u64>)> = std::thread::scope(|scope| {
        let handles: Vec<_> = shares
            .into_iter()
            .map(|share| {
                let s = &s;
                scope.spawn(move || {
                    let mut records = vec![Vec::new(); share.len()];
                    for i in 0..STEPS {
                        for ((k, c), record) in share.iter().zip(records.iter_mut()) {
                            s.step(c, *k, i, record);
                        }
                    }
                    let keys: Vec<usize> = share.iter().map(|(k, _)| *k).collect();
                    for (_, c) in share {
                        s.free(c);
                    }
                    keys.into_iter().zip(records).collect::<Vec<_>>()
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap()).collect()
    });
    together.sort_by_key(|(k, _)| *k);

    assert_eq!(together.len(), alone.len());
    for ((k, record), expected) in together.iter().zip(&alone) {
        assert_eq!(record.len(), expected.len(), "instance {k}");
        assert!(record == expected, "instance {k} differs when run with the others");
    }
    // the instances differ from each other (the comparison could not pass by all being equal)
    assert_ne!(alone[0], alone[1]);
}
