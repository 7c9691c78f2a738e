//! The C functions of the FMI 2.0 API (fmi2Functions.h) an FMU's binary must export for the
//! interfaces its modelDescription.xml declares. Importers resolve every function of an
//! interface when they load the binary (FMPy does, and fails on the first one missing), even
//! those a capability flag says are unsupported, so a binary without one is not an FMU.

/// Functions of both interfaces.
pub const COMMON: [&str; 25] = [
    "fmi2GetTypesPlatform",
    "fmi2GetVersion",
    "fmi2SetDebugLogging",
    "fmi2Instantiate",
    "fmi2FreeInstance",
    "fmi2SetupExperiment",
    "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode",
    "fmi2Terminate",
    "fmi2Reset",
    "fmi2GetReal",
    "fmi2GetInteger",
    "fmi2GetBoolean",
    "fmi2GetString",
    "fmi2SetReal",
    "fmi2SetInteger",
    "fmi2SetBoolean",
    "fmi2SetString",
    "fmi2GetFMUstate",
    "fmi2SetFMUstate",
    "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize",
    "fmi2SerializeFMUstate",
    "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative",
];

/// Model Exchange only.
pub const MODEL_EXCHANGE: [&str; 10] = [
    "fmi2EnterEventMode",
    "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode",
    "fmi2CompletedIntegratorStep",
    "fmi2SetTime",
    "fmi2SetContinuousStates",
    "fmi2GetDerivatives",
    "fmi2GetEventIndicators",
    "fmi2GetContinuousStates",
    "fmi2GetNominalsOfContinuousStates",
];

/// Co-Simulation only.
pub const CO_SIMULATION: [&str; 9] = [
    "fmi2SetRealInputDerivatives",
    "fmi2GetRealOutputDerivatives",
    "fmi2DoStep",
    "fmi2CancelStep",
    "fmi2GetStatus",
    "fmi2GetRealStatus",
    "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus",
    "fmi2GetStringStatus",
];

/// The functions a binary must export for the interfaces declared in `model_description` (the
/// XML this builder writes: its `<ModelExchange` and `<CoSimulation` elements).
pub fn required(model_description: &str) -> Vec<&'static str> {
    let mut functions = COMMON.to_vec();
    if model_description.contains("<ModelExchange") {
        functions.extend(MODEL_EXCHANGE);
    }
    if model_description.contains("<CoSimulation") {
        functions.extend(CO_SIMULATION);
    }
    functions
}

/// Both interfaces: every FMU this builder writes declares both.
pub fn model_exchange_and_co_simulation() -> Vec<&'static str> {
    [&COMMON[..], &MODEL_EXCHANGE[..], &CO_SIMULATION[..]].concat()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_interfaces_declared_decide_the_functions() {
        assert_eq!(model_exchange_and_co_simulation().len(), 44);
        let both = "<fmiModelDescription><ModelExchange modelIdentifier=\"B\"/><CoSimulation modelIdentifier=\"B\"/>";
        assert_eq!(required(both), model_exchange_and_co_simulation());
        let cs = required("<fmiModelDescription><CoSimulation modelIdentifier=\"B\"/>");
        assert!(cs.contains(&"fmi2DoStep") && !cs.contains(&"fmi2GetDerivatives"));
        assert_eq!(cs.len(), 34);
    }
}
