//! The FMI 2.0 state machine: which function may be called in which state
//! (standard 2.0.x, tables in sections 3.2.3 (Model Exchange) and 4.2.4 (Co-Simulation)).
//! The tables are encoded as bit masks so the check on every call is one AND.
#![allow(non_upper_case_globals)]

use std::fmt;

use super::Interface;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u16)]
pub enum ModelState {
    Instantiated = 1 << 0,
    InitializationMode = 1 << 1,
    EventMode = 1 << 2,
    ContinuousTimeMode = 1 << 3,
    StepComplete = 1 << 4,
    /// Never entered: fmi2DoStep is synchronous and never returns fmi2Pending.
    /// Kept so the tables (fmi2CancelStep, fmi2GetStatus) read as in the standard.
    StepInProgress = 1 << 5,
    StepFailed = 1 << 6,
    StepCanceled = 1 << 7,
    Terminated = 1 << 8,
    Error = 1 << 9,
    Fatal = 1 << 10,
}

use ModelState::*;

const ALL_STATES: [ModelState; 11] = [
    Instantiated,
    InitializationMode,
    EventMode,
    ContinuousTimeMode,
    StepComplete,
    StepInProgress,
    StepFailed,
    StepCanceled,
    Terminated,
    Error,
    Fatal,
];

impl ModelState {
    /// Stable number of the state in serialized FMU states, independent of the bit masks.
    pub fn code(self) -> u8 {
        match self {
            Instantiated => 0,
            InitializationMode => 1,
            EventMode => 2,
            ContinuousTimeMode => 3,
            StepComplete => 4,
            StepInProgress => 5,
            StepFailed => 6,
            StepCanceled => 7,
            Terminated => 8,
            Error => 9,
            Fatal => 10,
        }
    }

    pub fn from_code(code: u8) -> Option<ModelState> {
        ALL_STATES.into_iter().find(|s| s.code() == code)
    }

    /// Whether fmi2GetFMUstate can have seen an instance of `interface` in this state: the
    /// states of that interface's table, less Fatal (no FMU state functions) and
    /// StepInProgress (never entered).
    pub fn can_be_saved_in(self, interface: Interface) -> bool {
        let states = match interface {
            Interface::ModelExchange => {
                StateMask::of(&[Instantiated, InitializationMode, EventMode, ContinuousTimeMode, Terminated, Error])
            }
            Interface::CoSimulation => StateMask::of(&[
                Instantiated,
                InitializationMode,
                StepComplete,
                StepFailed,
                StepCanceled,
                Terminated,
                Error,
            ]),
        };
        states.contains(self)
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub struct StateMask(u16);

impl StateMask {
    pub const fn of(states: &[ModelState]) -> StateMask {
        let mut bits = 0;
        let mut i = 0;
        while i < states.len() {
            bits |= states[i] as u16;
            i += 1;
        }
        StateMask(bits)
    }

    #[inline]
    pub fn contains(self, state: ModelState) -> bool {
        self.0 & state as u16 != 0
    }
}

impl fmt::Display for StateMask {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut first = true;
        for s in ALL_STATES.into_iter().filter(|s| self.contains(*s)) {
            if !first {
                f.write_str(", ")?;
            }
            write!(f, "{s:?}")?;
            first = false;
        }
        if first {
            f.write_str("none")?;
        }
        Ok(())
    }
}

/// The calling rules of one FMI function.
pub struct FnSpec {
    pub name: &'static str,
    pub allowed: StateMask,
    /// Functions of only one interface are refused on instances of the other.
    pub interface: Option<Interface>,
}

impl FnSpec {
    /// `None` if the call is allowed, else the message to log.
    #[inline]
    pub fn refuse(&self, state: ModelState, interface: Interface) -> Option<String> {
        if let Some(only) = self.interface
            && only != interface
        {
            return Some(format!(
                "{} is a {only:?} function but this instance was instantiated for {interface:?}",
                self.name
            ));
        }
        if self.allowed.contains(state) {
            return None;
        }
        Some(format!("{} called in state {state:?}; allowed in: {}", self.name, self.allowed))
    }
}

const fn common(name: &'static str, allowed: StateMask) -> FnSpec {
    FnSpec { name, allowed, interface: None }
}
const fn me(name: &'static str, allowed: StateMask) -> FnSpec {
    FnSpec { name, allowed, interface: Some(Interface::ModelExchange) }
}
const fn cs(name: &'static str, allowed: StateMask) -> FnSpec {
    FnSpec { name, allowed, interface: Some(Interface::CoSimulation) }
}

/// Every state in which the instance is alive and not corrupted.
const ANY_BUT_FATAL: StateMask = StateMask::of(&[
    Instantiated,
    InitializationMode,
    EventMode,
    ContinuousTimeMode,
    StepComplete,
    StepFailed,
    StepCanceled,
    Terminated,
    Error,
]);
/// fmi2GetXXX: once initialization has begun; in Error "for diagnostics only".
const GETTERS: StateMask = StateMask::of(&[
    InitializationMode,
    EventMode,
    ContinuousTimeMode,
    StepComplete,
    StepFailed,
    StepCanceled,
    Terminated,
    Error,
]);
/// Discrete variables cannot change during continuous-time integration.
const SET_DISCRETE: StateMask = StateMask::of(&[Instantiated, InitializationMode, EventMode, StepComplete]);
const CS_STATUS: StateMask = StateMask::of(&[StepComplete, StepInProgress, StepFailed, Terminated]);

// Common functions.
pub const fmi2SetDebugLogging: FnSpec = common("fmi2SetDebugLogging", ANY_BUT_FATAL);
pub const fmi2SetupExperiment: FnSpec = common("fmi2SetupExperiment", StateMask::of(&[Instantiated]));
pub const fmi2EnterInitializationMode: FnSpec = common("fmi2EnterInitializationMode", StateMask::of(&[Instantiated]));
pub const fmi2ExitInitializationMode: FnSpec =
    common("fmi2ExitInitializationMode", StateMask::of(&[InitializationMode]));
pub const fmi2Terminate: FnSpec =
    common("fmi2Terminate", StateMask::of(&[EventMode, ContinuousTimeMode, StepComplete, StepFailed]));
pub const fmi2Reset: FnSpec = common("fmi2Reset", ANY_BUT_FATAL);
pub const fmi2GetReal: FnSpec = common("fmi2GetReal", GETTERS);
pub const fmi2GetInteger: FnSpec = common("fmi2GetInteger", GETTERS);
pub const fmi2GetBoolean: FnSpec = common("fmi2GetBoolean", GETTERS);
pub const fmi2GetString: FnSpec = common("fmi2GetString", GETTERS);
pub const fmi2SetReal: FnSpec = common(
    "fmi2SetReal",
    StateMask::of(&[Instantiated, InitializationMode, EventMode, ContinuousTimeMode, StepComplete]),
);
pub const fmi2SetInteger: FnSpec = common("fmi2SetInteger", SET_DISCRETE);
pub const fmi2SetBoolean: FnSpec = common("fmi2SetBoolean", SET_DISCRETE);
pub const fmi2SetString: FnSpec = common("fmi2SetString", SET_DISCRETE);
pub const fmi2GetFMUstate: FnSpec = common("fmi2GetFMUstate", ANY_BUT_FATAL);
pub const fmi2SetFMUstate: FnSpec = common("fmi2SetFMUstate", ANY_BUT_FATAL);
pub const fmi2FreeFMUstate: FnSpec = common("fmi2FreeFMUstate", ANY_BUT_FATAL);
pub const fmi2SerializedFMUstateSize: FnSpec = common("fmi2SerializedFMUstateSize", ANY_BUT_FATAL);
pub const fmi2SerializeFMUstate: FnSpec = common("fmi2SerializeFMUstate", ANY_BUT_FATAL);
pub const fmi2DeSerializeFMUstate: FnSpec = common("fmi2DeSerializeFMUstate", ANY_BUT_FATAL);
/// Wherever the getters are (tables of sections 3.2.3 and 4.2.4), Initialization Mode included:
/// hosts solving an algebraic loop through the FMU's feedthrough (OMSimulator's KINSOL) ask for
/// the Jacobian there, at the values the getters give in that mode.
pub const fmi2GetDirectionalDerivative: FnSpec = common("fmi2GetDirectionalDerivative", GETTERS);

// Model Exchange.
pub const fmi2EnterEventMode: FnSpec = me("fmi2EnterEventMode", StateMask::of(&[EventMode, ContinuousTimeMode]));
pub const fmi2NewDiscreteStates: FnSpec = me("fmi2NewDiscreteStates", StateMask::of(&[EventMode]));
pub const fmi2EnterContinuousTimeMode: FnSpec = me("fmi2EnterContinuousTimeMode", StateMask::of(&[EventMode]));
pub const fmi2CompletedIntegratorStep: FnSpec = me("fmi2CompletedIntegratorStep", StateMask::of(&[ContinuousTimeMode]));
pub const fmi2SetTime: FnSpec = me("fmi2SetTime", StateMask::of(&[EventMode, ContinuousTimeMode]));
pub const fmi2SetContinuousStates: FnSpec = me("fmi2SetContinuousStates", StateMask::of(&[ContinuousTimeMode]));
pub const fmi2GetDerivatives: FnSpec =
    me("fmi2GetDerivatives", StateMask::of(&[EventMode, ContinuousTimeMode, Terminated, Error]));
pub const fmi2GetEventIndicators: FnSpec = me(
    "fmi2GetEventIndicators",
    StateMask::of(&[InitializationMode, EventMode, ContinuousTimeMode, Terminated, Error]),
);
pub const fmi2GetContinuousStates: FnSpec = me(
    "fmi2GetContinuousStates",
    StateMask::of(&[InitializationMode, EventMode, ContinuousTimeMode, Terminated, Error]),
);
pub const fmi2GetNominalsOfContinuousStates: FnSpec = me(
    "fmi2GetNominalsOfContinuousStates",
    StateMask::of(&[Instantiated, EventMode, ContinuousTimeMode, Terminated, Error]),
);

// Co-Simulation.
pub const fmi2SetRealInputDerivatives: FnSpec =
    cs("fmi2SetRealInputDerivatives", StateMask::of(&[Instantiated, InitializationMode, StepComplete]));
pub const fmi2GetRealOutputDerivatives: FnSpec =
    cs("fmi2GetRealOutputDerivatives", StateMask::of(&[StepComplete, StepFailed, StepCanceled, Terminated, Error]));
pub const fmi2DoStep: FnSpec = cs("fmi2DoStep", StateMask::of(&[StepComplete]));
pub const fmi2CancelStep: FnSpec = cs("fmi2CancelStep", StateMask::of(&[StepInProgress]));
pub const fmi2GetStatus: FnSpec = cs("fmi2GetStatus", CS_STATUS);
pub const fmi2GetRealStatus: FnSpec = cs("fmi2GetRealStatus", CS_STATUS);
pub const fmi2GetIntegerStatus: FnSpec = cs("fmi2GetIntegerStatus", CS_STATUS);
pub const fmi2GetBooleanStatus: FnSpec = cs("fmi2GetBooleanStatus", CS_STATUS);
pub const fmi2GetStringStatus: FnSpec = cs("fmi2GetStringStatus", CS_STATUS);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refusal_names_state_and_allowed_states() {
        let msg = fmi2DoStep.refuse(Instantiated, Interface::CoSimulation).unwrap();
        assert_eq!(msg, "fmi2DoStep called in state Instantiated; allowed in: StepComplete");
        assert!(fmi2DoStep.refuse(StepComplete, Interface::CoSimulation).is_none());
        assert!(fmi2DoStep.refuse(StepComplete, Interface::ModelExchange).is_some());
        assert!(fmi2GetReal.refuse(Error, Interface::ModelExchange).is_none());
        assert!(fmi2Reset.refuse(Fatal, Interface::ModelExchange).is_some());
    }

    #[test]
    fn state_codes_are_distinct_and_round_trip() {
        for s in ALL_STATES {
            assert_eq!(ModelState::from_code(s.code()), Some(s));
        }
        assert_eq!(ModelState::from_code(11), None);
        assert!(StepComplete.can_be_saved_in(Interface::CoSimulation));
        assert!(!StepComplete.can_be_saved_in(Interface::ModelExchange));
        assert!(!ContinuousTimeMode.can_be_saved_in(Interface::CoSimulation));
        assert!(!Fatal.can_be_saved_in(Interface::CoSimulation));
        assert!(!StepInProgress.can_be_saved_in(Interface::CoSimulation));
    }

    /// The standard's tables allow fmi2GetDirectionalDerivative wherever the getters are,
    /// Initialization Mode included (section 2.1.9), and nowhere else.
    #[test]
    fn directional_derivative_is_allowed_where_the_getters_are() {
        for s in ALL_STATES {
            for i in [Interface::ModelExchange, Interface::CoSimulation] {
                assert_eq!(fmi2GetDirectionalDerivative.refuse(s, i).is_none(), fmi2GetReal.refuse(s, i).is_none());
            }
        }
        for s in [InitializationMode, EventMode, ContinuousTimeMode, Terminated, Error] {
            assert!(fmi2GetDirectionalDerivative.refuse(s, Interface::ModelExchange).is_none(), "{s:?}");
        }
        for s in [InitializationMode, StepComplete, StepFailed, StepCanceled] {
            assert!(fmi2GetDirectionalDerivative.refuse(s, Interface::CoSimulation).is_none(), "{s:?}");
        }
        let msg = fmi2GetDirectionalDerivative.refuse(Instantiated, Interface::CoSimulation).unwrap();
        assert_eq!(
            msg,
            "fmi2GetDirectionalDerivative called in state Instantiated; allowed in: InitializationMode, EventMode, \
             ContinuousTimeMode, StepComplete, StepFailed, StepCanceled, Terminated, Error"
        );
        assert!(fmi2GetDirectionalDerivative.refuse(Fatal, Interface::ModelExchange).is_some());
    }

    /// The FMU state functions may be called in every state but Fatal (and StepInProgress,
    /// which is never entered): tables of sections 3.2.3 and 4.2.4.
    #[test]
    fn fmu_state_functions_are_allowed_wherever_a_state_can_be_saved() {
        for f in [
            &fmi2GetFMUstate,
            &fmi2SetFMUstate,
            &fmi2FreeFMUstate,
            &fmi2SerializedFMUstateSize,
            &fmi2SerializeFMUstate,
            &fmi2DeSerializeFMUstate,
        ] {
            for s in ALL_STATES {
                for i in [Interface::ModelExchange, Interface::CoSimulation] {
                    if s.can_be_saved_in(i) {
                        assert!(f.refuse(s, i).is_none(), "{} in {s:?}", f.name);
                    }
                }
            }
            assert!(f.refuse(Fatal, Interface::CoSimulation).is_some());
            assert!(f.refuse(StepInProgress, Interface::CoSimulation).is_some());
        }
    }
}
