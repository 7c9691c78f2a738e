//! Where the builder writes, checked before any work: the FMU and every export. Nothing the user
//! named is overwritten by surprise (an export naming the input, the FMU or another export; an
//! existing file without `--force`; a symbolic link, which the rename would replace), and a
//! destination that cannot be written (a folder where a file is meant, a missing or read-only
//! folder, a name over 255 bytes) is refused in a second, naming its option, rather than after
//! minutes of reduction with the FMU already written. `reserve` then holds every output for the
//! build: locked against another build, and guarded at its rename (`place`).
//!
//! Files are compared by identity, not by spelling: the device and inode of an existing file
//! (so links and `./a/../b` are seen through), else the canonical folder and the file name.

use crate::error::BuildError;
use std::path::{Path, PathBuf};

/// One place the builder will write: a file, or a folder and the files it writes into it.
#[derive(Debug, Clone)]
pub struct Destination {
    /// The command-line option that names it (`-o`, `--export-vtk`, ...), for messages.
    pub option: &'static str,
    pub path: PathBuf,
    /// Empty for a file; the names written into the folder `path` for a folder export.
    pub files_in_folder: &'static [&'static str],
}

impl Destination {
    pub fn file(option: &'static str, path: &Path) -> Self {
        Destination { option, path: path.to_path_buf(), files_in_folder: &[] }
    }
    pub fn folder(option: &'static str, path: &Path, files: &'static [&'static str]) -> Self {
        Destination { option, path: path.to_path_buf(), files_in_folder: files }
    }

    /// The files this destination writes.
    fn files(&self) -> Vec<PathBuf> {
        if self.files_in_folder.is_empty() {
            vec![self.path.clone()]
        } else {
            self.files_in_folder.iter().map(|f| self.path.join(f)).collect()
        }
    }
}

/// What `--export-matrices` writes into its folder.
pub const MOUNTED_MATRIX_FILES: &[&str] = &["K.mtx", "M.mtx", "flange_dofs.txt"];
/// What `--export-free-free` writes into its folder.
pub const FREE_FREE_FILES: &[&str] = &["K.mtx", "M.mtx", "dofs.txt", "nodes.txt"];

/// A file's identity: (device, inode) when it exists, else its canonical folder and name.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Identity {
    Inode(u64, u64),
    Named(PathBuf),
}

fn identity(path: &Path) -> Option<Identity> {
    use std::os::unix::fs::MetadataExt;
    if let Ok(m) = std::fs::metadata(path) {
        return Some(Identity::Inode(m.dev(), m.ino()));
    }
    let name = path.file_name()?;
    let folder = folder_of(path);
    let folder = std::fs::canonicalize(folder).ok()?;
    Some(Identity::Named(folder.join(name)))
}

/// The folder a path's file goes into ("." for a bare name).
fn folder_of(path: &Path) -> &Path {
    path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."))
}

/// Checks what can be checked of the destinations before the input is even read: every
/// component of each name within NAME_MAX (255 bytes) and the folder it goes into there.
pub fn precheck(destinations: &[Destination]) -> Result<(), BuildError> {
    for d in destinations {
        let shown = format!("{} {}", d.option, d.path.display());
        check_name(&d.path, &shown)?;
        let folder = folder_of(&d.path);
        if !folder.is_dir() {
            return Err(refuse(&shown, format!("the folder {} does not exist; create it first", folder.display())));
        }
    }
    Ok(())
}

/// Linux refuses a name component over 255 bytes (NAME_MAX) and a path over 4095 (PATH_MAX):
/// said before the build, not when the output is written after it.
fn check_name(path: &Path, shown: &str) -> Result<(), BuildError> {
    use std::os::unix::ffi::OsStrExt;
    if let Some(long) = path.iter().find(|c| c.as_bytes().len() > 255) {
        return Err(refuse(
            shown,
            format!(
                "the name {}... is {} bytes long; a file or folder name may have at most 255 bytes. Name a shorter one",
                long.to_string_lossy().chars().take(40).collect::<String>(),
                long.as_bytes().len()
            ),
        ));
    }
    if path.as_os_str().as_bytes().len() > 4000 {
        return Err(refuse(shown, "the path is longer than the system allows (4096 bytes); name a shorter one".into()));
    }
    Ok(())
}

/// Checks every destination before the build: Ok, or the refusal naming the option, the path,
/// what is wrong and what to do. `inputs` are the files the build reads (the input file, its
/// meshes and matrices): never overwritten, `--force` or not.
pub fn check(destinations: &[Destination], inputs: &[PathBuf], force: bool) -> Result<(), BuildError> {
    let input_ids: Vec<(Identity, &PathBuf)> = inputs.iter().filter_map(|p| Some((identity(p)?, p))).collect();
    let mut written: Vec<(Identity, &Destination)> = Vec::new();
    for d in destinations {
        let shown = format!("{} {}", d.option, d.path.display());
        check_name(&d.path, &shown)?;
        if d.files_in_folder.is_empty() {
            check_file_place(d, &shown)?;
        } else {
            check_folder_place(d, &shown)?;
            // the folder itself, against a file output of the same name (either order)
            if let Some(id) = identity(&d.path) {
                if let Some((_, other)) = written.iter().find(|(i, _)| *i == id) {
                    return Err(refuse(
                        &shown,
                        format!(
                            "{} is also written by {} as a file; this option makes a folder there. Give each \
                             output its own name",
                            other.path.display(),
                            other.option
                        ),
                    ));
                }
                written.push((id, d));
            }
        }
        for file in d.files() {
            let Some(id) = check_file(d, &file, &shown, &input_ids, &written, force)? else { continue };
            written.push((id, d));
        }
    }
    Ok(())
}

/// One file a destination writes, against the inputs, the files written before it and what is
/// there; its identity when it has one.
fn check_file(
    d: &Destination,
    file: &Path,
    shown: &str,
    input_ids: &[(Identity, &PathBuf)],
    written: &[(Identity, &Destination)],
    force: bool,
) -> Result<Option<Identity>, BuildError> {
    if let Ok(m) = std::fs::metadata(file)
        && !m.is_file()
    {
        // a FIFO would block the write until some reader came; a device is no file to keep
        return Err(refuse(
            shown,
            format!(
                "{} is {}, not a regular file; name a file",
                file.display(),
                crate::input::file_read::file_type_words(m.file_type())
            ),
        ));
    }
    let Some(id) = identity(file) else { return Ok(None) };
    let this = if d.files_in_folder.is_empty() { "this".to_string() } else { file.display().to_string() };
    if let Some((_, input)) = input_ids.iter().find(|(i, _)| *i == id) {
        return Err(refuse(
            shown,
            format!("{this} is the input {}; writing it would destroy the input. Name another file", input.display()),
        ));
    }
    if let Some((_, other)) = written.iter().find(|(i, _)| *i == id) {
        return Err(refuse(
            shown,
            format!(
                "{} is also written by {} {}; the one written last would replace the other. Give each output its \
                 own name",
                file.display(),
                other.option,
                other.path.display()
            ),
        ));
    }
    let there = std::fs::symlink_metadata(file);
    if there.as_ref().is_ok_and(|m| m.file_type().is_symlink()) {
        let target = std::fs::read_link(file).map(|t| t.display().to_string()).unwrap_or_default();
        return Err(refuse(
            shown,
            format!(
                "{} is a symbolic link (to {target}); an output is put in place by renaming, which would replace \
                 the link, not write what it names. Name the file itself, or remove the link",
                file.display()
            ),
        ));
    }
    if !force && there.is_ok() {
        return Err(refuse(
            shown,
            format!(
                "{} exists; pass --force to overwrite it, or name another {}",
                file.display(),
                if d.files_in_folder.is_empty() { "file" } else { "folder" }
            ),
        ));
    }
    Ok(Some(id))
}

/// What a build holds from its check to its end: each output's lock, and the rename's guard.
#[derive(Debug)]
pub struct Reservation {
    _locks: Vec<crate::output::lock::OutputLock>,
    _guard: crate::output::place::Guard,
}

/// `check`, then every output locked against another build (waited for with `force`), the
/// temporary files of killed builds beside it swept, and this thread's writes guarded against
/// an output that becomes an input or another output while the build runs.
pub fn reserve(
    destinations: &[Destination],
    inputs: &[PathBuf],
    force: bool,
    quiet: bool,
) -> Result<Reservation, BuildError> {
    use std::os::unix::fs::MetadataExt;
    check(destinations, inputs, force)?;
    let mut locks = Vec::new();
    let mut taken = Vec::new();
    let mut outputs = Vec::new();
    for d in destinations {
        let shown = format!("{} {}", d.option, d.path.display());
        // a file and a folder export of one name share a lock: taken twice, it would wait for itself
        let lock_path = crate::output::lock::lock_path(&d.path);
        if !taken.contains(&lock_path) {
            locks.extend(crate::output::lock::lock(&d.path, &shown, force, quiet)?);
            taken.push(lock_path);
        }
        for file in d.files() {
            if let Some(name) = file.file_name() {
                crate::output::temp_files::sweep_stale(folder_of(&file), name);
            }
            outputs.push((d.option, file));
        }
    }
    let inputs = inputs.iter().map(|p| (p.clone(), std::fs::metadata(p).ok().map(|m| (m.dev(), m.ino())))).collect();
    let guard = crate::output::place::guard(crate::output::place::Guarded { inputs, outputs, force });
    Ok(Reservation { _locks: locks, _guard: guard })
}

fn check_file_place(d: &Destination, shown: &str) -> Result<(), BuildError> {
    if d.path.is_dir() {
        let example = d.path.join(match d.option {
            "-o" => "Model.fmu",
            "--export-vtk" => "part.vtk",
            "--export-inp" => "part.inp",
            "--sweep-svg" => "sweep.svg",
            _ => "report.json",
        });
        return Err(refuse(shown, format!("is a folder; give a file name, e.g. {} {}", d.option, example.display())));
    }
    writable_folder(folder_of(&d.path), shown)
}

fn check_folder_place(d: &Destination, shown: &str) -> Result<(), BuildError> {
    match std::fs::metadata(&d.path) {
        Ok(m) if m.is_dir() => writable_folder(&d.path, shown),
        Ok(_) => {
            Err(refuse(shown, "is a file; this option writes several files into a folder: name a folder".to_string()))
        }
        // created by the export, in a folder that must exist
        Err(_) => writable_folder(folder_of(&d.path), shown),
    }
}

/// Ok when `folder` exists and a file can be created in it (probed: permissions alone miss
/// read-only mounts and ACLs).
fn writable_folder(folder: &Path, shown: &str) -> Result<(), BuildError> {
    if !folder.is_dir() {
        return Err(refuse(shown, format!("the folder {} does not exist; create it first", folder.display())));
    }
    let probe = folder.join(format!(".fmu-builder-probe-{}", std::process::id()));
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(refuse(shown, format!("cannot write into the folder {}: {e}", folder.display())).caused_by(e)),
    }
}

/// The refusal of a destination: `shown` is its option and path as the user wrote them.
fn refuse(shown: &str, reason: String) -> BuildError {
    BuildError::destination(shown, reason)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("destinations-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn an_export_naming_the_input_is_refused_even_with_force_and_through_a_link() {
        let dir = scratch("input");
        let input = dir.join("beam.json");
        std::fs::write(&input, "{}").unwrap();
        let link = dir.join("link.vtk");
        std::os::unix::fs::symlink(&input, &link).unwrap();
        for path in [input.clone(), link, dir.join(".").join("beam.json")] {
            let e = check(&[Destination::file("--export-vtk", &path)], std::slice::from_ref(&input), true)
                .unwrap_err()
                .to_string();
            assert!(e.starts_with("--export-vtk ") && e.contains("would destroy the input"), "{e}");
        }
        assert_eq!(std::fs::read_to_string(&input).unwrap(), "{}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn two_outputs_naming_one_file_are_refused_whether_or_not_it_exists() {
        let dir = scratch("twice");
        let fmu = dir.join("B.fmu");
        let both = [
            Destination::file("-o", &fmu),
            Destination::file("--report", &dir.join("..").join(dir.file_name().unwrap()).join("B.fmu")),
        ];
        let e = check(&both, &[], false).unwrap_err().to_string();
        assert!(e.starts_with("--report ") && e.contains("is also written by -o"), "{e}");
        std::fs::write(&fmu, "x").unwrap();
        let e = check(&both, &[], true).unwrap_err().to_string();
        assert!(e.contains("is also written by -o"), "{e}");
        // a folder export named as the FMU, before or after it
        let folder = Destination::folder("--export-matrices", &dir.join("C.fmu"), MOUNTED_MATRIX_FILES);
        let file = Destination::file("-o", &dir.join("C.fmu"));
        let e = check(&[file.clone(), folder.clone()], &[], true).unwrap_err().to_string();
        assert!(e.starts_with("--export-matrices ") && e.contains("is also written by -o as a file"), "{e}");
        let e = check(&[folder, file], &[], true).unwrap_err().to_string();
        assert!(e.starts_with("-o ") && e.contains("is also written by --export-matrices"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn folders_missing_folders_existing_files_and_folder_exports_are_checked() {
        let dir = scratch("places");
        let e = check(&[Destination::file("--export-inp", &dir)], &[], false).unwrap_err().to_string();
        assert!(e.contains("is a folder; give a file name, e.g. --export-inp"), "{e}");
        let e =
            check(&[Destination::file("--report", &dir.join("no/such/r.json"))], &[], false).unwrap_err().to_string();
        assert!(e.starts_with("--report ") && e.contains("does not exist"), "{e}");
        let existing = dir.join("r.json");
        std::fs::write(&existing, "old").unwrap();
        let e = check(&[Destination::file("--report", &existing)], &[], false).unwrap_err().to_string();
        assert!(e.contains("exists; pass --force"), "{e}");
        assert!(check(&[Destination::file("--report", &existing)], &[], true).is_ok());
        // a folder export onto a file, and onto a folder holding the input's matrices
        let e = check(&[Destination::folder("--export-free-free", &existing, FREE_FREE_FILES)], &[], false)
            .unwrap_err()
            .to_string();
        assert!(e.contains("is a file; this option writes several files into a folder"), "{e}");
        let k = dir.join("K.mtx");
        std::fs::write(&k, "%%MatrixMarket").unwrap();
        let e =
            check(&[Destination::folder("--export-free-free", &dir, FREE_FREE_FILES)], std::slice::from_ref(&k), true)
                .unwrap_err()
                .to_string();
        assert!(e.contains("K.mtx is the input"), "{e}");
        assert!(
            check(&[Destination::folder("--export-matrices", &dir.join("new"), MOUNTED_MATRIX_FILES)], &[], false)
                .is_ok()
        );
        let e = check(&[Destination::file("--export-inp", Path::new("/dev/null"))], &[], true).unwrap_err().to_string();
        assert!(e.contains("/dev/null is a character device, not a regular file"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
