//! The .fmu zip archive: modelDescription.xml at the root, `binaries/<platform>/<id>.<dll|so|dylib>`
//! (no `lib` prefix, executable), `resources/...`, `documentation/...`; deflate, forward slashes.
//!
//! The archive is written to a temporary file next to the target and renamed into place only
//! when complete (`output::place`), so a failed build never leaves a half FMU where an importer
//! would pick it up.

use std::collections::HashSet;
use std::fs::File;
use std::io::{BufWriter, Seek, SeekFrom, Write};
use std::path::Path;

use zip::write::SimpleFileOptions;
use zip::{CompressionMethod, ZipWriter};

use super::is_model_identifier;
use crate::error::{BuildError, Refusal};
use crate::output::binaries::Platform;
use crate::output::place;

pub struct FmuArchive<'a> {
    pub model_description: String,
    pub model_identifier: &'a str,
    /// The runtime binary of each platform (at least one, one per platform).
    pub binaries: Vec<(Platform, &'a [u8])>,
    /// Paths relative to `resources/`, e.g. `reduced_body.bin`.
    pub resources: Vec<(String, Vec<u8>)>,
    /// Paths relative to `documentation/`; the caller provides `index.html`.
    pub documentation: Vec<(String, Vec<u8>)>,
}

/// Writes the FMU at `path`, replacing an existing file only once the new one is complete.
pub fn write_fmu(path: &Path, a: &FmuArchive) -> Result<(), BuildError> {
    let entries = entries(a).map_err(|e| BuildError::file(path, e.reason))?;
    place::write_with(path, |file| write_zip(file, &entries))
}

/// One archive entry: full name inside the zip, content, unix mode.
struct Entry<'a> {
    name: String,
    data: &'a [u8],
    mode: u32,
}

fn entries<'a>(a: &'a FmuArchive) -> Result<Vec<Entry<'a>>, Refusal> {
    if !is_model_identifier(a.model_identifier) {
        return Err(Refusal::from(format!("model identifier '{}' is not a valid C identifier", a.model_identifier)));
    }
    if a.binaries.is_empty() {
        return Err("there is no binary for any platform".into());
    }
    let mut list =
        vec![Entry { name: "modelDescription.xml".into(), data: a.model_description.as_bytes(), mode: 0o644 }];
    for (platform, data) in &a.binaries {
        if data.is_empty() {
            return Err(Refusal::from(format!("the {platform} binary is empty")));
        }
        let name = format!("binaries/{platform}/{}.{}", a.model_identifier, platform.extension());
        // Importers dlopen this file: it must be executable once extracted.
        list.push(Entry { name, data, mode: 0o755 });
    }
    for (folder, files) in [("resources", &a.resources), ("documentation", &a.documentation)] {
        for (name, data) in files {
            check_relative(name).map_err(|m| Refusal::from(format!("{folder} entry '{name}': {m}")))?;
            list.push(Entry { name: format!("{folder}/{name}"), data, mode: 0o644 });
        }
    }
    let mut seen = HashSet::new();
    for e in &list {
        if !seen.insert(e.name.as_str()) {
            return Err(Refusal::from(format!("the archive would contain '{}' twice", e.name)));
        }
    }
    Ok(list)
}

/// A path below a folder of the archive: forward slashes only, no empty, `.` or `..`
/// components (zip-slip on extraction), no absolute path.
fn check_relative(name: &str) -> Result<(), &'static str> {
    if name.contains('\\') {
        return Err("use forward slashes");
    }
    if name.contains('\0') {
        return Err("contains a NUL character");
    }
    if name.split('/').any(|c| c.is_empty() || c == "." || c == "..") {
        return Err("must be a relative path without empty, '.' or '..' components");
    }
    Ok(())
}

fn write_zip(file: File, entries: &[Entry]) -> Result<(), Refusal> {
    let mut zip = ZipWriter::new(Target { file: BufWriter::new(file), failed: false, position: 0 });
    let base = SimpleFileOptions::default().compression_method(CompressionMethod::Deflated);
    // Explicit directory entries: some importers extract entry by entry without creating parents.
    let mut dirs: Vec<&str> = Vec::new();
    for e in entries {
        let mut end = 0;
        while let Some(i) = e.name[end..].find('/') {
            end += i + 1;
            let d = &e.name[..end];
            if !dirs.contains(&d) {
                dirs.push(d);
                zip.add_directory(d, base.unix_permissions(0o755)).map_err(|e| failed(&format!("adding {d}"), e))?;
            }
        }
        let options = base.unix_permissions(e.mode).large_file(e.data.len() as u64 >= u32::MAX as u64);
        zip.start_file(e.name.as_str(), options).map_err(|err| failed(&format!("adding {}", e.name), err))?;
        zip.write_all(e.data).map_err(|err| failed(&format!("writing {}", e.name), err.into()))?;
    }
    let target = zip.finish().map_err(|e| failed("finishing the archive", e))?;
    if target.failed {
        return Err(Refusal::from("a write of the archive failed"));
    }
    let file = target.file.into_inner().map_err(|e| failed("flushing the archive", e.into_error().into()))?;
    file.sync_all().map_err(|e| failed("syncing the archive", e.into()))
}

/// The archive's file. After its first failed write or seek it takes everything and keeps
/// nothing: the zip writer, dropped on the error's way out, finalizes the archive, and would
/// otherwise print its own failure of that on standard error besides the builder's message.
struct Target {
    file: BufWriter<File>,
    failed: bool,
    /// Where the zip writer believes it is once the file failed.
    position: u64,
}

impl Write for Target {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if self.failed {
            self.position += buf.len() as u64;
            return Ok(buf.len());
        }
        let written = self.file.write(buf).inspect_err(|_| self.failed = true)?;
        self.position += written as u64;
        Ok(written)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        if self.failed { Ok(()) } else { self.file.flush().inspect_err(|_| self.failed = true) }
    }
}

impl Seek for Target {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        if !self.failed {
            self.position = self.file.seek(to).inspect_err(|_| self.failed = true)?;
            return Ok(self.position);
        }
        self.position = match to {
            SeekFrom::Start(p) => p,
            SeekFrom::Current(d) | SeekFrom::End(d) => self.position.saturating_add_signed(d),
        };
        Ok(self.position)
    }
}

/// A failed step of the archive's write; a full disk or the file size limit said as such.
fn failed(step: &str, e: zip::result::ZipError) -> Refusal {
    match e {
        zip::result::ZipError::Io(io) => Refusal::caused_by(format!("{step}: {}", place::io_words(&io)), io),
        other => Refusal::caused_by(format!("{step}: {other}"), other),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::io::Read;
    use std::path::PathBuf;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("fmu-archive-test-{}-{name}", std::process::id()));
        let _ = fs::remove_dir_all(&d);
        fs::create_dir_all(&d).unwrap();
        d
    }

    fn archive<'a>(binary: &'a [u8]) -> FmuArchive<'a> {
        FmuArchive {
            model_description: "<fmiModelDescription/>".into(),
            model_identifier: "Beam",
            binaries: vec![(Platform::Linux64, binary)],
            resources: vec![("reduced_body.bin".into(), vec![1, 2, 3])],
            documentation: vec![("index.html".into(), b"<html></html>".to_vec())],
        }
    }

    #[test]
    fn layout_modes_and_compression() {
        let dir = scratch("layout");
        let path = dir.join("Beam.fmu");
        let binary = vec![0x7f; 5000];
        write_fmu(&path, &archive(&binary)).unwrap();
        let mut zip = zip::ZipArchive::new(File::open(&path).unwrap()).unwrap();
        let names: Vec<String> = zip.file_names().map(|n| n.unwrap().into_owned()).collect();
        let mut files: Vec<&str> = names.iter().map(String::as_str).filter(|n| !n.ends_with('/')).collect();
        files.sort();
        assert_eq!(
            files,
            [
                "binaries/linux64/Beam.so",
                "documentation/index.html",
                "modelDescription.xml",
                "resources/reduced_body.bin"
            ]
        );
        assert!(names.iter().any(|n| n == "resources/"));
        {
            let mut so = zip.by_name("binaries/linux64/Beam.so").unwrap();
            assert_eq!(so.unix_mode().unwrap() & 0o777, 0o755);
            assert_eq!(so.compression(), CompressionMethod::Deflated);
            let mut data = Vec::new();
            so.read_to_end(&mut data).unwrap();
            assert_eq!(data, binary);
        }
        let mut md = String::new();
        zip.by_name("modelDescription.xml").unwrap().read_to_string(&mut md).unwrap();
        assert_eq!(md, "<fmiModelDescription/>");
        // nothing but the FMU is left in the directory
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_failed_build_leaves_no_file() {
        let dir = scratch("fail");
        let path = dir.join("Beam.fmu");
        let binary = [1u8];
        let bad_entries = [
            ("resources", "../evil"),
            ("resources", "/abs"),
            ("resources", "a\\b"),
            ("documentation", "a//b"),
            ("documentation", ""),
        ];
        for (folder, name) in bad_entries {
            let mut a = archive(&binary);
            let list = if folder == "resources" { &mut a.resources } else { &mut a.documentation };
            list.push((name.into(), vec![0]));
            let e = write_fmu(&path, &a).unwrap_err();
            assert!(e.to_string().contains(folder), "{e}");
        }
        let mut a = archive(&binary);
        a.resources.push(("reduced_body.bin".into(), vec![]));
        assert!(write_fmu(&path, &a).unwrap_err().to_string().contains("twice"));
        let mut a = archive(&binary);
        a.model_identifier = "lib-Beam";
        assert!(write_fmu(&path, &a).is_err());
        assert!(write_fmu(&path, &archive(&[])).is_err());
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);
        // an unwritable target directory is an error, not a panic
        assert!(write_fmu(&dir.join("missing/Beam.fmu"), &archive(&binary)).is_err());
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn each_platform_binary_at_its_name() {
        let dir = scratch("platforms");
        let path = dir.join("Beam.fmu");
        let (so, dll, dylib) = (vec![1u8; 10], vec![2u8; 10], vec![3u8; 10]);
        let mut a = archive(&so);
        a.binaries.extend([(Platform::Win64, &dll[..]), (Platform::Darwin64, &dylib[..])]);
        write_fmu(&path, &a).unwrap();
        let mut zip = zip::ZipArchive::new(File::open(&path).unwrap()).unwrap();
        for (name, data) in [
            ("binaries/linux64/Beam.so", &so),
            ("binaries/win64/Beam.dll", &dll),
            ("binaries/darwin64/Beam.dylib", &dylib),
        ] {
            let mut entry = zip.by_name(name).unwrap();
            assert_eq!(entry.unix_mode().unwrap() & 0o777, 0o755, "{name}");
            let mut read = Vec::new();
            entry.read_to_end(&mut read).unwrap();
            assert_eq!(&read, data, "{name}");
        }
        // one binary per platform, none empty, at least one
        let mut twice = archive(&so);
        twice.binaries.push((Platform::Linux64, &dll[..]));
        assert!(write_fmu(&path, &twice).unwrap_err().to_string().contains("twice"));
        let mut empty = archive(&so);
        empty.binaries.push((Platform::Win32, &[]));
        assert!(write_fmu(&path, &empty).unwrap_err().to_string().contains("the win32 binary is empty"));
        let mut none = archive(&so);
        none.binaries.clear();
        assert!(write_fmu(&path, &none).unwrap_err().to_string().contains("no binary"));
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn replaces_an_existing_fmu() {
        let dir = scratch("replace");
        let path = dir.join("Beam.fmu");
        fs::write(&path, b"old").unwrap();
        write_fmu(&path, &archive(&[1, 2])).unwrap();
        assert!(zip::ZipArchive::new(File::open(&path).unwrap()).is_ok());
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        let _ = fs::remove_dir_all(&dir);
    }
}
