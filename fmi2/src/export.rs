//! `export_fmi2!`: the 44 C symbols of FMI 2.0, each a thin forwarder to `api`.
//!
//! Symbols are unprefixed (binary FMU, no FMI2_FUNCTION_PREFIX), so a crate may invoke
//! the macro only once. Types are spelled with full `$crate` paths so the invocation
//! site needs no imports.

/// Emit all FMI 2.0 entry points for the model type `$model` (which implements
/// `fmi2::Model`). Invoke once, at the crate root of the cdylib that is the FMU's binary:
///
/// ```ignore
/// // lib.rs of the cdylib crate, which depends on fmi2
/// fmi2::export_fmi2!(crate::model::MyModel);
/// ```
///
/// The symbols are defined in the invoking crate (`$crate` paths reach this crate's `api`
/// and `types`), so they are exported from its binary.
#[macro_export]
macro_rules! export_fmi2 {
    ($model:ty) => {
        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetTypesPlatform() -> *const ::std::ffi::c_char {
            $crate::api::fmi2GetTypesPlatform()
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetVersion() -> *const ::std::ffi::c_char {
            $crate::api::fmi2GetVersion()
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetDebugLogging(
            c: $crate::types::fmi2Component,
            loggingOn: $crate::types::fmi2Boolean,
            nCategories: usize,
            categories: *const $crate::types::fmi2String,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetDebugLogging::<$model>(c, loggingOn, nCategories, categories) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Instantiate(
            instanceName: $crate::types::fmi2String,
            fmuType: $crate::types::fmi2Type,
            fmuGUID: $crate::types::fmi2String,
            fmuResourceLocation: $crate::types::fmi2String,
            functions: *const $crate::types::fmi2CallbackFunctions,
            visible: $crate::types::fmi2Boolean,
            loggingOn: $crate::types::fmi2Boolean,
        ) -> $crate::types::fmi2Component {
            unsafe {
                $crate::api::fmi2Instantiate::<$model>(
                    instanceName,
                    fmuType,
                    fmuGUID,
                    fmuResourceLocation,
                    functions,
                    visible,
                    loggingOn,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2FreeInstance(c: $crate::types::fmi2Component) {
            unsafe { $crate::api::fmi2FreeInstance::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetupExperiment(
            c: $crate::types::fmi2Component,
            toleranceDefined: $crate::types::fmi2Boolean,
            tolerance: $crate::types::fmi2Real,
            startTime: $crate::types::fmi2Real,
            stopTimeDefined: $crate::types::fmi2Boolean,
            stopTime: $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe {
                $crate::api::fmi2SetupExperiment::<$model>(
                    c,
                    toleranceDefined,
                    tolerance,
                    startTime,
                    stopTimeDefined,
                    stopTime,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterInitializationMode(
            c: $crate::types::fmi2Component,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2EnterInitializationMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2ExitInitializationMode(
            c: $crate::types::fmi2Component,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2ExitInitializationMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Terminate(c: $crate::types::fmi2Component) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2Terminate::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Reset(c: $crate::types::fmi2Component) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2Reset::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetReal(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetReal::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetInteger(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::types::fmi2Integer,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetInteger::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBoolean(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::types::fmi2Boolean,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetBoolean::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetString(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::types::fmi2String,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetString::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetReal(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetReal::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetInteger(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::types::fmi2Integer,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetInteger::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetBoolean(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::types::fmi2Boolean,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetBoolean::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetString(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::types::fmi2String,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetString::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetFMUstate(
            c: $crate::types::fmi2Component,
            FMUstate: *mut $crate::types::fmi2FMUstate,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetFMUstate::<$model>(c, FMUstate) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetFMUstate(
            c: $crate::types::fmi2Component,
            FMUstate: $crate::types::fmi2FMUstate,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetFMUstate::<$model>(c, FMUstate) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2FreeFMUstate(
            c: $crate::types::fmi2Component,
            FMUstate: *mut $crate::types::fmi2FMUstate,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2FreeFMUstate::<$model>(c, FMUstate) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
            c: $crate::types::fmi2Component,
            FMUstate: $crate::types::fmi2FMUstate,
            size: *mut usize,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SerializedFMUstateSize::<$model>(c, FMUstate, size) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializeFMUstate(
            c: $crate::types::fmi2Component,
            FMUstate: $crate::types::fmi2FMUstate,
            serializedState: *mut $crate::types::fmi2Byte,
            size: usize,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SerializeFMUstate::<$model>(c, FMUstate, serializedState, size) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
            c: $crate::types::fmi2Component,
            serializedState: *const $crate::types::fmi2Byte,
            size: usize,
            FMUstate: *mut $crate::types::fmi2FMUstate,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2DeSerializeFMUstate::<$model>(c, serializedState, size, FMUstate) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
            c: $crate::types::fmi2Component,
            vUnknown_ref: *const $crate::types::fmi2ValueReference,
            nUnknown: usize,
            vKnown_ref: *const $crate::types::fmi2ValueReference,
            nKnown: usize,
            dvKnown: *const $crate::types::fmi2Real,
            dvUnknown: *mut $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe {
                $crate::api::fmi2GetDirectionalDerivative::<$model>(
                    c,
                    vUnknown_ref,
                    nUnknown,
                    vKnown_ref,
                    nKnown,
                    dvKnown,
                    dvUnknown,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterEventMode(c: $crate::types::fmi2Component) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2EnterEventMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2NewDiscreteStates(
            c: $crate::types::fmi2Component,
            eventInfo: *mut $crate::types::fmi2EventInfo,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2NewDiscreteStates::<$model>(c, eventInfo) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(
            c: $crate::types::fmi2Component,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2EnterContinuousTimeMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
            c: $crate::types::fmi2Component,
            noSetFMUStatePriorToCurrentPoint: $crate::types::fmi2Boolean,
            enterEventMode: *mut $crate::types::fmi2Boolean,
            terminateSimulation: *mut $crate::types::fmi2Boolean,
        ) -> $crate::types::fmi2Status {
            unsafe {
                $crate::api::fmi2CompletedIntegratorStep::<$model>(
                    c,
                    noSetFMUStatePriorToCurrentPoint,
                    enterEventMode,
                    terminateSimulation,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetTime(
            c: $crate::types::fmi2Component,
            time: $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetTime::<$model>(c, time) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetContinuousStates(
            c: $crate::types::fmi2Component,
            x: *const $crate::types::fmi2Real,
            nx: usize,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetContinuousStates::<$model>(c, x, nx) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDerivatives(
            c: $crate::types::fmi2Component,
            derivatives: *mut $crate::types::fmi2Real,
            nx: usize,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetDerivatives::<$model>(c, derivatives, nx) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetEventIndicators(
            c: $crate::types::fmi2Component,
            eventIndicators: *mut $crate::types::fmi2Real,
            ni: usize,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetEventIndicators::<$model>(c, eventIndicators, ni) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetContinuousStates(
            c: $crate::types::fmi2Component,
            x: *mut $crate::types::fmi2Real,
            nx: usize,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetContinuousStates::<$model>(c, x, nx) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
            c: $crate::types::fmi2Component,
            x_nominal: *mut $crate::types::fmi2Real,
            nx: usize,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetNominalsOfContinuousStates::<$model>(c, x_nominal, nx) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            order: *const $crate::types::fmi2Integer,
            value: *const $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2SetRealInputDerivatives::<$model>(c, vr, nvr, order, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
            c: $crate::types::fmi2Component,
            vr: *const $crate::types::fmi2ValueReference,
            nvr: usize,
            order: *const $crate::types::fmi2Integer,
            value: *mut $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetRealOutputDerivatives::<$model>(c, vr, nvr, order, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DoStep(
            c: $crate::types::fmi2Component,
            currentCommunicationPoint: $crate::types::fmi2Real,
            communicationStepSize: $crate::types::fmi2Real,
            noSetFMUStatePriorToCurrentPoint: $crate::types::fmi2Boolean,
        ) -> $crate::types::fmi2Status {
            unsafe {
                $crate::api::fmi2DoStep::<$model>(
                    c,
                    currentCommunicationPoint,
                    communicationStepSize,
                    noSetFMUStatePriorToCurrentPoint,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CancelStep(c: $crate::types::fmi2Component) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2CancelStep::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStatus(
            c: $crate::types::fmi2Component,
            s: $crate::types::fmi2StatusKind,
            value: *mut $crate::types::fmi2Status,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealStatus(
            c: $crate::types::fmi2Component,
            s: $crate::types::fmi2StatusKind,
            value: *mut $crate::types::fmi2Real,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetRealStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetIntegerStatus(
            c: $crate::types::fmi2Component,
            s: $crate::types::fmi2StatusKind,
            value: *mut $crate::types::fmi2Integer,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetIntegerStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBooleanStatus(
            c: $crate::types::fmi2Component,
            s: $crate::types::fmi2StatusKind,
            value: *mut $crate::types::fmi2Boolean,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetBooleanStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStringStatus(
            c: $crate::types::fmi2Component,
            s: $crate::types::fmi2StatusKind,
            value: *mut $crate::types::fmi2String,
        ) -> $crate::types::fmi2Status {
            unsafe { $crate::api::fmi2GetStringStatus::<$model>(c, s, value) }
        }
    };
}
