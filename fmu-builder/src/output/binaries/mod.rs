//! The runtime binaries an FMU carries besides the builder's own linux64 one: binaries of
//! fmu-runtime built on other platforms (`--platform-binary PLATFORM=FILE`), each checked before
//! it is packaged as `binaries/<platform>/<modelIdentifier>.<dll|so|dylib>`.
//!
//! `platform` knows FMI 2.0's platform names, `fmi2_functions` the functions a binary must
//! export, `inspect` reads a binary (format, processor, shared library, exports) and `build_id`
//! tells whether it was built from the builder's own runtime source.

pub mod build_id;
pub mod fmi2_functions;
pub mod inspect;
pub mod platform;

pub use platform::Platform;

use std::path::{Path, PathBuf};

use crate::error::{BuildError, Refusal};

/// A runtime binary of another platform, read and checked.
#[derive(Debug, Clone)]
pub struct PlatformBinary {
    pub platform: Platform,
    pub path: PathBuf,
    pub data: Vec<u8>,
}

impl PlatformBinary {
    /// The command line's `PLATFORM=FILE`: the file read and checked for an FMU declaring both
    /// Model Exchange and Co-Simulation (as every FMU of this builder does).
    pub fn from_arg(arg: &str) -> Result<Self, BuildError> {
        let (name, file) = arg.split_once('=').filter(|(n, f)| !n.is_empty() && !f.is_empty()).ok_or_else(|| {
            BuildError::command_line(
                format!("--platform-binary {arg}"),
                "expected PLATFORM=FILE, e.g. win64=fmu_runtime.dll (platforms: win32, win64, linux32, linux64, darwin32, darwin64)",
            )
        })?;
        let platform = Platform::parse(name)
            .map_err(|reason| BuildError::command_line(format!("--platform-binary {arg}"), reason.reason))?;
        let path = PathBuf::from(file);
        let binary = Self::read(platform, &path)?;
        binary.check(&fmi2_functions::model_exchange_and_co_simulation())?;
        Ok(binary)
    }

    pub fn read(platform: Platform, path: &Path) -> Result<Self, BuildError> {
        if path.is_dir() {
            return Err(refused(
                path,
                platform,
                Refusal::from(format!("is a folder; give the {} file", platform.runtime_file())),
            ));
        }
        use crate::input::{file_read, size::Memory};
        let data = file_read::read(path, file_read::FileKind::PlatformBinary, Memory::of_this_machine().bytes)
            .map_err(|e| refused(path, platform, e))?;
        Ok(Self { platform, path: path.to_owned(), data })
    }

    /// Ok when the binary can be this platform's FMU binary exporting `required`, built from the
    /// builder's own runtime source; the error names the file, the platform and what is wrong.
    pub fn check(&self, required: &[&str]) -> Result<(), BuildError> {
        inspect::check(self.platform, &self.data, required)
            .and_then(|()| build_id::check(&self.data, build_id::own()))
            .map_err(|reason| refused(&self.path, self.platform, reason))
    }
}

fn refused(path: &Path, platform: Platform, reason: Refusal) -> BuildError {
    BuildError::Binary { path: path.to_owned(), platform: platform.to_string(), reason }
}

/// At most one binary per platform.
pub fn check_distinct(binaries: &[PlatformBinary]) -> Result<(), BuildError> {
    for (i, b) in binaries.iter().enumerate() {
        if let Some(first) = binaries[..i].iter().find(|o| o.platform == b.platform) {
            return Err(BuildError::command_line(
                format!("--platform-binary {}", b.platform),
                format!(
                    "given twice ({} and {}); an FMU has one binary per platform",
                    first.path.display(),
                    b.path.display()
                ),
            ));
        }
    }
    Ok(())
}
