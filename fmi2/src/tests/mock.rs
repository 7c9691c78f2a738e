//! One-mass spring x'' = -k x - d x' + u, the mock model for the layer's tests.
//! Extra variables exercise the layer: a panic trigger, a failure trigger, strings.
//! Its Jacobian is the constant matrix of a linear system, and the output derivatives
//! follow from the equation, so tests know the exact answers. Instantiated from a resources
//! folder whose path contains "no-derivatives", it provides neither.

use std::path::Path;

use crate::bytes::{DecodeError, Reader, Writer};
use crate::{Causality as C, Initial as I, Interface, Model, ModelError, VarInfo, VarType as T, Variability as V};

pub const GUID: &str = "{8c4e810f-3df3-4a00-8276-176fa3c9f000}";
/// The GUID of another FMU carrying the same runtime (resources containing "other-model").
pub const OTHER_GUID: &str = "{8c4e810f-3df3-4a00-8276-176fa3c9f001}";
/// The input's physical range: |u| beyond it is refused by `admissible_real`.
pub const U_LIMIT: f64 = 1e100;
/// Longer steps are not taken (fmi2Discard, nothing changed).
pub const MAX_STEP: f64 = 1e3;
/// A tolerance looser than this is advised against (fmi2SetupExperiment still succeeds).
pub const LOOSE_TOLERANCE: f64 = 1e-3;
/// From this time on, completed integrator steps and Co-Simulation steps come with a warning.
pub const WARN_AFTER: f64 = 50.0;

pub const X: u32 = 0;
pub const V_: u32 = 1;
pub const K: u32 = 2;
pub const U: u32 = 3;
pub const A: u32 = 4;
pub const D: u32 = 5;
pub const STEPS: u32 = 6;
pub const CRASH: u32 = 7;
pub const LABEL: u32 = 8;
pub const FAIL: u32 = 9;
pub const RESOURCES: u32 = 10;
/// The acceleration as an output: the one output with direct feedthrough from the input.
pub const ACC: u32 = 11;

const NAMES: [&str; 12] = ["x", "v", "k", "u", "a", "d", "steps", "crash", "label", "fail", "resources", "acc"];

const VARS: [VarInfo; 12] = [
    VarInfo { var_type: T::Real, causality: C::Output, variability: V::Continuous, initial: Some(I::Exact) },
    VarInfo { var_type: T::Real, causality: C::Local, variability: V::Continuous, initial: Some(I::Exact) },
    VarInfo { var_type: T::Real, causality: C::Parameter, variability: V::Fixed, initial: Some(I::Exact) },
    VarInfo { var_type: T::Real, causality: C::Input, variability: V::Continuous, initial: None },
    VarInfo { var_type: T::Real, causality: C::Local, variability: V::Continuous, initial: Some(I::Calculated) },
    VarInfo { var_type: T::Real, causality: C::Parameter, variability: V::Tunable, initial: None },
    VarInfo { var_type: T::Integer, causality: C::Output, variability: V::Discrete, initial: Some(I::Calculated) },
    VarInfo { var_type: T::Boolean, causality: C::Input, variability: V::Discrete, initial: None },
    VarInfo { var_type: T::String, causality: C::Parameter, variability: V::Fixed, initial: Some(I::Exact) },
    VarInfo { var_type: T::Boolean, causality: C::Input, variability: V::Discrete, initial: None },
    VarInfo { var_type: T::String, causality: C::CalculatedParameter, variability: V::Fixed, initial: None },
    VarInfo { var_type: T::Real, causality: C::Output, variability: V::Continuous, initial: Some(I::Calculated) },
];

/// Why the spring fails, each as the layer's tests expect it logged.
#[derive(Debug)]
pub enum SpringError {
    CannotLoad(String),
    InputRange(f64),
    RateRange,
    NonPositiveK(f64),
    NoSettableIntegers,
    Jacobian,
    NoDerivative,
    StepTooLong(f64),
    Solver(f64),
    Version(u32),
}

impl std::fmt::Display for SpringError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SpringError::CannotLoad(resources) => write!(f, "cannot load {resources}"),
            SpringError::InputRange(value) => write!(f, "|u| = {value:e} is beyond the input's range {U_LIMIT:e}"),
            SpringError::RateRange => write!(f, "beyond the input's range of rates {U_LIMIT:e}"),
            SpringError::NonPositiveK(value) => write!(f, "k must be > 0, got {value}"),
            SpringError::NoSettableIntegers => f.write_str("no settable integers"),
            SpringError::Jacobian => f.write_str("Jacobian failed"),
            SpringError::NoDerivative => f.write_str("no derivative after a failure"),
            SpringError::StepTooLong(h) => write!(f, "h = {h} needs more than {MAX_STEP} s of RK4 substeps"),
            SpringError::Solver(t) => write!(f, "solver failed at 50% of the step #r{X}# t = {t}"),
            SpringError::Version(version) => write!(f, "spring state version {version} is not 1"),
        }
    }
}

impl std::error::Error for SpringError {}

#[derive(Clone, Debug)]
pub struct Spring {
    resources: String,
    time: f64,
    x: f64,
    v: f64,
    k: f64,
    d: f64,
    u: f64,
    steps: i32,
    crash: bool,
    fail: bool,
    label: String,
}

impl Spring {
    fn accel(&self, x: f64, v: f64) -> f64 {
        if self.crash {
            panic!("crash requested at t = {}", self.time);
        }
        -self.k * x - self.d * v + self.u
    }

    fn has_derivatives(&self) -> bool {
        !self.resources.contains("no-derivatives")
    }

    /// d unknown / d known; x, v and u are the only knowns the layer lets through.
    fn partial(&self, unknown: u32, known: u32) -> f64 {
        match (unknown, known) {
            // x is an output, and v is der(x): each depends on itself only.
            (X, X) | (V_, V_) => 1.0,
            (X | V_, _) => 0.0,
            // a = der(v), and acc its copy as an output.
            (A | ACC, X) => -self.k,
            (A | ACC, V_) => -self.d,
            (A | ACC, U) => 1.0,
            _ => unreachable!("the layer checks unknowns and knowns"),
        }
    }

    fn start(resources: String) -> Spring {
        Spring {
            resources,
            time: 0.0,
            x: 1.0,
            v: 0.0,
            k: 1.0,
            d: 0.0,
            u: 0.0,
            steps: 0,
            crash: false,
            fail: false,
            label: "spring".into(),
        }
    }
}

impl Model for Spring {
    fn instantiate(resources: Option<&Path>, _interface: Interface) -> Result<Self, ModelError> {
        let resources = resources.map_or("none".to_string(), |p| p.display().to_string());
        if resources.contains("refuse") {
            return Err(ModelError::failed(SpringError::CannotLoad(resources)));
        }
        Ok(Spring::start(resources))
    }
    fn guid(&self) -> &str {
        if self.resources.contains("other-model") { OTHER_GUID } else { GUID }
    }
    fn admissible_real(&self, vr: u32, value: f64) -> Result<(), ModelError> {
        if vr == U && value.abs() > U_LIMIT {
            return Err(ModelError::refused(SpringError::InputRange(value)));
        }
        Ok(())
    }
    fn admissible_direction(&self, vr: u32, value: f64) -> Result<(), ModelError> {
        if vr == U && value.abs() > U_LIMIT {
            return Err(ModelError::refused(SpringError::RateRange));
        }
        Ok(())
    }
    fn var_info(&self, vr: u32) -> Option<VarInfo> {
        VARS.get(vr as usize).copied()
    }
    fn var_name(&self, vr: u32) -> Option<&str> {
        NAMES.get(vr as usize).copied()
    }
    fn get_real(&mut self, vr: u32) -> Result<f64, ModelError> {
        Ok(match vr {
            X => self.x,
            V_ => self.v,
            K => self.k,
            U => self.u,
            A | ACC => self.accel(self.x, self.v),
            D => self.d,
            _ => unreachable!("the layer checks value references"),
        })
    }
    fn set_real(&mut self, vr: u32, value: f64) -> Result<(), ModelError> {
        match vr {
            X => self.x = value,
            V_ => self.v = value,
            K if value <= 0.0 => return Err(ModelError::failed(SpringError::NonPositiveK(value))),
            K => self.k = value,
            U => self.u = value,
            D => self.d = value,
            _ => unreachable!("the layer checks settability"),
        }
        Ok(())
    }
    fn get_integer(&mut self, _vr: u32) -> Result<i32, ModelError> {
        Ok(self.steps)
    }
    fn set_integer(&mut self, _vr: u32, _value: i32) -> Result<(), ModelError> {
        Err(ModelError::failed(SpringError::NoSettableIntegers))
    }
    fn get_boolean(&mut self, vr: u32) -> Result<bool, ModelError> {
        Ok(if vr == CRASH { self.crash } else { self.fail })
    }
    fn set_boolean(&mut self, vr: u32, value: bool) -> Result<(), ModelError> {
        if vr == CRASH {
            self.crash = value
        } else {
            self.fail = value
        }
        Ok(())
    }
    fn get_string(&mut self, vr: u32) -> Result<String, ModelError> {
        Ok(if vr == LABEL { self.label.clone() } else { self.resources.clone() })
    }
    fn set_string(&mut self, _vr: u32, value: &str) -> Result<(), ModelError> {
        self.label = value.to_owned();
        Ok(())
    }
    fn n_states(&self) -> usize {
        2
    }
    fn n_event_indicators(&self) -> usize {
        1
    }
    fn set_time(&mut self, t: f64) {
        self.time = t;
    }
    fn get_continuous_states(&self, x: &mut [f64]) {
        x.copy_from_slice(&[self.x, self.v]);
    }
    fn set_continuous_states(&mut self, x: &[f64]) {
        (self.x, self.v) = (x[0], x[1]);
    }
    fn get_derivatives(&mut self, dx: &mut [f64]) -> Result<(), ModelError> {
        dx.copy_from_slice(&[self.v, self.accel(self.x, self.v)]);
        Ok(())
    }
    fn get_nominals(&self, nominals: &mut [f64]) {
        nominals.fill(1.0);
    }
    fn get_event_indicators(&mut self, z: &mut [f64]) -> Result<(), ModelError> {
        z[0] = self.x;
        Ok(())
    }
    fn enter_initialization(&mut self, start_time: f64) -> Result<(), ModelError> {
        self.time = start_time;
        Ok(())
    }
    fn exit_initialization(&mut self) -> Result<(), ModelError> {
        Ok(())
    }
    fn provides_directional_derivative(&self) -> bool {
        self.has_derivatives()
    }
    fn is_continuous_state(&self, vr: u32) -> bool {
        matches!(vr, X | V_)
    }
    fn is_state_derivative(&self, vr: u32) -> bool {
        matches!(vr, V_ | A)
    }
    fn directional_derivative(
        &mut self,
        unknowns: &[u32],
        knowns: &[u32],
        dv_known: &[f64],
        dv_unknown: &mut [f64],
    ) -> Result<(), ModelError> {
        if self.fail {
            return Err(ModelError::failed(SpringError::Jacobian));
        }
        for (&unknown, dv) in unknowns.iter().zip(dv_unknown) {
            *dv = knowns.iter().zip(dv_known).map(|(&known, &seed)| self.partial(unknown, known) * seed).sum();
        }
        Ok(())
    }
    fn max_output_derivative_order(&self) -> i32 {
        if self.has_derivatives() { 1 } else { 0 }
    }
    /// do_step holds u over a step, so d acc/dt = -k v - d a.
    fn get_real_output_derivative(&mut self, vr: u32, order: i32) -> Result<f64, ModelError> {
        assert_eq!(order, 1, "the layer checks the order");
        if self.fail {
            return Err(ModelError::failed(SpringError::NoDerivative));
        }
        Ok(match vr {
            X => self.v,
            ACC => -self.k * self.v - self.d * self.accel(self.x, self.v),
            _ => unreachable!("the layer checks for outputs"),
        })
    }
    fn tolerance_advice(&self, tolerance: f64) -> Option<String> {
        (tolerance > LOOSE_TOLERANCE).then(|| format!("tolerance {tolerance} is looser than {LOOSE_TOLERANCE}"))
    }
    fn completed_integrator_step(&mut self, time: f64) -> Option<String> {
        (time >= WARN_AFTER).then(|| format!("integrated past t = {WARN_AFTER}"))
    }
    fn take_warning(&mut self) -> Option<&'static str> {
        (self.time >= WARN_AFTER).then_some("stepped past the warning time")
    }
    fn do_step(&mut self, t: f64, h: f64) -> Result<(), ModelError> {
        if h > MAX_STEP {
            return Err(ModelError::discard(SpringError::StepTooLong(h)));
        }
        if self.fail {
            return Err(ModelError::failed(SpringError::Solver(t)));
        }
        // Classical RK4 with sub-steps of at most 1 ms.
        let n = (h / 1e-3).ceil().max(1.0) as usize;
        let dt = h / n as f64;
        for _ in 0..n {
            let f = |x: f64, v: f64| (v, self.accel(x, v));
            let (x, v) = (self.x, self.v);
            let k1 = f(x, v);
            let k2 = f(x + dt / 2.0 * k1.0, v + dt / 2.0 * k1.1);
            let k3 = f(x + dt / 2.0 * k2.0, v + dt / 2.0 * k2.1);
            let k4 = f(x + dt * k3.0, v + dt * k3.1);
            self.x += dt / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0);
            self.v += dt / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1);
        }
        self.time = t + h;
        self.steps += 1;
        Ok(())
    }
    fn reset(&mut self) -> Result<(), ModelError> {
        *self = Spring::start(std::mem::take(&mut self.resources));
        Ok(())
    }
    /// Everything but `resources` (instantiate's), behind a version of its own.
    fn save_state(&self, out: &mut Vec<u8>) {
        let mut w = Writer::new(out);
        w.u32(1);
        for v in [self.time, self.x, self.v, self.k, self.d, self.u] {
            w.f64(v);
        }
        w.u32(self.steps as u32);
        w.bool(self.crash);
        w.bool(self.fail);
        w.str(&self.label);
    }
    fn load_state(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        let mut r = Reader::new(bytes);
        let version = r.u32("spring state version")?;
        if version != 1 {
            return Err(DecodeError::invalid(SpringError::Version(version)));
        }
        let [time, x, v, k, d, u] = r.f64_array::<6>("spring reals")?;
        let steps = r.u32("steps")? as i32;
        let crash = r.bool("crash")?;
        let fail = r.bool("fail")?;
        let label = r.str("label")?.to_owned();
        r.finish("spring state")?;
        *self =
            Spring { resources: std::mem::take(&mut self.resources), time, x, v, k, d, u, steps, crash, fail, label };
        Ok(())
    }
}
