//! Messages to the host's fmi2CallbackLogger.
//!
//! The callback is C-variadic and printf-like, so the text always travels as the
//! argument of a constant "%s" format: a '%' in a model message can never be
//! interpreted. Importers additionally expand `#r<vr>#` / `#i<vr>#` references
//! in the text, where "##" stands for a literal '#', hence the escaping.

use std::ffi::{CStr, CString};

use super::types::{fmi2CallbackLogger, fmi2ComponentEnvironment, fmi2Status};

/// Log categories; modelDescription.xml must declare exactly these names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Category {
    LogAll,
    LogStatusWarning,
    LogStatusError,
}

impl Category {
    pub const ALL: [Category; 3] = [Category::LogAll, Category::LogStatusWarning, Category::LogStatusError];

    pub fn name(self) -> &'static CStr {
        match self {
            Category::LogAll => c"logAll",
            Category::LogStatusWarning => c"logStatusWarning",
            Category::LogStatusError => c"logStatusError",
        }
    }

    pub fn from_name(name: &[u8]) -> Option<Category> {
        Self::ALL.into_iter().find(|c| c.name().to_bytes() == name)
    }

    fn bit(self) -> u8 {
        1 << self as u8
    }
}

pub struct Logger {
    /// Own copy: the host may free the string it passed to fmi2Instantiate.
    instance_name: CString,
    callback: Option<fmi2CallbackLogger>,
    environment: fmi2ComponentEnvironment,
    /// Bit set of `Category::bit`; errors bypass it.
    enabled: u8,
}

impl Logger {
    pub fn new(
        instance_name: CString,
        callback: Option<fmi2CallbackLogger>,
        environment: fmi2ComponentEnvironment,
        logging_on: bool,
    ) -> Self {
        let mut logger = Logger { instance_name, callback, environment, enabled: 0 };
        logger.set_debug_logging(logging_on, &Category::ALL);
        logger
    }

    pub fn instance_name(&self) -> &CStr {
        &self.instance_name
    }

    /// `categories` empty with `on` means all categories, as fmi2SetDebugLogging specifies.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[Category]) {
        self.enabled = 0;
        if on {
            let list = if categories.is_empty() { &Category::ALL[..] } else { categories };
            for c in list {
                self.enabled |= c.bit();
            }
        }
    }

    /// Cheap pre-check so hot paths only format a message when someone will read it.
    #[inline]
    pub fn is_enabled(&self, category: Category) -> bool {
        self.callback.is_some() && (category == Category::LogStatusError || self.enabled & category.bit() != 0)
    }

    pub fn log(&self, status: fmi2Status, category: Category, text: &str) {
        if self.is_enabled(category) {
            self.emit(status, category, text);
        }
    }

    /// A warning the host must see to act on it (it integrates in a way that cannot work):
    /// logged whatever the debug logging, as errors and discards are.
    pub fn advice(&self, text: &str) {
        self.emit(fmi2Status::fmi2Warning, Category::LogStatusWarning, text);
    }

    fn emit(&self, status: fmi2Status, category: Category, text: &str) {
        let Some(callback) = self.callback else {
            return;
        };
        let text = escape(text);
        // SAFETY: the host guarantees the callback is valid for the instance's lifetime;
        // every pointer passed is a NUL-terminated string we own for the duration of the call.
        unsafe {
            callback(
                self.environment,
                self.instance_name.as_ptr(),
                status,
                category.name().as_ptr(),
                c"%s".as_ptr(),
                text.as_ptr(),
            )
        }
    }

    pub fn error(&self, text: &str) {
        self.log(fmi2Status::fmi2Error, Category::LogStatusError, text);
    }

    /// A refused evaluation (fmi2Discard): logged whatever the debug logging, as errors are, since
    /// the host needs the reason to act on it (a smaller step, other states).
    pub fn discard(&self, text: &str) {
        self.log(fmi2Status::fmi2Discard, Category::LogStatusError, text);
    }

    pub fn fatal(&self, text: &str) {
        self.log(fmi2Status::fmi2Fatal, Category::LogStatusError, text);
    }

    pub fn warning(&self, status: fmi2Status, text: &str) {
        self.log(status, Category::LogStatusWarning, text);
    }

    /// Call tracing under "logAll"; the closure keeps formatting off the hot path.
    #[inline]
    pub fn trace(&self, text: impl FnOnce() -> String) {
        if self.is_enabled(Category::LogAll) {
            self.log(fmi2Status::fmi2OK, Category::LogAll, &text());
        }
    }
}

/// '#' -> "##" for the importer's variable-reference expansion; NUL cannot be
/// represented in a C string, so it becomes U+FFFD rather than silently truncating.
fn escape(text: &str) -> CString {
    let mut out = Vec::with_capacity(text.len() + 1);
    for &b in text.as_bytes() {
        match b {
            b'#' => out.extend_from_slice(b"##"),
            0 => out.extend_from_slice("\u{FFFD}".as_bytes()),
            _ => out.push(b),
        }
    }
    CString::new(out).expect("NUL bytes were replaced")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_hash_and_nul() {
        assert_eq!(escape("a#r1#b%s").as_bytes(), b"a##r1##b%s");
        assert_eq!(escape("x\0y").to_str().unwrap(), "x\u{FFFD}y");
    }

    #[test]
    fn category_names_round_trip() {
        for c in Category::ALL {
            assert_eq!(Category::from_name(c.name().to_bytes()), Some(c));
        }
        assert_eq!(Category::from_name(b"logEvents"), None);
    }
}
