//! The scratch of a Co-Simulation step: what the step keeps to undo itself, the quasi-static
//! shift's copies, the coupled step's loads and coupling at the step's end, the free body's
//! substep copies, and the coupled propagator's [`Workspace`]. Allocated once with the body
//! (sized by its modes and flanges), taken out by `step` and lent as `&mut` down the functions
//! that need it, so their signatures say that a step allocates nothing.
//!
//! Scratch, not state: every step writes what it reads here before reading it (the zero load
//! rate excepted, which nothing writes), so a saved FMU state leaves it out and a copy of the body
//! (an FMU state restored by cloning) has buffers of its own, whatever they hold.

use super::coupling_terms::term_count;
use super::inputs::SteppedInputs;
use super::{
    BodyInputs, Coordinates, Coupling, FlangeLoad, FrameState, HostMount, InitialFrame, InputRates, MountMotion,
    Parameters,
};
use crate::coupled_propagator::CoupledPropagator;
use crate::reduced::ReducedBody;
use crate::workspace::Workspace;

/// Everything of the step's scratch, one part per path through it.
#[derive(Debug, Clone, Default)]
pub(super) struct StepWorkspace {
    /// The modes and force flanges it was made for: a step checks them before using it.
    modes: usize,
    flanges: usize,
    pub(super) start: StepStart,
    pub(super) jump: JumpWork,
    /// Sized for a mounted body only (empty for a free one).
    pub(super) coupled: CoupledWork,
    /// Sized for a free-floating body only (empty for a mounted one).
    pub(super) free: FreeWork,
}

impl StepWorkspace {
    /// The workspace of a body's steps; the coupled propagator's part only where the body can
    /// couple its modes (a mounted body with rotation or stiffening terms).
    pub(super) fn for_body(body: &ReducedBody) -> Self {
        let (n, flanges) = (body.n_modes(), body.flanges.len());
        let couples = body.modes_couple();
        Self {
            modes: n,
            flanges,
            start: StepStart::new(n, flanges, body.free_floating),
            jump: JumpWork::new(n),
            coupled: if body.free_floating { CoupledWork::default() } else { CoupledWork::new(n, flanges, couples) },
            free: if body.free_floating { FreeWork::new(n) } else { FreeWork::default() },
        }
    }

    /// Whether it was made for a body of `n` modes and `flanges` force flanges. A body's own
    /// always is; the check turns any other (the empty one a step leaves while it runs) into a
    /// refused step instead of an out-of-bounds panic.
    pub(super) fn fits(&self, n: usize, flanges: usize) -> bool {
        self.modes == n && self.flanges == flanges
    }
}

/// What a step changes, kept from its start, so that a step that is not taken leaves the body as
/// it was: the host can read it, save it, or restore an earlier state and go on. The body's own
/// parts, copied whole (their unchanging fields along: one copy, no list of fields to keep in
/// step with what a step writes).
#[derive(Debug, Clone)]
pub(super) struct StepStart {
    pub(super) coords: Coordinates,
    pub(super) inputs: BodyInputs,
    pub(super) stepped: SteppedInputs,
}

impl Default for StepStart {
    fn default() -> Self {
        Self {
            coords: Coordinates { q: Vec::new(), qd: Vec::new(), frame: None },
            inputs: BodyInputs {
                mount: MountMotion::default(),
                loads: Vec::new(),
                params: Parameters { g: [0.0; 3], alpha: 0.0, beta: 0.0 },
                initial_frame: InitialFrame::default(),
                rates: InputRates::default(),
                host: HostMount::default(),
            },
            stepped: SteppedInputs::default(),
        }
    }
}

impl StepStart {
    fn new(n: usize, flanges: usize, free_floating: bool) -> Self {
        Self {
            coords: Coordinates { q: vec![0.0; n], qd: vec![0.0; n], frame: free_floating.then(FrameState::default) },
            inputs: BodyInputs {
                loads: vec![FlangeLoad::default(); flanges],
                rates: InputRates::held(flanges),
                ..Self::default().inputs
            },
            stepped: SteppedInputs::new(flanges),
        }
    }
}

/// Copies of the quasi-static shift across a load change (`input_jump`): the body's q, q' before
/// it and the algebraic modes' equilibrium under the old inputs (n each).
#[derive(Debug, Clone, Default)]
pub(super) struct JumpWork {
    pub(super) q: Vec<f64>,
    pub(super) qd: Vec<f64>,
    pub(super) equilibrium: Vec<f64>,
}

impl JumpWork {
    pub(super) fn new(n: usize) -> Self {
        Self { q: vec![0.0; n], qd: vec![0.0; n], equilibrium: vec![0.0; n] }
    }
}

/// Workspace of a mounted body's step with coupling terms: the inputs and coupling at the
/// step's end and their midpoint, and the coupled propagator's scratch.
#[derive(Debug, Clone, Default)]
pub(super) struct CoupledWork {
    /// The predictor-corrector's loads (n each).
    pub(super) f0: Vec<f64>,
    pub(super) f1: Vec<f64>,
    /// The coupling at the step's midpoint (ramped inputs, n x n each) and a zero load rate
    /// (held inputs, n; never written).
    pub(super) c_d_mid: Vec<f64>,
    pub(super) c_k_mid: Vec<f64>,
    pub(super) zeros: Vec<f64>,
    /// The coefficients of the midpoint coupling (see `coupling_terms`).
    pub(super) coef_mid: Vec<f64>,
    pub(super) loads_end: Vec<FlangeLoad>,
    pub(super) coupling_end: Coupling<f64>,
    /// The exponential's and the advance's scratch, [`CoupledPropagator::workspace_req`] values
    /// (none for a body whose modes never couple).
    pub(super) propagator: Workspace,
}

impl CoupledWork {
    fn new(n: usize, flanges: usize, couples: bool) -> Self {
        Self {
            f0: vec![0.0; n],
            f1: vec![0.0; n],
            c_d_mid: vec![0.0; n * n],
            c_k_mid: vec![0.0; n * n],
            zeros: vec![0.0; n],
            coef_mid: vec![0.0; term_count(flanges)],
            loads_end: vec![FlangeLoad::default(); flanges],
            // its coefficients only: the step's drift and a renewal's midpoint need no more
            coupling_end: Coupling { coef: vec![0.0; term_count(flanges)], ..Coupling::default() },
            propagator: Workspace::new(CoupledPropagator::workspace_req(if couples { n } else { 0 })),
        }
    }
}

/// Workspace of a free-floating body's step: the substep's start state and its two coupling
/// loads (n each).
#[derive(Debug, Clone, Default)]
pub(super) struct FreeWork {
    pub(super) q0: Vec<f64>,
    pub(super) qd0: Vec<f64>,
    pub(super) load0: Vec<f64>,
    pub(super) load1: Vec<f64>,
}

impl FreeWork {
    fn new(n: usize) -> Self {
        Self { q0: vec![0.0; n], qd0: vec![0.0; n], load0: vec![0.0; n], load1: vec![0.0; n] }
    }
}

#[cfg(test)]
mod tests {
    use super::super::FlexibleBody;
    use crate::reduced::{RotationTerms, two_mode_body};
    use std::sync::Arc;

    /// A copy of a body (an FMU state restored by cloning) steps in a workspace of its own: the
    /// two stepped in turn with different loads end bit for bit where each ends stepped alone,
    /// through the coupled propagator's exponentials and the step's undo copies.
    #[test]
    fn a_clone_steps_in_its_own_workspace() {
        let mut reduced = two_mode_body();
        let g = vec![0.0, 0.4, -0.4, 0.0, 0.0, 0.1, -0.1, 0.0, 0.0, 0.0, 0.0, 0.0];
        let o_mat: Vec<f64> = (0..36).map(|k| if k % 5 == 0 { 0.3 } else { 0.01 }).collect();
        reduced.rotation = Some(RotationTerms { g, o_mat, o_vec: vec![0.01; 18] });
        let mut a = FlexibleBody::new(Arc::new(reduced));
        a.mount_mut().w = [0.0, 0.0, 20.0];
        let mut b = a.clone();
        let scratch = |x: &mut FlexibleBody| x.stepper.work.coupled.propagator.carve([1]).unwrap()[0].as_ptr();
        assert_ne!(scratch(&mut a), scratch(&mut b));
        assert_ne!(a.stepper.work.start.coords.q.as_ptr(), b.stepper.work.start.coords.q.as_ptr());
        let (mut alone_a, mut alone_b) = (a.clone(), b.clone());
        let run = |x: &mut FlexibleBody, f: f64| {
            x.load_mut(0).f = [0.0, f, 1.0];
            x.mount_rate_mut().w = [0.0, 0.0, f];
            x.step(1e-3).unwrap();
        };
        for k in 0..30 {
            let (fa, fb) = (1.0 + k as f64, -3.0 * k as f64);
            run(&mut a, fa);
            run(&mut b, fb);
            run(&mut alone_a, fa);
        }
        for k in 0..30 {
            run(&mut alone_b, -3.0 * k as f64);
        }
        assert_eq!((a.q(), a.qd()), (alone_a.q(), alone_a.qd()));
        assert_eq!((b.q(), b.qd()), (alone_b.q(), alone_b.qd()));
        assert_ne!(a.q(), b.q());
    }
}
