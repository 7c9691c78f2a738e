//! The host's logger as a Rust test gives it to the FMI functions.
//!
//! FMI's `fmi2CallbackLogger` is C-variadic, and stable Rust cannot define a C-variadic function.
//! Every message of the FMI layer is logged as `logger(env, name, status, category, "%s", text)`,
//! so a Rust function taking `text` as a sixth fixed parameter ([`FixedLogger`]) receives that call
//! unchanged on the platforms whose calling convention passes a variadic pointer argument where it
//! passes a fixed one; [`variadic`] is the one cast that relies on it.
//!
//! The status type is a parameter because the fmi2 crate's own unit tests see their crate's
//! `fmi2Status`, a type distinct from the one this crate links; everyone else uses the default.

use fmi2::types::{fmi2CallbackFunctions, fmi2Status};
use std::cell::{Ref, RefCell};
use std::ffi::{CStr, c_char, c_void};

// Apple arm64 passes every variadic argument on the stack and fixed ones in registers: the cast
// below would read a register the caller never set.
#[cfg(all(target_vendor = "apple", target_arch = "aarch64"))]
compile_error!("the FMI logger shim needs variadic and fixed pointer arguments passed alike (not so on Apple arm64)");

/// A logger written in Rust: `fmi2CallbackLogger` with the one vararg the FMI layer passes (the
/// text for its "%s" format) as a fixed parameter.
pub type FixedLogger<S = fmi2Status> =
    unsafe extern "C" fn(*mut c_void, *const c_char, S, *const c_char, *const c_char, *const c_char);

/// `fmi2CallbackLogger` over the status type `S` (the same type as `fmi2CallbackLogger` for the
/// `fmi2Status` it names).
pub type VariadicLogger<S = fmi2Status> =
    unsafe extern "C" fn(*mut c_void, *const c_char, S, *const c_char, *const c_char, ...);

/// `logger` as FMI's variadic logger type.
///
/// Sound for calls with exactly one variadic argument, a pointer, which is how the FMI layer logs
/// (`"%s"` and its text); a logger must check the format before reading its sixth parameter if it
/// may be called otherwise.
pub fn variadic<S>(logger: FixedLogger<S>) -> VariadicLogger<S> {
    // SAFETY: both are pointers to `extern "C"` functions of the same first five parameters; on
    // x86-64 System V, Windows x64 and AArch64 outside Apple (the compile_error above) a variadic
    // pointer argument is passed exactly as a fixed sixth pointer parameter, and the count of
    // vector registers a variadic call adds in %al is ignored by a callee that does not read it.
    // The caller's side of the contract is the one vararg of the layer's "%s" format (see above).
    unsafe { std::mem::transmute::<FixedLogger<S>, VariadicLogger<S>>(logger) }
}

/// Callbacks with only a logger: `logger`, handed `environment` as its first argument.
pub fn callbacks_with(logger: FixedLogger, environment: *mut c_void) -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: Some(variadic(logger)),
        componentEnvironment: environment,
        ..fmi2CallbackFunctions::NONE
    }
}

/// A logger that drops every message, for tests that judge by status alone.
pub extern "C" fn quiet(
    _: *mut c_void,
    _: *const c_char,
    _: fmi2Status,
    _: *const c_char,
    _: *const c_char,
    _: *const c_char,
) {
}

/// A NULL or NUL-terminated C string as text (lossy: fuzzed model files log names of any bytes).
///
/// # Safety
/// `p` is NULL or points to a NUL-terminated string.
pub unsafe fn text(p: *const c_char) -> String {
    if p.is_null() { String::new() } else { unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned() }
}

/// A logger that prints `[instance] status category: message` on stderr, as a host would.
///
/// # Safety
/// As the FMI layer calls it: every string NULL or NUL-terminated, `arg` a string wherever
/// `message` is "%s".
pub unsafe extern "C" fn stderr(
    _: *mut c_void,
    instance: *const c_char,
    status: fmi2Status,
    category: *const c_char,
    message: *const c_char,
    arg: *const c_char,
) {
    // SAFETY: the FMI layer passes NUL-terminated strings; the sixth parameter is read only
    // behind the format that carries it
    unsafe {
        let message = text(message);
        let message = if message == "%s" { text(arg) } else { message };
        eprintln!("[{}] {:?} {}: {}", text(instance), status, text(category), message);
    }
}

/// One logged message.
#[derive(Clone, Debug)]
pub struct Entry<S = fmi2Status> {
    pub status: S,
    pub category: String,
    pub text: String,
}

/// Every message the FMI layer logged through [`Log::logger`], with the log as the callbacks'
/// component environment. Keep it at a fixed address (boxed, or borrowed for the instance's
/// life) while an instance may log.
pub struct Log<S = fmi2Status>(RefCell<Vec<Entry<S>>>);

impl<S> Default for Log<S> {
    fn default() -> Self {
        Self(RefCell::new(Vec::new()))
    }
}

impl<S: Copy> Log<S> {
    /// The logger that records into the log given as its environment.
    pub fn logger() -> VariadicLogger<S> {
        variadic(record::<S>)
    }

    /// What the callbacks hand the logger as its first argument.
    pub fn environment(&self) -> *mut c_void {
        self as *const Self as *mut c_void
    }

    pub fn entries(&self) -> Ref<'_, Vec<Entry<S>>> {
        self.0.borrow()
    }

    pub fn len(&self) -> usize {
        self.0.borrow().len()
    }

    pub fn is_empty(&self) -> bool {
        self.0.borrow().is_empty()
    }

    pub fn contains(&self, needle: &str) -> bool {
        self.0.borrow().iter().any(|e| e.text.contains(needle))
    }

    /// The last message's text; empty when nothing was logged.
    pub fn last(&self) -> String {
        self.0.borrow().last().map(|e| e.text.clone()).unwrap_or_default()
    }

    pub fn last_entry(&self) -> Option<Entry<S>> {
        self.0.borrow().last().cloned()
    }

    /// Messages of `category`.
    pub fn count(&self, category: &str) -> usize {
        self.0.borrow().iter().filter(|e| e.category == category).count()
    }

    pub fn clear(&self) {
        self.0.borrow_mut().clear();
    }
}

impl Log<fmi2Status> {
    /// Callbacks whose logger records into this log.
    pub fn callbacks(&self) -> fmi2CallbackFunctions {
        fmi2CallbackFunctions {
            logger: Some(Self::logger()),
            componentEnvironment: self.environment(),
            ..fmi2CallbackFunctions::NONE
        }
    }
}

/// The recording logger: every message of the layer names its instance and comes as "%s" with
/// its text (a message formatted otherwise would make the sixth parameter garbage).
unsafe extern "C" fn record<S: Copy>(
    env: *mut c_void,
    name: *const c_char,
    status: S,
    category: *const c_char,
    message: *const c_char,
    arg: *const c_char,
) {
    assert!(!name.is_null(), "a message without an instance name");
    assert!(!message.is_null(), "a message without a format");
    // SAFETY: `env` is the `Log<S>` the callbacks were made with (`Log::environment`), alive while
    // its instance logs; the strings are NUL-terminated, the text read only behind its "%s"
    unsafe {
        assert_eq!(CStr::from_ptr(message).to_bytes(), b"%s", "the FMI layer logs every message as \"%s\"");
        let log = &*(env as *const Log<S>);
        log.0.borrow_mut().push(Entry { status, category: text(category), text: text(arg) });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmi2::types::fmi2Status::*;

    /// The call the FMI layer makes, through the variadic type.
    fn log_through(callbacks: &fmi2CallbackFunctions, status: fmi2Status, category: &CStr, text: &CStr) {
        let logger = callbacks.logger.unwrap();
        unsafe {
            logger(
                callbacks.componentEnvironment,
                c"instance".as_ptr(),
                status,
                category.as_ptr(),
                c"%s".as_ptr(),
                text.as_ptr(),
            )
        };
    }

    #[test]
    fn the_log_records_what_the_variadic_logger_is_given() {
        let log = Log::default();
        let callbacks = log.callbacks();
        assert_eq!(callbacks.componentEnvironment, log.environment());
        assert!(log.is_empty() && log.last().is_empty() && log.last_entry().is_none());
        log_through(&callbacks, fmi2Warning, c"logStatusWarning", c"50% done, 100% sure");
        log_through(&callbacks, fmi2Error, c"logStatusError", c"broken");
        assert_eq!(log.len(), 2);
        assert_eq!(log.last(), "broken");
        let last = log.last_entry().unwrap();
        assert_eq!((last.status, last.category.as_str()), (fmi2Error, "logStatusError"));
        assert_eq!(log.entries()[0].text, "50% done, 100% sure");
        assert!(log.contains("100% sure") && !log.contains("absent"));
        assert_eq!(log.count("logStatusWarning"), 1);
        log.clear();
        assert!(log.is_empty());
    }

    #[test]
    fn quiet_and_stderr_loggers_take_the_call() {
        for logger in [quiet as FixedLogger, stderr] {
            let callbacks = callbacks_with(logger, std::ptr::null_mut());
            log_through(&callbacks, fmi2OK, c"logAll", c"a message");
        }
    }
}
