//! Generic implementations of the 44 FMI 2.0 functions; `export_fmi2!` forwards to them.
//!
//! Every function runs under [`guarded`], which owns the cross-cutting rules: null
//! component, calling sequence, panics never unwinding into C, logging of failures
//! and the move to the Error state after a model failure.
//!
//! # Safety
//! Every function has the contract of its namesake in the FMI 2.0 standard: an
//! fmi2Component from fmi2Instantiate of the same `M`, arrays of the stated length,
//! NUL-terminated strings. NULL pointers are detected and refused, not dereferenced.
#![allow(non_snake_case, non_upper_case_globals, clippy::missing_safety_doc)]

use std::any::Any;
use std::ffi::{CStr, CString, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};

use super::access::check_settable;
use super::instance::{Instance, SNAPSHOT_MAGIC, Snapshot};
use super::logger::{Category, Logger};
use super::resource::{ResourceError, parse_resource_location};
use super::serial;
use super::state::{self as spec, FnSpec, ModelState};
use super::types::fmi2Status::{fmi2Discard, fmi2Error, fmi2Fatal, fmi2OK};
use super::types::*;
use super::{Causality, Interface, Model, ModelError, VarInfo, VarType};

/// Why a call failed; decides what happens to the instance.
pub enum Failure {
    /// Refused by the state machine; the message is complete.
    State(String),
    /// Bad arguments or unsupported feature: nothing was computed, the instance stays usable.
    Usage(String),
    /// The model returned Err: its state is unknown, so the instance enters Error.
    Model(String),
    /// Model Exchange: the equations gave a non-finite number at the states and inputs the host
    /// set. Nothing changed in the instance; the standard's answer is fmi2Discard, so an
    /// integrator can retry with a smaller step (FMI 2.0.x, section 2.1.3).
    Discard(String),
}

type Outcome = Result<fmi2Status, Failure>;

/// Why fmi2Instantiate made no instance (logged after "fmi2Instantiate: ").
#[derive(Debug)]
pub enum InstantiateError {
    MissingName,
    InvalidType(fmi2Type),
    ResourceNotUtf8,
    Resource(ResourceError),
    /// The model could not be loaded ([`Model::instantiate`]).
    Model(ModelError),
    /// The host's fmuGUID (None: NULL) is not the model's.
    GuidMismatch {
        expected: String,
        got: Option<String>,
    },
}

impl std::fmt::Display for InstantiateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            InstantiateError::MissingName => f.write_str("missing instance name"),
            InstantiateError::InvalidType(t) => write!(f, "invalid fmuType {t}"),
            InstantiateError::ResourceNotUtf8 => f.write_str("fmuResourceLocation is not valid UTF-8"),
            InstantiateError::Resource(e) => std::fmt::Display::fmt(e, f),
            InstantiateError::Model(e) => std::fmt::Display::fmt(e, f),
            InstantiateError::GuidMismatch { expected, got } => {
                write!(f, "GUID mismatch: expected {expected} got {}", got.as_deref().unwrap_or("NULL"))
            }
        }
    }
}

impl std::error::Error for InstantiateError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            InstantiateError::Resource(e) => e.source(),
            InstantiateError::Model(e) => e.source(),
            _ => None,
        }
    }
}

fn usage(msg: impl Into<String>) -> Failure {
    Failure::Usage(msg.into())
}

fn not_supported(capability: &str) -> Outcome {
    Err(usage(format!("not supported by this FMU (capability flag {capability}=false)")))
}

fn panic_message(payload: &(dyn Any + Send)) -> &str {
    payload
        .downcast_ref::<&str>()
        .copied()
        .or_else(|| payload.downcast_ref::<String>().map(String::as_str))
        .unwrap_or("(non-string panic payload)")
}

/// Common prologue and epilogue of every function taking an fmi2Component.
#[inline]
unsafe fn guarded<M: Model>(
    c: fmi2Component,
    rules: &FnSpec,
    op: impl FnOnce(&mut Instance<M>) -> Outcome,
) -> fmi2Status {
    // Without an instance there is no logger to tell anyone.
    if c.is_null() {
        return fmi2Error;
    }
    let ptr = c.cast::<Instance<M>>();
    let result = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: a non-null fmi2Component is one we returned from fmi2Instantiate.
        let inst = unsafe { &mut *ptr };
        if let Some(msg) = rules.refuse(inst.state, inst.interface) {
            return Err(Failure::State(msg));
        }
        op(inst)
    }));
    // SAFETY: the borrow inside the closure has ended, whether it returned or unwound.
    let inst = unsafe { &mut *ptr };
    match result {
        Ok(Ok(status)) => status,
        Ok(Err(Failure::State(msg))) => {
            inst.logger.error(&msg);
            fmi2Error
        }
        Ok(Err(Failure::Usage(msg))) => {
            inst.logger.error(&format!("{}: {msg}", rules.name));
            fmi2Error
        }
        Ok(Err(Failure::Model(msg))) => {
            inst.state = ModelState::Error;
            inst.logger.error(&format!("{}: {msg}", rules.name));
            fmi2Error
        }
        Ok(Err(Failure::Discard(msg))) => {
            inst.logger.discard(&format!("{}: {msg}", rules.name));
            fmi2Discard
        }
        Err(payload) => {
            let msg = format!("{}: panic in the model: {}", rules.name, panic_message(&*payload));
            // A panic while recovering leaves nothing to recover to.
            if rules.name == spec::fmi2Reset.name {
                inst.state = ModelState::Fatal;
                inst.logger.fatal(&msg);
                fmi2Fatal
            } else {
                inst.state = ModelState::Error;
                inst.logger.error(&msg);
                fmi2Error
            }
        }
    }
}

/// A C array as a slice; C may pass NULL when the length is zero.
unsafe fn in_slice<'a, T>(p: *const T, n: usize, what: &str) -> Result<&'a [T], Failure> {
    if n == 0 {
        Ok(&[])
    } else if p.is_null() {
        Err(usage(format!("argument {what} must not be NULL")))
    } else {
        // SAFETY: the host promises `n` valid elements.
        Ok(unsafe { std::slice::from_raw_parts(p, n) })
    }
}

unsafe fn out_slice<'a, T>(p: *mut T, n: usize, what: &str) -> Result<&'a mut [T], Failure> {
    if n == 0 {
        Ok(&mut [])
    } else if p.is_null() {
        Err(usage(format!("argument {what} must not be NULL")))
    } else {
        // SAFETY: the host promises `n` writable elements.
        Ok(unsafe { std::slice::from_raw_parts_mut(p, n) })
    }
}

unsafe fn out_ref<'a, T>(p: *mut T, what: &str) -> Result<&'a mut T, Failure> {
    // SAFETY: non-null out pointers point to a writable T by contract.
    unsafe { p.as_mut() }.ok_or_else(|| usage(format!("argument {what} must not be NULL")))
}

fn check_len(n: usize, expected: usize, what: &str) -> Result<(), Failure> {
    if n == expected { Ok(()) } else { Err(usage(format!("{what} = {n} but the model has {expected}"))) }
}

/// "value reference 7 (tip.u[1])": users read names, hosts pass numbers.
fn describe<M: Model>(model: &M, vr: u32) -> String {
    match model.var_name(vr) {
        Some(name) => format!("value reference {vr} ({name})"),
        None => format!("value reference {vr}"),
    }
}

fn var_of_type<M: Model>(model: &M, vr: u32, expected: VarType) -> Result<VarInfo, Failure> {
    let info = model.var_info(vr).ok_or_else(|| usage(format!("unknown value reference {vr}")))?;
    if info.var_type != expected {
        return Err(usage(format!("{} is a {:?} variable, not {expected:?}", describe(model, vr), info.var_type)));
    }
    Ok(info)
}

fn settable<M: Model>(inst: &Instance<M>, vr: u32, expected: VarType) -> Result<(), Failure> {
    let info = var_of_type(&inst.model, vr, expected)?;
    check_settable(&info, inst.state).map_err(|e| usage(format!("{}: {e}", describe(&inst.model, vr))))
}

/// A model's failure as the layer answers it, as the model classified it: unknown state (Error),
/// nothing changed and the host may retry (Discard), or inputs refused like a value out of range
/// (a usage error). `say` words the message from the model's.
fn model_failure(e: ModelError, say: impl FnOnce(&ModelError) -> String) -> Failure {
    let msg = say(&e);
    match e {
        ModelError::Failed(_) => Failure::Model(msg),
        ModelError::Discard(_) => Failure::Discard(msg),
        ModelError::Refused(_) => Failure::Usage(msg),
    }
}

/// [`model_failure`] with the model's message as it is.
fn failure(e: ModelError) -> Failure {
    model_failure(e, ToString::to_string)
}

/// [`model_failure`] of a call about value reference `vr`, named by its number.
fn failure_of(vr: u32) -> impl FnOnce(ModelError) -> Failure {
    move |e| model_failure(e, |e| format!("value reference {vr}: {e}"))
}

/// [`model_failure`] of a call about one variable, named as [`describe`] does.
fn failure_at<M: Model>(model: &M, vr: u32) -> impl FnOnce(ModelError) -> Failure + '_ {
    move |e| model_failure(e, |e| format!("{}: {e}", describe(model, vr)))
}

/// A non-finite number the model computed is never handed out with fmi2OK. In Model Exchange
/// it comes from states or inputs the host chose (the host may retry: fmi2Discard); in
/// Co-Simulation the FMU's own state produced it, which is no state to go on from (fmi2Error).
fn non_finite<M: Model>(inst: &Instance<M>, what: String, value: f64) -> Failure {
    let msg = format!("{what} evaluates to {value} at the present states and inputs");
    match inst.interface {
        Interface::ModelExchange => Failure::Discard(msg),
        Interface::CoSimulation => Failure::Model(msg),
    }
}

/// The first non-finite entry of `values` as a failure, naming `what[i]`.
fn check_finite<M: Model>(inst: &Instance<M>, values: &[f64], what: &str) -> Result<(), Failure> {
    match values.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(non_finite(inst, format!("{what}[{i}]"), values[i])),
        None => Ok(()),
    }
}

/// A Real value from the host: finite, and within the model's range for `vr`.
fn admissible<M: Model>(model: &M, vr: u32, value: f64) -> Result<(), Failure> {
    if !value.is_finite() {
        return Err(usage(format!("{}: {value} is not a finite number", describe(model, vr))));
    }
    model.admissible_real(vr, value).map_err(failure_at(model, vr))
}

fn to_bool(b: fmi2Boolean) -> bool {
    b != fmi2False
}

fn from_bool(b: bool) -> fmi2Boolean {
    if b { fmi2True } else { fmi2False }
}

// ---------------------------------------------------------------------------
// Inquiry and instance life cycle
// ---------------------------------------------------------------------------

pub fn fmi2GetTypesPlatform() -> *const c_char {
    fmi2TypesPlatform.as_ptr()
}

pub fn fmi2GetVersion() -> *const c_char {
    fmi2Version.as_ptr()
}

pub unsafe fn fmi2Instantiate<M: Model>(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    // SAFETY: non-null pointers from the host are valid for the duration of the call.
    let callbacks = unsafe { functions.as_ref() }.copied().unwrap_or(fmi2CallbackFunctions::NONE);
    let name =
        if instanceName.is_null() { CString::default() } else { unsafe { CStr::from_ptr(instanceName) }.to_owned() };
    let logger = Logger::new(name, callbacks.logger, callbacks.componentEnvironment, to_bool(loggingOn));

    let result = catch_unwind(AssertUnwindSafe(|| -> Result<(M, Interface), InstantiateError> {
        if logger.instance_name().is_empty() {
            return Err(InstantiateError::MissingName);
        }
        let interface = match fmuType {
            fmi2ModelExchange => Interface::ModelExchange,
            fmi2CoSimulation => Interface::CoSimulation,
            other => return Err(InstantiateError::InvalidType(other)),
        };
        let resources = if fmuResourceLocation.is_null() {
            None
        } else {
            let uri = unsafe { CStr::from_ptr(fmuResourceLocation) };
            let uri = uri.to_str().map_err(|_| InstantiateError::ResourceNotUtf8)?;
            Some(parse_resource_location(uri).map_err(InstantiateError::Resource)?)
        };
        logger.trace(|| {
            let dir = resources.as_deref().map_or("none".into(), |p| p.display().to_string());
            format!("fmi2Instantiate: {interface:?}, resources {dir}")
        });
        let model = M::instantiate(resources.as_deref(), interface).map_err(InstantiateError::Model)?;
        let guid = if fmuGUID.is_null() { None } else { Some(unsafe { CStr::from_ptr(fmuGUID) }.to_string_lossy()) };
        if guid.as_deref() != Some(model.guid()) {
            return Err(InstantiateError::GuidMismatch {
                expected: model.guid().to_owned(),
                got: guid.map(|g| g.into_owned()),
            });
        }
        Ok((model, interface))
    }));
    match result {
        Ok(Ok((model, interface))) => {
            Box::into_raw(Box::new(Instance::new(model, interface, logger, callbacks))).cast()
        }
        Ok(Err(e)) => {
            logger.error(&format!("fmi2Instantiate: {e}"));
            std::ptr::null_mut()
        }
        Err(payload) => {
            logger.error(&format!("fmi2Instantiate: panic in the model: {}", panic_message(&*payload)));
            std::ptr::null_mut()
        }
    }
}

pub unsafe fn fmi2FreeInstance<M: Model>(c: fmi2Component) {
    if c.is_null() {
        return;
    }
    // Allowed in every state: refusing would only leak the instance.
    let _ = catch_unwind(AssertUnwindSafe(|| {
        // SAFETY: `c` came from Box::into_raw in fmi2Instantiate and is freed only here.
        let instance = unsafe { Box::from_raw(c.cast::<Instance<M>>()) };
        instance.logger.trace(|| "fmi2FreeInstance".into());
        drop(instance);
    }));
}

pub unsafe fn fmi2SetDebugLogging<M: Model>(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetDebugLogging, |inst| {
            let names = in_slice(categories, nCategories, "categories[]")?;
            let mut list = Vec::with_capacity(names.len());
            for &name in names {
                if name.is_null() {
                    return Err(usage("argument categories[] contains NULL"));
                }
                let name = CStr::from_ptr(name).to_bytes();
                let category = Category::from_name(name)
                    .ok_or_else(|| usage(format!("unknown log category \"{}\"", String::from_utf8_lossy(name))))?;
                list.push(category);
            }
            inst.logger.set_debug_logging(to_bool(loggingOn), &list);
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetupExperiment<M: Model>(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetupExperiment, |inst| {
            if !startTime.is_finite() {
                return Err(usage(format!("startTime must be finite but is {startTime}")));
            }
            if to_bool(toleranceDefined) && !(tolerance > 0.0 && tolerance.is_finite()) {
                return Err(usage(format!("tolerance must be a positive number but is {tolerance}")));
            }
            if to_bool(stopTimeDefined) && !(stopTime.is_finite() && stopTime >= startTime) {
                return Err(usage(format!(
                    "stopTime = {stopTime} must be finite and not before startTime = {startTime}"
                )));
            }
            inst.logger.trace(|| format!("fmi2SetupExperiment: startTime {startTime}"));
            inst.tolerance = to_bool(toleranceDefined).then_some(tolerance);
            inst.start_time = startTime;
            inst.time = startTime;
            inst.stop_time = to_bool(stopTimeDefined).then_some(stopTime);
            // The experiment is set up as asked: the advice goes to the logger only, since
            // hosts (OMSimulator, fmusim) drop a run on any status but fmi2OK.
            if let Some(advice) = inst.tolerance.and_then(|t| inst.model.tolerance_advice(t)) {
                inst.logger.advice(&format!("fmi2SetupExperiment: {advice}"));
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2EnterInitializationMode<M: Model>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2EnterInitializationMode, |inst| {
            inst.logger.trace(|| "fmi2EnterInitializationMode".into());
            inst.model.enter_initialization(inst.start_time).map_err(failure)?;
            inst.state = ModelState::InitializationMode;
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2ExitInitializationMode<M: Model>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2ExitInitializationMode, |inst| {
            inst.logger.trace(|| "fmi2ExitInitializationMode".into());
            inst.model.exit_initialization().map_err(failure)?;
            // a host that never states its tolerance (fmusim) is warned where it would have been
            // at fmi2SetupExperiment with a loose one
            if inst.interface == Interface::ModelExchange
                && inst.tolerance.is_none()
                && let Some(advice) = inst.model.unstated_tolerance_advice()
            {
                inst.logger.advice(&format!("fmi2ExitInitializationMode: {advice}"));
            }
            inst.state = match inst.interface {
                Interface::ModelExchange => ModelState::EventMode,
                Interface::CoSimulation => ModelState::StepComplete,
            };
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2Terminate<M: Model>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2Terminate, |inst| {
            inst.logger.trace(|| "fmi2Terminate".into());
            inst.state = ModelState::Terminated;
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2Reset<M: Model>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2Reset, |inst| {
            inst.logger.trace(|| "fmi2Reset".into());
            inst.model.reset().map_err(failure)?;
            inst.reset_experiment();
            Ok(fmi2OK)
        })
    }
}

// ---------------------------------------------------------------------------
// Getting and setting variable values
// ---------------------------------------------------------------------------

pub unsafe fn fmi2GetReal<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetReal, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = out_slice(value, nvr, "value[]")?;
            for (&r, v) in vrs.iter().zip(values) {
                var_of_type(&inst.model, r, VarType::Real)?;
                let x = inst.model.get_real(r).map_err(failure_at(&inst.model, r))?;
                if !x.is_finite() {
                    return Err(non_finite(inst, describe(&inst.model, r), x));
                }
                *v = x;
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2GetInteger<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetInteger, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = out_slice(value, nvr, "value[]")?;
            for (&r, v) in vrs.iter().zip(values) {
                var_of_type(&inst.model, r, VarType::Integer)?;
                *v = inst.model.get_integer(r).map_err(failure_of(r))?;
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2GetBoolean<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetBoolean, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = out_slice(value, nvr, "value[]")?;
            for (&r, v) in vrs.iter().zip(values) {
                var_of_type(&inst.model, r, VarType::Boolean)?;
                *v = from_bool(inst.model.get_boolean(r).map_err(failure_of(r))?);
            }
            Ok(fmi2OK)
        })
    }
}

/// The returned pointers stay valid until the next fmi2GetString or fmi2FreeInstance.
pub unsafe fn fmi2GetString<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetString, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = out_slice(value, nvr, "value[]")?;
            inst.string_buffer.clear();
            for (&r, v) in vrs.iter().zip(values) {
                var_of_type(&inst.model, r, VarType::String)?;
                let s = inst.model.get_string(r).map_err(failure_of(r))?;
                let s =
                    CString::new(s).map_err(|_| Failure::Model(format!("value reference {r}: string contains NUL")))?;
                // The CString's heap buffer does not move when the Vec grows.
                *v = s.as_ptr();
                inst.string_buffer.push(s);
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetReal<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetReal, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = in_slice(value, nvr, "value[]")?;
            // all checked before any is set: a refused call changes nothing
            for (&r, &v) in vrs.iter().zip(values) {
                settable(inst, r, VarType::Real)?;
                admissible(&inst.model, r, v)?;
            }
            // values that only make sense together (a rotation matrix's nine entries)
            inst.model.admissible_reals(vrs, values).map_err(failure)?;
            for (&r, &v) in vrs.iter().zip(values) {
                inst.model.set_real(r, v).map_err(failure_of(r))?;
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetInteger<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetInteger, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = in_slice(value, nvr, "value[]")?;
            for (&r, &v) in vrs.iter().zip(values) {
                settable(inst, r, VarType::Integer)?;
                inst.model.set_integer(r, v).map_err(failure_of(r))?;
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetBoolean<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetBoolean, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = in_slice(value, nvr, "value[]")?;
            for (&r, &v) in vrs.iter().zip(values) {
                settable(inst, r, VarType::Boolean)?;
                inst.model.set_boolean(r, to_bool(v)).map_err(failure_of(r))?;
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetString<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetString, |inst| {
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let values = in_slice(value, nvr, "value[]")?;
            for (&r, &v) in vrs.iter().zip(values) {
                settable(inst, r, VarType::String)?;
                if v.is_null() {
                    return Err(usage(format!("value for value reference {r} is NULL")));
                }
                let s = CStr::from_ptr(v)
                    .to_str()
                    .map_err(|_| usage(format!("value for value reference {r} is not valid UTF-8")))?;
                inst.model.set_string(r, s).map_err(failure_of(r))?;
            }
            Ok(fmi2OK)
        })
    }
}

// ---------------------------------------------------------------------------
// FMU state: an fmi2FMUstate is a Box<Snapshot<M>> (canGetAndSetFMUstate=true)
// ---------------------------------------------------------------------------

pub unsafe fn fmi2GetFMUstate<M: Model>(c: fmi2Component, FMUstate: *mut fmi2FMUstate) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetFMUstate, |inst| {
            let slot = out_ref(FMUstate, "FMUstate")?;
            let snapshot = inst.snapshot();
            if slot.is_null() {
                *slot = Box::into_raw(Box::new(snapshot)).cast();
            } else {
                // The standard lets the host hand back a state to be overwritten in place.
                snapshot_ref::<M>(*slot)?;
                *slot.cast::<Snapshot<M>>() = snapshot;
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetFMUstate<M: Model>(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetFMUstate, |inst| {
            let snapshot = snapshot_ref::<M>(FMUstate)?;
            // a state of another FMU's instance has the same layout when that FMU carries this
            // runtime too: only the GUID tells them apart
            if snapshot.model.guid() != inst.model.guid() {
                return Err(usage(format!(
                    "the FMU state belongs to the model with GUID {}, not this FMU's {}",
                    snapshot.model.guid(),
                    inst.model.guid()
                )));
            }
            if snapshot.interface != inst.interface {
                return Err(usage(format!(
                    "the FMU state is of a {:?} instance; this instance was instantiated for {:?}",
                    snapshot.interface, inst.interface
                )));
            }
            inst.restore(snapshot);
            inst.logger.trace(|| format!("fmi2SetFMUstate: time {}", inst.time));
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2FreeFMUstate<M: Model>(c: fmi2Component, FMUstate: *mut fmi2FMUstate) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2FreeFMUstate, |_inst| {
            let slot = out_ref(FMUstate, "FMUstate")?;
            if !slot.is_null() {
                snapshot_ref::<M>(*slot)?;
                drop(Box::from_raw(slot.cast::<Snapshot<M>>()));
                *slot = std::ptr::null_mut();
            }
            Ok(fmi2OK)
        })
    }
}

// Serialized FMU states (canSerializeFMUstate=true); the byte format is in `serial`.
// DeSerialize only builds an FMU state; fmi2SetFMUstate applies it, as the standard has it.
// Bytes that fail a check are a usage error: logged, fmi2Error, nothing built, and the
// instance stays in its state (it can go on, restore another state, reset or be freed).

unsafe fn snapshot_ref<'a, M>(FMUstate: fmi2FMUstate) -> Result<&'a Snapshot<M>, Failure> {
    let p = FMUstate.cast::<Snapshot<M>>();
    if p.is_null() {
        return Err(usage("argument FMUstate must not be NULL"));
    }
    // SAFETY: the host passes a pointer to readable memory of at least a state's size; only the
    // leading u64 is read before it is known to be one of our states.
    let magic = unsafe { std::ptr::addr_of!((*p).magic).read_unaligned() };
    if magic != SNAPSHOT_MAGIC {
        return Err(usage(
            "argument FMUstate is not an FMU state of this runtime (fmi2GetFMUstate or fmi2DeSerializeFMUstate make them)",
        ));
    }
    // SAFETY: the magic marks a Snapshot<M> made by fmi2GetFMUstate/fmi2DeSerializeFMUstate.
    Ok(unsafe { &*p })
}

pub unsafe fn fmi2SerializedFMUstateSize<M: Model>(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SerializedFMUstateSize, |_inst| {
            let snapshot = snapshot_ref::<M>(FMUstate)?;
            let size = out_ref(size, "size")?;
            *size = serial::serialize(snapshot).len();
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SerializeFMUstate<M: Model>(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SerializeFMUstate, |inst| {
            let snapshot = snapshot_ref::<M>(FMUstate)?;
            let bytes = serial::serialize(snapshot);
            if size != bytes.len() {
                return Err(usage(format!(
                    "size = {size} but the serialized FMU state has {} bytes (the size fmi2SerializedFMUstateSize returns)",
                    bytes.len()
                )));
            }
            out_slice(serializedState.cast::<u8>(), size, "serializedState[]")?.copy_from_slice(&bytes);
            inst.logger.trace(|| format!("fmi2SerializeFMUstate: {size} bytes, time {}", snapshot.time));
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2DeSerializeFMUstate<M: Model>(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2DeSerializeFMUstate, |inst| {
            let bytes = in_slice(serializedState.cast::<u8>(), size, "serializedState[]")?;
            let slot = out_ref(FMUstate, "FMUstate")?;
            let snapshot = serial::deserialize(bytes, &inst.model, inst.interface).map_err(|e| usage(e.to_string()))?;
            inst.logger.trace(|| format!("fmi2DeSerializeFMUstate: {size} bytes, time {}", snapshot.time));
            if slot.is_null() {
                *slot = Box::into_raw(Box::new(snapshot)).cast();
            } else {
                // As fmi2GetFMUstate: a state handed back is overwritten in place.
                snapshot_ref::<M>(*slot)?;
                *slot.cast::<Snapshot<M>>() = snapshot;
            }
            Ok(fmi2OK)
        })
    }
}

/// Whether the C arrays `a[..n]` and `b[..m]` share memory: a host may hand the same buffer
/// for the seed and the result, and Rust must not see it as both `&` and `&mut`.
fn overlap<T>(a: *const T, n: usize, b: *const T, m: usize) -> bool {
    let size = std::mem::size_of::<T>();
    let (a, b) = (a as usize, b as usize);
    let (a_end, b_end) = (a.saturating_add(n.saturating_mul(size)), b.saturating_add(m.saturating_mul(size)));
    n > 0 && m > 0 && a < b_end && b < a_end
}

/// Why `vr` cannot be an unknown of a directional derivative, if it cannot.
fn check_unknown<M: Model>(model: &M, vr: u32, interface: Interface) -> Result<(), Failure> {
    let info = var_of_type(model, vr, VarType::Real)?;
    let me = interface == Interface::ModelExchange;
    if info.causality == Causality::Output || (me && model.is_state_derivative(vr)) {
        return Ok(());
    }
    let expected = if me {
        "an output or the derivative of a continuous state"
    } else if model.is_state_derivative(vr) {
        "an output (state derivatives are unknowns in Model Exchange only)"
    } else {
        "an output"
    };
    Err(usage(format!("unknown {} has causality {:?}; expected {expected}", describe(model, vr), info.causality)))
}

/// Why `vr` cannot be a known of a directional derivative, if it cannot.
fn check_known<M: Model>(model: &M, vr: u32, interface: Interface) -> Result<(), Failure> {
    let info = var_of_type(model, vr, VarType::Real)?;
    let me = interface == Interface::ModelExchange;
    if info.causality == Causality::Input || (me && model.is_continuous_state(vr)) {
        return Ok(());
    }
    let expected = if me {
        "an input or a continuous state"
    } else if model.is_continuous_state(vr) {
        "an input (continuous states are knowns in Model Exchange only)"
    } else {
        "an input"
    };
    Err(usage(format!("known {} has causality {:?}; expected {expected}", describe(model, vr), info.causality)))
}

/// The Jacobian of outputs (and, in Model Exchange, state derivatives) with respect to inputs
/// (and states) times a seed: what implicit solvers, linearization and co-simulation masters
/// with algebraic loops ask for (FMI 2.0.x section 2.1.9).
pub unsafe fn fmi2GetDirectionalDerivative<M: Model>(
    c: fmi2Component,
    vUnknown_ref: *const fmi2ValueReference,
    nUnknown: usize,
    vKnown_ref: *const fmi2ValueReference,
    nKnown: usize,
    dvKnown: *const fmi2Real,
    dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetDirectionalDerivative, |inst| {
            if !inst.model.provides_directional_derivative() {
                return not_supported("providesDirectionalDerivative");
            }
            // Nothing asked, nothing to write: the knowns do not matter.
            if nUnknown == 0 {
                return Ok(fmi2OK);
            }
            let unknowns = in_slice(vUnknown_ref, nUnknown, "vUnknown_ref[]")?;
            let knowns = in_slice(vKnown_ref, nKnown, "vKnown_ref[]")?;
            // A seed in the result buffer is copied out before the buffer is written.
            let seed_copy: Vec<f64>;
            let seed = if overlap(dvKnown, nKnown, dvUnknown.cast_const(), nUnknown) {
                seed_copy = in_slice(dvKnown, nKnown, "dvKnown[]")?.to_vec();
                &seed_copy[..]
            } else {
                in_slice(dvKnown, nKnown, "dvKnown[]")?
            };
            let result = out_slice(dvUnknown, nUnknown, "dvUnknown[]")?;
            for &r in unknowns {
                check_unknown(&inst.model, r, inst.interface)?;
            }
            for (i, (&r, &dv)) in knowns.iter().zip(seed).enumerate() {
                check_known(&inst.model, r, inst.interface)?;
                if !dv.is_finite() {
                    return Err(usage(format!(
                        "dvKnown[{i}] = {dv} for known {} is not finite",
                        describe(&inst.model, r)
                    )));
                }
                // the seed is a rate along the known: the range fmi2SetRealInputDerivatives has
                inst.model.admissible_direction(r, dv).map_err(|e| {
                    model_failure(e, |e| format!("dvKnown[{i}] = {dv:e} for known {}: {e}", describe(&inst.model, r)))
                })?;
            }
            inst.logger.trace(|| format!("fmi2GetDirectionalDerivative: {nUnknown} unknowns, {nKnown} knowns"));
            let computed = inst.model.directional_derivative(unknowns, knowns, seed, result);
            computed.map_err(failure)?;
            check_finite(inst, result, "dvUnknown")?;
            Ok(fmi2OK)
        })
    }
}

// ---------------------------------------------------------------------------
// Model Exchange
// ---------------------------------------------------------------------------

pub unsafe fn fmi2EnterEventMode<M: Model>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2EnterEventMode, |inst| {
            inst.state = ModelState::EventMode;
            Ok(fmi2OK)
        })
    }
}

/// The trait has no discrete states or time events yet, so event iteration ends at once.
pub unsafe fn fmi2NewDiscreteStates<M: Model>(c: fmi2Component, eventInfo: *mut fmi2EventInfo) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2NewDiscreteStates, |_inst| {
            *out_ref(eventInfo, "eventInfo")? = fmi2EventInfo {
                newDiscreteStatesNeeded: fmi2False,
                terminateSimulation: fmi2False,
                nominalsOfContinuousStatesChanged: fmi2False,
                valuesOfContinuousStatesChanged: fmi2False,
                nextEventTimeDefined: fmi2False,
                nextEventTime: 0.0,
            };
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2EnterContinuousTimeMode<M: Model>(c: fmi2Component) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2EnterContinuousTimeMode, |inst| {
            inst.state = ModelState::ContinuousTimeMode;
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2CompletedIntegratorStep<M: Model>(
    c: fmi2Component,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    enterEventMode: *mut fmi2Boolean,
    terminateSimulation: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2CompletedIntegratorStep, |inst| {
            let enter = out_ref(enterEventMode, "enterEventMode")?;
            let terminate = out_ref(terminateSimulation, "terminateSimulation")?;
            *enter = fmi2False;
            *terminate = fmi2False;
            // The step stands: the warning is the logger's, the status fmi2OK, since a host that
            // stops on fmi2Warning would lose the run the warning is meant to improve.
            if let Some(warning) = inst.model.completed_integrator_step(inst.time) {
                inst.logger.advice(&format!("fmi2CompletedIntegratorStep: {warning}"));
            }
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetTime<M: Model>(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetTime, |inst| {
            if !time.is_finite() {
                return Err(usage(format!("time = {time} is not a finite number")));
            }
            inst.time = time;
            inst.model.set_time(time);
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2SetContinuousStates<M: Model>(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetContinuousStates, |inst| {
            check_len(nx, inst.model.n_states(), "nx")?;
            let x = in_slice(x, nx, "x[]")?;
            if let Some(i) = x.iter().position(|v| !v.is_finite()) {
                return Err(usage(format!("x[{i}] = {} is not a finite number; no state was set", x[i])));
            }
            inst.model.set_continuous_states(x);
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2GetDerivatives<M: Model>(c: fmi2Component, derivatives: *mut fmi2Real, nx: usize) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetDerivatives, |inst| {
            check_len(nx, inst.model.n_states(), "nx")?;
            let dx = out_slice(derivatives, nx, "derivatives[]")?;
            let computed = inst.model.get_derivatives(dx);
            computed.map_err(failure)?;
            check_finite(inst, dx, "derivatives")?;
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2GetEventIndicators<M: Model>(
    c: fmi2Component,
    eventIndicators: *mut fmi2Real,
    ni: usize,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetEventIndicators, |inst| {
            check_len(ni, inst.model.n_event_indicators(), "ni")?;
            let z = out_slice(eventIndicators, ni, "eventIndicators[]")?;
            inst.model.get_event_indicators(z).map_err(failure)?;
            check_finite(inst, z, "eventIndicators")?;
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2GetContinuousStates<M: Model>(c: fmi2Component, x: *mut fmi2Real, nx: usize) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetContinuousStates, |inst| {
            check_len(nx, inst.model.n_states(), "nx")?;
            let x = out_slice(x, nx, "x[]")?;
            inst.model.get_continuous_states(x);
            check_finite(inst, x, "x")?;
            Ok(fmi2OK)
        })
    }
}

pub unsafe fn fmi2GetNominalsOfContinuousStates<M: Model>(
    c: fmi2Component,
    x_nominal: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetNominalsOfContinuousStates, |inst| {
            check_len(nx, inst.model.n_states(), "nx")?;
            let nominals = out_slice(x_nominal, nx, "x_nominal[]")?;
            inst.model.get_nominals(nominals);
            check_finite(inst, nominals, "x_nominal")?;
            Ok(fmi2OK)
        })
    }
}

// ---------------------------------------------------------------------------
// Co-Simulation
// ---------------------------------------------------------------------------

/// First input derivatives for the next step (canInterpolateInputs, maxInputDerivativeOrder 1).
pub unsafe fn fmi2SetRealInputDerivatives<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2SetRealInputDerivatives, |inst| {
            if !inst.model.can_interpolate_inputs() {
                return not_supported("canInterpolateInputs");
            }
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let orders = in_slice(order, nvr, "order[]")?;
            let values = in_slice(value, nvr, "value[]")?;
            // all checked before any is set, as fmi2SetReal does: a refused call changes nothing
            for ((&r, &k), &v) in vrs.iter().zip(orders).zip(values) {
                let info = var_of_type(&inst.model, r, VarType::Real)?;
                if info.causality != Causality::Input {
                    return Err(usage(format!("{}: input derivatives are for inputs only", describe(&inst.model, r))));
                }
                if k != 1 {
                    return Err(usage(format!(
                        "{}: derivative order {k} requested; this FMU interpolates inputs to first order (maxInputDerivativeOrder 1)",
                        describe(&inst.model, r)
                    )));
                }
                if !v.is_finite() {
                    return Err(usage(format!("{}: input derivative {v} is not finite", describe(&inst.model, r))));
                }
                inst.model.admissible_direction(r, v).map_err(|e| {
                    model_failure(e, |e| format!("{}: input derivative {v:e}: {e}", describe(&inst.model, r)))
                })?;
            }
            for (&r, &v) in vrs.iter().zip(values) {
                inst.model.set_real_input_derivative(r, v).map_err(failure_of(r))?;
            }
            Ok(fmi2OK)
        })
    }
}

/// Time derivatives of outputs at the current communication point, for a master that
/// extrapolates them over its next step (maxOutputDerivativeOrder).
pub unsafe fn fmi2GetRealOutputDerivatives<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *mut fmi2Real,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetRealOutputDerivatives, |inst| {
            let max_order = inst.model.max_output_derivative_order();
            if max_order < 1 {
                return not_supported("maxOutputDerivativeOrder>0");
            }
            let vrs = in_slice(vr, nvr, "vr[]")?;
            let orders = in_slice(order, nvr, "order[]")?;
            let values = out_slice(value, nvr, "value[]")?;
            // All checked before any is computed: a refused call writes nothing.
            for (&r, &k) in vrs.iter().zip(orders) {
                let info = var_of_type(&inst.model, r, VarType::Real)?;
                if info.causality != Causality::Output {
                    return Err(usage(format!(
                        "{} has causality {:?}; output derivatives are for outputs only",
                        describe(&inst.model, r),
                        info.causality
                    )));
                }
                if !(1..=max_order).contains(&k) {
                    return Err(usage(format!(
                        "{}: derivative order {k} requested; this FMU provides orders 1 to {max_order} (maxOutputDerivativeOrder {max_order})",
                        describe(&inst.model, r)
                    )));
                }
            }
            inst.logger.trace(|| format!("fmi2GetRealOutputDerivatives: {nvr} values"));
            for ((&r, &k), v) in vrs.iter().zip(orders).zip(values) {
                let x = inst.model.get_real_output_derivative(r, k).map_err(failure_at(&inst.model, r))?;
                if !x.is_finite() {
                    return Err(non_finite(inst, format!("derivative {k} of {}", describe(&inst.model, r)), x));
                }
                *v = x;
            }
            Ok(fmi2OK)
        })
    }
}

/// Relative tolerance between the host's communication point and our accumulated time:
/// both are sums of the same step sizes, possibly rounded in a different order.
const TIME_TOLERANCE: f64 = 1e-9;

pub unsafe fn fmi2DoStep<M: Model>(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    let (t, h) = (currentCommunicationPoint, communicationStepSize);
    unsafe {
        guarded::<M>(c, &spec::fmi2DoStep, |inst| {
            // Also rejects NaN.
            if !(h > 0.0 && h.is_finite()) {
                return Err(usage(format!("communicationStepSize must be > 0 but is {h}")));
            }
            // Scale by every magnitude involved so the check stays relative near t = 0.
            let scale = inst.time.abs().max(t.abs()).max(inst.start_time.abs()).max(h);
            if !t.is_finite() || (t - inst.time).abs() > TIME_TOLERANCE * scale {
                return Err(usage(format!("currentCommunicationPoint = {t} but the FMU is at time {}", inst.time)));
            }
            if !(inst.time + h).is_finite() {
                return Err(usage(format!(
                    "communicationStepSize = {h} takes the time {} beyond any finite number",
                    inst.time
                )));
            }
            inst.logger.trace(|| format!("fmi2DoStep: t = {t}, h = {h}"));
            match inst.model.do_step(inst.time, h) {
                Ok(()) => {}
                // Not taken, the model as before the step: the standard's stepFailed, from which
                // the master restores a saved FMU state and retries with a shorter step (FMI 2.0.x
                // section 4.2.2); fmi2LastSuccessfulTime stays at the step's start
                Err(ModelError::Discard(reason)) => {
                    inst.state = ModelState::StepFailed;
                    inst.last_do_step_status = fmi2Discard;
                    return Err(Failure::Discard(format!("step from t = {t} by h = {h} not taken: {reason}")));
                }
                // refused before anything was done, as fmi2SetReal refuses a value: same state
                Err(ModelError::Refused(reason)) => {
                    return Err(usage(format!(
                        "{reason}; the step is refused with fmi2Error before anything was done, the instance \
                         unchanged: set valid inputs and step again"
                    )));
                }
                Err(ModelError::Failed(reason)) => {
                    inst.last_do_step_status = fmi2Error;
                    return Err(Failure::Model(reason.to_string()));
                }
            }
            inst.last_do_step_status = fmi2OK;
            inst.time += h;
            // The step was taken: fmi2OK, as masters (OMSimulator, fmusim) end the run on any
            // other status. The warning is logged whatever the debug logging, since the status
            // no longer carries it.
            if let Some(warning) = inst.model.take_warning() {
                inst.logger.advice(&format!("fmi2DoStep: {warning}"));
            }
            Ok(fmi2OK)
        })
    }
}

/// Allowed only while a step is pending, which never happens: the state check refuses it.
pub unsafe fn fmi2CancelStep<M: Model>(c: fmi2Component) -> fmi2Status {
    unsafe { guarded::<M>(c, &spec::fmi2CancelStep, |_| Ok(fmi2OK)) }
}

/// fmi2Discard is the standard's answer for a status kind the slave cannot provide.
fn status_unavailable<M: Model>(inst: &Instance<M>, function: &str, kind: fmi2StatusKind) -> Outcome {
    inst.logger.warning(
        fmi2Discard,
        &format!("{function}: status kind {kind} is not available (fmi2DoStep is never asynchronous)"),
    );
    Ok(fmi2Discard)
}

pub unsafe fn fmi2GetStatus<M: Model>(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetStatus, |inst| {
            let value = out_ref(value, "value")?;
            if s == fmi2DoStepStatus {
                *value = inst.last_do_step_status;
                Ok(fmi2OK)
            } else {
                status_unavailable(inst, "fmi2GetStatus", s)
            }
        })
    }
}

pub unsafe fn fmi2GetRealStatus<M: Model>(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetRealStatus, |inst| {
            let value = out_ref(value, "value")?;
            if s == fmi2LastSuccessfulTime {
                *value = inst.time;
                Ok(fmi2OK)
            } else {
                status_unavailable(inst, "fmi2GetRealStatus", s)
            }
        })
    }
}

pub unsafe fn fmi2GetIntegerStatus<M: Model>(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetIntegerStatus, |inst| {
            out_ref(value, "value")?;
            status_unavailable(inst, "fmi2GetIntegerStatus", s)
        })
    }
}

pub unsafe fn fmi2GetBooleanStatus<M: Model>(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetBooleanStatus, |inst| {
            let value = out_ref(value, "value")?;
            if s == fmi2Terminated {
                // The model never asks to end the simulation.
                *value = fmi2False;
                Ok(fmi2OK)
            } else {
                status_unavailable(inst, "fmi2GetBooleanStatus", s)
            }
        })
    }
}

pub unsafe fn fmi2GetStringStatus<M: Model>(c: fmi2Component, s: fmi2StatusKind, value: *mut fmi2String) -> fmi2Status {
    unsafe {
        guarded::<M>(c, &spec::fmi2GetStringStatus, |inst| {
            out_ref(value, "value")?;
            status_unavailable(inst, "fmi2GetStringStatus", s)
        })
    }
}
