//! The contract between `cargo xtask runtime`, which builds the FMU's linux64 runtime once, and
//! fmu-builder/build.rs, which embeds it: where the binary lies in the target folder, the record
//! beside it (`runtime.info`: its kind, the glibc a native one needs, the hash of the sources it
//! was built from, the hash of the binary) and how the source hash is computed. One file, included
//! by both (`#[path]`), so the two cannot disagree; std only, since a build script compiles it.
//! Each side uses its half: the writer's functions are dead code in build.rs and the reader's in
//! xtask.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The folder of the target directory that holds the runtime and its record.
pub const DIR: &str = "fmu-runtime";
/// The runtime cdylib, as `cargo xtask runtime` places it in `DIR`.
pub const SO: &str = "libfmu_runtime.so";
/// The record beside it.
pub const INFO: &str = "runtime.info";
/// The command that builds (or rebuilds) the runtime, for every message that asks for it.
pub const COMMAND: &str = "cargo xtask runtime";

/// What the runtime binary is built from, relative to the workspace root: files, and folders whose
/// every file counts. The workspace manifest, the lock file and the cargo configuration are in,
/// whole: a change there that leaves the runtime as it was costs one `cargo xtask runtime`, in
/// which cargo finds nothing to recompile; one that changes it is never missed.
pub const INPUTS: &[&str] = &[
    "Cargo.toml",
    "Cargo.lock",
    ".cargo/config.toml",
    "fmi2/Cargo.toml",
    "fmi2/src",
    "fmu-runtime/Cargo.toml",
    "fmu-runtime/build.rs",
    "fmu-runtime/src",
];

/// What `runtime.info` says of the binary beside it.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// "portable, glibc 2.17 or newer, linked by zig X" or "native, glibc of the build machine or
    /// newer": the builder's `FMU_RUNTIME_LINUX64`.
    pub kind: String,
    /// The newest glibc a native binary needs, e.g. "2.34"; empty for a portable one: the
    /// builder's `FMU_RUNTIME_NATIVE_GLIBC`.
    pub native_glibc: String,
    /// The cargo profile it was built with.
    pub profile: String,
    /// `hash_inputs` of the tree it was built from.
    pub sources: String,
    /// `hash_bytes` of the binary.
    pub binary: String,
}

impl Record {
    pub fn to_text(&self) -> String {
        format!(
            "# written by `{COMMAND}`, read by fmu-builder/build.rs (fmu-builder/build/runtime_stamp.rs)\n\
             kind={}\nnative_glibc={}\nprofile={}\nsources={}\nbinary={}\n",
            self.kind, self.native_glibc, self.profile, self.sources, self.binary
        )
    }

    pub fn parse(text: &str) -> Result<Record, String> {
        let field = |key: &str| {
            text.lines()
                .find_map(|line| line.strip_prefix(key).and_then(|rest| rest.strip_prefix('=')))
                .map(str::to_string)
                .ok_or_else(|| format!("no `{key}=` line"))
        };
        Ok(Record {
            kind: field("kind")?,
            native_glibc: field("native_glibc")?,
            profile: field("profile")?,
            sources: field("sources")?,
            binary: field("binary")?,
        })
    }
}

/// Every file of `INPUTS` below `root` that exists, named relative to it with forward slashes,
/// sorted: the same list on every file system.
pub fn input_files(root: &Path) -> Result<Vec<(String, PathBuf)>, String> {
    let mut files = Vec::new();
    for input in INPUTS {
        collect(&root.join(input), input, &mut files)?;
    }
    files.sort();
    Ok(files)
}

fn collect(path: &Path, name: &str, out: &mut Vec<(String, PathBuf)>) -> Result<(), String> {
    if path.is_file() {
        out.push((name.to_string(), path.to_path_buf()));
    } else if path.is_dir() {
        let entries = std::fs::read_dir(path).map_err(|e| format!("cannot list {}: {e}", path.display()))?;
        for entry in entries {
            let entry = entry.map_err(|e| format!("cannot list {}: {e}", path.display()))?;
            let file_name = entry.file_name().to_string_lossy().into_owned();
            collect(&entry.path(), &format!("{name}/{file_name}"), out)?;
        }
    }
    Ok(())
}

/// One hash of the names and contents of `input_files(root)`.
pub fn hash_inputs(root: &Path) -> Result<String, String> {
    let mut hash = Fnv1a64::new();
    for (name, path) in input_files(root)? {
        let bytes = std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        hash.update(name.as_bytes());
        hash.update(&[0]);
        hash.update(&(bytes.len() as u64).to_le_bytes());
        hash.update(&bytes);
    }
    Ok(format!("fnv1a64:{:016x}", hash.0))
}

/// The hash of a binary, as the record gives it.
pub fn hash_bytes(bytes: &[u8]) -> String {
    let mut hash = Fnv1a64::new();
    hash.update(bytes);
    format!("fnv1a64:{:016x}", hash.0)
}

/// 64-bit FNV-1a: tells one source tree or binary from another (a consistency check between
/// builds, not a defence against forgery).
struct Fnv1a64(u64);

impl Fnv1a64 {
    fn new() -> Self {
        Self(0xcbf2_9ce4_8422_2325)
    }
    fn update(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// The newest `GLIBC_x.y[.z]` symbol version named in a shared library (the names of its version
/// needs are plain strings in its dynamic string table), e.g. "2.34".
pub fn newest_glibc(so: &[u8]) -> Option<String> {
    const TAG: &[u8] = b"GLIBC_";
    let mut newest: Option<Vec<u32>> = None;
    let mut i = 0;
    while let Some(pos) = so[i..].windows(TAG.len()).position(|w| w == TAG) {
        let start = i + pos + TAG.len();
        let end = start + so[start..].iter().take_while(|b| b.is_ascii_digit() || **b == b'.').count();
        let parts: Option<Vec<u32>> =
            std::str::from_utf8(&so[start..end]).ok().and_then(|v| v.split('.').map(|p| p.parse().ok()).collect());
        if let Some(parts) = parts.filter(|p| p.len() >= 2)
            && newest.as_ref().is_none_or(|n| parts > *n)
        {
            newest = Some(parts);
        }
        i = end.max(start);
    }
    newest.map(|v| v.iter().map(u32::to_string).collect::<Vec<_>>().join("."))
}

/// Why `bytes` is not a 64-bit little-endian ELF shared object whose dynamic symbol table defines
/// `symbol`; Ok when it is. Read from the section headers, without running anything.
pub fn check_elf_exports(bytes: &[u8], symbol: &str) -> Result<(), String> {
    let u16_at = |at: usize| bytes.get(at..at + 2).map(|b| u16::from_le_bytes([b[0], b[1]]));
    let u32_at = |at: usize| bytes.get(at..at + 4).map(|b| u32::from_le_bytes(b.try_into().unwrap_or_default()));
    let u64_at = |at: usize| {
        bytes.get(at..at + 8).and_then(|b| usize::try_from(u64::from_le_bytes(b.try_into().unwrap_or_default())).ok())
    };
    if bytes.get(..4) != Some(b"\x7fELF".as_slice()) {
        return Err("it is not an ELF file".to_string());
    }
    if bytes.get(4..6) != Some([2u8, 1].as_slice()) {
        return Err("it is not a 64-bit little-endian ELF file".to_string());
    }
    if u16_at(16) != Some(3) {
        return Err("it is not a shared object (ELF type ET_DYN)".to_string());
    }
    let truncated = || "its section headers are truncated".to_string();
    let (shoff, shentsize, shnum) =
        (u64_at(0x28).ok_or_else(truncated)?, u16_at(0x3a).ok_or_else(truncated)?, u16_at(0x3c).ok_or_else(truncated)?);
    let section = |i: usize| shoff + i * usize::from(shentsize);
    // SHT_DYNSYM; its sh_link names the string table of the symbol names
    let dynsym = (0..usize::from(shnum))
        .find(|&i| u32_at(section(i) + 4) == Some(11))
        .ok_or_else(|| "it has no dynamic symbol table".to_string())?;
    let (sym_off, sym_size) =
        (u64_at(section(dynsym) + 0x18).ok_or_else(truncated)?, u64_at(section(dynsym) + 0x20).ok_or_else(truncated)?);
    let strtab = u32_at(section(dynsym) + 0x28).ok_or_else(truncated)? as usize;
    let str_off = u64_at(section(strtab) + 0x18).ok_or_else(truncated)?;
    for entry in (sym_off..sym_off + sym_size).step_by(24) {
        let (Some(name), Some(shndx)) = (u32_at(entry), u16_at(entry + 6)) else { break };
        let start = str_off + name as usize;
        let name = bytes.get(start..).and_then(|s| s.split(|&b| b == 0).next()).unwrap_or_default();
        if name == symbol.as_bytes() && shndx != 0 {
            return Ok(());
        }
    }
    Err(format!("it does not export {symbol}"))
}
