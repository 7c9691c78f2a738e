//! Whether a file can be a platform's FMU binary: its format (PE, ELF, Mach-O), its processor,
//! that it is a shared library (not a program, an object file or an import library) and that it
//! exports the fmi2 functions the FMU needs. The file is read with the `object` crate and
//! never executed; each refusal is a sentence saying what the file is and what was expected.

use crate::error::Refusal;
use object::read::elf::{ElfFile, FileHeader, ProgramHeader};
use object::read::macho::{FatArch, MachHeader, MachOFatFile, MachOFile};
use object::{Architecture, Endianness, FileKind, Object};

use super::platform::{Format, Platform, Processor};

/// Ok when `data` can be `platform`'s binary exporting `required`; else what is wrong.
pub fn check(platform: Platform, data: &[u8], required: &[&str]) -> Result<(), Refusal> {
    let kind = FileKind::parse(data).map_err(|_| {
        Refusal::from(format!(
            "is not a shared library in a format this tool reads (PE, ELF, Mach-O); {platform} needs {}",
            platform.format().describe()
        ))
    })?;
    match kind {
        FileKind::MachOFat32 => {
            check_universal(platform, MachOFatFile::<object::macho::FatArch32>::parse(data), data, required)
        }
        FileKind::MachOFat64 => {
            check_universal(platform, MachOFatFile::<object::macho::FatArch64>::parse(data), data, required)
        }
        FileKind::Archive => Err(Refusal::from(format!(
            "is an archive (a static or import library, such as fmu_runtime.dll.lib), not a shared library; {platform} needs {}, e.g. {} from `cargo build -p fmu-runtime --release`",
            platform.format().describe(),
            platform.runtime_file()
        ))),
        _ => check_single(platform, data, required, true),
    }
}

/// One binary (not universal); `check_processor` is false for the other slices of a universal
/// Mach-O file, which serve hosts of other processors.
fn check_single(platform: Platform, data: &[u8], required: &[&str], check_processor: bool) -> Result<(), Refusal> {
    let file = object::File::parse(data)
        .map_err(|e| Refusal::caused_by(format!("cannot be read as an object file: {e}"), e))?;
    let expected = platform.format();
    let found = match &file {
        object::File::Pe32(_) | object::File::Pe64(_) => Some(Format::Pe),
        object::File::Elf32(_) | object::File::Elf64(_) => Some(Format::Elf),
        object::File::MachO32(_) | object::File::MachO64(_) => Some(Format::MachO),
        _ => None,
    };
    match found {
        Some(f) if f == expected => {}
        Some(f) => {
            return Err(Refusal::from(format!("is {}, not {} as {platform} needs", f.describe(), expected.describe())));
        }
        None => {
            return Err(Refusal::from(format!(
                "is an object file (COFF), not a shared library; {platform} needs {}",
                expected.describe()
            )));
        }
    }
    if check_processor {
        check_architecture(platform, file.architecture())?;
    }
    check_shared_library(&file)?;
    check_exports(&file, required)
}

fn check_architecture(platform: Platform, found: Architecture) -> Result<(), Refusal> {
    let wanted = match platform.processor() {
        Processor::X86 => Architecture::I386,
        Processor::X86_64 => Architecture::X86_64,
    };
    if found == wanted {
        return Ok(());
    }
    let mut reason =
        format!("is built for {}, but {platform} is {}", describe_architecture(found), platform.processor().describe());
    if !matches!(found, Architecture::I386 | Architecture::X86_64) {
        reason.push_str(&format!(
            "; FMI 2.0 has no platform for {} binaries (its platforms are x86 and x86-64 only)",
            describe_architecture(found)
        ));
        if platform == Platform::Darwin64 && found == Architecture::Aarch64 {
            reason.push_str(
                "; for Macs with Apple silicon, pass a universal binary with an x86_64 slice (lipo -create), which hosts of either processor load",
            );
        }
    }
    Err(Refusal::from(reason))
}

fn describe_architecture(a: Architecture) -> String {
    match a {
        Architecture::X86_64 => "x86-64".into(),
        Architecture::X86_64_X32 => "x86-64 with 32-bit pointers (x32)".into(),
        Architecture::I386 => "x86 (32-bit)".into(),
        Architecture::Aarch64 => "aarch64 (arm64)".into(),
        Architecture::Arm => "32-bit ARM".into(),
        other => format!("{other:?}").to_lowercase(),
    }
}

/// A library a host can load: an ELF without a program interpreter (a position-independent
/// program is ET_DYN too, but names one), a PE with the DLL flag, a Mach-O dylib or bundle.
fn check_shared_library(file: &object::File) -> Result<(), Refusal> {
    match file {
        object::File::Elf32(f) => elf_shared_library(f),
        object::File::Elf64(f) => elf_shared_library(f),
        object::File::MachO32(f) => macho_shared_library(f),
        object::File::MachO64(f) => macho_shared_library(f),
        _ => match file.kind() {
            object::ObjectKind::Dynamic => Ok(()),
            object::ObjectKind::Executable => Err("is a Windows program (.exe), not a DLL".into()),
            other => Err(Refusal::from(format!("is not a DLL (kind {other:?})"))),
        },
    }
}

fn elf_shared_library<Elf: FileHeader<Endian = Endianness>>(f: &ElfFile<Elf>) -> Result<(), Refusal> {
    let endian = f.endian();
    match f.elf_header().e_type(endian) {
        object::elf::ET_DYN => {}
        object::elf::ET_EXEC => return Err("is a program (ELF type EXEC), not a shared library".into()),
        object::elf::ET_REL => return Err("is an object file (ELF type REL), not a shared library".into()),
        other => return Err(Refusal::from(format!("is not a shared library (ELF type {other})"))),
    }
    if f.elf_program_headers().iter().any(|p| p.p_type(endian) == object::elf::PT_INTERP) {
        return Err("is a program (it names a program interpreter), not a shared library".into());
    }
    Ok(())
}

fn macho_shared_library<Mach: MachHeader<Endian = Endianness>>(f: &MachOFile<Mach>) -> Result<(), Refusal> {
    match f.macho_header().filetype(f.endian()) {
        object::macho::MH_DYLIB | object::macho::MH_BUNDLE => Ok(()),
        object::macho::MH_EXECUTE => Err("is a program (Mach-O MH_EXECUTE), not a dynamic library".into()),
        object::macho::MH_OBJECT => Err("is an object file (Mach-O MH_OBJECT), not a dynamic library".into()),
        other => Err(Refusal::from(format!("is not a dynamic library (Mach-O file type {other})"))),
    }
}

fn check_exports(file: &object::File, required: &[&str]) -> Result<(), Refusal> {
    let exports = file.exports().map_err(|e| Refusal::caused_by(format!("its export table cannot be read: {e}"), e))?;
    // Mach-O prefixes C symbols with an underscore
    let strip = matches!(file, object::File::MachO32(_) | object::File::MachO64(_));
    let names: std::collections::HashSet<&[u8]> =
        exports.iter().map(|e| e.name()).map(|n| if strip { n.strip_prefix(b"_").unwrap_or(n) } else { n }).collect();
    let missing: Vec<&str> = required.iter().copied().filter(|f| !names.contains(f.as_bytes())).collect();
    if missing.is_empty() {
        Ok(())
    } else {
        Err(Refusal::from(format!(
            "does not export {} of the {} fmi2 functions the FMU's modelDescription.xml needs: {}",
            missing.len(),
            required.len(),
            missing.join(", ")
        )))
    }
}

/// A universal (fat) Mach-O file: it must hold a slice of the platform's processor, and every
/// slice must be a dynamic library exporting the functions.
fn check_universal<Fat: FatArch>(
    platform: Platform,
    parsed: object::Result<MachOFatFile<Fat>>,
    data: &[u8],
    required: &[&str],
) -> Result<(), Refusal> {
    if platform.format() != Format::MachO {
        return Err(Refusal::from(format!(
            "is a universal macOS binary (Mach-O), not {} as {platform} needs",
            platform.format().describe()
        )));
    }
    let fat = parsed.map_err(|e| Refusal::caused_by(format!("cannot be read as a universal Mach-O binary: {e}"), e))?;
    let wanted = match platform.processor() {
        Processor::X86 => Architecture::I386,
        Processor::X86_64 => Architecture::X86_64,
    };
    let mut found = Vec::new();
    for arch in fat.arches() {
        let a = arch.architecture();
        let slice = arch.data(data).map_err(|e| {
            Refusal::caused_by(format!("has a slice for {} that cannot be read: {e}", describe_architecture(a)), e)
        })?;
        check_single(platform, slice, required, false).map_err(|e| Refusal {
            reason: format!("has a slice for {} that {e}", describe_architecture(a)),
            cause: e.cause,
        })?;
        found.push(describe_architecture(a));
    }
    if fat.arches().iter().any(|a| a.architecture() == wanted) {
        Ok(())
    } else {
        Err(Refusal::from(format!(
            "is a universal binary with slices for {} but none for {}, which {platform} is",
            found.join(", "),
            platform.processor().describe()
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::binaries::fmi2_functions;
    use crate::output::package::RUNTIME_SO;

    #[test]
    fn the_embedded_runtime_is_a_valid_linux64_binary_and_nothing_else() {
        let all = fmi2_functions::model_exchange_and_co_simulation();
        check(Platform::Linux64, RUNTIME_SO, &all).unwrap();
        let e = check(Platform::Win64, RUNTIME_SO, &all).unwrap_err().reason;
        assert!(e.contains("is a Linux shared object (ELF), not a Windows DLL (PE)"), "{e}");
        let e = check(Platform::Darwin64, RUNTIME_SO, &all).unwrap_err().reason;
        assert!(e.contains("Mach-O"), "{e}");
        let e = check(Platform::Linux32, RUNTIME_SO, &all).unwrap_err().reason;
        assert!(e.contains("is built for x86-64, but linux32 is x86 (32-bit)"), "{e}");
        let e = check(Platform::Linux64, RUNTIME_SO, &["fmi2DoStep", "fmi3DoStep"]).unwrap_err().reason;
        assert!(e.contains("does not export 1 of the 2 fmi2 functions") && e.ends_with(": fmi3DoStep"), "{e}");
    }

    #[test]
    fn damaged_or_foreign_files_are_refused_without_panicking() {
        let all = fmi2_functions::model_exchange_and_co_simulation();
        for bad in [&b""[..], b"MZ", b"\x7fELF", b"not a binary at all", b"!<arch>\n", &RUNTIME_SO[..4096]] {
            assert!(check(Platform::Linux64, bad, &all).is_err());
        }
        // an import library (fmu_runtime.dll.lib): an archive, not the DLL
        let e = check(Platform::Win64, format!("!<arch>\n{:60}", "").as_bytes(), &all).unwrap_err().reason;
        assert!(e.contains("archive") && e.contains("fmu_runtime.dll"), "{e}");
        // a universal header whose slice lies beyond the file
        let mut fat = Vec::new();
        for word in [0xcafe_babe_u32, 1, object::macho::CPU_TYPE_X86_64, 3, 4096, 1 << 20, 12] {
            fat.extend_from_slice(&word.to_be_bytes());
        }
        assert!(check(Platform::Darwin64, &fat, &all).is_err());
        // a universal file whose x86-64 slice is an ELF
        let mut fat = Vec::new();
        let offset = 4096_u32;
        for word in [0xcafe_babe_u32, 1, object::macho::CPU_TYPE_X86_64, 3, offset, RUNTIME_SO.len() as u32, 12] {
            fat.extend_from_slice(&word.to_be_bytes());
        }
        fat.resize(offset as usize, 0);
        fat.extend_from_slice(RUNTIME_SO);
        let e = check(Platform::Darwin64, &fat, &all).unwrap_err().reason;
        assert!(e.starts_with("has a slice for x86-64 that is a Linux shared object (ELF)"), "{e}");
    }
}
