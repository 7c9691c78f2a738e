//! `export_fmi2!`: the 44 C symbols of FMI 2.0, each a thin forwarder to `api`.
//!
//! Symbols are unprefixed (binary FMU, no FMI2_FUNCTION_PREFIX), so a crate may invoke
//! the macro only once. Types are spelled with full `$crate` paths so the invocation
//! site needs no imports.

/// Emit all FMI 2.0 entry points for the model type `$model` (which implements
/// `fmi::Model`). Invoke once, at the crate root of the cdylib:
///
/// ```ignore
/// // lib.rs of the cdylib crate that contains `pub mod fmi;`
/// export_fmi2!(crate::model::MyModel);
/// // or, from a crate depending on fmu-runtime:
/// fmu_runtime::export_fmi2!(my_model::MyModel);
/// ```
///
/// `$crate::fmi` must be the path of this module, i.e. `fmi` declared at the crate root.
#[macro_export]
macro_rules! export_fmi2 {
    ($model:ty) => {
        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetTypesPlatform() -> *const ::std::ffi::c_char {
            $crate::fmi::api::fmi2GetTypesPlatform()
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetVersion() -> *const ::std::ffi::c_char {
            $crate::fmi::api::fmi2GetVersion()
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetDebugLogging(
            c: $crate::fmi::types::fmi2Component,
            loggingOn: $crate::fmi::types::fmi2Boolean,
            nCategories: usize,
            categories: *const $crate::fmi::types::fmi2String,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2SetDebugLogging::<$model>(
                    c,
                    loggingOn,
                    nCategories,
                    categories,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Instantiate(
            instanceName: $crate::fmi::types::fmi2String,
            fmuType: $crate::fmi::types::fmi2Type,
            fmuGUID: $crate::fmi::types::fmi2String,
            fmuResourceLocation: $crate::fmi::types::fmi2String,
            functions: *const $crate::fmi::types::fmi2CallbackFunctions,
            visible: $crate::fmi::types::fmi2Boolean,
            loggingOn: $crate::fmi::types::fmi2Boolean,
        ) -> $crate::fmi::types::fmi2Component {
            unsafe {
                $crate::fmi::api::fmi2Instantiate::<$model>(
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
        pub unsafe extern "C" fn fmi2FreeInstance(c: $crate::fmi::types::fmi2Component) {
            unsafe { $crate::fmi::api::fmi2FreeInstance::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetupExperiment(
            c: $crate::fmi::types::fmi2Component,
            toleranceDefined: $crate::fmi::types::fmi2Boolean,
            tolerance: $crate::fmi::types::fmi2Real,
            startTime: $crate::fmi::types::fmi2Real,
            stopTimeDefined: $crate::fmi::types::fmi2Boolean,
            stopTime: $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2SetupExperiment::<$model>(
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
            c: $crate::fmi::types::fmi2Component,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2EnterInitializationMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2ExitInitializationMode(
            c: $crate::fmi::types::fmi2Component,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2ExitInitializationMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Terminate(
            c: $crate::fmi::types::fmi2Component,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2Terminate::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2Reset(
            c: $crate::fmi::types::fmi2Component,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2Reset::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetReal(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetReal::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetInteger(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::fmi::types::fmi2Integer,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetInteger::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBoolean(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::fmi::types::fmi2Boolean,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetBoolean::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetString(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *mut $crate::fmi::types::fmi2String,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetString::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetReal(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SetReal::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetInteger(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::fmi::types::fmi2Integer,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SetInteger::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetBoolean(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::fmi::types::fmi2Boolean,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SetBoolean::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetString(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            value: *const $crate::fmi::types::fmi2String,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SetString::<$model>(c, vr, nvr, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetFMUstate(
            c: $crate::fmi::types::fmi2Component,
            FMUstate: *mut $crate::fmi::types::fmi2FMUstate,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetFMUstate::<$model>(c, FMUstate) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetFMUstate(
            c: $crate::fmi::types::fmi2Component,
            FMUstate: $crate::fmi::types::fmi2FMUstate,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SetFMUstate::<$model>(c, FMUstate) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2FreeFMUstate(
            c: $crate::fmi::types::fmi2Component,
            FMUstate: *mut $crate::fmi::types::fmi2FMUstate,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2FreeFMUstate::<$model>(c, FMUstate) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
            c: $crate::fmi::types::fmi2Component,
            FMUstate: $crate::fmi::types::fmi2FMUstate,
            size: *mut usize,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SerializedFMUstateSize::<$model>(c, FMUstate, size) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SerializeFMUstate(
            c: $crate::fmi::types::fmi2Component,
            FMUstate: $crate::fmi::types::fmi2FMUstate,
            serializedState: *mut $crate::fmi::types::fmi2Byte,
            size: usize,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2SerializeFMUstate::<$model>(
                    c,
                    FMUstate,
                    serializedState,
                    size,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
            c: $crate::fmi::types::fmi2Component,
            serializedState: *const $crate::fmi::types::fmi2Byte,
            size: usize,
            FMUstate: *mut $crate::fmi::types::fmi2FMUstate,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2DeSerializeFMUstate::<$model>(
                    c,
                    serializedState,
                    size,
                    FMUstate,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
            c: $crate::fmi::types::fmi2Component,
            vUnknown_ref: *const $crate::fmi::types::fmi2ValueReference,
            nUnknown: usize,
            vKnown_ref: *const $crate::fmi::types::fmi2ValueReference,
            nKnown: usize,
            dvKnown: *const $crate::fmi::types::fmi2Real,
            dvUnknown: *mut $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2GetDirectionalDerivative::<$model>(
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
        pub unsafe extern "C" fn fmi2EnterEventMode(
            c: $crate::fmi::types::fmi2Component,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2EnterEventMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2NewDiscreteStates(
            c: $crate::fmi::types::fmi2Component,
            eventInfo: *mut $crate::fmi::types::fmi2EventInfo,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2NewDiscreteStates::<$model>(c, eventInfo) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2EnterContinuousTimeMode(
            c: $crate::fmi::types::fmi2Component,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2EnterContinuousTimeMode::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
            c: $crate::fmi::types::fmi2Component,
            noSetFMUStatePriorToCurrentPoint: $crate::fmi::types::fmi2Boolean,
            enterEventMode: *mut $crate::fmi::types::fmi2Boolean,
            terminateSimulation: *mut $crate::fmi::types::fmi2Boolean,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2CompletedIntegratorStep::<$model>(
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
            c: $crate::fmi::types::fmi2Component,
            time: $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SetTime::<$model>(c, time) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetContinuousStates(
            c: $crate::fmi::types::fmi2Component,
            x: *const $crate::fmi::types::fmi2Real,
            nx: usize,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2SetContinuousStates::<$model>(c, x, nx) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetDerivatives(
            c: $crate::fmi::types::fmi2Component,
            derivatives: *mut $crate::fmi::types::fmi2Real,
            nx: usize,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetDerivatives::<$model>(c, derivatives, nx) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetEventIndicators(
            c: $crate::fmi::types::fmi2Component,
            eventIndicators: *mut $crate::fmi::types::fmi2Real,
            ni: usize,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetEventIndicators::<$model>(c, eventIndicators, ni) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetContinuousStates(
            c: $crate::fmi::types::fmi2Component,
            x: *mut $crate::fmi::types::fmi2Real,
            nx: usize,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetContinuousStates::<$model>(c, x, nx) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
            c: $crate::fmi::types::fmi2Component,
            x_nominal: *mut $crate::fmi::types::fmi2Real,
            nx: usize,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2GetNominalsOfContinuousStates::<$model>(c, x_nominal, nx)
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2SetRealInputDerivatives(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            order: *const $crate::fmi::types::fmi2Integer,
            value: *const $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2SetRealInputDerivatives::<$model>(c, vr, nvr, order, value)
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealOutputDerivatives(
            c: $crate::fmi::types::fmi2Component,
            vr: *const $crate::fmi::types::fmi2ValueReference,
            nvr: usize,
            order: *const $crate::fmi::types::fmi2Integer,
            value: *mut $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2GetRealOutputDerivatives::<$model>(c, vr, nvr, order, value)
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2DoStep(
            c: $crate::fmi::types::fmi2Component,
            currentCommunicationPoint: $crate::fmi::types::fmi2Real,
            communicationStepSize: $crate::fmi::types::fmi2Real,
            noSetFMUStatePriorToCurrentPoint: $crate::fmi::types::fmi2Boolean,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe {
                $crate::fmi::api::fmi2DoStep::<$model>(
                    c,
                    currentCommunicationPoint,
                    communicationStepSize,
                    noSetFMUStatePriorToCurrentPoint,
                )
            }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2CancelStep(
            c: $crate::fmi::types::fmi2Component,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2CancelStep::<$model>(c) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStatus(
            c: $crate::fmi::types::fmi2Component,
            s: $crate::fmi::types::fmi2StatusKind,
            value: *mut $crate::fmi::types::fmi2Status,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetRealStatus(
            c: $crate::fmi::types::fmi2Component,
            s: $crate::fmi::types::fmi2StatusKind,
            value: *mut $crate::fmi::types::fmi2Real,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetRealStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetIntegerStatus(
            c: $crate::fmi::types::fmi2Component,
            s: $crate::fmi::types::fmi2StatusKind,
            value: *mut $crate::fmi::types::fmi2Integer,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetIntegerStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetBooleanStatus(
            c: $crate::fmi::types::fmi2Component,
            s: $crate::fmi::types::fmi2StatusKind,
            value: *mut $crate::fmi::types::fmi2Boolean,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetBooleanStatus::<$model>(c, s, value) }
        }

        #[unsafe(no_mangle)]
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub unsafe extern "C" fn fmi2GetStringStatus(
            c: $crate::fmi::types::fmi2Component,
            s: $crate::fmi::types::fmi2StatusKind,
            value: *mut $crate::fmi::types::fmi2String,
        ) -> $crate::fmi::types::fmi2Status {
            unsafe { $crate::fmi::api::fmi2GetStringStatus::<$model>(c, s, value) }
        }
    };
}
