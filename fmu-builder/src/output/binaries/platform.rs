//! The platforms FMI 2.0 names for an FMU's binaries (the `binaries/` folder of its FMU layout):
//! win32, win64, linux32, linux64, darwin32, darwin64, each with the file format, the processor
//! and the file extension an importer on it expects. FMI 2.0 names x86 and x86-64 platforms
//! only: an aarch64 (arm64) binary has no folder of its own there (FMI 3.0's platform tuples,
//! e.g. `aarch64-linux`, add them).

use std::fmt;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Platform {
    Win32,
    Win64,
    Linux32,
    Linux64,
    Darwin32,
    Darwin64,
}

/// The binary file format of a platform's shared libraries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    Pe,
    Elf,
    MachO,
}

/// The processor a platform's binaries are for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Processor {
    X86,
    X86_64,
}

impl Platform {
    pub const ALL: [Platform; 6] = [
        Platform::Win32,
        Platform::Win64,
        Platform::Linux32,
        Platform::Linux64,
        Platform::Darwin32,
        Platform::Darwin64,
    ];

    /// The folder below `binaries/`.
    pub fn name(self) -> &'static str {
        match self {
            Platform::Win32 => "win32",
            Platform::Win64 => "win64",
            Platform::Linux32 => "linux32",
            Platform::Linux64 => "linux64",
            Platform::Darwin32 => "darwin32",
            Platform::Darwin64 => "darwin64",
        }
    }

    /// A platform by its FMI 2.0 name; the error lists the names (and says why there is no
    /// aarch64 one).
    pub fn parse(name: &str) -> Result<Self, crate::error::Refusal> {
        Self::ALL.into_iter().find(|p| p.name() == name).ok_or_else(|| {
            let names: Vec<&str> = Self::ALL.iter().map(|p| p.name()).collect();
            crate::error::Refusal::from(format!(
                "'{name}' is not an FMI 2.0 platform: expected one of {} (FMI 2.0 names x86 and x86-64 platforms only, none for aarch64/arm64)",
                names.join(", ")
            ))
        })
    }

    pub fn format(self) -> Format {
        match self {
            Platform::Win32 | Platform::Win64 => Format::Pe,
            Platform::Linux32 | Platform::Linux64 => Format::Elf,
            Platform::Darwin32 | Platform::Darwin64 => Format::MachO,
        }
    }

    pub fn processor(self) -> Processor {
        match self {
            Platform::Win32 | Platform::Linux32 | Platform::Darwin32 => Processor::X86,
            Platform::Win64 | Platform::Linux64 | Platform::Darwin64 => Processor::X86_64,
        }
    }

    /// The extension of `binaries/<platform>/<modelIdentifier>.<extension>`.
    pub fn extension(self) -> &'static str {
        match self.format() {
            Format::Pe => "dll",
            Format::Elf => "so",
            Format::MachO => "dylib",
        }
    }

    /// The file `cargo build -p fmu-runtime --release` writes on this platform (in
    /// `target/release/`).
    pub fn runtime_file(self) -> &'static str {
        match self.format() {
            Format::Pe => "fmu_runtime.dll",
            Format::Elf => "libfmu_runtime.so",
            Format::MachO => "libfmu_runtime.dylib",
        }
    }
}

impl fmt::Display for Platform {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl Format {
    pub fn describe(self) -> &'static str {
        match self {
            Format::Pe => "a Windows DLL (PE)",
            Format::Elf => "a Linux shared object (ELF)",
            Format::MachO => "a macOS dynamic library (Mach-O)",
        }
    }
}

impl Processor {
    pub fn describe(self) -> &'static str {
        match self {
            Processor::X86 => "x86 (32-bit)",
            Processor::X86_64 => "x86-64",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_list_the_valid_ones() {
        for p in Platform::ALL {
            assert_eq!(Platform::parse(p.name()), Ok(p));
        }
        let e = Platform::parse("aarch64-linux").unwrap_err().reason;
        assert!(e.contains("win32, win64, linux32, linux64, darwin32, darwin64") && e.contains("aarch64"), "{e}");
        assert!(Platform::parse("Win64").is_err());
    }

    #[test]
    fn file_names_follow_each_platform() {
        assert_eq!((Platform::Win64.extension(), Platform::Win64.runtime_file()), ("dll", "fmu_runtime.dll"));
        assert_eq!((Platform::Linux32.extension(), Platform::Linux32.processor()), ("so", Processor::X86));
        assert_eq!((Platform::Darwin64.extension(), Platform::Darwin64.format()), ("dylib", Format::MachO));
    }
}
