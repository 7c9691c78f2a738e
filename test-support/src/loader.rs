//! An FMU's shared library and the fmi2 functions a co-simulation master calls, loaded the way a
//! host loads them (`RTLD_NOW | RTLD_LOCAL`, through `libloading`), each symbol proven to come from
//! that binary and not from anything the process already links.

use fmi2::types::*;
use libloading::os::unix::{Library, RTLD_LOCAL, RTLD_NOW, Symbol};
use std::ffi::{CStr, c_void};
use std::path::{Path, PathBuf};

pub type Instantiate = unsafe extern "C" fn(
    fmi2String,
    fmi2Type,
    fmi2String,
    fmi2String,
    *const fmi2CallbackFunctions,
    fmi2Boolean,
    fmi2Boolean,
) -> fmi2Component;
pub type FreeInstance = unsafe extern "C" fn(fmi2Component);
pub type SetupExperiment =
    unsafe extern "C" fn(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real, fmi2Boolean, fmi2Real) -> fmi2Status;
pub type ComponentOnly = unsafe extern "C" fn(fmi2Component) -> fmi2Status;
pub type NewDiscreteStates = unsafe extern "C" fn(fmi2Component, *mut fmi2EventInfo) -> fmi2Status;
pub type DoStep = unsafe extern "C" fn(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean) -> fmi2Status;
pub type SetReal = unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *const fmi2Real) -> fmi2Status;
pub type GetReal = unsafe extern "C" fn(fmi2Component, *const fmi2ValueReference, usize, *mut fmi2Real) -> fmi2Status;
pub type SetStates = unsafe extern "C" fn(fmi2Component, *const fmi2Real, usize) -> fmi2Status;
pub type GetStates = unsafe extern "C" fn(fmi2Component, *mut fmi2Real, usize) -> fmi2Status;
pub type GetFmuState = unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status;
pub type SetFmuState = unsafe extern "C" fn(fmi2Component, fmi2FMUstate) -> fmi2Status;
pub type FreeFmuState = unsafe extern "C" fn(fmi2Component, *mut fmi2FMUstate) -> fmi2Status;

/// The fmi2 entry points a master uses. From [`FmuBinary::open`] they are valid while that
/// binary is; a driver may also fill them with the functions linked into its own process.
#[derive(Clone, Copy)]
pub struct Fmi2Functions {
    pub instantiate: Instantiate,
    pub free_instance: FreeInstance,
    pub setup_experiment: SetupExperiment,
    pub enter_initialization_mode: ComponentOnly,
    pub exit_initialization_mode: ComponentOnly,
    pub terminate: ComponentOnly,
    pub new_discrete_states: NewDiscreteStates,
    pub enter_continuous_time_mode: ComponentOnly,
    pub do_step: DoStep,
    pub set_real: SetReal,
    pub get_real: GetReal,
    pub set_continuous_states: SetStates,
    pub get_derivatives: GetStates,
    pub get_fmu_state: GetFmuState,
    pub set_fmu_state: SetFmuState,
    pub free_fmu_state: FreeFmuState,
}

/// A loaded FMU binary and its functions; unloaded on drop, so it must outlive every instance
/// and every copy of its functions.
pub struct FmuBinary {
    functions: Fmi2Functions,
    path: PathBuf,
    _library: Library,
}

impl FmuBinary {
    /// Loads `path` (e.g. `binaries/linux64/<modelIdentifier>.so` of an unzipped FMU) and
    /// resolves its fmi2 functions.
    pub fn open(path: &Path) -> Result<Self, String> {
        let path = path.canonicalize().map_err(|e| format!("{}: {e}", path.display()))?;
        // SAFETY: loading runs the library's initialisers: the FMU's binary is the runtime this
        // workspace builds. RTLD_LOCAL keeps each FMU's fmi2* symbols to itself, as hosts load them.
        let library = unsafe { Library::open(Some(&path), RTLD_NOW | RTLD_LOCAL) }
            .map_err(|e| format!("loading {}: {e}", path.display()))?;
        // SAFETY (every `resolve` below): each symbol is the FMI 2.0 function of that name, whose
        // signature the standard fixes and the field's type spells.
        let functions = unsafe {
            Fmi2Functions {
                instantiate: resolve(&library, &path, c"fmi2Instantiate")?,
                free_instance: resolve(&library, &path, c"fmi2FreeInstance")?,
                setup_experiment: resolve(&library, &path, c"fmi2SetupExperiment")?,
                enter_initialization_mode: resolve(&library, &path, c"fmi2EnterInitializationMode")?,
                exit_initialization_mode: resolve(&library, &path, c"fmi2ExitInitializationMode")?,
                terminate: resolve(&library, &path, c"fmi2Terminate")?,
                new_discrete_states: resolve(&library, &path, c"fmi2NewDiscreteStates")?,
                enter_continuous_time_mode: resolve(&library, &path, c"fmi2EnterContinuousTimeMode")?,
                do_step: resolve(&library, &path, c"fmi2DoStep")?,
                set_real: resolve(&library, &path, c"fmi2SetReal")?,
                get_real: resolve(&library, &path, c"fmi2GetReal")?,
                set_continuous_states: resolve(&library, &path, c"fmi2SetContinuousStates")?,
                get_derivatives: resolve(&library, &path, c"fmi2GetDerivatives")?,
                get_fmu_state: resolve(&library, &path, c"fmi2GetFMUstate")?,
                set_fmu_state: resolve(&library, &path, c"fmi2SetFMUstate")?,
                free_fmu_state: resolve(&library, &path, c"fmi2FreeFMUstate")?,
            }
        };
        Ok(Self { functions, path, _library: library })
    }

    pub fn functions(&self) -> &Fmi2Functions {
        &self.functions
    }

    /// The loaded file (canonical path).
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// The function `name` of `library` (loaded from `path`), checked to be defined in that file: a
/// host calling through it reaches the FMU's binary, never a same-named function of the process.
///
/// # Safety
/// `T` is the type of the function `name` (a function pointer); the copy returned is valid while
/// `library` stays loaded.
unsafe fn resolve<T: Copy>(library: &Library, path: &Path, name: &CStr) -> Result<T, String> {
    let symbol: Symbol<T> =
        unsafe { library.get(name.to_bytes_with_nul()) }.map_err(|e| format!("{}: {e}", path.display()))?;
    let function = *symbol;
    let defined_in =
        defining_object(symbol.into_raw()).ok_or_else(|| format!("dladdr failed for {}", name.to_string_lossy()))?;
    if defined_in != path {
        return Err(format!(
            "{} resolved to {} instead of the FMU's binary {}",
            name.to_string_lossy(),
            defined_in.display(),
            path.display()
        ));
    }
    Ok(function)
}

/// The file of the loaded object that defines `address` (dladdr).
fn defining_object(address: *mut c_void) -> Option<PathBuf> {
    let mut info: libc::Dl_info = unsafe { std::mem::zeroed() };
    // SAFETY: dladdr only reads the address and fills `info`; its file name is a NUL-terminated
    // string owned by the loader, copied before anything could unload it.
    unsafe {
        if libc::dladdr(address, &mut info) == 0 || info.dli_fname.is_null() {
            return None;
        }
        let name = CStr::from_ptr(info.dli_fname);
        Some(PathBuf::from(std::ffi::OsStr::from_encoded_bytes_unchecked(name.to_bytes())))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_file_is_an_error_naming_it() {
        let e = FmuBinary::open(Path::new("/nonexistent/model.so")).err().unwrap();
        assert!(e.contains("/nonexistent/model.so"), "{e}");
    }

    #[test]
    fn a_library_without_fmi2_functions_is_refused() {
        // the C library this process links: loadable, but no FMU
        let libc_path = defining_object(libc::printf as *mut c_void).expect("dladdr of printf");
        let e = FmuBinary::open(&libc_path).err().unwrap();
        assert!(e.contains("fmi2Instantiate"), "{e}");
    }
}
