//! What the workspace's tests and its benchmark share, kept in one place so that the one unsafe
//! logger cast, the allocation counter and the loading of an FMU's binary each exist once.
//! A dev-dependency only (and the benchmark's): the runtime cdylib never links it.
//!
//! - [`logger`]: FMI's C-variadic logger callback written in Rust, and a log that records what
//!   the FMI layer reports.
//! - [`alloc`]: the counting global allocator behind every "no allocation per step" check.
//! - [`loader`]: an FMU's shared library and its fmi2 entry points, through `libloading`.
//! - [`scratch`]: a temporary folder per test or case (FMU resources, input files), removed on drop.
//! - [`reference`]: textbook computations tests compare against (symmetric eigenvalues).
//! - [`fuzz`] (feature `fuzz`): the fuzz targets' proptest settings and memory ceiling.

pub mod alloc;
#[cfg(feature = "fuzz")]
pub mod fuzz;
pub mod loader;
pub mod logger;
pub mod reference;
pub mod scratch;

// this crate's own tests check the counter, so their binary must count
#[cfg(test)]
#[global_allocator]
static ALLOCATOR: alloc::Counting = alloc::Counting;
