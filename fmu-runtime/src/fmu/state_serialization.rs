//! The body's part of a serialized FMU state (fmi2SerializeFMUstate, fmi2GetFMUstate).

use super::BodyFmu;
use super::error::VariableError;
use super::values::{admissible, real_value};
use crate::body::{
    BodyError, BodyInputs, BodyState, Coordinates, CouplingReference, FlangeLoad, FrameState, HostMount, InitialFrame,
    InputRates, MountMotion, OutOfRange, Parameters, SteppedState, term_count,
};
use fmi2::bytes::{DecodeError, Reader, Writer};
use fmi2::{Causality, VarType};
use std::fmt;

/// Version of the body's part of a serialized FMU state (the layer has its own).
/// Layout, little-endian: version (u32), modes n (u32), force flanges m (u32), free-floating
/// (u8 0/1), static_start (u8 0/1), then f64s: mount r[3] R[9] (row-major) v[3] w[3] a[3] z[3];
/// per force flange f[3] t[3]; g[3], alpha, beta; q[n]; qd[n]; initial r[3] phi[3] v[3] w[3];
/// free-floating only: frame r[3] quaternion[4] v[3] W[3]; then the input derivatives set for
/// the next step: flag (u8 0/1), mount rates r[3] R[9] v[3] w[3] a[3] z[3], per force flange
/// f[3] t[3]; since version 2 the coupled transition's reference: flag (u8), then h, alpha,
/// beta, C_d[n*n], C_k[n*n]; since version 3 the loads the last step ended with: flag (u8),
/// then mount a[3] z[3], per force flange f[3] t[3], g[3], alpha, beta; since version 4 the
/// reference's C_k is followed by a flag (u8) and, where set, its coupling coefficients (15 + 6
/// per force flange: w[3] z[3], w_i w_j for ij = 11 12 13 22 23 33, a_B[3], per force flange
/// the body-frame f[3] t[3]).
/// Sizes are checked against the body before any array is read.
pub const BODY_STATE_VERSION: u32 = 4;

/// Why well-formed state bytes are refused for this body (the reader's own errors name the
/// field); carried by [`DecodeError::Invalid`].
#[derive(Clone, PartialEq)]
pub enum BodyStateError {
    /// Written by a newer runtime.
    NewerVersion(u32),
    VersionZero,
    /// The state of a body with other sizes.
    OtherBody {
        n: usize,
        nf: usize,
        free: bool,
        n_body: usize,
        nf_body: usize,
        free_body: bool,
    },
    /// The state does not fit the body (its caches, coupling reference or stepped loads).
    Body(BodyError),
    /// A restored input or parameter that cannot be read.
    Value(VariableError),
    /// A restored input or parameter outside the range fmi2SetReal accepts.
    Inadmissible {
        name: String,
        value: f64,
        source: OutOfRange,
    },
}

impl fmt::Display for BodyStateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let free_floating = |free: bool| if free { ", free-floating" } else { "" };
        match self {
            BodyStateError::NewerVersion(version) => write!(
                f,
                "body state version {version} was written by a newer runtime (this one reads up to {BODY_STATE_VERSION})"
            ),
            BodyStateError::VersionZero => f.write_str("body state version 0 is invalid"),
            BodyStateError::OtherBody { n, nf, free, n_body, nf_body, free_body } => write!(
                f,
                "the state is of a body with {n} modes, {nf} force flanges{}; this one has {n_body}, {nf_body}{}",
                free_floating(*free),
                free_floating(*free_body),
            ),
            BodyStateError::Body(e) => fmt::Display::fmt(e, f),
            BodyStateError::Value(e) => fmt::Display::fmt(e, f),
            BodyStateError::Inadmissible { name, value, source } => write!(f, "{name} = {value}: {source}"),
        }
    }
}

impl std::error::Error for BodyStateError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            BodyStateError::Body(e) => e.source(),
            BodyStateError::Value(e) => e.source(),
            BodyStateError::Inadmissible { source, .. } => Some(source),
            _ => None,
        }
    }
}

impl BodyFmu {
    pub(super) fn write_state(&self, out: &mut Vec<u8>) {
        let s = self.body.state();
        let mut w = Writer::new(out);
        w.u32(BODY_STATE_VERSION);
        w.u32(s.coordinates.q.len() as u32);
        w.u32(s.inputs.loads.len() as u32);
        w.bool(s.coordinates.frame.is_some());
        w.bool(self.static_start);
        write_mount(&mut w, &s.inputs.mount);
        write_loads(&mut w, &s.inputs.loads);
        write_parameters(&mut w, &s.inputs.params);
        w.f64s(&s.coordinates.q);
        w.f64s(&s.coordinates.qd);
        let i = &s.inputs.initial_frame;
        for v in [&i.r, &i.phi, &i.v, &i.w] {
            w.f64s(v);
        }
        if let Some(f) = &s.coordinates.frame {
            write_frame_state(&mut w, f);
        }
        w.bool(s.inputs.rates.any);
        write_mount(&mut w, &s.inputs.rates.mount);
        write_loads(&mut w, &s.inputs.rates.loads);
        w.bool(s.coupling_reference.is_some());
        if let Some(c) = &s.coupling_reference {
            w.f64(c.h);
            w.f64(c.alpha);
            w.f64(c.beta);
            w.f64s(&c.c_d);
            w.f64s(&c.c_k);
            w.bool(c.coef.is_some());
            if let Some(coef) = &c.coef {
                w.f64s(coef);
            }
        }
        w.bool(s.stepped_inputs.is_some());
        if let Some(st) = &s.stepped_inputs {
            w.f64s(&st.a);
            w.f64s(&st.z);
            write_loads(&mut w, &st.loads);
            write_parameters(&mut w, &st.params);
        }
    }

    pub(super) fn read_state(&mut self, bytes: &[u8]) -> Result<(), DecodeError> {
        let mut r = Reader::new(bytes);
        let version = r.u32("body state version")?;
        if version > BODY_STATE_VERSION {
            return Err(DecodeError::invalid(BodyStateError::NewerVersion(version)));
        }
        if version == 0 {
            return Err(DecodeError::invalid(BodyStateError::VersionZero));
        }
        let n = r.u32("number of modes")? as usize;
        let nf = r.u32("number of force flanges")? as usize;
        let free = r.bool("free-floating flag")?;
        let static_start = r.bool("static_start")?;
        // sizes first: the bytes must describe this body before anything is read by them
        let (n_body, nf_body, free_body) = (self.body.n_modes(), self.body.loads().len(), self.body.frame().is_some());
        if (n, nf, free) != (n_body, nf_body, free_body) {
            return Err(DecodeError::invalid(BodyStateError::OtherBody { n, nf, free, n_body, nf_body, free_body }));
        }
        let state = read_body_state(&mut r, version, n, nf, free)?;
        r.finish("body state")?;
        self.body = self.body.with_state(state).map_err(|e| DecodeError::invalid(BodyStateError::Body(e)))?;
        self.static_start = static_start;
        self.check_restored_knowns().map_err(DecodeError::invalid)
    }

    /// What the host can set, restored from bytes, obeys the rule fmi2SetReal applies.
    fn check_restored_knowns(&mut self) -> Result<(), BodyStateError> {
        let knowns =
            self.table.variables.iter().filter(|v| matches!(v.causality, Causality::Input | Causality::Parameter));
        for v in knowns {
            if v.var_type == VarType::Real {
                let value = real_value(&mut self.body, v.quantity).map_err(BodyStateError::Value)?;
                admissible(v.quantity, value).map_err(|source| BodyStateError::Inadmissible {
                    name: v.name.clone(),
                    value,
                    source,
                })?;
            }
        }
        Ok(())
    }
}

/// The body's state after the header, its sizes checked.
fn read_body_state(r: &mut Reader, version: u32, n: usize, nf: usize, free: bool) -> Result<BodyState, DecodeError> {
    let mount = read_mount(r, "")?;
    let loads = read_loads(r, nf, "flange force", "flange torque")?;
    let params = Parameters { g: r.f64_array("g")?, alpha: r.f64("damping.alpha")?, beta: r.f64("damping.beta")? };
    let mut q = vec![0.0; n];
    r.f64s_into(&mut q, "q")?;
    let mut qd = vec![0.0; n];
    r.f64s_into(&mut qd, "qd")?;
    let initial_frame = InitialFrame {
        r: r.f64_array("initial.r")?,
        phi: r.f64_array("initial.phi")?,
        v: r.f64_array("initial.v")?,
        w: r.f64_array("initial.w")?,
    };
    let frame = if free { Some(read_frame_state(r)?) } else { None };
    let any = r.bool("input rates flag")?;
    let rate_mount = read_mount(r, " rate")?;
    let rate_loads = read_loads(r, nf, "flange force rate", "flange torque rate")?;
    let coupling_reference = if version >= 2 && r.bool("coupling reference flag")? {
        Some(read_coupling_reference(r, version, n, nf)?)
    } else {
        None
    };
    let stepped_inputs =
        if version >= 3 && r.bool("stepped inputs flag")? { Some(read_stepped_inputs(r, nf)?) } else { None };
    let rates = InputRates { mount: rate_mount, loads: rate_loads, any };
    let coordinates = Coordinates { q, qd, frame };
    let inputs = BodyInputs { mount, loads, params, initial_frame, rates, host: HostMount::default() };
    Ok(BodyState { coordinates, inputs, coupling_reference, stepped_inputs })
}

fn write_mount(w: &mut Writer, m: &MountMotion) {
    for v in [&m.r[..], &m.rot, &m.v, &m.w, &m.a, &m.z] {
        w.f64s(v);
    }
}

/// The mount's motion or (`suffix` " rate") its rates.
fn read_mount(r: &mut Reader, suffix: &str) -> Result<MountMotion, DecodeError> {
    let what = |name: &str| format!("mount {name}{suffix}");
    Ok(MountMotion {
        r: r.f64_array(&what("r"))?,
        rot: r.f64_array(&what("R"))?,
        v: r.f64_array(&what("v"))?,
        w: r.f64_array(&what("w"))?,
        a: r.f64_array(&what("a"))?,
        z: r.f64_array(&what("z"))?,
    })
}

/// Force and torque of every force flange, in flange order.
fn write_loads(w: &mut Writer, loads: &[FlangeLoad]) {
    for l in loads {
        w.f64s(&l.f);
        w.f64s(&l.t);
    }
}

fn read_loads(r: &mut Reader, nf: usize, force: &str, torque: &str) -> Result<Vec<FlangeLoad>, DecodeError> {
    let mut loads = Vec::with_capacity(nf);
    for _ in 0..nf {
        loads.push(FlangeLoad { f: r.f64_array(force)?, t: r.f64_array(torque)? });
    }
    Ok(loads)
}

fn write_parameters(w: &mut Writer, p: &Parameters) {
    w.f64s(&p.g);
    w.f64(p.alpha);
    w.f64(p.beta);
}

fn write_frame_state(w: &mut Writer, f: &FrameState) {
    w.f64s(&f.r);
    w.f64s(&f.quat);
    w.f64s(&f.v);
    w.f64s(&f.w_body);
}

fn read_frame_state(r: &mut Reader) -> Result<FrameState, DecodeError> {
    Ok(FrameState {
        r: r.f64_array("frame r")?,
        quat: r.f64_array("frame quaternion")?,
        v: r.f64_array("frame v")?,
        w_body: r.f64_array("frame W")?,
    })
}

fn read_coupling_reference(
    r: &mut Reader,
    version: u32,
    n: usize,
    nf: usize,
) -> Result<CouplingReference, DecodeError> {
    let (h, alpha, beta) =
        (r.f64("coupling reference h")?, r.f64("coupling reference alpha")?, r.f64("coupling reference beta")?);
    let mut c_d = vec![0.0; n * n];
    r.f64s_into(&mut c_d, "coupling reference C_d")?;
    let mut c_k = vec![0.0; n * n];
    r.f64s_into(&mut c_k, "coupling reference C_k")?;
    let coef = if version >= 4 && r.bool("coupling reference coefficients flag")? {
        let mut coef = vec![0.0; term_count(nf)];
        r.f64s_into(&mut coef, "coupling reference coefficients")?;
        Some(coef)
    } else {
        None
    };
    Ok(CouplingReference { h, alpha, beta, c_d, c_k, coef })
}

fn read_stepped_inputs(r: &mut Reader, nf: usize) -> Result<SteppedState, DecodeError> {
    let (a, z) = (r.f64_array("stepped mount a")?, r.f64_array("stepped mount z")?);
    let loads = read_loads(r, nf, "stepped force", "stepped torque")?;
    let params = Parameters {
        g: r.f64_array("stepped g")?,
        alpha: r.f64("stepped damping.alpha")?,
        beta: r.f64("stepped damping.beta")?,
    };
    Ok(SteppedState { a, z, loads, params })
}

/// The message, as the FMU logs it (see `body::BodyError`: no derived dump in the binary).
impl std::fmt::Debug for BodyStateError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        std::fmt::Display::fmt(self, f)
    }
}
