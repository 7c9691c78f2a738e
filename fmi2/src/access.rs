//! Which variables fmi2SetXXX may change in which state (FMI 2.0.x, footnotes of the
//! state-machine tables for fmi2SetReal etc.).

use super::state::ModelState;
use super::{Causality, Initial, VarInfo, Variability};

/// The `initial` attribute in effect when modelDescription.xml omits it
/// (FMI 2.0.x section 2.2.7, table of default values).
pub fn effective_initial(info: &VarInfo) -> Option<Initial> {
    if info.initial.is_some() {
        return info.initial;
    }
    match (info.causality, info.variability) {
        // Inputs and the independent variable carry no `initial`.
        (Causality::Input | Causality::Independent, _) => None,
        (_, Variability::Constant) | (Causality::Parameter, _) => Some(Initial::Exact),
        _ => Some(Initial::Calculated),
    }
}

/// A variable that may not be set in the instance's present state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NotSettable {
    pub causality: Causality,
    pub variability: Variability,
    /// The `initial` in effect (the default where modelDescription.xml omits it).
    pub initial: Option<Initial>,
    pub state: ModelState,
}

impl std::fmt::Display for NotSettable {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "a variable with causality {:?}, variability {:?}, initial ", self.causality, self.variability)?;
        match self.initial {
            Some(i) => write!(f, "{i:?}")?,
            None => f.write_str("none")?,
        }
        write!(f, " cannot be set in state {:?}", self.state)
    }
}

impl std::error::Error for NotSettable {}

/// `Ok` if the variable may be set in `state`; `Err` explains why not.
pub fn check_settable(info: &VarInfo, state: ModelState) -> Result<(), NotSettable> {
    let initial = effective_initial(info);
    let is_input = info.causality == Causality::Input;
    let allowed = info.variability != Variability::Constant
        && info.causality != Causality::Independent
        && match state {
            // Start values: whatever the model does not calculate itself.
            ModelState::Instantiated => is_input || matches!(initial, Some(Initial::Exact | Initial::Approx)),
            // Approx values are only guesses for the initialization solver, fixed by now.
            ModelState::InitializationMode => is_input || initial == Some(Initial::Exact),
            ModelState::EventMode | ModelState::StepComplete => {
                is_input || (info.causality == Causality::Parameter && info.variability == Variability::Tunable)
            }
            // Only continuous inputs may change between events.
            ModelState::ContinuousTimeMode => is_input && info.variability == Variability::Continuous,
            _ => false,
        };
    if allowed {
        Ok(())
    } else {
        Err(NotSettable { causality: info.causality, variability: info.variability, initial, state })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::VarType;

    fn var(causality: Causality, variability: Variability, initial: Option<Initial>) -> VarInfo {
        VarInfo { var_type: VarType::Real, causality, variability, initial }
    }

    #[test]
    fn fixed_parameter_only_before_initialization_ends() {
        let k = var(Causality::Parameter, Variability::Fixed, None);
        assert!(check_settable(&k, ModelState::Instantiated).is_ok());
        assert!(check_settable(&k, ModelState::InitializationMode).is_ok());
        assert!(check_settable(&k, ModelState::StepComplete).is_err());
        assert!(check_settable(&k, ModelState::EventMode).is_err());
    }

    #[test]
    fn tunable_parameter_and_inputs_later_too() {
        let p = var(Causality::Parameter, Variability::Tunable, Some(Initial::Exact));
        assert!(check_settable(&p, ModelState::StepComplete).is_ok());
        assert!(check_settable(&p, ModelState::EventMode).is_ok());
        assert!(check_settable(&p, ModelState::ContinuousTimeMode).is_err());
        let u = var(Causality::Input, Variability::Continuous, None);
        for s in [
            ModelState::Instantiated,
            ModelState::InitializationMode,
            ModelState::EventMode,
            ModelState::ContinuousTimeMode,
            ModelState::StepComplete,
        ] {
            assert!(check_settable(&u, s).is_ok(), "{s:?}");
        }
        assert!(check_settable(&u, ModelState::Terminated).is_err());
        let d = var(Causality::Input, Variability::Discrete, None);
        assert!(check_settable(&d, ModelState::ContinuousTimeMode).is_err());
    }

    #[test]
    fn calculated_and_constant_never() {
        let y = var(Causality::Output, Variability::Continuous, None);
        let c = var(Causality::Local, Variability::Constant, Some(Initial::Exact));
        let cp = var(Causality::CalculatedParameter, Variability::Fixed, None);
        for s in [ModelState::Instantiated, ModelState::InitializationMode, ModelState::StepComplete] {
            assert!(check_settable(&y, s).is_err());
            assert!(check_settable(&c, s).is_err());
            assert!(check_settable(&cp, s).is_err());
        }
        // A state with a start value may be set before initialization.
        let x = var(Causality::Output, Variability::Continuous, Some(Initial::Exact));
        assert!(check_settable(&x, ModelState::Instantiated).is_ok());
        assert!(check_settable(&x, ModelState::StepComplete).is_err());
        let guess = var(Causality::Local, Variability::Continuous, Some(Initial::Approx));
        assert!(check_settable(&guess, ModelState::Instantiated).is_ok());
        assert!(check_settable(&guess, ModelState::InitializationMode).is_err());
    }
}
