//! Stage 5, output: what the user gets. The report of a build (`report`), its printed summary
//! (`summary`, its numbers formatted by `numbers`) and the verdict on how far the FMU holds (`verdict`), the HTML documentation
//! (`documentation`), the FMU's modelDescription.xml and archive (`fmu`), the check that everything it carries is finite (`finite`), and the packaging
//! of it all with the runtime binaries (`package`; `binaries` checks those built on other
//! platforms). `destinations` checks, before any work, that every output can be written and
//! overwrites nothing it should not, and reserves it (`lock`); `place` writes every output
//! through a temporary file and a checked rename, `temp_files` removes those files when the
//! build is interrupted or was killed.

pub mod binaries;
pub mod destinations;
pub mod documentation;
pub mod finite;
pub mod fmu;
pub mod lock;
pub mod mesh_view;
pub mod model_exchange;
pub mod numbers;
pub mod package;
pub mod place;
pub mod plausibility;
pub mod plot;
pub mod report;
pub mod summary;
pub mod temp_files;
pub mod verdict;
