//! What external fuzzers found, each through the exported C functions as a host calls them:
//! a step or input rate far beyond the body's range (never fmi2OK with a non-finite state; the
//! instance stays usable), seeds beyond the range fmi2SetReal has, a free body's states that
//! cannot be evaluated in Model Exchange (fmi2Discard, then recovery), a mount orientation that
//! is no rotation, and a free body's step whose substeps would take seconds.

use fmi2::types::*;
use fmu_runtime::interface::VariableTable;
use fmu_runtime::reduced::{ReducedBody, free_two_mode_body, rotating_two_mode_body, two_mode_body};
use std::ffi::CString;
use std::ptr::null_mut;
use std::time::Instant;
use test_support::logger::Log;
use test_support::scratch::{Scratch, file_uri};

use fmi2Status::*;

/// An instance of `reduced` through fmi2Instantiate, its resources in a folder of its own.
struct Fmu {
    c: fmi2Component,
    table: VariableTable,
    log: Box<Log>,
    _callbacks: Box<fmi2CallbackFunctions>,
    /// Removed after the instance is freed (fields drop after `Drop::drop`).
    _dir: Scratch,
}

impl Fmu {
    fn new(mut reduced: ReducedBody, kind: fmi2Type, tag: &str) -> Fmu {
        reduced.seal();
        let dir = Scratch::new(&format!("fmu-runtime-guards-{tag}"));
        let res = dir.folder("resources");
        std::fs::write(res.join(fmu_runtime::format::RESOURCE_FILE), reduced.to_bytes()).unwrap();
        let uri = file_uri(&res);
        let guid = CString::new(reduced.guid.clone()).unwrap();
        let log = Box::<Log>::default();
        let cb = Box::new(log.callbacks());
        let name = CString::new(tag).unwrap();
        let c = unsafe {
            fmu_runtime::fmi2Instantiate(name.as_ptr(), kind, guid.as_ptr(), uri.as_ptr(), &*cb, fmi2False, fmi2True)
        };
        assert!(!c.is_null(), "{:?}", log.last());
        Fmu { c, table: VariableTable::new(&reduced), log, _callbacks: cb, _dir: dir }
    }

    fn vr(&self, name: &str) -> u32 {
        self.table.value_reference(name).unwrap_or_else(|| panic!("no variable {name}"))
    }

    fn set(&self, names: &[&str], values: &[f64]) -> fmi2Status {
        let vrs: Vec<u32> = names.iter().map(|n| self.vr(n)).collect();
        unsafe { fmu_runtime::fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    fn get(&self, name: &str) -> (fmi2Status, f64) {
        let vr = self.vr(name);
        let mut v = f64::NAN;
        let s = unsafe { fmu_runtime::fmi2GetReal(self.c, &vr, 1, &mut v) };
        (s, v)
    }

    fn initialize(&self) {
        unsafe {
            assert_eq!(fmu_runtime::fmi2SetupExperiment(self.c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
            assert_eq!(fmu_runtime::fmi2EnterInitializationMode(self.c), fmi2OK);
            assert_eq!(fmu_runtime::fmi2ExitInitializationMode(self.c), fmi2OK, "{:?}", self.log.last());
        }
    }

    fn step(&self, t: f64, h: f64) -> fmi2Status {
        unsafe { fmu_runtime::fmi2DoStep(self.c, t, h, fmi2True) }
    }

    fn save(&self) -> fmi2FMUstate {
        let mut s: fmi2FMUstate = null_mut();
        assert_eq!(unsafe { fmu_runtime::fmi2GetFMUstate(self.c, &mut s) }, fmi2OK);
        s
    }

    fn restore(&self, s: fmi2FMUstate) {
        assert_eq!(unsafe { fmu_runtime::fmi2SetFMUstate(self.c, s) }, fmi2OK, "{:?}", self.log.last());
    }

    fn last_successful_time(&self) -> f64 {
        let mut t = f64::NAN;
        assert_eq!(unsafe { fmu_runtime::fmi2GetRealStatus(self.c, fmi2LastSuccessfulTime, &mut t) }, fmi2OK);
        t
    }

    /// The message logged with the last call's status, which must be `status`.
    fn reason(&self, status: fmi2Status) -> String {
        let (logged, text) = self.log.last_entry().map_or((fmi2OK, String::new()), |e| (e.status, e.text));
        assert_eq!(logged, status, "{text}");
        text
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmu_runtime::fmi2FreeInstance(self.c) };
    }
}

fn assert_contains(text: &str, needles: &[&str]) {
    for n in needles {
        assert!(text.contains(n), "expected {n:?} in: {text}");
    }
}

/// fmi2DoStep(t = 0, h = 1e306) never answers fmi2OK with a non-finite state: it is either a
/// finite state (the damped static answer) or not taken (fmi2Discard naming what overflowed),
/// and then the instance reads, and a master that restores the state saved before the step
/// goes on with a step of 1 ms. The coupled transition (a spinning mount) is checked too.
#[test]
fn a_step_of_1e306_s_is_never_ok_with_a_non_finite_state() {
    for (tag, reduced, spin) in [("fixed", two_mode_body(), 0.0), ("spinning", rotating_two_mode_body(), 30.0)] {
        let fmu = Fmu::new(reduced, fmi2CoSimulation, &format!("huge-step-{tag}"));
        assert_eq!(fmu.set(&["base.w[3]"], &[spin]), fmi2OK);
        fmu.initialize();
        assert_eq!(fmu.set(&["tip.f[2]", "tip.f[3]"], &[3.0, -2.0]), fmi2OK);
        let saved = fmu.save();
        let status = fmu.step(0.0, 1e306);
        let (read, q1) = fmu.get("q[1]");
        if status == fmi2OK || status == fmi2Warning {
            assert_eq!(read, fmi2OK, "{tag}: {:?}", fmu.log.last());
            assert!(q1.is_finite(), "{tag}: q[1] = {q1}");
        } else {
            assert_eq!(status, fmi2Discard, "{tag}: {:?}", fmu.log.last());
            // the reason was logged with the step; the state before it is what the host reads
            assert_eq!((read, q1), (fmi2OK, 0.0), "{tag}: {:?}", fmu.log.last());
            assert_eq!(fmu.last_successful_time(), 0.0);
            fmu.restore(saved);
        }
        let t = if status == fmi2Discard { 0.0 } else { 1e306 };
        assert_eq!(fmu.step(t, 1e-3), fmi2OK, "{tag}: {:?}", fmu.log.last());
        assert!(fmu.get("tip.u[2]").1.is_finite());
        unsafe { fmu_runtime::fmi2FreeFMUstate(fmu.c, &mut { saved }) };
    }
}

/// An input derivative of 1e300 is refused as fmi2SetReal refuses a value of 1e300: fmi2Error
/// naming the variable, nothing set, the instance in its state; a step of 1 ms then works. A
/// rate within the range whose step would carry the input past it is a step not taken.
#[test]
fn input_derivatives_beyond_the_range_are_refused_and_the_instance_stays_usable() {
    let fmu = Fmu::new(two_mode_body(), fmi2CoSimulation, "input-rates");
    fmu.initialize();
    let vrs = [fmu.vr("tip.f[1]"), fmu.vr("tip.f[2]")];
    let order = [1, 1];
    for rate in [1e200, 1e300, -1e308] {
        let values = [1.0, rate];
        let s = unsafe {
            fmu_runtime::fmi2SetRealInputDerivatives(fmu.c, vrs.as_ptr(), 2, order.as_ptr(), values.as_ptr())
        };
        assert_eq!(s, fmi2Error);
        assert_contains(&fmu.reason(fmi2Error), &["fmi2SetRealInputDerivatives", "tip.f[2]", "beyond 1e100"]);
    }
    // nothing was set (not even tip.f[1]'s valid rate): a step holds the load at zero
    assert_eq!(fmu.step(0.0, 1e-3), fmi2OK, "{:?}", fmu.log.last());
    assert_eq!(fmu.get("tip.f[1]"), (fmi2OK, 0.0));
    // a rate in range, over a step that carries the input beyond it: not taken
    let values = [1e99, 0.0];
    let s =
        unsafe { fmu_runtime::fmi2SetRealInputDerivatives(fmu.c, vrs.as_ptr(), 2, order.as_ptr(), values.as_ptr()) };
    assert_eq!(s, fmi2OK);
    let saved = fmu.save();
    assert_eq!(fmu.step(1e-3, 1e10), fmi2Discard);
    assert_contains(&fmu.reason(fmi2Discard), &["tip.f[1]", "beyond 1e100", "state before the step is kept"]);
    assert_eq!(fmu.get("tip.f[1]"), (fmi2OK, 0.0));
    assert_eq!(fmu.last_successful_time(), 1e-3);
    fmu.restore(saved);
    assert_eq!(fmu.step(1e-3, 1e-3), fmi2OK, "{:?}", fmu.log.last());
    let (status, f) = fmu.get("tip.f[1]");
    assert!(status == fmi2OK && (f / 1e96 - 1.0).abs() < 1e-12, "{f}");
}

/// A directional derivative's seed of 1e308 is refused with the known's name, in both
/// interfaces, and the next derivative is computed.
#[test]
fn directional_seeds_beyond_the_range_are_refused() {
    for (kind, tag) in [(fmi2CoSimulation, "cs"), (fmi2ModelExchange, "me")] {
        let fmu = Fmu::new(two_mode_body(), kind, &format!("seed-{tag}"));
        fmu.initialize();
        let (unknown, known) = (fmu.vr("tip.u[2]"), fmu.vr("tip.f[2]"));
        let directional = |seed: f64| {
            let mut out = f64::NAN;
            let s =
                unsafe { fmu_runtime::fmi2GetDirectionalDerivative(fmu.c, &unknown, 1, &known, 1, &seed, &mut out) };
            (s, out)
        };
        let (s, out) = directional(1e308);
        assert_eq!(s, fmi2Error);
        assert!(out.is_nan(), "written on a refused call");
        assert_contains(&fmu.reason(fmi2Error), &["dvKnown[0] = 1e308", "tip.f[2]", "beyond 1e100"]);
        let (s, out) = directional(1.0);
        assert_eq!(s, fmi2OK, "{tag}: {:?}", fmu.log.last());
        assert!(out.is_finite());
    }
}

/// Model Exchange of a free body: a state whose quaternion is no orientation (norm 0 or
/// overflowing) answers fmi2Discard naming frame.Q, as a mounted body's unevaluable state does,
/// and valid states set next are evaluated again.
#[test]
fn a_free_body_discards_states_it_cannot_evaluate_and_recovers() {
    let fmu = Fmu::new(free_two_mode_body(), fmi2ModelExchange, "free-me");
    fmu.initialize();
    unsafe {
        let mut info = fmi2EventInfo::default();
        assert_eq!(fmu_runtime::fmi2NewDiscreteStates(fmu.c, &mut info), fmi2OK);
        assert_eq!(fmu_runtime::fmi2EnterContinuousTimeMode(fmu.c), fmi2OK);
    }
    let nx = fmu.table.state_variables().count();
    let mut x = vec![0.0; nx];
    let mut dx = vec![0.0; nx];
    unsafe {
        assert_eq!(fmu_runtime::fmi2GetContinuousStates(fmu.c, x.as_mut_ptr(), nx), fmi2OK);
        let quat = nx - 10; // frame r[3], Q[4], v[3], W[3]: Q starts 10 from the end
        for bad in [[1e200, 0.0, 0.0, 0.0], [0.0; 4], [1e200, 1e200, -1e200, 1e200]] {
            let mut y = x.clone();
            y[quat..quat + 4].copy_from_slice(&bad);
            assert_eq!(fmu_runtime::fmi2SetContinuousStates(fmu.c, y.as_ptr(), nx), fmi2OK);
            assert_eq!(fmu_runtime::fmi2GetDerivatives(fmu.c, dx.as_mut_ptr(), nx), fmi2Discard);
            assert_contains(&fmu.reason(fmi2Discard), &["fmi2GetDerivatives", "frame.Q", "no orientation"]);
            assert_eq!(fmu.get("frame.Q[1]").0, fmi2OK);
            assert_eq!(fmu.get("body.energy").0, fmi2Discard);
        }
        assert_eq!(fmu_runtime::fmi2SetContinuousStates(fmu.c, x.as_ptr(), nx), fmi2OK);
        assert_eq!(fmu_runtime::fmi2GetDerivatives(fmu.c, dx.as_mut_ptr(), nx), fmi2OK, "{:?}", fmu.log.last());
        assert!(dx.iter().all(|v| v.is_finite()));
    }
}

/// A mount orientation far from the rotations: refused by fmi2SetReal when the call sets the
/// whole matrix; set entry by entry, refused where it is used (an evaluation answers
/// fmi2Discard, a step fmi2Error without changing the instance's state), each naming base.R;
/// a valid matrix set next works. One slightly off (an entry-wise interpolation) is used as
/// its nearest rotation.
#[test]
fn a_mount_orientation_that_is_no_rotation_is_refused_and_the_instance_stays_usable() {
    let names: Vec<String> = (1..=3).flat_map(|i| (1..=3).map(move |j| format!("base.R[{i},{j}]"))).collect();
    let names: Vec<&str> = names.iter().map(String::as_str).collect();
    for (kind, tag) in [(fmi2CoSimulation, "cs"), (fmi2ModelExchange, "me")] {
        let fmu = Fmu::new(two_mode_body(), kind, &format!("rotation-{tag}"));
        // all nine in one call: refused before initialisation as after
        let sheared = [1.0, 0.8, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        assert_eq!(fmu.set(&names, &sheared), fmi2Error);
        assert_contains(&fmu.reason(fmi2Error), &["fmi2SetReal", "base.R is not a proper rotation matrix", "1e-2"]);
        fmu.initialize();
        let mirrored = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, -1.0];
        assert_eq!(fmu.set(&names, &mirrored), fmi2Error);
        assert_contains(&fmu.reason(fmi2Error), &["base.R", "determinant"]);
        assert_eq!(fmu.get("base.R[3,3]"), (fmi2OK, 1.0), "nothing of the refused call was set");
        // entry by entry: accepted, refused where used
        assert_eq!(fmu.set(&["base.R[1,2]"], &[0.8]), fmi2OK);
        assert_eq!(fmu.get("tip.r[1]").0, fmi2Discard);
        assert_contains(&fmu.reason(fmi2Discard), &["tip.r[1]", "base.R is not a proper rotation matrix"]);
        if kind == fmi2CoSimulation {
            assert_eq!(fmu.step(0.0, 1e-3), fmi2Error);
            assert_contains(&fmu.reason(fmi2Error), &["fmi2DoStep", "base.R is not a proper rotation matrix"]);
        }
        // slightly off (the entry-wise mean of two rotations 0.1 rad apart): accepted
        let (a, b) = (0.3f64, 0.4f64);
        let mean = [
            0.5 * (a.cos() + b.cos()),
            -0.5 * (a.sin() + b.sin()),
            0.0,
            0.5 * (a.sin() + b.sin()),
            0.5 * (a.cos() + b.cos()),
            0.0,
            0.0,
            0.0,
            1.0,
        ];
        assert_eq!(fmu.set(&names, &mean), fmi2OK, "{:?}", fmu.log.last());
        assert_eq!(fmu.get("tip.r[1]").0, fmi2OK);
        if kind == fmi2CoSimulation {
            assert_eq!(fmu.step(0.0, 1e-3), fmi2OK, "{:?}", fmu.log.last());
        }
    }
}

/// A free body spinning at 300 rad/s: a step of 16 s would need 960 000 substeps of 0.005 rad.
/// It returns within the wall-time bound, either done or not taken (fmi2Discard before any work,
/// naming the substeps, the bound and the largest step at this spin); a master that restores
/// the saved state and takes that largest step proceeds, as does one that halves the step until
/// it fits.
#[test]
fn a_long_step_of_a_fast_spinning_free_body_is_bounded_in_time() {
    let fmu = Fmu::new(free_two_mode_body(), fmi2CoSimulation, "free-spin");
    assert_eq!(fmu.set(&["initial.w[3]"], &[300.0]), fmi2OK, "{:?}", fmu.log.last());
    fmu.initialize();
    let saved = fmu.save();
    fmu.log.clear();
    let start = Instant::now();
    let status = fmu.step(0.0, 16.0);
    let took = start.elapsed().as_secs_f64();
    println!("h = 16 s at 300 rad/s: {status:?} in {took:.4} s");
    assert!(took < 2.0, "a step of 16 s took {took} s");
    assert_eq!(status, fmi2Discard, "{:?}", fmu.log.last());
    let reason = fmu.reason(fmi2Discard);
    assert_contains(&reason, &["needs 96000", "substeps of at most 0.005 rad", "largest step at this spin is h = "]);
    assert_eq!(fmu.last_successful_time(), 0.0);
    let largest: f64 =
        reason.split("largest step at this spin is h = ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    assert!(largest > 0.0 && largest < 16.0, "{largest}");
    fmu.restore(saved);
    let start = Instant::now();
    assert_eq!(fmu.step(0.0, largest), fmi2OK, "{:?}", fmu.log.last());
    let took = start.elapsed().as_secs_f64();
    println!("the largest step, h = {largest} s: {took:.4} s");
    assert!(took < 2.0, "the largest step took {took} s");
    // halving: 8 s, then 4 s, ... until one is taken
    fmu.restore(saved);
    let mut h = 16.0;
    loop {
        h /= 2.0;
        let s = fmu.step(0.0, h);
        if s == fmi2OK {
            break;
        }
        assert_eq!(s, fmi2Discard);
        fmu.restore(saved);
    }
    assert!(h <= largest);
    assert!(fmu.get("body.energy").1.is_finite());
    unsafe { fmu_runtime::fmi2FreeFMUstate(fmu.c, &mut { saved }) };
}
