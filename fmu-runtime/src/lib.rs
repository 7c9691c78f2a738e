//! FMI 2.0 runtime of a reduced flexible body. Two layers, as in the Reference-FMUs:
//! the `fmi2` crate knows the C API and the FMI state machine and nothing of mechanics; `body`
//! knows the reduced equations and nothing of C; `fmu` implements `fmi2::Model` for the body,
//! and `interface` maps FMU variables onto it. `format`/`reduced` define the reduced-model file
//! the builder writes into `resources/`.

pub mod assembly;
pub mod body;
pub mod coupled_propagator;
pub mod explicit_host;
pub mod fmu;
pub mod format;
pub mod interface;
pub mod kinematics;
pub mod matmul;
pub mod matvec;
pub mod propagator;
pub mod reduced;
pub mod scalar;
pub mod workspace;

fmi2::export_fmi2!(crate::fmu::any::AnyFmu);

include!(concat!(env!("OUT_DIR"), "/build_id.rs"));

/// What precedes [`BUILD_ID`] in the binary: the builder finds the identity of a runtime binary
/// of any format (ELF, PE, Mach-O) by this text in its bytes.
pub const BUILD_ID_MARKER: &str = "FMU_RUNTIME_BUILD_ID=";

/// `BUILD_ID_MARKER` + `BUILD_ID` as a NUL-terminated C string, exported (and so kept by the
/// linker) from every build of the runtime, so that the builder can refuse a binary built on
/// another platform from another source (see build.rs).
#[unsafe(no_mangle)]
pub static FMU_RUNTIME_BUILD_ID: [u8; BUILD_ID_MARKER.len() + BUILD_ID.len() + 1] = marked_build_id();

const fn marked_build_id<const N: usize>() -> [u8; N] {
    let mut out = [0u8; N];
    let (marker, id) = (BUILD_ID_MARKER.as_bytes(), BUILD_ID.as_bytes());
    let mut i = 0;
    while i < marker.len() {
        out[i] = marker[i];
        i += 1;
    }
    while i < marker.len() + id.len() {
        out[i] = id[i - marker.len()];
        i += 1;
    }
    out
}
