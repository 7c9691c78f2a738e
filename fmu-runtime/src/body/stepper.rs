//! Co-Simulation's step machinery: the exact transitions, the reference the coupled one was made
//! for, the inputs the last step ended with, the step's scratch and its warning.

use super::inputs::SteppedInputs;
use super::step_workspace::StepWorkspace;
use super::{CouplingReference, term_count};
use crate::coupled_propagator::CoupledPropagator;
use crate::propagator::ModalPropagator;
use crate::reduced::ReducedBody;

/// What a [`FlexibleBody`](super::FlexibleBody) keeps between Co-Simulation steps beyond its
/// coordinates and inputs: the transitions (expensive to make, so kept while the step size,
/// damping and coupling they were made for hold), the coupling reference and the stepped inputs
/// (which a saved state carries, as later steps depend on them), and the scratch a step works in.
/// `f64` only; a body in dual numbers holds an empty one (stepping is not differentiated).
#[derive(Debug, Clone)]
pub(super) struct Stepper {
    pub(super) propagator: ModalPropagator,
    /// Exact transition of the coupled modes (mounted bodies with rotation or stiffening terms).
    pub(super) coupled: CoupledPropagator,
    /// The coefficients of the coupling `coupled` was made for, where known (every renewal sets
    /// them).
    pub(super) reference_coef: Vec<f64>,
    pub(super) reference_coef_known: bool,
    /// The inputs of the last step, to move the algebraic modes when they change.
    pub(super) stepped: SteppedInputs,
    /// The step's scratch (its start, to undo it; the coupled propagator's workspace; ...),
    /// allocated here once and lent to the step's functions. Not state.
    pub(super) work: StepWorkspace,
    /// A warning of the last step for the host's log.
    pub(super) warning: Option<&'static str>,
}

impl Stepper {
    /// The machinery of a body at rest: nothing stepped yet.
    pub(super) fn for_body(body: &ReducedBody) -> Self {
        let n = body.n_modes();
        let nf = body.flanges.len();
        Self {
            propagator: ModalPropagator::with_modes(n),
            coupled: if body.modes_couple() { CoupledPropagator::with_modes(n) } else { CoupledPropagator::default() },
            reference_coef: vec![0.0; term_count(nf)],
            reference_coef_known: false,
            stepped: SteppedInputs::new(nf),
            work: StepWorkspace::for_body(body),
            warning: None,
        }
    }

    /// The empty machinery of a body that does not step (the dual copy).
    pub(super) fn none() -> Self {
        Self {
            propagator: ModalPropagator::with_modes(0),
            coupled: CoupledPropagator::default(),
            reference_coef: Vec::new(),
            reference_coef_known: false,
            stepped: SteppedInputs::default(),
            work: StepWorkspace::default(),
            warning: None,
        }
    }

    /// The coupling the exact coupled transition was last made for, as a saved state holds it.
    pub(super) fn coupling_reference(&self) -> Option<CouplingReference> {
        self.coupled.key().map(|(h, alpha, beta)| {
            let (c_d, c_k) = self.coupled.reference();
            let coef = self.reference_coef_known.then(|| self.reference_coef.clone());
            CouplingReference { h, alpha, beta, c_d: c_d.to_vec(), c_k: c_k.to_vec(), coef }
        })
    }
}
