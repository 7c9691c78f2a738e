//! Drives the generic FMI entry points (what the exported C symbols forward to) the way an importer would, over a mock model.

mod mock;

use std::ffi::{CStr, CString};
use std::ptr::{null, null_mut};

use crate::api;
use crate::types::fmi2Status::*;
use crate::types::*;
use mock::*;

type Log = test_support::logger::Log<fmi2Status>;

fn callbacks(log: &Log) -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: Some(Log::logger()),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log.environment(),
    }
}

fn instantiate_with(log: &Log, kind: fmi2Type, guid: &str, uri: Option<&str>, logging_on: bool) -> fmi2Component {
    // Temporaries freed right after the call: the layer must have copied them.
    let name = CString::new("spring #1").unwrap();
    let guid = CString::new(guid).unwrap();
    let uri = uri.map(|u| CString::new(u).unwrap());
    let cb = Box::new(callbacks(log));
    unsafe {
        api::fmi2Instantiate::<Spring>(
            name.as_ptr(),
            kind,
            guid.as_ptr(),
            uri.as_ref().map_or(null(), |u| u.as_ptr()),
            &*cb,
            fmi2False,
            logging_on as fmi2Boolean,
        )
    }
}

fn instantiate(log: &Log, kind: fmi2Type) -> fmi2Component {
    let c = instantiate_with(log, kind, GUID, Some("file:///tmp/spring/resources"), false);
    assert!(!c.is_null(), "{}", log.last());
    c
}

fn get_real(c: fmi2Component, vr: u32) -> f64 {
    let mut v = f64::NAN;
    assert_eq!(unsafe { api::fmi2GetReal::<Spring>(c, &vr, 1, &mut v) }, fmi2OK);
    v
}

fn set_real(c: fmi2Component, vr: u32, v: f64) -> fmi2Status {
    unsafe { api::fmi2SetReal::<Spring>(c, &vr, 1, &v) }
}

fn set_bool(c: fmi2Component, vr: u32, v: bool) -> fmi2Status {
    let v = v as fmi2Boolean;
    unsafe { api::fmi2SetBoolean::<Spring>(c, &vr, 1, &v) }
}

fn get_string(c: fmi2Component, vr: u32) -> String {
    let mut s: fmi2String = null();
    assert_eq!(unsafe { api::fmi2GetString::<Spring>(c, &vr, 1, &mut s) }, fmi2OK);
    unsafe { CStr::from_ptr(s) }.to_str().unwrap().to_owned()
}

fn initialize(c: fmi2Component, start: f64) {
    unsafe {
        assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2False, 0.0, start, fmi2False, 0.0), fmi2OK);
        assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2ExitInitializationMode::<Spring>(c), fmi2OK);
    }
}

/// Steps from `t` to `t_end` with step `h`; returns the final time.
fn run_cs(c: fmi2Component, mut t: f64, t_end: f64, h: f64) -> f64 {
    while t < t_end - h / 2.0 {
        assert_eq!(unsafe { api::fmi2DoStep::<Spring>(c, t, h, fmi2True) }, fmi2OK);
        t += h;
    }
    t
}

#[test]
fn version_and_platform() {
    unsafe {
        assert_eq!(CStr::from_ptr(api::fmi2GetVersion()).to_str().unwrap(), "2.0");
        assert_eq!(CStr::from_ptr(api::fmi2GetTypesPlatform()).to_str().unwrap(), "default");
    }
}

#[test]
fn instantiate_checks_guid_and_type() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    unsafe { api::fmi2FreeInstance::<Spring>(c) };

    let c = instantiate_with(&log, fmi2CoSimulation, "{wrong}", None, false);
    assert!(c.is_null());
    assert!(log.contains(&format!("GUID mismatch: expected {GUID} got {{wrong}}")), "{}", log.last());
    assert_eq!(log.entries().last().unwrap().status, fmi2Error);
    assert_eq!(log.entries().last().unwrap().category, "logStatusError");

    assert!(instantiate_with(&log, 7, GUID, None, false).is_null());
    assert!(log.contains("invalid fmuType 7"));

    // Model refusal is reported too.
    assert!(instantiate_with(&log, fmi2CoSimulation, GUID, Some("file:///refuse"), false).is_null());
    assert!(log.contains("cannot load /refuse"));

    // No callbacks at all: still works, just silent.
    let name = c"silent";
    let guid = CString::new(GUID).unwrap();
    let c = unsafe {
        api::fmi2Instantiate::<Spring>(name.as_ptr(), fmi2ModelExchange, guid.as_ptr(), null(), null(), 0, 1)
    };
    assert!(!c.is_null());
    assert_eq!(unsafe { api::fmi2DoStep::<Spring>(c, 0.0, 1.0, 0) }, fmi2Error);
    unsafe { api::fmi2FreeInstance::<Spring>(c) };

    // Missing instance name.
    let cb = callbacks(&log);
    let c = unsafe { api::fmi2Instantiate::<Spring>(null(), fmi2ModelExchange, guid.as_ptr(), null(), &cb, 0, 0) };
    assert!(c.is_null());
    assert!(log.contains("missing instance name"));
}

#[test]
fn instantiate_resource_uri_variants() {
    let log = Log::default();
    for uri in [
        "file:/tmp/my%20fmu/resources",
        "file://localhost/tmp/my%20fmu/resources/",
        "file:///tmp/my%20fmu/resources",
        "file:////tmp/my%20fmu/resources/",
    ] {
        let c = instantiate_with(&log, fmi2CoSimulation, GUID, Some(uri), false);
        assert!(!c.is_null(), "{uri}: {}", log.last());
        unsafe { api::fmi2EnterInitializationMode::<Spring>(c) };
        assert_eq!(get_string(c, RESOURCES), "/tmp/my fmu/resources", "{uri}");
        unsafe { api::fmi2FreeInstance::<Spring>(c) };
    }
    let c = instantiate_with(&log, fmi2CoSimulation, GUID, None, false);
    unsafe { api::fmi2EnterInitializationMode::<Spring>(c) };
    assert_eq!(get_string(c, RESOURCES), "none");
    unsafe { api::fmi2FreeInstance::<Spring>(c) };

    for uri in ["http://example.com/resources", "file://server/share", ""] {
        assert!(instantiate_with(&log, fmi2CoSimulation, GUID, Some(uri), false).is_null(), "{uri}");
        assert!(log.last().contains("fmuResourceLocation"), "{}", log.last());
    }
}

#[test]
fn state_machine_errors() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    unsafe {
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.0, 0.1, 0), fmi2Error);
        assert_eq!(log.last(), "fmi2DoStep called in state Instantiated; allowed in: StepComplete");
        let mut x = 0.0;
        assert_eq!(api::fmi2GetReal::<Spring>(c, &X, 1, &mut x), fmi2Error);
        assert!(log.last().starts_with("fmi2GetReal called in state Instantiated"));
        // ME function on a CS instance.
        assert_eq!(api::fmi2SetTime::<Spring>(c, 1.0), fmi2Error);
        assert!(log.last().contains("ModelExchange function"), "{}", log.last());

        // Before initialization: parameters and states with start values may be set.
        assert_eq!(set_real(c, K, 4.0), fmi2OK);
        assert_eq!(set_real(c, X, 2.0), fmi2OK);
        assert_eq!(set_real(c, A, 2.0), fmi2Error);
        assert!(log.last().contains("value reference 4"), "{}", log.last());
        initialize(c, 0.0);

        assert_eq!(set_real(c, K, 5.0), fmi2Error);
        assert!(log.last().contains("value reference 2") && log.last().contains("Fixed"), "{}", log.last());
        assert_eq!(set_real(c, X, 1.0), fmi2Error);
        assert!(log.last().contains("causality Output"), "{}", log.last());
        // Tunable parameter and input are fine.
        assert_eq!(set_real(c, D, 0.1), fmi2OK);
        assert_eq!(set_real(c, U, 0.5), fmi2OK);

        let vr = 99;
        assert_eq!(api::fmi2GetReal::<Spring>(c, &vr, 1, &mut x), fmi2Error);
        assert_eq!(log.last(), "fmi2GetReal: unknown value reference 99");
        assert_eq!(set_real(c, CRASH, 1.0), fmi2Error);
        assert_eq!(log.last(), "fmi2SetReal: value reference 7 (crash) is a Boolean variable, not Real");

        // Null pointers.
        assert_eq!(api::fmi2GetReal::<Spring>(c, &X, 1, null_mut()), fmi2Error);
        assert_eq!(log.last(), "fmi2GetReal: argument value[] must not be NULL");
        assert_eq!(api::fmi2GetReal::<Spring>(c, null(), 1, &mut x), fmi2Error);
        assert_eq!(api::fmi2GetReal::<Spring>(c, null(), 0, null_mut()), fmi2OK);
        assert_eq!(api::fmi2GetReal::<Spring>(null_mut(), &X, 1, &mut x), fmi2Error);
        assert_eq!(api::fmi2GetStatus::<Spring>(c, fmi2DoStepStatus, null_mut()), fmi2Error);

        // DoStep argument checks.
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.5, 0.1, 0), fmi2Error);
        assert!(log.last().contains("currentCommunicationPoint = 0.5"), "{}", log.last());
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.0, 0.0, 0), fmi2Error);
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.0, f64::NAN, 0), fmi2Error);
        assert_eq!(api::fmi2DoStep::<Spring>(c, f64::NAN, 0.1, 0), fmi2Error);
        assert_eq!(api::fmi2CancelStep::<Spring>(c), fmi2Error);

        // Usage errors leave the instance usable.
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.0, 0.1, 0), fmi2OK);
        assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2Error);
        assert_eq!(api::fmi2Terminate::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.1, 0.1, 0), fmi2Error);
        assert_eq!(api::fmi2GetReal::<Spring>(c, &X, 1, &mut x), fmi2OK);
        api::fmi2FreeInstance::<Spring>(c);
    }
    for e in log.entries().iter() {
        assert_eq!(e.status, fmi2Error);
        assert_eq!(e.category, "logStatusError");
    }
}

#[test]
fn co_simulation_run() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    assert_eq!(set_real(c, K, 4.0), fmi2OK);
    initialize(c, 1.0);
    // 0.1 does not sum exactly; the host's t and ours differ in the last bits.
    let t = run_cs(c, 1.0, 2.0, 0.1);
    let x = get_real(c, X);
    assert!((x - (2.0f64).cos()).abs() < 1e-9, "x = {x}");
    unsafe {
        let mut n = 0;
        assert_eq!(api::fmi2GetInteger::<Spring>(c, &STEPS, 1, &mut n), fmi2OK);
        assert_eq!(n, 10);
        let mut time = 0.0;
        assert_eq!(api::fmi2GetRealStatus::<Spring>(c, fmi2LastSuccessfulTime, &mut time), fmi2OK);
        assert!((time - t).abs() < 1e-12);
        let mut status = fmi2Fatal;
        assert_eq!(api::fmi2GetStatus::<Spring>(c, fmi2DoStepStatus, &mut status), fmi2OK);
        assert_eq!(status, fmi2OK);
        let mut b = fmi2True;
        assert_eq!(api::fmi2GetBooleanStatus::<Spring>(c, fmi2Terminated, &mut b), fmi2OK);
        assert_eq!(b, fmi2False);
        let mut i = 0;
        assert_eq!(api::fmi2GetIntegerStatus::<Spring>(c, fmi2DoStepStatus, &mut i), fmi2Discard);
        let mut s = null();
        assert_eq!(api::fmi2GetStringStatus::<Spring>(c, fmi2PendingStatus, &mut s), fmi2Discard);
        assert_eq!(api::fmi2GetRealStatus::<Spring>(c, fmi2DoStepStatus, &mut time), fmi2Discard);

        // Unsupported capabilities say so (more in derivatives_need_the_capability).
        let order = 1;
        let v = 0.0;
        assert_eq!(api::fmi2SetRealInputDerivatives::<Spring>(c, &U, 1, &order, &v), fmi2Error);
        assert!(log.last().contains("canInterpolateInputs=false"), "{}", log.last());

        assert_eq!(api::fmi2Terminate::<Spring>(c), fmi2OK);
        // Reset and run again from scratch, with the default k = 1.
        assert_eq!(api::fmi2Reset::<Spring>(c), fmi2OK);
        initialize(c, 0.0);
        run_cs(c, 0.0, 1.0, 0.25);
        assert!((get_real(c, X) - 1.0f64.cos()).abs() < 1e-9);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

/// The host integrates with classical RK4 through the ME functions.
#[test]
fn model_exchange_run() {
    let log = Log::default();
    let c = instantiate(&log, fmi2ModelExchange);
    unsafe {
        let mut nominal = [0.0; 2];
        assert_eq!(api::fmi2GetNominalsOfContinuousStates::<Spring>(c, nominal.as_mut_ptr(), 2), fmi2OK);
        assert_eq!(nominal, [1.0, 1.0]);
        assert_eq!(set_real(c, K, 4.0), fmi2OK);
        initialize(c, 0.0);
        let mut info = fmi2EventInfo { newDiscreteStatesNeeded: 7, ..Default::default() };
        assert_eq!(api::fmi2NewDiscreteStates::<Spring>(c, &mut info), fmi2OK);
        assert_eq!(info, fmi2EventInfo::default());
        assert_eq!(api::fmi2EnterContinuousTimeMode::<Spring>(c), fmi2OK);

        let mut x = [0.0; 2];
        assert_eq!(api::fmi2GetContinuousStates::<Spring>(c, x.as_mut_ptr(), 2), fmi2OK);
        assert_eq!(x, [1.0, 0.0]);
        let deriv = |t: f64, x: &[f64; 2]| -> [f64; 2] {
            let mut dx = [0.0; 2];
            assert_eq!(api::fmi2SetTime::<Spring>(c, t), fmi2OK);
            assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, x.as_ptr(), 2), fmi2OK);
            assert_eq!(api::fmi2GetDerivatives::<Spring>(c, dx.as_mut_ptr(), 2), fmi2OK);
            dx
        };
        let h = 0.001;
        let mut t = 0.0;
        for _ in 0..1000 {
            let k1 = deriv(t, &x);
            let k2 = deriv(t + h / 2.0, &[x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]]);
            let k3 = deriv(t + h / 2.0, &[x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]]);
            let k4 = deriv(t + h, &[x[0] + h * k3[0], x[1] + h * k3[1]]);
            for i in 0..2 {
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            t += h;
            assert_eq!(api::fmi2SetTime::<Spring>(c, t), fmi2OK);
            assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, x.as_ptr(), 2), fmi2OK);
            let (mut enter, mut term) = (fmi2True, fmi2True);
            assert_eq!(api::fmi2CompletedIntegratorStep::<Spring>(c, fmi2True, &mut enter, &mut term), fmi2OK);
            assert_eq!((enter, term), (fmi2False, fmi2False));
        }
        assert!((get_real(c, X) - 2.0f64.cos()).abs() < 1e-9);
        let mut z = [0.0];
        assert_eq!(api::fmi2GetEventIndicators::<Spring>(c, z.as_mut_ptr(), 1), fmi2OK);
        assert_eq!(z[0], x[0]);

        // Size and state checks.
        assert_eq!(api::fmi2GetEventIndicators::<Spring>(c, z.as_mut_ptr(), 2), fmi2Error);
        assert_eq!(log.last(), "fmi2GetEventIndicators: ni = 2 but the model has 1");
        assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, x.as_ptr(), 1), fmi2Error);
        assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, null(), 2), fmi2Error);
        assert_eq!(api::fmi2NewDiscreteStates::<Spring>(c, &mut info), fmi2Error);
        assert!(log.last().starts_with("fmi2NewDiscreteStates called in state ContinuousTimeMode"));
        // Discrete inputs only change at events.
        assert_eq!(set_bool(c, FAIL, true), fmi2Error);
        assert_eq!(api::fmi2EnterEventMode::<Spring>(c), fmi2OK);
        assert_eq!(set_bool(c, FAIL, false), fmi2OK);
        assert_eq!(api::fmi2DoStep::<Spring>(c, t, 0.1, 0), fmi2Error);
        assert_eq!(api::fmi2Terminate::<Spring>(c), fmi2OK);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

#[test]
fn panic_in_model_is_contained() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    run_cs(c, 0.0, 0.5, 0.1);
    assert_eq!(set_bool(c, CRASH, true), fmi2OK);
    unsafe {
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.5, 0.1, 0), fmi2Error);
        assert!(log.last().starts_with("fmi2DoStep: panic in the model: crash requested"), "{}", log.last());
        let mut status = fmi2OK;
        // Error state: only diagnostics, state restore, reset, free.
        assert_eq!(api::fmi2GetStatus::<Spring>(c, fmi2DoStepStatus, &mut status), fmi2Error);
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.5, 0.1, 0), fmi2Error);
        assert!(log.last().starts_with("fmi2DoStep called in state Error"));
        let mut b = 0;
        assert_eq!(api::fmi2GetBoolean::<Spring>(c, &CRASH, 1, &mut b), fmi2OK);
        assert_eq!(b, fmi2True);
        assert_eq!(api::fmi2Reset::<Spring>(c), fmi2OK);
        initialize(c, 0.0);
        run_cs(c, 0.0, 1.0, 0.1);
        assert!((get_real(c, X) - 1.0f64.cos()).abs() < 1e-9);
        api::fmi2FreeInstance::<Spring>(c);
    }

    // The same through a Model Exchange call.
    let c = instantiate(&log, fmi2ModelExchange);
    initialize(c, 0.0);
    assert_eq!(set_bool(c, CRASH, true), fmi2OK);
    let mut dx = [0.0; 2];
    unsafe {
        assert_eq!(api::fmi2GetDerivatives::<Spring>(c, dx.as_mut_ptr(), 2), fmi2Error);
        assert!(log.last().starts_with("fmi2GetDerivatives: panic in the model"));
        api::fmi2FreeInstance::<Spring>(c);
    }
}

#[test]
fn model_error_enters_error_state_and_message_is_escaped() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    assert_eq!(set_bool(c, FAIL, true), fmi2OK);
    unsafe {
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.0, 0.1, 0), fmi2Error);
        // '%' arrives untouched (it is the "%s" argument), '#' doubled for the importer.
        assert_eq!(log.last(), "fmi2DoStep: solver failed at 50% of the step ##r0## t = 0");
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.0, 0.1, 0), fmi2Error);
        assert!(log.last().contains("state Error"));
        // Rejected value from the model: also Error.
        assert_eq!(api::fmi2Reset::<Spring>(c), fmi2OK);
        assert_eq!(set_real(c, K, -1.0), fmi2Error);
        assert_eq!(log.last(), "fmi2SetReal: value reference 2: k must be > 0, got -1");
        assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2Error);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

#[test]
fn fmu_state_round_trip() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    run_cs(c, 0.0, 0.5, 0.1);
    let x_half = get_real(c, X);
    let mut state: fmi2FMUstate = null_mut();
    unsafe {
        assert_eq!(api::fmi2GetFMUstate::<Spring>(c, &mut state), fmi2OK);
        assert!(!state.is_null());
        run_cs(c, 0.5, 1.0, 0.1);
        let x_end = get_real(c, X);

        assert_eq!(api::fmi2SetFMUstate::<Spring>(c, state), fmi2OK);
        assert_eq!(get_real(c, X), x_half);
        let mut time = 0.0;
        assert_eq!(api::fmi2GetRealStatus::<Spring>(c, fmi2LastSuccessfulTime, &mut time), fmi2OK);
        assert!((time - 0.5).abs() < 1e-12);
        run_cs(c, 0.5, 1.0, 0.1);
        assert_eq!(get_real(c, X), x_end);

        // Reusing the handle overwrites it in place.
        let old = state;
        assert_eq!(api::fmi2GetFMUstate::<Spring>(c, &mut state), fmi2OK);
        assert_eq!(state, old);

        // Recovery from the Error state by restoring.
        assert_eq!(set_bool(c, FAIL, true), fmi2OK);
        let t = 0.1 * 10.0;
        assert_eq!(api::fmi2DoStep::<Spring>(c, t, 0.1, 0), fmi2Error);
        assert_eq!(api::fmi2SetFMUstate::<Spring>(c, state), fmi2OK);
        assert_eq!(api::fmi2DoStep::<Spring>(c, t, 0.1, 0), fmi2OK);

        assert_eq!(api::fmi2FreeFMUstate::<Spring>(c, &mut state), fmi2OK);
        assert!(state.is_null());
        assert_eq!(api::fmi2FreeFMUstate::<Spring>(c, &mut state), fmi2OK);
        assert_eq!(api::fmi2SetFMUstate::<Spring>(c, null_mut()), fmi2Error);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

#[test]
fn debug_logging_categories() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    assert_eq!(log.count("logAll"), 0);
    unsafe {
        let cats = [c"logAll".as_ptr()];
        assert_eq!(api::fmi2SetDebugLogging::<Spring>(c, fmi2True, 1, cats.as_ptr()), fmi2OK);
        run_cs(c, 0.0, 0.2, 0.1);
        assert_eq!(log.count("logAll"), 2);
        assert!(log.contains("fmi2DoStep: t = 0.1, h = 0.1"));
        // Discard of an unavailable status kind goes to logStatusWarning, still off.
        let mut i = 0;
        assert_eq!(api::fmi2GetIntegerStatus::<Spring>(c, fmi2DoStepStatus, &mut i), fmi2Discard);
        assert_eq!(log.count("logStatusWarning"), 0);
        assert_eq!(api::fmi2SetDebugLogging::<Spring>(c, fmi2True, 0, null()), fmi2OK);
        assert_eq!(api::fmi2GetIntegerStatus::<Spring>(c, fmi2DoStepStatus, &mut i), fmi2Discard);
        assert_eq!(log.count("logStatusWarning"), 1);
        assert_eq!(api::fmi2SetDebugLogging::<Spring>(c, fmi2False, 0, null()), fmi2OK);
        log.clear();
        run_cs(c, 0.2, 0.3, 0.1);
        assert_eq!(log.count("logAll"), 0);

        let bad = [c"logEvents".as_ptr()];
        assert_eq!(api::fmi2SetDebugLogging::<Spring>(c, fmi2True, 1, bad.as_ptr()), fmi2Error);
        assert_eq!(log.last(), "fmi2SetDebugLogging: unknown log category \"logEvents\"");
        assert_eq!(api::fmi2SetDebugLogging::<Spring>(c, fmi2True, 1, null()), fmi2Error);
        api::fmi2FreeInstance::<Spring>(c);
    }
    // loggingOn at instantiation enables tracing from the start.
    let log = Log::default();
    let c = instantiate_with(&log, fmi2CoSimulation, GUID, None, true);
    assert!(log.contains("fmi2Instantiate"));
    unsafe { api::fmi2FreeInstance::<Spring>(c) };
}

#[test]
fn strings() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    unsafe {
        let v = [c"mass #2".as_ptr()];
        assert_eq!(api::fmi2SetString::<Spring>(c, &LABEL, 1, v.as_ptr()), fmi2OK);
        let nul = [null()];
        assert_eq!(api::fmi2SetString::<Spring>(c, &LABEL, 1, nul.as_ptr()), fmi2Error);
        assert_eq!(api::fmi2SetString::<Spring>(c, &RESOURCES, 1, v.as_ptr()), fmi2Error);
        initialize(c, 0.0);
        let vrs = [LABEL, RESOURCES];
        let mut out = [null(); 2];
        assert_eq!(api::fmi2GetString::<Spring>(c, vrs.as_ptr(), 2, out.as_mut_ptr()), fmi2OK);
        assert_eq!(CStr::from_ptr(out[0]).to_str().unwrap(), "mass #2");
        assert_eq!(CStr::from_ptr(out[1]).to_str().unwrap(), "/tmp/spring/resources");
        assert_eq!(api::fmi2SetString::<Spring>(c, &LABEL, 1, v.as_ptr()), fmi2Error);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

#[test]
fn many_instances_are_independent() {
    let (log_a, log_b) = (Log::default(), Log::default());
    let a = instantiate(&log_a, fmi2CoSimulation);
    let b = instantiate(&log_b, fmi2CoSimulation);
    assert_eq!(set_real(b, K, 4.0), fmi2OK);
    initialize(a, 0.0);
    initialize(b, 0.0);
    for i in 0..10 {
        let t = i as f64 * 0.1;
        assert_eq!(unsafe { api::fmi2DoStep::<Spring>(a, t, 0.1, 0) }, fmi2OK);
        assert_eq!(unsafe { api::fmi2DoStep::<Spring>(b, t, 0.1, 0) }, fmi2OK);
    }
    assert!((get_real(a, X) - 1.0f64.cos()).abs() < 1e-9);
    assert!((get_real(b, X) - 2.0f64.cos()).abs() < 1e-9);
    assert_eq!(unsafe { api::fmi2DoStep::<Spring>(a, 0.0, 0.1, 0) }, fmi2Error);
    assert!(log_a.contains("currentCommunicationPoint"));
    assert!(log_b.entries().is_empty());
    unsafe {
        api::fmi2FreeInstance::<Spring>(a);
        api::fmi2FreeInstance::<Spring>(b);
        api::fmi2FreeInstance::<Spring>(null_mut());
    }
}

// ---------------------------------------------------------------------------
// Serialized FMU states
// ---------------------------------------------------------------------------

fn get_state(c: fmi2Component) -> fmi2FMUstate {
    let mut state: fmi2FMUstate = null_mut();
    assert_eq!(unsafe { api::fmi2GetFMUstate::<Spring>(c, &mut state) }, fmi2OK);
    state
}

fn free_state(c: fmi2Component, mut state: fmi2FMUstate) {
    assert_eq!(unsafe { api::fmi2FreeFMUstate::<Spring>(c, &mut state) }, fmi2OK);
}

fn serialize(c: fmi2Component, state: fmi2FMUstate) -> Vec<u8> {
    let mut size = 0;
    assert_eq!(unsafe { api::fmi2SerializedFMUstateSize::<Spring>(c, state, &mut size) }, fmi2OK);
    let mut buf = vec![0 as fmi2Byte; size];
    assert_eq!(unsafe { api::fmi2SerializeFMUstate::<Spring>(c, state, buf.as_mut_ptr(), size) }, fmi2OK);
    buf.into_iter().map(|b| b as u8).collect()
}

/// fmi2DeSerializeFMUstate into a new FMU state.
fn deserialize(c: fmi2Component, bytes: &[u8]) -> Result<fmi2FMUstate, fmi2Status> {
    let mut state: fmi2FMUstate = null_mut();
    let status = unsafe { api::fmi2DeSerializeFMUstate::<Spring>(c, bytes.as_ptr().cast(), bytes.len(), &mut state) };
    if status == fmi2OK {
        assert!(!state.is_null());
        Ok(state)
    } else {
        // nothing half-built is handed out
        assert!(state.is_null());
        Err(status)
    }
}

/// Recompute the CRC after editing bytes, to reach the checks behind it.
fn reseal(bytes: &mut [u8]) {
    let end = bytes.len() - 4;
    let crc = crc32fast::hash(&bytes[..end]);
    bytes[end..].copy_from_slice(&crc.to_le_bytes());
}

fn model_state_of(c: fmi2Component) -> crate::state::ModelState {
    unsafe { (*c.cast::<crate::instance::Instance<Spring>>()).state }
}

/// Steps `n` times by `h` from `t`, changing the input on the way; every x and v bit pattern.
fn trajectory(c: fmi2Component, t: f64, h: f64, n: usize) -> Vec<u64> {
    let mut out = Vec::new();
    for i in 0..n {
        assert_eq!(set_real(c, U, (i as f64 * 0.37).sin()), fmi2OK);
        assert_eq!(unsafe { api::fmi2DoStep::<Spring>(c, t + i as f64 * h, h, fmi2False) }, fmi2OK);
        out.push(get_real(c, X).to_bits());
        out.push(get_real(c, V_).to_bits());
    }
    out
}

#[test]
fn serialized_state_continues_bit_identically_in_a_fresh_instance() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    assert_eq!(set_real(c, K, 3.7), fmi2OK);
    let label = [c"serialized #1".as_ptr()];
    assert_eq!(unsafe { api::fmi2SetString::<Spring>(c, &LABEL, 1, label.as_ptr()) }, fmi2OK);
    initialize(c, 0.25);
    assert_eq!(set_real(c, D, 0.3), fmi2OK);
    trajectory(c, 0.25, 0.1, 7);
    let mut t = 0.0;
    assert_eq!(unsafe { api::fmi2GetRealStatus::<Spring>(c, fmi2LastSuccessfulTime, &mut t) }, fmi2OK);
    let state = get_state(c);
    let bytes = serialize(c, state);
    assert_eq!(&bytes[..8], b"FLEXSTAT");
    let expected = trajectory(c, t, 0.1, 20);

    // A fresh instance, not even initialised: deserialize, then set.
    let fresh_log = Log::default();
    let f = instantiate(&fresh_log, fmi2CoSimulation);
    let restored = deserialize(f, &bytes).unwrap_or_else(|_| panic!("{}", fresh_log.last()));
    assert_eq!(model_state_of(f), crate::state::ModelState::Instantiated, "deserialize alone applies nothing");
    assert_eq!(unsafe { api::fmi2SetFMUstate::<Spring>(f, restored) }, fmi2OK);
    assert_eq!(model_state_of(f), crate::state::ModelState::StepComplete);
    let mut time = 0.0;
    assert_eq!(unsafe { api::fmi2GetRealStatus::<Spring>(f, fmi2LastSuccessfulTime, &mut time) }, fmi2OK);
    assert_eq!(time.to_bits(), t.to_bits());
    assert_eq!(get_string(f, LABEL), "serialized #1");
    assert_eq!(get_string(f, RESOURCES), "/tmp/spring/resources", "instantiate's, not the state's");
    assert_eq!(trajectory(f, t, 0.1, 20), expected);
    let mut n = 0;
    assert_eq!(unsafe { api::fmi2GetInteger::<Spring>(f, &STEPS, 1, &mut n) }, fmi2OK);
    assert_eq!(n, 27);
    // Serializing the restored state gives the same bytes.
    assert_eq!(serialize(f, restored), bytes);

    // Deserializing into a state handed back overwrites it in place.
    let mut reused = get_state(f);
    let old = reused;
    let status = unsafe { api::fmi2DeSerializeFMUstate::<Spring>(f, bytes.as_ptr().cast(), bytes.len(), &mut reused) };
    assert_eq!(status, fmi2OK);
    assert_eq!(reused, old);
    assert_eq!(unsafe { api::fmi2SetFMUstate::<Spring>(f, reused) }, fmi2OK);
    assert_eq!(trajectory(f, t, 0.1, 20), expected);

    free_state(f, restored);
    free_state(f, reused);
    free_state(c, state);
    unsafe {
        api::fmi2FreeInstance::<Spring>(c);
        api::fmi2FreeInstance::<Spring>(f);
    }
}

#[test]
fn serialized_state_restores_model_exchange_states_and_derivatives() {
    let log = Log::default();
    let c = instantiate(&log, fmi2ModelExchange);
    assert_eq!(set_real(c, K, 2.5), fmi2OK);
    initialize(c, 0.0);
    unsafe {
        assert_eq!(api::fmi2EnterContinuousTimeMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2SetTime::<Spring>(c, 0.3), fmi2OK);
        let x = [0.123456789, -0.987654321];
        assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, x.as_ptr(), 2), fmi2OK);
    }
    assert_eq!(set_real(c, U, 0.7), fmi2OK);
    let state = get_state(c);
    let bytes = serialize(c, state);
    let derivatives = |c: fmi2Component| {
        let (mut x, mut dx) = ([0.0; 2], [0.0; 2]);
        unsafe {
            assert_eq!(api::fmi2GetContinuousStates::<Spring>(c, x.as_mut_ptr(), 2), fmi2OK);
            assert_eq!(api::fmi2GetDerivatives::<Spring>(c, dx.as_mut_ptr(), 2), fmi2OK);
        }
        [x, dx].concat().iter().map(|v| v.to_bits()).collect::<Vec<_>>()
    };
    let expected = derivatives(c);

    let f = instantiate(&log, fmi2ModelExchange);
    let restored = deserialize(f, &bytes).unwrap();
    assert_eq!(unsafe { api::fmi2SetFMUstate::<Spring>(f, restored) }, fmi2OK);
    assert_eq!(model_state_of(f), crate::state::ModelState::ContinuousTimeMode);
    assert_eq!(derivatives(f), expected);
    free_state(f, restored);
    free_state(c, state);
    unsafe {
        api::fmi2FreeInstance::<Spring>(c);
        api::fmi2FreeInstance::<Spring>(f);
    }
}

#[test]
fn bad_serialized_states_are_refused_with_a_reason() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    run_cs(c, 0.0, 0.3, 0.1);
    let state = get_state(c);
    let bytes = serialize(c, state);
    let refused = |bytes: &[u8], reason: &str| {
        assert_eq!(deserialize(c, bytes), Err(fmi2Error), "accepted; expected: {reason}");
        assert!(log.last().starts_with("fmi2DeSerializeFMUstate: "), "{}", log.last());
        assert!(log.last().contains(reason), "{} (expected {reason})", log.last());
    };

    // Every truncation, and a byte too many.
    for cut in 0..bytes.len() {
        refused(&bytes[..cut], "truncated");
    }
    refused(&[bytes.as_slice(), &[0]].concat(), "header says");
    // Any flipped bit is caught: in the header by its own check, behind it by the CRC.
    for i in 0..bytes.len() {
        for bit in [0x01, 0x80] {
            let mut b = bytes.clone();
            b[i] ^= bit;
            assert_eq!(deserialize(c, &b), Err(fmi2Error), "flip at {i}");
            if i >= 20 {
                assert!(log.last().contains("CRC-32"), "flip at {i}: {}", log.last());
            }
        }
    }
    refused(b"PK\x03\x04 certainly not an FMU state", "not a serialized FMU state of this runtime");

    let edited = |offset: usize, value: &[u8]| {
        let mut b = bytes.clone();
        b[offset..offset + value.len()].copy_from_slice(value);
        reseal(&mut b);
        b
    };
    refused(&edited(8, &2u32.to_le_bytes()), "written by a newer runtime (format version 2");
    refused(&edited(8, &0u32.to_le_bytes()), "format version 0");
    refused(&edited(12, &u64::MAX.to_le_bytes()), "impossible payload length");
    refused(&edited(20, &[7]), "invalid interface code 7");
    refused(&edited(21, &[99]), "invalid model state code 99");
    refused(&edited(21, &[3]), "invalid model state code 3 for CoSimulation"); // ContinuousTimeMode
    refused(&edited(21, &[10]), "invalid model state code 10"); // Fatal
    refused(&edited(22, &[5]), "invalid fmi2DoStep status code 5");
    refused(&edited(23, &[2]), "stop time defined is 2, not a boolean");
    refused(&edited(53, b"9"), "belongs to the model with GUID {9c4e810f");
    refused(&edited(48, &1000u32.to_le_bytes()), "truncated: GUID needs 1000 bytes");
    let model_at = 60 + GUID.len();
    refused(&edited(model_at - 8, &9999u64.to_le_bytes()), "model section length = 9999");
    refused(&edited(model_at - 8, &1u64.to_le_bytes()), "unexpected bytes after the model section");
    refused(&edited(model_at, &2u32.to_le_bytes()), "model state: spring state version 2 is not 1");
    // crash flag (after version, 6 reals, steps) set to 2
    refused(&edited(model_at + 4 + 48 + 4, &[2]), "model state: crash is 2, not a boolean");

    // A Model Exchange state does not fit a Co-Simulation instance, nor the other way round.
    let me = instantiate(&log, fmi2ModelExchange);
    let me_state = get_state(me);
    let me_bytes = serialize(me, me_state);
    refused(&me_bytes, "is of a ModelExchange instance; this instance was instantiated for CoSimulation");
    assert_eq!(unsafe { api::fmi2SetFMUstate::<Spring>(c, me_state) }, fmi2Error);
    assert!(log.last().contains("ModelExchange instance"), "{}", log.last());

    // Argument checks of the three functions.
    unsafe {
        let mut size = 0;
        assert_eq!(api::fmi2SerializedFMUstateSize::<Spring>(c, null_mut(), &mut size), fmi2Error);
        assert_eq!(log.last(), "fmi2SerializedFMUstateSize: argument FMUstate must not be NULL");
        assert_eq!(api::fmi2SerializedFMUstateSize::<Spring>(c, state, null_mut()), fmi2Error);
        let mut buf = vec![0 as fmi2Byte; bytes.len() + 1];
        assert_eq!(api::fmi2SerializeFMUstate::<Spring>(c, state, buf.as_mut_ptr(), bytes.len() + 1), fmi2Error);
        assert!(
            log.last().contains(&format!(
                "size = {} but the serialized FMU state has {} bytes",
                bytes.len() + 1,
                bytes.len()
            )),
            "{}",
            log.last()
        );
        assert!(buf.iter().all(|&b| b == 0), "nothing written on a refused call");
        assert_eq!(api::fmi2SerializeFMUstate::<Spring>(c, state, buf.as_mut_ptr(), bytes.len() - 1), fmi2Error);
        assert_eq!(api::fmi2SerializeFMUstate::<Spring>(c, state, null_mut(), bytes.len()), fmi2Error);
        assert_eq!(log.last(), "fmi2SerializeFMUstate: argument serializedState[] must not be NULL");
        assert_eq!(api::fmi2SerializeFMUstate::<Spring>(c, null_mut(), buf.as_mut_ptr(), bytes.len()), fmi2Error);
        assert_eq!(api::fmi2DeSerializeFMUstate::<Spring>(c, null(), bytes.len(), &mut null_mut()), fmi2Error);
        assert_eq!(
            api::fmi2DeSerializeFMUstate::<Spring>(c, bytes.as_ptr().cast(), bytes.len(), null_mut()),
            fmi2Error
        );
        assert_eq!(log.last(), "fmi2DeSerializeFMUstate: argument FMUstate must not be NULL");

        // A refused state leaves the handle handed in as it was.
        let mut reused = get_state(c);
        let before = serialize(c, reused);
        assert_eq!(
            api::fmi2DeSerializeFMUstate::<Spring>(c, me_bytes.as_ptr().cast(), me_bytes.len(), &mut reused),
            fmi2Error
        );
        assert_eq!(serialize(c, reused), before);
        free_state(c, reused);
    }

    // Refused bytes are a usage error: the instance stays where it was and carries on.
    assert_eq!(model_state_of(c), crate::state::ModelState::StepComplete);
    let t = run_cs(c, 0.3, 0.6, 0.1);
    assert!((t - 0.6).abs() < 1e-12);
    free_state(c, state);
    free_state(me, me_state);
    unsafe {
        api::fmi2FreeInstance::<Spring>(c);
        api::fmi2FreeInstance::<Spring>(me);
    }
}

/// After a model failure (Error state) a serialized state brings the instance back.
#[test]
fn serialized_state_recovers_from_the_error_state() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    run_cs(c, 0.0, 0.2, 0.1);
    let state = get_state(c);
    let bytes = serialize(c, state);
    free_state(c, state);
    assert_eq!(set_bool(c, FAIL, true), fmi2OK);
    assert_eq!(unsafe { api::fmi2DoStep::<Spring>(c, 0.2, 0.1, 0) }, fmi2Error);
    assert_eq!(model_state_of(c), crate::state::ModelState::Error);
    // In Error, only the FMU state functions (and getters, reset, free) are allowed.
    let restored = deserialize(c, &bytes).unwrap();
    assert_eq!(unsafe { api::fmi2SetFMUstate::<Spring>(c, restored) }, fmi2OK);
    assert_eq!(model_state_of(c), crate::state::ModelState::StepComplete);
    let mut b = fmi2True;
    assert_eq!(unsafe { api::fmi2GetBoolean::<Spring>(c, &FAIL, 1, &mut b) }, fmi2OK);
    assert_eq!(b, fmi2False);
    run_cs(c, 0.2, 0.5, 0.1);
    free_state(c, restored);
    unsafe { api::fmi2FreeInstance::<Spring>(c) };
}

// ---------------------------------------------------------------------------
// Directional derivatives and output derivatives
// ---------------------------------------------------------------------------

/// fmi2GetDirectionalDerivative into a result prefilled with NaN, to see what was written.
fn directional(c: fmi2Component, unknowns: &[u32], knowns: &[u32], seed: &[f64]) -> (fmi2Status, Vec<f64>) {
    assert_eq!(knowns.len(), seed.len());
    let mut out = vec![f64::NAN; unknowns.len()];
    let status = unsafe {
        api::fmi2GetDirectionalDerivative::<Spring>(
            c,
            unknowns.as_ptr(),
            unknowns.len(),
            knowns.as_ptr(),
            knowns.len(),
            seed.as_ptr(),
            out.as_mut_ptr(),
        )
    };
    (status, out)
}

fn output_derivatives(c: fmi2Component, vrs: &[u32], orders: &[i32]) -> (fmi2Status, Vec<f64>) {
    assert_eq!(vrs.len(), orders.len());
    let mut out = vec![f64::NAN; vrs.len()];
    let status = unsafe {
        api::fmi2GetRealOutputDerivatives::<Spring>(c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), out.as_mut_ptr())
    };
    (status, out)
}

/// A refusal: fmi2Error, one logStatusError message from `function` giving `reason`,
/// the instance still in the state it was in.
fn assert_refused(c: fmi2Component, log: &Log, status: fmi2Status, function: &str, reason: &str) {
    let state = model_state_of(c);
    assert_eq!(status, fmi2Error, "accepted; expected: {reason}");
    let last = log.entries().last().cloned().expect("no message logged");
    assert_eq!((last.status, last.category.as_str()), (fmi2Error, "logStatusError"));
    assert!(last.text.starts_with(function), "{} (expected from {function})", last.text);
    assert!(last.text.contains(reason), "{} (expected {reason})", last.text);
    assert_eq!(model_state_of(c), state);
}

/// The Jacobian of the linear spring, d(der(x), der(v), x, acc) / d(x, v, u), column by column
/// and for a mixed seed, in Event Mode, Continuous-Time Mode and after fmi2Terminate.
#[test]
fn directional_derivatives_model_exchange() {
    let log = Log::default();
    let c = instantiate(&log, fmi2ModelExchange);
    assert_eq!(set_real(c, K, 4.0), fmi2OK);
    initialize(c, 0.0);
    assert_eq!(set_real(c, D, 0.3), fmi2OK);
    assert_eq!(set_real(c, U, 0.7), fmi2OK);
    let (k, d) = (4.0, 0.3);
    let unknowns = [V_, A, X, ACC];
    let knowns = [X, V_, U];
    let jacobian = [[0.0, 1.0, 0.0], [-k, -d, 1.0], [1.0, 0.0, 0.0], [-k, -d, 1.0]];
    let check = |c: fmi2Component| {
        for j in 0..3 {
            let mut seed = [0.0; 3];
            seed[j] = 1.0;
            let (status, column) = directional(c, &unknowns, &knowns, &seed);
            assert_eq!(status, fmi2OK, "{}", log.last());
            assert_eq!(column, jacobian.map(|row| row[j]), "column {j}");
        }
        let seed = [0.5, -2.0, 3.0];
        let (status, dv) = directional(c, &unknowns, &knowns, &seed);
        assert_eq!(status, fmi2OK);
        let expected = jacobian.map(|row| row.iter().zip(seed).map(|(j, s)| j * s).sum::<f64>());
        assert_eq!(dv, expected);
    };
    check(c);
    unsafe {
        assert_eq!(api::fmi2EnterContinuousTimeMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2SetTime::<Spring>(c, 0.1), fmi2OK);
        let x = [0.2, -0.4];
        assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, x.as_ptr(), 2), fmi2OK);
    }
    check(c);

    // Any subset, in any order, repeats included.
    let (status, dv) = directional(c, &[ACC, ACC, X], &[U, X, U], &[1.0, 2.0, 0.5]);
    assert_eq!(status, fmi2OK);
    assert_eq!(dv, [1.5 - 2.0 * k, 1.5 - 2.0 * k, 2.0]);
    // No knowns: the zero vector.
    let (status, dv) = directional(c, &[A, X], &[], &[]);
    assert_eq!(status, fmi2OK);
    assert_eq!(dv, [0.0, 0.0]);
    unsafe {
        // No unknowns: nothing to compute, any pointer may be NULL.
        assert_eq!(api::fmi2GetDirectionalDerivative::<Spring>(c, null(), 0, null(), 3, null(), null_mut()), fmi2OK);
        // The seed in the result buffer, as a C host may pass it: read before written.
        let mut buf = [1.0, 10.0, 100.0];
        let (u, kn) = ([X, A, ACC], [X, V_, U]);
        assert_eq!(
            api::fmi2GetDirectionalDerivative::<Spring>(
                c,
                u.as_ptr(),
                3,
                kn.as_ptr(),
                3,
                buf.as_ptr(),
                buf.as_mut_ptr()
            ),
            fmi2OK
        );
        assert_eq!(buf, [1.0, -k - 10.0 * d + 100.0, -k - 10.0 * d + 100.0]);
        // Overlapping by one element.
        let mut buf = [1.0, 10.0, 100.0];
        let p = buf.as_mut_ptr();
        assert_eq!(api::fmi2GetDirectionalDerivative::<Spring>(c, u.as_ptr(), 2, kn.as_ptr(), 2, p.add(1), p), fmi2OK);
        assert_eq!(buf, [10.0, -10.0 * k - 100.0 * d, 100.0]);

        assert_eq!(api::fmi2Terminate::<Spring>(c), fmi2OK);
    }
    check(c);
    unsafe { api::fmi2FreeInstance::<Spring>(c) };
}

/// In Co-Simulation only outputs with respect to inputs: acc feeds through, x does not.
#[test]
fn directional_derivatives_co_simulation() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    run_cs(c, 0.0, 0.3, 0.1);
    let (status, dv) = directional(c, &[X, ACC], &[U], &[2.5]);
    assert_eq!(status, fmi2OK, "{}", log.last());
    assert_eq!(dv, [0.0, 2.5]);
    // Tracing names the call.
    let cats = [c"logAll".as_ptr()];
    assert_eq!(unsafe { api::fmi2SetDebugLogging::<Spring>(c, fmi2True, 1, cats.as_ptr()) }, fmi2OK);
    assert_eq!(directional(c, &[ACC], &[U], &[1.0]).0, fmi2OK);
    assert_eq!(log.last(), "fmi2GetDirectionalDerivative: 1 unknowns, 1 knowns");
    assert_eq!(model_state_of(c), crate::state::ModelState::StepComplete);
    run_cs(c, 0.3, 0.5, 0.1);
    unsafe { api::fmi2FreeInstance::<Spring>(c) };
}

/// Initialization Mode answers the Jacobian at the start values and parameters set there, the
/// same as after fmi2ExitInitializationMode at the same values, in both interfaces.
#[test]
fn directional_derivatives_in_initialization_mode() {
    for kind in [fmi2ModelExchange, fmi2CoSimulation] {
        let log = Log::default();
        let c = instantiate(&log, kind);
        assert_eq!(set_real(c, K, 4.0), fmi2OK);
        assert_eq!(set_real(c, D, 0.3), fmi2OK);
        unsafe {
            assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
            assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2OK);
        }
        assert_eq!(set_real(c, U, 0.7), fmi2OK);
        let (unknowns, knowns, seed): (&[u32], &[u32], &[f64]) = if kind == fmi2ModelExchange {
            (&[V_, A, X, ACC], &[X, V_, U], &[0.5, -2.0, 3.0])
        } else {
            (&[X, ACC], &[U], &[2.5])
        };
        let (status, initializing) = directional(c, unknowns, knowns, seed);
        assert_eq!(status, fmi2OK, "{}", log.last());
        assert_eq!(model_state_of(c), crate::state::ModelState::InitializationMode);
        let expected: &[f64] = if kind == fmi2ModelExchange {
            &[-2.0, -4.0 * 0.5 + 0.3 * 2.0 + 3.0, 0.5, -4.0 * 0.5 + 0.3 * 2.0 + 3.0]
        } else {
            &[0.0, 2.5]
        };
        assert_eq!(initializing, expected);
        assert_eq!(unsafe { api::fmi2ExitInitializationMode::<Spring>(c) }, fmi2OK);
        let (status, after) = directional(c, unknowns, knowns, seed);
        assert_eq!((status, after), (fmi2OK, initializing));
        assert!(log.entries().iter().all(|e| e.status == fmi2OK), "{:?}", log.last());
        unsafe { api::fmi2FreeInstance::<Spring>(c) };
    }
}

#[test]
fn directional_derivative_refusals_leave_the_instance_usable() {
    const F: &str = "fmi2GetDirectionalDerivative: ";
    let log = Log::default();
    for kind in [fmi2CoSimulation, fmi2ModelExchange] {
        let c = instantiate(&log, kind);
        let refused = |(status, out): (fmi2Status, Vec<f64>), reason: &str| {
            assert_refused(c, &log, status, "fmi2GetDirectionalDerivative", reason);
            assert!(out.iter().all(|v| v.is_nan()), "written on a refused call: {out:?}");
        };
        let works = || {
            let (status, dv) = directional(c, &[ACC], &[U], &[1.0]);
            assert_eq!((status, dv), (fmi2OK, vec![1.0]), "{}", log.last());
        };

        // Not before initialization has begun (the getters' states), then from Initialization
        // Mode on, as the standard's tables allow.
        let before = "called in state Instantiated; allowed in: InitializationMode, EventMode, ContinuousTimeMode, StepComplete, StepFailed, StepCanceled, Terminated, Error";
        refused(directional(c, &[ACC], &[U], &[1.0]), before);
        assert_eq!(set_real(c, K, 2.0), fmi2OK);
        unsafe {
            assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
            assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2OK);
        }
        works();
        assert_eq!(unsafe { api::fmi2ExitInitializationMode::<Spring>(c) }, fmi2OK);
        works();

        // Unknowns: Real outputs, and in Model Exchange state derivatives.
        refused(
            directional(c, &[U], &[U], &[1.0]),
            &format!("{F}unknown value reference 3 (u) has causality Input; expected an output"),
        );
        refused(directional(c, &[ACC, K], &[U], &[1.0]), "unknown value reference 2 (k) has causality Parameter");
        refused(directional(c, &[ACC, 99], &[U], &[1.0]), &format!("{F}unknown value reference 99"));
        refused(
            directional(c, &[STEPS], &[U], &[1.0]),
            &format!("{F}value reference 6 (steps) is a Integer variable, not Real"),
        );
        // Knowns: Real inputs, and in Model Exchange continuous states.
        refused(
            directional(c, &[ACC], &[ACC], &[1.0]),
            "known value reference 11 (acc) has causality Output; expected an input",
        );
        refused(directional(c, &[ACC], &[D], &[1.0]), "known value reference 5 (d) has causality Parameter");
        refused(directional(c, &[ACC], &[U, 99], &[1.0, 1.0]), &format!("{F}unknown value reference 99"));
        refused(directional(c, &[ACC], &[CRASH], &[1.0]), "value reference 7 (crash) is a Boolean variable, not Real");
        if kind == fmi2CoSimulation {
            refused(
                directional(c, &[A], &[U], &[1.0]),
                "unknown value reference 4 (a) has causality Local; expected an output (state derivatives are unknowns in Model Exchange only)",
            );
            refused(
                directional(c, &[ACC], &[V_], &[1.0]),
                "known value reference 1 (v) has causality Local; expected an input (continuous states are knowns in Model Exchange only)",
            );
            refused(
                directional(c, &[ACC], &[X], &[1.0]),
                "known value reference 0 (x) has causality Output; expected an input (continuous states are knowns in Model Exchange only)",
            );
        } else {
            refused(directional(c, &[U], &[U], &[1.0]), "expected an output or the derivative of a continuous state");
            refused(
                directional(c, &[ACC], &[ACC], &[1.0]),
                "known value reference 11 (acc) has causality Output; expected an input or a continuous state",
            );
            let (status, dv) = directional(c, &[A], &[V_], &[1.0]);
            assert_eq!((status, dv), (fmi2OK, vec![0.0]), "{}", log.last());
        }
        // Seeds must be numbers.
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            refused(
                directional(c, &[ACC], &[U, U], &[1.0, bad]),
                &format!("{F}dvKnown[1] = {bad} for known value reference 3 (u) is not finite"),
            );
        }
        // NULL arrays with a count.
        unsafe {
            let (u, k, seed, mut out) = ([ACC], [U], [1.0], [f64::NAN]);
            let call = |u: *const u32, k: *const u32, seed: *const f64, out: *mut f64| {
                api::fmi2GetDirectionalDerivative::<Spring>(c, u, 1, k, 1, seed, out)
            };
            let status = call(null(), k.as_ptr(), seed.as_ptr(), out.as_mut_ptr());
            refused((status, out.to_vec()), &format!("{F}argument vUnknown_ref[] must not be NULL"));
            let status = call(u.as_ptr(), null(), seed.as_ptr(), out.as_mut_ptr());
            refused((status, out.to_vec()), &format!("{F}argument vKnown_ref[] must not be NULL"));
            let status = call(u.as_ptr(), k.as_ptr(), null(), out.as_mut_ptr());
            refused((status, out.to_vec()), &format!("{F}argument dvKnown[] must not be NULL"));
            let status = call(u.as_ptr(), k.as_ptr(), seed.as_ptr(), null_mut());
            assert_refused(c, &log, status, F, "argument dvUnknown[] must not be NULL");
        }
        works();
        unsafe { api::fmi2FreeInstance::<Spring>(c) };
    }
}

#[test]
fn output_derivatives_co_simulation() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    assert_eq!(set_real(c, K, 4.0), fmi2OK);
    initialize(c, 0.0);
    assert_eq!(set_real(c, D, 0.3), fmi2OK);
    assert_eq!(set_real(c, U, 0.7), fmi2OK);
    run_cs(c, 0.0, 0.5, 0.1);
    let (x, v, a) = (get_real(c, X), get_real(c, V_), get_real(c, ACC));
    let (status, dv) = output_derivatives(c, &[X, ACC, X], &[1, 1, 1]);
    assert_eq!(status, fmi2OK, "{}", log.last());
    assert_eq!(dv, [v, -4.0 * v - 0.3 * a, v]);
    assert!(v != 0.0 && x != 1.0, "the spring has moved");
    assert_eq!(unsafe { api::fmi2GetRealOutputDerivatives::<Spring>(c, null(), 0, null(), null_mut()) }, fmi2OK);

    // Refusals: logged, nothing written, the instance carries on.
    const F: &str = "fmi2GetRealOutputDerivatives: ";
    let refused = |(status, out): (fmi2Status, Vec<f64>), reason: &str| {
        assert_refused(c, &log, status, "fmi2GetRealOutputDerivatives", reason);
        assert!(out.iter().all(|v| v.is_nan()), "written on a refused call: {out:?}");
    };
    for order in [0, 2, -1] {
        refused(
            output_derivatives(c, &[X, ACC], &[1, order]),
            &format!(
                "{F}value reference 11 (acc): derivative order {order} requested; this FMU provides orders 1 to 1 (maxOutputDerivativeOrder 1)"
            ),
        );
    }
    refused(
        output_derivatives(c, &[U], &[1]),
        &format!("{F}value reference 3 (u) has causality Input; output derivatives are for outputs only"),
    );
    refused(output_derivatives(c, &[X, V_], &[1, 1]), "value reference 1 (v) has causality Local");
    refused(
        output_derivatives(c, &[STEPS], &[1]),
        &format!("{F}value reference 6 (steps) is a Integer variable, not Real"),
    );
    refused(output_derivatives(c, &[99], &[1]), &format!("{F}unknown value reference 99"));
    unsafe {
        let (vr, order, mut out) = ([X], [1], [f64::NAN]);
        let status = api::fmi2GetRealOutputDerivatives::<Spring>(c, null(), 1, order.as_ptr(), out.as_mut_ptr());
        refused((status, out.to_vec()), &format!("{F}argument vr[] must not be NULL"));
        let status = api::fmi2GetRealOutputDerivatives::<Spring>(c, vr.as_ptr(), 1, null(), out.as_mut_ptr());
        refused((status, out.to_vec()), &format!("{F}argument order[] must not be NULL"));
        let status = api::fmi2GetRealOutputDerivatives::<Spring>(c, vr.as_ptr(), 1, order.as_ptr(), null_mut());
        assert_refused(c, &log, status, F, "argument value[] must not be NULL");
    }
    let t = run_cs(c, 0.5, 0.6, 0.1);
    assert_eq!(output_derivatives(c, &[X], &[1]), (fmi2OK, vec![get_real(c, V_)]));
    // Still at the last communication point after fmi2Terminate.
    assert_eq!(unsafe { api::fmi2Terminate::<Spring>(c) }, fmi2OK);
    assert_eq!(output_derivatives(c, &[X], &[1]), (fmi2OK, vec![get_real(c, V_)]));
    assert!((t - 0.6).abs() < 1e-12);
    unsafe { api::fmi2FreeInstance::<Spring>(c) };

    // Only between steps, and only in Co-Simulation.
    let c = instantiate(&log, fmi2CoSimulation);
    assert_refused(
        c,
        &log,
        output_derivatives(c, &[X], &[1]).0,
        "fmi2GetRealOutputDerivatives called in state Instantiated",
        "allowed in: StepComplete, StepFailed, StepCanceled, Terminated, Error",
    );
    unsafe {
        assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2OK);
        assert_refused(
            c,
            &log,
            output_derivatives(c, &[X], &[1]).0,
            "fmi2GetRealOutputDerivatives called in state InitializationMode",
            "allowed in: StepComplete",
        );
        api::fmi2FreeInstance::<Spring>(c);
    }
    let c = instantiate(&log, fmi2ModelExchange);
    initialize(c, 0.0);
    assert_refused(
        c,
        &log,
        output_derivatives(c, &[X], &[1]).0,
        "fmi2GetRealOutputDerivatives is a CoSimulation function",
        "instantiated for ModelExchange",
    );
    unsafe { api::fmi2FreeInstance::<Spring>(c) };
}

/// A model without the capabilities: both functions say which flag is false, and nothing else changes.
#[test]
fn derivatives_need_the_capability() {
    let log = Log::default();
    for kind in [fmi2CoSimulation, fmi2ModelExchange] {
        let c = instantiate_with(&log, kind, GUID, Some("file:///tmp/no-derivatives/resources"), false);
        assert!(!c.is_null(), "{}", log.last());
        initialize(c, 0.0);
        let (status, out) = directional(c, &[ACC], &[U], &[1.0]);
        assert_refused(
            c,
            &log,
            status,
            "fmi2GetDirectionalDerivative",
            "fmi2GetDirectionalDerivative: not supported by this FMU (capability flag providesDirectionalDerivative=false)",
        );
        assert!(out[0].is_nan());
        if kind == fmi2CoSimulation {
            let (status, out) = output_derivatives(c, &[X], &[1]);
            assert_refused(
                c,
                &log,
                status,
                "fmi2GetRealOutputDerivatives",
                "fmi2GetRealOutputDerivatives: not supported by this FMU (capability flag maxOutputDerivativeOrder>0=false)",
            );
            assert!(out[0].is_nan());
            run_cs(c, 0.0, 0.2, 0.1);
        }
        assert!((get_real(c, ACC) + get_real(c, X)).abs() < 1e-15, "a = -x with k = 1, d = u = 0");
        unsafe { api::fmi2FreeInstance::<Spring>(c) };
    }
}

/// The model's Err is a model failure, not a refusal: the instance enters Error, where
/// both functions still answer for diagnostics, until it is reset.
#[test]
fn derivative_failures_of_the_model_enter_the_error_state() {
    use crate::state::ModelState;
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    run_cs(c, 0.0, 0.2, 0.1);
    assert_eq!(set_bool(c, FAIL, true), fmi2OK);
    assert_eq!(directional(c, &[ACC], &[U], &[1.0]).0, fmi2Error);
    assert_eq!(log.last(), "fmi2GetDirectionalDerivative: Jacobian failed");
    assert_eq!(model_state_of(c), ModelState::Error);
    // Allowed in Error (diagnostics); the model still fails.
    assert_eq!(output_derivatives(c, &[ACC], &[1]).0, fmi2Error);
    assert_eq!(log.last(), "fmi2GetRealOutputDerivatives: value reference 11 (acc): no derivative after a failure");
    unsafe {
        assert_eq!(api::fmi2Reset::<Spring>(c), fmi2OK);
        initialize(c, 0.0);
    }
    assert_eq!(directional(c, &[ACC], &[U], &[1.0]), (fmi2OK, vec![1.0]));
    assert_eq!(output_derivatives(c, &[X], &[1]), (fmi2OK, vec![0.0]));

    // A panic in the model is contained the same way.
    assert_eq!(set_bool(c, CRASH, true), fmi2OK);
    assert_eq!(output_derivatives(c, &[ACC], &[1]).0, fmi2Error);
    assert!(
        log.last().starts_with("fmi2GetRealOutputDerivatives: panic in the model: crash requested"),
        "{}",
        log.last()
    );
    assert_eq!(model_state_of(c), ModelState::Error);
    unsafe { api::fmi2FreeInstance::<Spring>(c) };
}

/// The minimal reproducers: a non-finite value set by the host is refused with the
/// variable named and the instance left usable; a non-finite value the equations produce never
/// leaves with fmi2OK.
#[test]
fn non_finite_inputs_are_refused_and_the_instance_stays_usable() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        assert_eq!(set_real(c, U, bad), fmi2Error);
        assert!(
            log.last().contains("value reference 3 (u)") && log.last().contains("not a finite number"),
            "{}",
            log.last()
        );
    }
    // finite but beyond the model's range: the model's reason, and nothing set
    assert_eq!(set_real(c, U, -1e308), fmi2Error);
    assert!(log.last().contains("(u)") && log.last().contains("beyond the input's range"), "{}", log.last());
    // one refused value refuses the whole call: nothing of it is set
    let (vrs, values) = ([K, U], [3.0, f64::NAN]);
    assert_eq!(unsafe { api::fmi2SetReal::<Spring>(c, vrs.as_ptr(), 2, values.as_ptr()) }, fmi2Error);
    assert_eq!(model_state_of(c), crate::state::ModelState::Instantiated);
    unsafe {
        assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2True, -1.0, 0.0, fmi2False, 0.0), fmi2Error);
        assert!(log.last().contains("tolerance"), "{}", log.last());
        assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2False, 0.0, 0.0, fmi2True, f64::NAN), fmi2Error);
        assert!(log.last().contains("stopTime"), "{}", log.last());
        assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2False, 0.0, 1e308, fmi2False, 0.0), fmi2OK);
        assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2ExitInitializationMode::<Spring>(c), fmi2OK);
        assert_eq!((get_real(c, U), get_real(c, K)), (0.0, 1.0), "nothing of the refused calls was set");
        // t + h overflows
        assert_eq!(api::fmi2DoStep::<Spring>(c, 1e308, 1e308, fmi2True), fmi2Error);
        assert!(log.last().contains("beyond any finite number"), "{}", log.last());
        assert_eq!(api::fmi2DoStep::<Spring>(c, 1e308, 1e-3, fmi2True), fmi2OK, "{}", log.last());
        api::fmi2FreeInstance::<Spring>(c);
    }
}

#[test]
fn non_finite_results_in_model_exchange_are_discarded_with_the_reason() {
    let log = Log::default();
    let c = instantiate(&log, fmi2ModelExchange);
    assert_eq!(set_real(c, D, 2.0), fmi2OK);
    initialize(c, 0.0);
    unsafe {
        assert_eq!(api::fmi2EnterContinuousTimeMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2SetTime::<Spring>(c, f64::NAN), fmi2Error);
        assert!(log.last().contains("fmi2SetTime: time = NaN is not a finite number"), "{}", log.last());
        let nan = [0.5, f64::NAN];
        assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, nan.as_ptr(), 2), fmi2Error);
        assert!(log.last().contains("x[1] = NaN is not a finite number"), "{}", log.last());
        let mut x = [0.0; 2];
        assert_eq!(api::fmi2GetContinuousStates::<Spring>(c, x.as_mut_ptr(), 2), fmi2OK);
        assert_eq!(x, [1.0, 0.0], "a refused call sets no state");

        // finite states whose derivative overflows: -d v = -2e308
        let huge = [0.0, 1e308];
        assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, huge.as_ptr(), 2), fmi2OK);
        let mut dx = [0.0; 2];
        let status = api::fmi2GetDerivatives::<Spring>(c, dx.as_mut_ptr(), 2);
        assert_eq!(status, fmi2Discard, "{dx:?}");
        assert!(log.last().contains("fmi2GetDerivatives: derivatives[1] evaluates to -inf"), "{}", log.last());
        let (vr, mut a) = (A, 0.0);
        assert_eq!(api::fmi2GetReal::<Spring>(c, &vr, 1, &mut a), fmi2Discard);
        assert!(log.last().contains("value reference 4 (a) evaluates to -inf"), "{}", log.last());
        assert_eq!(model_state_of(c), crate::state::ModelState::ContinuousTimeMode, "the host may retry");
        let fine = [0.0, 1.0];
        assert_eq!(api::fmi2SetContinuousStates::<Spring>(c, fine.as_ptr(), 2), fmi2OK);
        assert_eq!(api::fmi2GetDerivatives::<Spring>(c, dx.as_mut_ptr(), 2), fmi2OK);
        assert_eq!(dx, [1.0, -2.0]);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

/// A state of another FMU carrying this runtime has the same layout: the GUID must refuse it.
/// Memory that is no state at all is refused by its first word.
#[test]
fn fmu_states_of_another_model_or_no_state_at_all_are_refused() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    let other = instantiate_with(&log, fmi2CoSimulation, OTHER_GUID, Some("file:///tmp/other-model/resources"), false);
    assert!(!other.is_null(), "{}", log.last());
    initialize(c, 0.0);
    initialize(other, 0.0);
    let foreign = get_state(other);
    unsafe {
        assert_eq!(api::fmi2SetFMUstate::<Spring>(c, foreign), fmi2Error);
        assert!(
            log.last().contains("belongs to the model with GUID {8c4e810f-3df3-4a00-8276-176fa3c9f001}"),
            "{}",
            log.last()
        );
        assert_eq!(model_state_of(c), crate::state::ModelState::StepComplete);
        // the serialized form is refused as well
        let bytes = serialize(other, foreign);
        assert_eq!(deserialize(c, &bytes).err(), Some(fmi2Error));
        assert!(log.last().contains("GUID"), "{}", log.last());

        let not_a_state = vec![0u64; 64];
        let p = not_a_state.as_ptr() as fmi2FMUstate;
        assert_eq!(api::fmi2SetFMUstate::<Spring>(c, p), fmi2Error);
        assert!(log.last().contains("not an FMU state of this runtime"), "{}", log.last());
        let mut slot = p;
        assert_eq!(api::fmi2FreeFMUstate::<Spring>(c, &mut slot), fmi2Error);
        assert_eq!(api::fmi2GetFMUstate::<Spring>(c, &mut slot), fmi2Error, "a foreign handle is not overwritten");
        assert_eq!(not_a_state, vec![0u64; 64]);
        free_state(other, foreign);
        api::fmi2FreeInstance::<Spring>(other);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

/// A step the model does not take (ModelError::Discard) answers fmi2Discard with its reason:
/// the slave is in stepFailed with its time and state as before the step, can be read, and
/// restoring the FMU state saved before the step lets the master retry with a shorter step.
#[test]
fn a_step_not_taken_is_discarded_and_the_master_retries_from_a_saved_state() {
    let log = Log::default();
    let c = instantiate(&log, fmi2CoSimulation);
    initialize(c, 0.0);
    assert_eq!(set_real(c, U, 1.0), fmi2OK);
    let t = run_cs(c, 0.0, 0.2, 0.1);
    let x = get_real(c, X);
    unsafe {
        let mut saved: fmi2FMUstate = null_mut();
        assert_eq!(api::fmi2GetFMUstate::<Spring>(c, &mut saved), fmi2OK);
        assert_eq!(api::fmi2DoStep::<Spring>(c, t, 1e4, 0), fmi2Discard);
        assert!(log.last().starts_with("fmi2DoStep: step from t = "), "{}", log.last());
        assert!(log.last().contains("needs more than 1000 s"), "{}", log.last());
        assert_eq!(model_state_of(c), crate::state::ModelState::StepFailed);
        let mut status = fmi2OK;
        assert_eq!(api::fmi2GetStatus::<Spring>(c, fmi2DoStepStatus, &mut status), fmi2OK);
        assert_eq!(status, fmi2Discard);
        let mut last = f64::NAN;
        assert_eq!(api::fmi2GetRealStatus::<Spring>(c, fmi2LastSuccessfulTime, &mut last), fmi2OK);
        assert_eq!(last, t);
        assert_eq!(get_real(c, X), x);
        // stepFailed takes no step (the standard's table): the master restores and retries
        assert_eq!(api::fmi2DoStep::<Spring>(c, t, 500.0, 0), fmi2Error);
        assert_eq!(api::fmi2SetFMUstate::<Spring>(c, saved), fmi2OK);
        assert_eq!(api::fmi2DoStep::<Spring>(c, t, 500.0, 0), fmi2OK);
        assert_eq!(api::fmi2FreeFMUstate::<Spring>(c, &mut saved), fmi2OK);
        api::fmi2FreeInstance::<Spring>(c);
    }
}

/// Rates (input derivatives, directional seeds) beyond the model's range are refused as
/// fmi2SetReal refuses a value: fmi2Error naming the variable, nothing set, same state.
#[test]
fn seeds_beyond_the_models_range_are_refused_and_the_instance_stays_usable() {
    let log = Log::default();
    for kind in [fmi2CoSimulation, fmi2ModelExchange] {
        let c = instantiate(&log, kind);
        initialize(c, 0.0);
        let (status, out) = directional(c, &[ACC], &[U], &[1e300]);
        assert_refused(
            c,
            &log,
            status,
            "fmi2GetDirectionalDerivative",
            "dvKnown[0] = 1e300 for known value reference 3 (u): beyond the input's range of rates 1e100",
        );
        assert!(out[0].is_nan());
        assert_eq!(directional(c, &[ACC], &[U], &[1.0]), (fmi2OK, vec![1.0]));
        unsafe { api::fmi2FreeInstance::<Spring>(c) };
    }
}

// ---------------------------------------------------------------------------
// Warnings of calls that succeeded
// ---------------------------------------------------------------------------

/// Entries logged under logStatusWarning whose text contains `needle`.
fn warnings(log: &Log, needle: &str) -> usize {
    log.entries()
        .iter()
        .filter(|e| e.category == "logStatusWarning" && e.status == fmi2Warning && e.text.contains(needle))
        .count()
}

/// A call that did what it was asked answers fmi2OK, whatever it warns of: hosts (OMSimulator,
/// fmusim) drop the run on any other status. The warning reaches the logger (logStatusWarning)
/// with debug logging off, since the status no longer carries it.
#[test]
fn warnings_of_successful_calls_are_logged_with_fmi2ok() {
    let log = Log::default();
    // Model Exchange: a loose tolerance, then integrator steps the model warns about.
    let c = instantiate(&log, fmi2ModelExchange);
    unsafe {
        assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2True, 1e-2, 0.0, fmi2False, 0.0), fmi2OK);
        assert_eq!(warnings(&log, "fmi2SetupExperiment: tolerance 0.01 is looser than 0.001"), 1, "{}", log.last());
        assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2ExitInitializationMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2EnterContinuousTimeMode::<Spring>(c), fmi2OK);
        let (mut enter, mut terminate) = (fmi2True, fmi2True);
        assert_eq!(api::fmi2SetTime::<Spring>(c, 1.0), fmi2OK);
        assert_eq!(api::fmi2CompletedIntegratorStep::<Spring>(c, fmi2True, &mut enter, &mut terminate), fmi2OK);
        assert_eq!(warnings(&log, "fmi2CompletedIntegratorStep"), 0);
        assert_eq!(api::fmi2SetTime::<Spring>(c, WARN_AFTER), fmi2OK);
        assert_eq!(api::fmi2CompletedIntegratorStep::<Spring>(c, fmi2True, &mut enter, &mut terminate), fmi2OK);
        assert_eq!((enter, terminate), (fmi2False, fmi2False));
        assert_eq!(warnings(&log, "fmi2CompletedIntegratorStep: integrated past t = 50"), 1, "{}", log.last());
        assert_eq!(model_state_of(c), crate::state::ModelState::ContinuousTimeMode);
        api::fmi2FreeInstance::<Spring>(c);
    }
    // A tolerance the model accepts: nothing logged.
    log.clear();
    let c = instantiate(&log, fmi2CoSimulation);
    unsafe {
        assert_eq!(api::fmi2SetupExperiment::<Spring>(c, fmi2True, 1e-6, 0.0, fmi2False, 0.0), fmi2OK);
        assert!(log.is_empty(), "{}", log.last());
        assert_eq!(api::fmi2EnterInitializationMode::<Spring>(c), fmi2OK);
        assert_eq!(api::fmi2ExitInitializationMode::<Spring>(c), fmi2OK);
        // Co-Simulation: the step that ends past the warning time is taken and says so in the log.
        assert_eq!(api::fmi2DoStep::<Spring>(c, 0.0, 40.0, fmi2True), fmi2OK);
        assert!(log.is_empty(), "{}", log.last());
        assert_eq!(api::fmi2DoStep::<Spring>(c, 40.0, 20.0, fmi2True), fmi2OK);
        assert_eq!(warnings(&log, "fmi2DoStep: stepped past the warning time"), 1, "{}", log.last());
        assert_eq!(model_state_of(c), crate::state::ModelState::StepComplete);
        let mut status = fmi2Error;
        assert_eq!(api::fmi2GetStatus::<Spring>(c, fmi2DoStepStatus, &mut status), fmi2OK);
        assert_eq!(status, fmi2OK);
        let mut t = 0.0;
        assert_eq!(api::fmi2GetRealStatus::<Spring>(c, fmi2LastSuccessfulTime, &mut t), fmi2OK);
        assert_eq!(t, 60.0);
        api::fmi2FreeInstance::<Spring>(c);
    }
}
