//! The host's callbacks as these tests give them to the exported C functions: a logger written
//! in Rust, passed as FMI's C-variadic logger type.

use fmi2::types::*;
use std::ffi::{c_char, c_void};

/// A logger taking the one vararg the FMI layer passes (the text for its "%s" format) as a fixed
/// parameter.
pub type FixedLogger =
    unsafe extern "C" fn(*mut c_void, *const c_char, fmi2Status, *const c_char, *const c_char, *const c_char);

/// Callbacks with `logger` and `environment` (handed back to the logger as its first argument).
pub fn callbacks_with(logger: FixedLogger, environment: *mut c_void) -> fmi2CallbackFunctions {
    // Stable Rust cannot define a C-variadic function; on x86-64 SysV the fixed and variadic
    // pointer arguments travel alike (as in the FMI layer's own tests).
    // SAFETY: the same calling convention for the arguments the layer passes (see above)
    let logger: fmi2CallbackLogger = unsafe { std::mem::transmute(logger) };
    fmi2CallbackFunctions {
        logger: Some(logger),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: environment,
    }
}
